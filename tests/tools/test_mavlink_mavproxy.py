"""MAVProxy (scripted through a stdin pipe, as its users script it) flies the real vehicle:
parameter download, `param set`, a mode change, arm, take-off, `wp load` of a QGC WPL 110
file, and a landing that ends disarmed.

Quirks honoured (see /work/shared/MAVLINK_FC.md): `--non-interactive` would ignore stdin, so
commands go through a pipe; the `terrain` module is left out of --default-modules (it starts
a tile download that hangs without internet); MAVProxy always exits with status 1.
"""

from __future__ import annotations

import os
import queue
import re
import shutil
import subprocess
import sys
import threading
import time

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_port  # noqa: E402

from silbridge.fc_sil import params as P  # noqa: E402

MAVPROXY = shutil.which("mavproxy.py") or os.path.join(os.path.dirname(sys.executable),
                                                       "mavproxy.py")
pytestmark = pytest.mark.skipif(not os.path.exists(MAVPROXY), reason="MAVProxy not installed")


class MavProxy:
    def __init__(self, port: int | None, cwd: str, *, master: str | None = None,
                 modules: str = "cmdlong,mode,param,wp,arm", nowait: bool = True):
        master = master or f"udpin:127.0.0.1:{port}"
        self.proc = subprocess.Popen(
            [sys.executable, MAVPROXY, f"--master={master}", f"--default-modules={modules}",
             "--no-state", *(["--nowait"] if nowait else [])],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
            cwd=cwd, bufsize=1, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.lines: queue.Queue = queue.Queue()
        self.seen: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))

    def send(self, command: str) -> None:
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()

    def expect(self, pattern: str, timeout_s: float = 20.0) -> re.Match:
        rx = re.compile(pattern)
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            try:
                line = self.lines.get(timeout=max(0.0, min(0.2, end - time.monotonic())))
            except queue.Empty:
                continue
            self.seen.append(line)
            m = rx.search(line)
            if m:
                return m
        raise AssertionError(f"MAVProxy never printed /{pattern}/; last lines:\n"
                             + "\n".join(self.seen[-30:]))

    def close(self) -> int:
        try:
            self.proc.communicate(input="", timeout=20)     # closing stdin quits MAVProxy
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.communicate()
        return self.proc.returncode


def test_mavproxy_params_mode_arm_takeoff_wp_load_land(tmp_path):
    port = free_udp_port()
    v = SitlVehicle([f"udpout:127.0.0.1:{port}"], speed=4.0, processes=1)
    wpl = tmp_path / "mission.txt"
    wpl.write_text("QGC WPL 110\n"
                   "0\t1\t0\t16\t0\t0\t0\t0\t47.3977420\t8.5455940\t488.0\t1\n"
                   "1\t0\t3\t22\t0\t0\t0\t0\t0\t0\t10\t1\n"
                   "2\t0\t3\t16\t0\t0\t0\t0\t47.3979000\t8.5456000\t10\t1\n"
                   "3\t0\t3\t20\t0\t0\t0\t0\t0\t0\t0\t1\n")
    mp = MavProxy(port, str(tmp_path))
    try:
        mp.expect(rf"Received {len(P.PARAMS)} parameters", 60.0)
        # MAVProxy asks for its streams (REQUEST_DATA_STREAM ALL) when the rate setting
        # changes or every 15 s; change it so position telemetry flows at once
        mp.send("set streamrate 5")
        mp.send("param set WPNAV_SPEED 800")
        # MAVProxy's cache changes only with the autopilot's PARAM_VALUE echo: ask until then
        shown = None
        for _ in range(20):
            mp.send("param show WPNAV_SPEED")
            shown = float(mp.expect(r"WPNAV_SPEED\s+(\S+)").group(1))
            if shown == 800.0:
                break
            time.sleep(0.25)
        assert shown == 800.0
        mp.send("mode GUIDED")
        mp.expect(r"DO_SET_MODE: ACCEPTED")
        mp.send("arm throttle")
        mp.expect(r"COMPONENT_ARM_DISARM: ACCEPTED")
        mp.send("takeoff 5")
        mp.expect(r"NAV_TAKEOFF: ACCEPTED")
        alt_mm = 0
        end = time.monotonic() + 30.0
        while alt_mm < 4500 and time.monotonic() < end:
            time.sleep(0.5)
            mp.send("status GLOBAL_POSITION_INT")
            alt_mm = int(mp.expect(r"relative_alt\s*:\s*(-?\d+)").group(1))
        assert alt_mm >= 4500, "take-off did not reach 5 m"
        mp.send(f"wp load {wpl}")
        mp.expect(r"MISSION_ACK: TYPE_MISSION: ACCEPTED")
        mp.send("wp list")
        mp.expect(r"Requesting 4 waypoints")
        mp.expect(r"^20 ")                    # the RTL item came back
        mp.send("mode LAND")
        mp.expect(r"DISARMED", 60.0)
    except AssertionError as exc:
        raise AssertionError(f"{exc}\nthe vehicle said:\n{v.stop()[-3000:]}") from None
    finally:
        rc = mp.close()
        err = v.stop()
    assert rc == 1, "MAVProxy exits with status 1 (its normal exit)"
    assert "Traceback" not in err, err[-3000:]
