"""Our FC on the bridge's battery (issue 28): it reads the physics-side pack, reports it to a
ground station, and its battery failsafe acts on a battery fault of the physics.

- Lockstep with the real vehicle (vehicle_harness.py): the FC's battery is the bridge's pack
  at its last report; SYS_STATUS and BATTERY_STATUS built from the vehicle carry those values.
- A [[failure]] capacity_loss mid-flight: remaining falls below BATT_LOW_MAH at once, and the
  FC says "Battery 1 is low" and switches to BATT_FS_LOW_ACT's mode (LAND).
- `fly --processes 2`: the FC process consumes the same BATTERY records over shared memory
  and over MAVLink HIL (UDP): BATTERY_STATUS from the bridge end is rebuilt bit for bit.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from vehicle_harness import fly_scripted  # noqa: E402

from silbridge.fc_sil.snapshot import build_snapshot  # noqa: E402
from silbridge.mavlink.gcs import telemetry  # noqa: E402
from silbridge.mavlink.gcs.vehicle_api import CopterMode  # noqa: E402
from silbridge.tools.logs.mcap_log import read_log  # noqa: E402

SB = [sys.executable, "-m", "silbridge.tools"]


def _scenario(tmp_path, body: str = "") -> str:
    p = tmp_path / "batt.toml"
    p.write_text('name = "batt"\nseed = 1\nduration_s = 60.0\ntakeoff_alt_m = 5.0\n\n' + body)
    return str(p)


def _hover(script_after, duration_s, **kw):
    st = {}

    def script(f):
        if f.t_s > 2 and "up" not in st:
            st["up"] = True
            f.v.set_mode(CopterMode.GUIDED)
            f.v.arm(False)
            f.v.takeoff(5.0)
        script_after(f, st)

    f, res = fly_scripted(script, duration_s=duration_s, **kw)
    return f, res, st


def test_the_fc_reads_the_bridges_pack_and_reports_it(tmp_path):
    def after(f, st):
        b, p = f.v.battery, f.sim.battery
        if b.valid and b.sim_ns == f.sim.battery.reports * 100_000_000:
            st.setdefault("pairs", []).append((b.voltage_v, p.voltage_v, b.current_a, p.current_a,
                                               b.consumed_mah, p.consumed_mah))
        if f.t_s > 7.9 and "snap" not in st:
            st["snap"] = build_snapshot(f.v)
            st["truth"] = (p.voltage_v, p.current_a, p.consumed_mah, round(100 * p.remaining))

    f, res, st = _hover(after, 8.2, scenario=_scenario(tmp_path))
    pairs = np.array(st["pairs"])
    assert len(pairs) > 40
    assert np.abs(pairs[:, 0] - pairs[:, 1]).max() <= 0.005     # whole mV per cell
    assert np.abs(pairs[:, 2] - pairs[:, 3]).max() <= 0.005     # cA
    assert np.abs(pairs[:, 4] - pairs[:, 5]).max() <= 0.5       # whole mAh
    assert pairs[-1, 2] > 5.0                                   # flying: the motors' current
    snap = st["snap"]
    v, i, mah, pct = st["truth"]
    ss = telemetry.sys_status(snap, telemetry.TelemetryContext())[0]
    bs = telemetry.battery_status(snap, telemetry.TelemetryContext())[0]
    assert abs(ss.voltage_battery - v * 1000) <= 10 and abs(ss.current_battery - i * 100) <= 3
    assert abs(bs.current_consumed - mah) <= 2 and bs.current_battery == ss.current_battery
    assert ss.battery_remaining == pct == bs.battery_remaining


def test_a_capacity_loss_in_flight_triggers_the_battery_failsafe(tmp_path):
    body = ('[[failure]]\nunit = "battery"\ntype = "capacity_loss"\nat_s = 8.0\n'
            'fraction = 0.6\n')

    def after(f, st):
        if f.t_s < 7.9:
            st["before"] = (f.v.mode.number, f.v.battery.remaining_mah)
        if f.v.mode.number == CopterMode.LAND and "land_s" not in st:
            st["land_s"] = f.t_s

    f, res, st = _hover(after, 10.0, scenario=_scenario(tmp_path, body),
                        params={"BATT_LOW_MAH": 2000, "BATT_FS_LOW_ACT": 1})
    mode, rem = st["before"]
    assert mode == CopterMode.GUIDED and rem > 3000             # no failsafe before the fault
    assert any("Battery 1 is low" in m[2] for m in f.v.messages)
    assert 8.0 <= st["land_s"] < 8.5                             # the next report, then LAND
    assert f.v.battery.remaining_mah < 1400
    assert not res.crashed


def _battery_log(tmp_path, transport: str) -> np.ndarray:
    log = tmp_path / f"{transport}.mcap"
    p = subprocess.run(SB + ["fly", "--processes", "2", "--transport", transport, "--scenario",
                             _scenario(tmp_path), "--duration", "3", "--log", str(log),
                             "--json"], capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stderr[-2000:]
    return read_log(str(log)).channels["/battery"]


def test_over_udp_hil_the_fc_reads_the_same_battery(tmp_path):
    shm, udp = _battery_log(tmp_path, "shm"), _battery_log(tmp_path, "udp")
    assert len(shm) == len(udp) == 30
    for f in ("sim_ns", "seq", "voltage_v", "current_a", "consumed_mah", "remaining",
              "temperature_c", "lowest_cell_v", "cell_count"):
        assert np.array_equal(shm[f], udp[f]), f
    assert mav.MAVLINK_MSG_ID_BATTERY_STATUS == 147    # the message the bridge end sends
