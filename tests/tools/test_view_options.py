"""Bad input to the viewing options (--live, --viz-hz, --tlog): one clear line, exit status 2,
nothing started, nothing written."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest

from silbridge.tools.logs.live_view import DEFAULT_PORT, LiveViewError, parse_address


def _fly(*args, tmp_path):
    return subprocess.run([sys.executable, "-m", "silbridge.tools", "fly", "--duration", "1",
                           "--processes", "1", *args], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)


def test_parse_address():
    assert parse_address(None) == ("127.0.0.1", DEFAULT_PORT)
    assert parse_address("") == ("127.0.0.1", DEFAULT_PORT)
    assert parse_address("9000") == ("127.0.0.1", 9000)
    assert parse_address(":0") == ("127.0.0.1", 0)
    assert parse_address("0.0.0.0:8766") == ("0.0.0.0", 8766)
    assert parse_address("[::1]:8766") == ("::1", 8766)
    for bad in ("host:port", "127.0.0.1:70000", "x"):
        with pytest.raises(LiveViewError, match="--live"):
            parse_address(bad)


@pytest.mark.parametrize("args, message", [
    (["--live", "localhost:http"], "--live wants HOST:PORT or PORT"),
    (["--viz-hz", "-5"], "--viz-hz must be >= 0"),
    (["--tlog", "x.tlog"], "--tlog logs the MAVLink GCS traffic"),
])
def test_bad_options_say_what_to_do(tmp_path, args, message):
    out = _fly(*args, tmp_path=tmp_path)
    assert out.returncode == 2, out.stderr
    assert message in out.stderr
    assert list(tmp_path.iterdir()) == []


def test_live_on_a_busy_port_fails_at_once(tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        out = _fly("--live", f"127.0.0.1:{port}", "--log", "run.mcap", tmp_path=tmp_path)
    assert out.returncode == 2, out.stderr
    assert f"cannot serve the live view on 127.0.0.1:{port}" in out.stderr
    assert "choose another port" in out.stderr


def test_tlog_in_a_missing_folder_fails_before_flying(tmp_path):
    out = _fly("--mavlink", "--no-default-gcs", "--tlog", str(tmp_path / "no" / "x.tlog"),
               tmp_path=tmp_path)
    assert out.returncode == 2, out.stderr
    assert "cannot create the telemetry log" in out.stderr
