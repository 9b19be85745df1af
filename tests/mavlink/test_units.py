"""Pure pieces without sockets: frame splitting, .parm files, WPL files, parameter coercion,
stream scheduling, MAVFTP replies, telemetry encoders on odd snapshots."""

from __future__ import annotations

import collections
import math
import os

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs import ftp

from silbridge.mavlink.gcs import telemetry
from silbridge.mavlink.errors import MissionFileError, ParamFileError
from silbridge.mavlink.framing import FrameDecoder, RxCounters
from silbridge.mavlink.gcs.mission_store import MissionStore, check_item
from silbridge.mavlink.gcs.param_types import coerce
from silbridge.mavlink.gcs.params_file import (apply_parm, format_value, load_parm, parse_parm,
                                           save_parm, save_store)
from silbridge.mavlink.gcs.stream_clock import StreamClock
from silbridge.mavlink.gcs.streams import StreamSchedule
from silbridge.mavlink.gcs.vehicle_api import MissionItem, VehicleSnapshot
from silbridge.mavlink.gcs.wpl import format_wpl, parse_wpl

from mavtest_vehicle import DeclaredParamStore


def _frame(msg, sysid=255) -> bytes:
    return bytes(msg.pack(mav.MAVLink(None, srcSystem=sysid, srcComponent=190)))


def test_decoder_datagram_and_stream_semantics():
    hb = _frame(mav.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
    c = RxCounters()
    d = FrameDecoder(mav.MAVLink(None), c)
    assert len(d.feed(hb + hb, datagram=True)) == 2
    # a truncated frame at the end of a datagram does not spoil the next datagram
    assert d.feed(hb[:7], datagram=True) == [] and c.rx_malformed == 1
    assert len(d.feed(hb, datagram=True)) == 1
    # on a stream the tail waits for the rest
    s = FrameDecoder(mav.MAVLink(None), RxCounters())
    assert s.feed(hb[:5], datagram=False) == []
    assert len(s.feed(hb[5:] + b"\x00\x01" + hb, datagram=False)) == 2
    assert c.rx_ok == 3


def test_parm_roundtrip_and_errors(tmp_path):
    store = DeclaredParamStore()
    store.set("ATC_RAT_RLL_P", 0.125)
    path = tmp_path / "a.parm"
    save_store(path, store)
    text = path.read_text()
    assert "ATC_RAT_RLL_D    0.0036\n" in text and "SYSID_MYGCS      255\n" in text
    fresh = DeclaredParamStore()
    assert apply_parm(fresh, load_parm(path)) == []
    assert [fresh.get(n) for n in fresh.names()] == [store.get(n) for n in store.names()]
    # float32 values come back bit-exact with the fewest digits
    f32 = mav.MAVLink_param_value_message(b"X", 0.135, 9, 1, 0)
    wire = mav.MAVLink(None).decode(bytearray(f32.pack(mav.MAVLink(None, 1, 1)))).param_value
    assert format_value(wire, 9) == "0.135"
    entries = parse_parm("# comment\nA,1\nB\t2.5  # trailing\n\n")
    assert entries == [("A", 1.0), ("B", 2.5)]
    with pytest.raises(ParamFileError):
        parse_parm("ONLY_NAME\n")
    with pytest.raises(ParamFileError):
        parse_parm("A notanumber\n")
    with pytest.raises(ParamFileError):
        load_parm(tmp_path / "missing.parm")
    problems = apply_parm(fresh, [("NOPE", 1.0), ("ATC_RAT_RLL_P", 9.0), ("RTL_ALT", math.nan)])
    assert len(problems) == 3 and "unknown" in problems[0]
    assert math.isclose(fresh.get("ATC_RAT_RLL_P")[0], 0.125)


def test_parm_save_is_atomic(tmp_path, monkeypatch):
    path = tmp_path / "p.parm"
    save_parm(path, [("A", 1, mav.MAV_PARAM_TYPE_INT8)])

    def boom(fd):
        raise OSError(5, "disk on fire")
    monkeypatch.setattr(os, "fsync", boom)
    with pytest.raises(OSError):
        save_parm(path, [("A", 2, mav.MAV_PARAM_TYPE_INT8)])
    assert path.read_text() == "A                1\n"
    assert [p.name for p in tmp_path.iterdir()] == ["p.parm"]


def test_coerce_rules():
    assert coerce(3.6, mav.MAV_PARAM_TYPE_INT8) == (4, None)
    assert coerce(-129, mav.MAV_PARAM_TYPE_INT8)[1] is not None
    assert coerce(70000, mav.MAV_PARAM_TYPE_UINT16)[1] is not None
    assert coerce(float("nan"), mav.MAV_PARAM_TYPE_REAL32)[1] is not None
    assert coerce(-float("inf"), mav.MAV_PARAM_TYPE_INT32)[1] is not None
    assert coerce(0.5, mav.MAV_PARAM_TYPE_REAL32) == (0.5, None)


def test_wpl_parse_errors_and_format():
    items = [MissionItem(0, 0, 16, x=-353632621, y=1491652374, z=584.0),
             MissionItem(1, 2, 178, param1=1, param2=5.5, param3=-1)]
    text = format_wpl(items)
    assert text.splitlines()[1].split("\t")[8:10] == ["-35.36326210", "149.16523740"]
    assert all(a.same_content(b) for a, b in zip(items, parse_wpl(text), strict=True))
    with pytest.raises(MissionFileError):
        parse_wpl("QGC WPL 100\n")
    with pytest.raises(MissionFileError):
        parse_wpl("QGC WPL 110\n0\t1\t0\t16\n")
    with pytest.raises(MissionFileError):
        parse_wpl("QGC WPL 110\n1\t0\t0\t16\t0\t0\t0\t0\t0\t0\t0\t1\n")


def test_mission_store_rules():
    store = MissionStore(capacity=3)
    home = MissionItem(0, 0, 16)
    assert store.replace([home, MissionItem(1, 3, 22, z=10), MissionItem(2, 2, 20)]) == 0
    assert store.replace([home] * 4) == mav.MAV_MISSION_NO_SPACE
    assert store.replace([home, MissionItem(2, 3, 16)]) == mav.MAV_MISSION_INVALID_SEQUENCE
    assert store.count() == 3
    assert check_item(MissionItem(1, 3, 19, param1=-1)) == mav.MAV_MISSION_INVALID_PARAM1
    assert check_item(MissionItem(1, 2, 178, param2=math.nan)) == mav.MAV_MISSION_INVALID_PARAM2
    assert check_item(MissionItem(1, 3, 16, param4=math.inf)) == mav.MAV_MISSION_INVALID_PARAM4
    assert check_item(MissionItem(1, 2, 16)) == mav.MAV_MISSION_UNSUPPORTED_FRAME
    assert check_item(MissionItem(1, 3, 16, y=1_900_000_000)) == mav.MAV_MISSION_INVALID_PARAM6_Y
    store.clear()
    assert store.items() == (home,)


def test_stream_schedule_skips_instead_of_bursting():
    clock = StreamClock()
    s = StreamSchedule(clock)
    s.set_interval(30, 100_000)

    def due_at(sim_ms):
        clock.update(sim_ms * 1000, 0)
        return s.due()
    assert 30 in due_at(0)
    assert 30 not in due_at(50)
    assert 30 in due_at(100)
    assert due_at(5000).count(30) == 1          # a 5 s stall yields one send, not fifty
    assert 30 not in due_at(5050)
    s.set_interval(30, 1e-3)
    assert s.intervals_us[30] == 4000           # clamped to 250 Hz
    s.set_interval(31, math.inf)
    assert s.intervals_us[31] == 3_600_000_000  # clamped to an hour
    s.request_data_stream(mav.MAV_DATA_STREAM_EXTRA1, 0, False)
    assert 30 not in s.intervals_us


def test_stream_schedule_counts_on_sim_time():
    # 20 ms snapshots (the vehicle's 50 Hz): 10, 30 and 50 Hz come at their rate per simulated
    # second, whatever the wall clock did; 100 Hz gets one message per snapshot.
    clock = StreamClock()
    s = StreamSchedule(clock)
    for mid, hz in ((30, 10), (33, 30), (24, 50), (74, 100)):
        s.set_interval(mid, 1e6 / hz)
    sent = collections.Counter()
    for k in range(501):                       # 10 simulated seconds
        clock.update(k * 20_000, wall_us=k * 4_000)
        sent.update(s.due())
    assert sent[30] == 101 and sent[24] == 501 and sent[74] == 501
    assert 300 <= sent[33] <= 301
    assert sent[0] == 11                       # HEARTBEAT at 1 Hz of sim time


def test_stream_clock_runs_on_sim_time_and_never_back():
    c = StreamClock()
    assert c.update(5_000_000, 0) == 5_000_000
    assert c.update(5_000_000, 900_000) == 5_000_000          # still, within STILL_US
    assert c.update(5_000_000, 3_000_000) == 7_000_000        # still: the wall clock goes on
    assert c.update(5_020_000, 3_001_000) == 7_000_000        # moves again: from there
    assert c.update(5_040_000, 3_002_000) == 7_020_000
    assert c.update(0, 3_003_000) == 7_020_000                # restarted at 0: never back
    assert c.update(20_000, 3_004_000) == 7_040_000


def test_stream_clock_pace_tells_when_to_wake():
    c = StreamClock()
    assert c.wall_us_until(1_000_000) is None                 # no pace yet
    for k in range(60):                                       # 20 ms snapshots at 5x
        c.update(k * 20_000, k * 4_000)
    assert c.pace == pytest.approx(5.0)
    assert c.wall_us_until(c.now_us + 100_000) == pytest.approx(20_000)
    assert c.wall_us_until(c.now_us - 1) == 0


def test_ftp_replies():
    def req(opcode, seq=1):
        p = bytearray(251)
        p[0:2] = seq.to_bytes(2, "little")
        p[3] = opcode
        return p
    assert ftp.reply_payload(req(2))[3] == ftp.OP_ACK               # reset sessions
    r = ftp.reply_payload(req(3))                                   # list directory
    assert r[3] == ftp.OP_NAK and r[12] == ftp.ERR_FILE_NOT_FOUND
    assert ftp.reply_payload(req(5))[12] == ftp.ERR_INVALID_SESSION
    assert ftp.reply_payload(req(77))[12] == ftp.ERR_UNKNOWN_COMMAND
    assert ftp.reply_payload(req(ftp.OP_ACK)) is None
    assert int.from_bytes(ftp.reply_payload(req(4, 65535))[0:2], "little") == 0


def test_encoders_survive_odd_snapshots():
    odd = VehicleSnapshot(time_boot_ms=2**40, custom_mode=-5, roll_rad=math.nan,
                          yaw_rad=math.inf, lat_e7=10**12, battery_voltage_v=1e9,
                          battery_current_a=1e9, battery_remaining_pct=500,
                          servo_us=tuple(range(20)), rc_channels_us=(70000,) * 30,
                          vel_ned_m_s=(math.nan, 1e9, -1e9), flight_custom_version="ü" * 20,
                          home_set=True, pid_rows=())
    ctx = telemetry.TelemetryContext(mission_total=70000, pid_mask=0xF)
    codec = mav.MAVLink(None, 1, 1)
    for mid, enc in telemetry.ENCODERS.items():
        for m in enc(odd, ctx):
            m.pack(codec)          # must not raise


def test_bench_runs(capsys):
    from silbridge.mavlink.gcs import bench
    import json
    assert bench.main(["--json", "--seconds", "0.2"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["decode_frames_per_s"] > 0 and res["command_rtt"]["n"] > 0
    assert res["server_cpu"]["msgs_per_s"] > 0
