"""Parameters end to end: `silbridge params` (list, show, diff, export), and the running
vehicle's .parm file (`--params FILE`): a PARAM_SET is saved atomically and loaded at the next
start; the mission file (`--mission FILE`) is saved on upload and flown after a restart."""

from __future__ import annotations

import json
import os
import sys

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_port, gcs_for, wait_for  # noqa: E402

from silbridge.fc_sil import params as P  # noqa: E402
from silbridge.mavlink.gcs.wpl import load_wpl  # noqa: E402
from silbridge.tools.cli.cli import main  # noqa: E402


def _run(capsys, *argv):
    rc = main(["params", *argv])
    out, err = capsys.readouterr()
    return rc, out, err


def test_params_list_show_json(capsys):
    rc, out, _ = _run(capsys, "list", "--json")
    data = json.loads(out)
    assert rc == 0 and data["count"] == len(P.PARAMS)
    first = data["params"][0]
    assert {"name", "value", "unit", "min", "max", "default", "type"} <= set(first)
    rc, out, _ = _run(capsys, "show", "wpnav_radius", "--json")
    row = json.loads(out)
    assert (row["name"], row["value"], row["unit"]) == ("WPNAV_RADIUS", 200.0, "cm")
    rc, out, err = _run(capsys, "show", "WPNAV_RADUIS")
    assert rc == 2 and "did you mean WPNAV_RADIUS" in err


def test_params_diff_and_export(tmp_path, capsys):
    a = tmp_path / "a.parm"
    a.write_text("WPNAV_SPEED 800\nDISARM_DELAY 5\nNOT_A_PARAM 1\nATC_RAT_RLL_P 9\n")
    b = tmp_path / "b.parm"
    b.write_text("WPNAV_SPEED 800\nRTL_ALT 2500\n")
    rc, out, _ = _run(capsys, "diff", str(a), "--json")
    d = json.loads(out)
    assert {r["name"]: (r["a"], r["b"]) for r in d["differences"]} == {
        "DISARM_DELAY": (10, 5), "WPNAV_SPEED": (1000.0, 800.0)}
    assert len(d["problems"]) == 2          # unknown name, out of range
    rc, out, _ = _run(capsys, "diff", str(a), str(b), "--json")
    names = {r["name"] for r in json.loads(out)["differences"]}
    assert names == {"DISARM_DELAY", "RTL_ALT"}
    exported = tmp_path / "out.parm"
    rc, _, _ = _run(capsys, "export", "--format", "parm", "--file", str(a), "-o", str(exported))
    assert rc == 0
    lines = dict(line.split() for line in exported.read_text().splitlines())
    assert len(lines) == len(P.PARAMS) and lines["WPNAV_SPEED"] == "800"
    rc, out, _ = _run(capsys, "export", "--format", "json")
    assert json.loads(out)["DISARM_DELAY"] == 10
    rc, out, _ = _run(capsys, "export", "--format", "md")
    assert out.count("\n") == len(P.PARAMS) + 2


def test_vehicle_saves_and_reloads_its_parm_and_mission_files(tmp_path):
    parm = tmp_path / "vehicle.parm"
    wpl = tmp_path / "mission.txt"

    def start():
        port = free_udp_port()
        v = SitlVehicle([f"udpin:127.0.0.1:{port}"], speed=4.0, processes=1,
                        extra=["--params", str(parm), "--save-params", "--mission", str(wpl)])
        c = gcs_for(port)
        assert wait_for(c, "HEARTBEAT", timeout_s=60) is not None, v.stop()[-3000:]
        return v, c

    v, c = start()
    try:
        c.send(mav.MAVLink_param_set_message(1, 1, b"WPNAV_SPEED", 640.0, 9))
        pv = wait_for(c, "PARAM_VALUE", lambda m: m.param_id == "WPNAV_SPEED")
        assert pv is not None and pv.param_value == 640.0
        # a three-item mission: home, take-off, one waypoint
        items = [mav.MAVLink_mission_item_int_message(1, 1, 0, 0, 16, 0, 1, 0, 0, 0, 0,
                                                      473977420, 85455940, 488.0, 0),
                 mav.MAVLink_mission_item_int_message(1, 1, 1, 3, 22, 1, 1, 0, 0, 0, 0,
                                                      0, 0, 10.0, 0),
                 mav.MAVLink_mission_item_int_message(1, 1, 2, 6, 16, 0, 1, 0, 0, 0, 0,
                                                      473979000, 85456000, 10.0, 0)]
        c.send(mav.MAVLink_mission_count_message(1, 1, len(items), 0))
        for _ in items:
            req = wait_for(c, "MISSION_REQUEST_INT", timeout_s=5) or \
                wait_for(c, "MISSION_REQUEST", timeout_s=1)
            assert req is not None
            c.send(items[req.seq])
        ack = wait_for(c, "MISSION_ACK", timeout_s=5)
        assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED
        assert wait_for(c, "STATUSTEXT", lambda m: False, timeout_s=1.0) is None  # let it save
    finally:
        c.close()
        v.stop()
    assert "WPNAV_SPEED      640" in parm.read_text()
    assert [it.command for it in load_wpl(wpl)] == [16, 22, 16]

    v, c = start()
    try:
        c.send(mav.MAVLink_param_request_read_message(1, 1, b"WPNAV_SPEED", -1))
        pv = wait_for(c, "PARAM_VALUE", lambda m: m.param_id == "WPNAV_SPEED")
        assert pv is not None and pv.param_value == 640.0
        c.send(mav.MAVLink_mission_request_list_message(1, 1, 0))
        cnt = wait_for(c, "MISSION_COUNT", timeout_s=5)
        assert cnt is not None and cnt.count == 3
    finally:
        c.close()
        v.stop()


@pytest.mark.parametrize("bad", ["WPNAV_SPEED fast\n", "A_NAME_THAT_IS_TOO_LONG 1\n"])
def test_a_broken_parm_file_stops_the_start_with_a_clear_message(tmp_path, bad):
    parm = tmp_path / "bad.parm"
    parm.write_text(bad)
    v = SitlVehicle([f"udpin:127.0.0.1:{free_udp_port()}"], speed=4.0, processes=1,
                    extra=["--params", str(parm)], duration_s=5, wait_checks=False)
    out, err = v.wait(60)
    assert v.proc.returncode == 2
    assert "bad.parm:1" in err and "Traceback" not in err
