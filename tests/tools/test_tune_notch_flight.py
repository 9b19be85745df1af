"""`silbridge tune notch` end to end on real lockstep flights of V2 (a bent prop):
a fresh hover, the proposal, the .parm, the flight with it, and the issue's target
(gyro noise after filtering at least 10 dB lower); the same from the log it flew; and
with ESC telemetry in the scenario, MODE 3."""

from __future__ import annotations

import json

import pytest

from silbridge.bridge.scenario import SCENARIO_DIR
from silbridge.mavlink.gcs.params_file import load_parm
from silbridge.tools.cli.cli import main
from silbridge.tools.logs.log_reader import read_log

DURATION = "24"     # take-off and a steady hover: the window is the second half


def _notch(capsys, *argv) -> dict:
    rc = main(["tune", "notch", *argv, "--duration", DURATION, "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return json.loads(out)


def _flown(path: str) -> dict:
    return read_log(path, channels=[]).metadata["params"]


def test_fresh_hover_then_its_log(tmp_path, capsys):
    d = _notch(capsys, "--scenario", "V2", "--out", str(tmp_path / "a"))
    ev, v = d["evidence"], d["proposal"]
    assert v["INS_HNTCH_MODE"] == 1 and v["INS_HNTCH_ENABLE"] == 1
    assert v["INS_HNTCH_FREQ"] == pytest.approx(ev["fundamental_hz"], rel=0.03)
    assert v["INS_HNTCH_BW"] == pytest.approx(v["INS_HNTCH_FREQ"] / 2, abs=0.1)
    assert v["INS_HNTCH_HMNCS"] & 1 and 0 < v["INS_HNTCH_REF"] < 1
    assert dict(load_parm(d["parm_file"])) == pytest.approx(v, rel=1e-6)
    flown = _flown(d["after_log"])          # the "after" flight flew the proposal
    for name, value in v.items():
        assert flown[name] == pytest.approx(value, rel=1e-6)
    n = d["noise"]
    assert n["change_db"] <= -10.0 and n["met"], n
    assert n["after"]["total_dps"] < n["before"]["total_dps"]
    assert n["band_hz"] == [20.0, 200.0]

    # From that log: the same "before", the same proposal
    again = _notch(capsys, d["source_log"], "--out", str(tmp_path / "b"))
    assert again["proposal"] == v
    assert again["noise"]["before"] == n["before"]
    assert again["flight"]["seed"] == 1 and again["flight"]["duration_s"] == float(DURATION)


def test_esc_telemetry_scenario_gives_mode_3(tmp_path, capsys):
    sc = tmp_path / "v2_esc.toml"
    sc.write_text((SCENARIO_DIR / "V2.toml").read_text() + "\n[esc]\ntelemetry_hz = 50.0\n")
    d = _notch(capsys, "--scenario", str(sc), "--out", str(tmp_path / "esc"))
    v, ev = d["proposal"], d["evidence"]
    assert ev["esc"] and v["INS_HNTCH_MODE"] == 3 and v["INS_HNTCH_REF"] == 1.0
    assert v["INS_HNTCH_FREQ"] <= ev["fundamental_hz"]
    assert d["noise"]["change_db"] <= -10.0, d["noise"]


def test_a_missing_log_is_refused(tmp_path, capsys):
    rc = main(["tune", "notch", str(tmp_path / "nope.mcap"), "--out", str(tmp_path)])
    _, err = capsys.readouterr()
    assert rc == 2 and "no such log" in err
