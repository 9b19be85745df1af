"""MAVProxy 1.8 used the ordinary way on silbridge and (SILBRIDGE_ARDUCOPTER set) the real
ArduCopter 4.6: its fence, rally and wp modules (load, list, clear), then GUIDED, arm,
take-off and `status GLOBAL_POSITION_INT`, then a second MAVProxy session on the same vehicle.

What the two must share:
* no "fence breach" on connecting (the SYS_STATUS geofence bit is healthy without a breach;
  ArduCopter's default FENCE_TYPE 7 shows as "fence present");
* MAVProxy asks for its streams once at start-up (before it knows the vehicle, so the request
  goes nowhere) and then every 15 s; `status GLOBAL_POSITION_INT` shows the message once that
  request arrived. The autopilot remembers the rates (ArduCopter's SRn_*), so a second session
  sees the message at once, without waiting for MAVProxy's next request.
"""

from __future__ import annotations

import os
import sys
import time

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from autopilots import KINDS, mavproxy_path, start  # noqa: E402
from gcs_session import offset_e7  # noqa: E402
from test_mavlink_mavproxy import MavProxy  # noqa: E402

pytestmark = pytest.mark.skipif(mavproxy_path() is None, reason="MAVProxy not installed")
HOMES = {"silbridge": (47.397742, 8.545594), "arducopter": (-35.363261, 149.165230)}
MODULES = "cmdlong,mode,param,wp,arm,fence,rally"


def _wpl(rows) -> str:
    lines = ["QGC WPL 110"]
    for i, (frame, cmd, p1, lat, lon, alt) in enumerate(rows):
        lines.append("\t".join(str(v) for v in (i, 0, frame, cmd, p1, 0, 0, 0, f"{lat:.8f}",
                                                 f"{lon:.8f}", alt, 1)))
    return "\n".join(lines) + "\n"


def _files(tmp_path, home):
    def at(n, e):
        lat, lon = offset_e7(*home, n, e)
        return lat / 1e7, lon / 1e7
    fence = [(0, 5001, 4, *at(n, e), 0) for n, e in ((-60, -60), (60, -60), (60, 60), (-60, 60))]
    fence.append((0, 5004, 10, *at(30, 30), 0))
    rally = [(3, 5100, 0, *at(40, 0), 15), (3, 5100, 0, *at(0, -40), 20)]
    mission = [(0, 16, 0, *home, 0), (3, 22, 0, 0.0, 0.0, 10), (3, 16, 0, *at(30, 0), 10),
               (3, 20, 0, 0.0, 0.0, 0)]
    out = {}
    for name, rows in (("fence", fence), ("rally", rally), ("mission", mission)):
        p = tmp_path / f"{name}.txt"
        p.write_text(_wpl(rows))
        out[name] = str(p)
    return out


@pytest.mark.parametrize("kind", KINDS)
def test_mavproxy_fence_rally_wp_status_and_second_session(kind, tmp_path):
    ap = start(kind, tmp_path, arducopter_speedup=5.0)   # MAVProxy's own pace is wall time
    files = _files(tmp_path, HOMES[kind])
    mp = None
    try:
        t_start = time.monotonic()
        mp = MavProxy(None, str(tmp_path), master=ap.mavproxy_master, modules=MODULES,
                      nowait=False)
        mp.expect(r"Detected vehicle", 30.0)
        mp.expect(r"Received \d+ parameters", 60.0)
        assert not any("fence breach" in line for line in mp.seen), mp.seen[-20:]

        mp.send(f"fence load {files['fence']}")
        mp.expect(r"MISSION_ACK: TYPE_FENCE: ACCEPTED")
        mp.send("fence list")
        mp.expect(r"Requesting 5 fence items")
        mp.expect(r"^5004 ")
        mp.send(f"rally load {files['rally']}")
        mp.expect(r"MISSION_ACK: TYPE_RALLY: ACCEPTED")
        mp.send("rally list")
        mp.expect(r"Requesting 2 rally items")
        mp.expect(r"^5100 .* 20\.0+ ")
        mp.send(f"wp load {files['mission']}")
        mp.expect(r"MISSION_ACK: TYPE_MISSION: ACCEPTED")
        mp.send("wp list")
        mp.expect(r"Requesting 4 waypoints")
        mp.send("fence clear")
        mp.expect(r"MISSION_ACK: TYPE_FENCE: ACCEPTED")
        mp.send("fence list")
        mp.expect(r"Requesting 0 fence items")
        mp.send("rally clear")
        mp.expect(r"MISSION_ACK: TYPE_RALLY: ACCEPTED")
        mp.send("rally list")
        mp.expect(r"Requesting 0 rally items")
        mp.send("wp clear")
        mp.send("wp list")
        # home only; ArduCopter before its home is set: nothing
        mp.expect(r"Requesting [01] waypoints")

        mp.send("mode GUIDED")
        mp.expect(r"DO_SET_MODE: ACCEPTED")
        end = time.monotonic() + 90.0
        while True:                                   # ArduCopter: until its EKF is ready
            mp.send("arm throttle")
            if mp.expect(r"COMPONENT_ARM_DISARM: (\w+)").group(1) == "ACCEPTED":
                break
            assert time.monotonic() < end, "never armed"
            time.sleep(2.0)
        mp.send("takeoff 10")
        mp.expect(r"NAV_TAKEOFF: ACCEPTED")
        alt_mm = 0
        end = time.monotonic() + 60.0
        while alt_mm < 8000 and time.monotonic() < end:
            time.sleep(1.0)
            mp.send("status GLOBAL_POSITION_INT")
            try:
                alt_mm = int(mp.expect(r"relative_alt\s*:\s*(-?\d+)", 2.0).group(1))
            except AssertionError:
                # nothing before MAVProxy's first stream request (15 s after its start)
                assert time.monotonic() - t_start < 25.0, "no GLOBAL_POSITION_INT at all"
        assert alt_mm >= 8000, f"take-off did not reach 10 m ({alt_mm} mm)"
        mp.close()

        # a second session: the vehicle remembered the rates, the position is there at once
        mp = MavProxy(None, str(tmp_path), master=ap.mavproxy_master, modules=MODULES,
                      nowait=False)
        mp.expect(r"Detected vehicle", 30.0)
        time.sleep(2.0)
        mp.send("status GLOBAL_POSITION_INT")
        alt_mm = int(mp.expect(r"relative_alt\s*:\s*(-?\d+)", 3.0).group(1))
        assert alt_mm >= 8000, alt_mm
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        if mp is not None:
            mp.close()
        ap.stop()
