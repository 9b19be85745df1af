"""`--params FILE` acts in every mode and is read-only unless `--save-params` (issue 22).

Before: in lockstep (the default) the file was ignored and the defaults flew; in real time a
mistyped path was created and every PARAM_SET rewrote the tuned file.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_port, gcs_for, wait_for  # noqa: E402

from silbridge.mavlink.gcs.params_file import load_parm  # noqa: E402
from silbridge.tools.logs.mcap_log import read_log  # noqa: E402

SB = [sys.executable, "-m", "silbridge.tools"]
GAIN, VALUE = "ATC_RAT_RLL_P", 0.3        # default 0.135 (fc_sil/params.py)
# S1 sits on the ground for its first 5 s, where a roll gain changes nothing: 8 s flies.
SECONDS = "8"


def _fly(*extra) -> dict:
    p = subprocess.run(SB + ["fly", "--duration", SECONDS, "--json", *extra],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout)


@pytest.fixture
def tuned(tmp_path):
    path = tmp_path / "tuned.parm"
    path.write_text(f"{GAIN} {VALUE}\n")
    return path


@pytest.mark.parametrize("processes", ["1", "2"])
def test_lockstep_flies_the_params_file(tuned, processes):
    default = _fly("--processes", processes)["trace_hash"]
    from_file = _fly("--processes", processes, "--params", str(tuned))["trace_hash"]
    from_flag = _fly("--processes", processes, "--param", f"{GAIN}={VALUE}")["trace_hash"]
    assert from_file != default
    assert from_file == from_flag


@pytest.mark.parametrize("mode", [["--lockstep"], ["--speed", "4"]], ids=["lockstep", "rt"])
@pytest.mark.parametrize("mavlink", ["--mavlink", "--no-mavlink"])
@pytest.mark.parametrize("processes", ["1", "2"])
def test_every_mode_starts_from_the_params_file(tmp_path, tuned, mode, mavlink, processes):
    """The FC's parameter set at start (the log records it) holds the file's value."""
    log = tmp_path / "run.mcap"
    gcs = ["--no-default-gcs", "--gcs", f"udpin:127.0.0.1:{free_udp_port()}"] \
        if mavlink == "--mavlink" else []
    p = subprocess.run(SB + ["fly", *mode, mavlink, *gcs, "--processes", processes,
                             "--duration", "1", "--params", str(tuned), "--log", str(log),
                             "--viz-hz", "0", "--json"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    assert read_log(str(log)).metadata["params"][GAIN] == pytest.approx(VALUE)
    assert tuned.read_text() == f"{GAIN} {VALUE}\n"


@pytest.mark.parametrize("command", [["fly"], ["sitl"], ["fly", "--speed", "2"],
                                     ["bridge"], ["fc"]])
def test_a_missing_params_file_is_refused(tmp_path, command):
    missing = tmp_path / "tunde.parm"
    p = subprocess.run(SB + [*command, "--params", str(missing)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert f"--params {missing}: no such file" in p.stderr and "Traceback" not in p.stderr
    assert not missing.exists()


def test_save_params_needs_a_file_and_a_gcs(tuned):
    p = subprocess.run(SB + ["fly", "--save-params"], capture_output=True, text=True)
    assert p.returncode == 2 and "add --params FILE" in p.stderr
    p = subprocess.run(SB + ["fly", "--params", str(tuned), "--save-params"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "MAVLink vehicle" in p.stderr


def _param_set(port, value):
    c = gcs_for(port)
    try:
        assert wait_for(c, "HEARTBEAT", timeout_s=60) is not None
        c.send(mav.MAVLink_param_set_message(1, 1, b"WPNAV_SPEED", value, 9))
        pv = wait_for(c, "PARAM_VALUE", lambda m: m.param_id == "WPNAV_SPEED")
        assert pv is not None and pv.param_value == value
        c.send(mav.MAVLink_command_long_message(1, 1, mav.MAV_CMD_PREFLIGHT_STORAGE, 0,
                                                1, 0, 0, 0, 0, 0, 0))
        ack = wait_for(c, "COMMAND_ACK", lambda m: m.command == mav.MAV_CMD_PREFLIGHT_STORAGE)
        # the server's save delay passes while we wait for a message that never comes
        assert wait_for(c, "STATUSTEXT", lambda m: False, timeout_s=1.5) is None
        return ack
    finally:
        c.close()


def test_param_set_leaves_a_read_only_file_byte_identical(tuned):
    before = tuned.read_bytes()
    port = free_udp_port()
    v = SitlVehicle([f"udpin:127.0.0.1:{port}"], speed=4.0, processes=1,
                    extra=["--params", str(tuned)])
    try:
        ack = _param_set(port, 640.0)
    finally:
        v.stop()
    assert ack is not None and ack.result == mav.MAV_RESULT_DENIED
    assert tuned.read_bytes() == before


def test_save_params_creates_the_file_and_writes_param_sets(tmp_path):
    path = tmp_path / "new.parm"
    port = free_udp_port()
    v = SitlVehicle([f"udpin:127.0.0.1:{port}"], speed=4.0, processes=2,
                    extra=["--params", str(path), "--save-params"])
    try:
        ack = _param_set(port, 640.0)
    finally:
        err = v.stop()
    assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED
    assert f"created {path}" in err
    assert dict(load_parm(path))["WPNAV_SPEED"] == 640.0
