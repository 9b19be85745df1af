"""`silbridge tune` end to end: `tune auto` on a tiny budget writes a .parm that the
MAVLink vehicle (`silbridge fly --params FILE`) loads, and its --json has the issue's
keys; `tune step` and `tune sysid` print their figures; bad input is refused."""

from __future__ import annotations

import json
import os
import struct
import sys

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_port, gcs_for, wait_for  # noqa: E402

from silbridge.tools.cli.cli import main  # noqa: E402


def _f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def _tune(capsys, *argv):
    rc = main(["tune", *argv])
    out, err = capsys.readouterr()
    return rc, out, err


def test_tune_auto_tiny_budget_writes_a_parm_the_vehicle_loads(tmp_path, capsys):
    out_dir = tmp_path / "auto"
    other = tmp_path / "other.parm"      # a gain set scored beside ours (--compare)
    other.write_text("ATC_RAT_RLL_P 0.12\nATC_ANG_RLL_P 6\n")
    rc, out, err = _tune(capsys, "auto", "--axis", "roll", "--trials", "2", "--runs", "1",
                         "--jobs", "2", "--out", str(out_dir), "--no-progress", "--json",
                         "--compare", str(other))
    assert rc == 0, err
    d = json.loads(out)
    assert {"params", "margins", "before", "after", "parm_file", "margins_before",
            "verdict"} <= set(d)
    assert set(d["margins"]) == {"roll"}
    for key in ("phase_margin_deg", "gain_margin_db", "crossover_hz", "bandwidth_hz",
                "delay_margin_ms"):
        assert key in d["margins"]["roll"]
    for side in ("before", "after"):
        assert set(d[side]) == {"S1", "S4"}
        assert "pwm_pp_us" in d[side]["S1"] and "sat_pct" in d[side]["S4"]
    assert "ATC_RAT_RLL_P" in d["params"] and "ATC_ANG_RLL_P" in d["params"]
    assert float(d["params"]["INS_GYRO_FILTER"]).is_integer()    # an INT16, as in ArduCopter
    cmp = d["compare"]["other"]
    assert cmp["params"] == {"ATC_RAT_RLL_P": 0.12, "ATC_ANG_RLL_P": 6.0}
    assert "att_rms_cmd_deg" in cmp["table1"]["S4"] and "att_p95_cmd_deg" in cmp["table1"]["S4"]
    assert "phase_margin_deg" in cmp["margins"]["roll"] and "other" in d["verdict"]["beats"]
    assert "S4 attitude RMS vs the command" in err and "other" in err
    parm = d["parm_file"]
    assert os.path.exists(parm) and (out_dir / "index.html").exists()

    port = free_udp_port()
    v = SitlVehicle([f"udpin:127.0.0.1:{port}"], speed=4.0, processes=1,
                    extra=["--params", parm])
    c = gcs_for(port)
    try:
        assert wait_for(c, "HEARTBEAT", timeout_s=60) is not None, v.stop()[-3000:]
        for name in ("ATC_RAT_RLL_P", "ATC_RAT_RLL_D", "INS_GYRO_FILTER"):
            c.send(mav.MAVLink_param_request_read_message(1, 1, name.encode(), -1))
            pv = wait_for(c, "PARAM_VALUE", lambda m, n=name: m.param_id == n)
            assert pv is not None and pv.param_value == pytest.approx(_f32(d["params"][name]),
                                                                     rel=1e-6)
    finally:
        c.close()
        v.stop()


def test_tune_step_reports_rise_overshoot_settling(tmp_path, capsys):
    rc, out, err = _tune(capsys, "step", "--axis", "pitch", "--repeat", "1", "--jobs", "1",
                         "--out", str(tmp_path), "--json")
    assert rc == 0, err
    st = json.loads(out)["axes"]["pitch"]
    assert 0.02 < st["step"]["rise_time_s"] < 1.0
    assert 0.0 <= st["step"]["overshoot_pct"] < 60.0
    assert st["step"]["settling_time_s"] is not None and st["step"]["settling_time_s"] < 2.0
    assert len(st["steps"]) == 4                       # +A, level, -A, level
    assert (tmp_path / "pitch_doublet.png").exists()


def test_bad_axis_and_bad_param_are_refused(capsys):
    rc, _, err = _tune(capsys, "sysid", "--axis", "rol")
    assert rc == 2 and "--axis" in err
    rc, _, err = _tune(capsys, "sysid", "--axis", "roll", "--param", "ATC_RAT_RLL_P=99")
    assert rc == 2 and "ATC_RAT_RLL_P" in err


def test_tune_sysid_json_and_report(tmp_path, capsys):
    rc, out, err = _tune(capsys, "sysid", "--axis", "pitch", "--inject", "both", "--jobs", "2",
                         "--f-start", "1", "--t-rec", "25", "--fade-in", "3",
                         "--out", str(tmp_path), "--json")
    assert rc == 0, err
    d = json.loads(out)
    s = d["axes"]["pitch"]
    for key in ("phase_margin_deg", "gain_margin_db", "crossover_hz", "bandwidth_hz",
                "delay_margin_ms"):
        assert key in s
    assert 20.0 < s["phase_margin_deg"] < 90.0 and 1.0 < s["crossover_hz"] < 20.0
    assert 2.0 < s["bandwidth_hz"] < 40.0
    assert s["plant_vs_model"]["max_gain_err_db"] < 2.0
    for f in ("index.html", "report.md", "pitch_plant.png", "pitch_open_loop.png",
              "pitch_closed_loop.png", "pitch_sensitivity.png"):
        assert (tmp_path / f).exists(), f
