"""MAVSDK 4.x telemetry rates against silbridge and (SILBRIDGE_ARDUCOPTER set) the real
ArduCopter 4.6: every ``Telemetry.set_rate_*`` a script may call gets the same answer from
both, health comes good, and the position stream arrives at the asked rate.

What each set_rate_* sends (logged on the wire): SET_MESSAGE_INTERVAL for the message(s) behind
it. Both autopilots accept every one except ALTITUDE (141), ODOMETRY (331),
ACTUATOR_CONTROL_TARGET (140), ACTUATOR_OUTPUT_STATUS (375) and HIL_STATE_QUATERNION (115,
ground truth), which ArduCopter cannot send and DENIES (MAVSDK: COMMAND_DENIED);
set_rate_health is EKF_STATUS_REPORT (193), set_rate_distance_sensor DISTANCE_SENSOR (132,
accepted, sent only with a rangefinder: neither has one).

Rates: both autopilots pace telemetry on their simulated clock, so at 3x (silbridge) and 5x
(ArduCopter) real time they send 3x and 5x the asked rate per wall second; the rate is checked
in sim time (wall rate over the speed asked for), with generous bounds (a loaded 2-core
machine may run the simulation below the speed asked for). test_telemetry_sim_time.py counts
the rates on time_boot_ms instead.
"""

from __future__ import annotations

import os
import sys
import threading
import time

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from waits import until  # noqa: E402

from autopilots import ARDUCOPTER_SPEEDUP, KINDS, start  # noqa: E402

mavsdk = pytest.importorskip("mavsdk")
if not hasattr(mavsdk, "Mavsdk"):
    pytest.skip("these tests use the MAVSDK 4.x Python binding (pip install 'mavsdk>=4')",
                allow_module_level=True)

from mavsdk import ComponentType, Configuration, Mavsdk  # noqa: E402
from mavsdk.plugins.telemetry import Telemetry  # noqa: E402

mavsdk.log_subscribe(lambda level, msg, file, line: True)    # keep MAVSDK's log quiet

DENIED_BY_ARDUCOPTER = {"set_rate_actuator_control_target", "set_rate_actuator_output_status",
                        "set_rate_altitude", "set_rate_ground_truth", "set_rate_odometry"}


@pytest.mark.parametrize("kind", KINDS)
def test_every_set_rate_and_the_position_rate(kind, tmp_path):
    ap = start(kind, tmp_path)
    m = None
    try:
        m = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        m.add_any_connection(ap.mavsdk_url)
        system = m.first_autopilot(30.0)
        assert system is not None, "MAVSDK found no autopilot"
        tel = Telemetry(system)
        results = {}
        for name in sorted(n for n in dir(tel) if n.startswith("set_rate_")
                           and not n.endswith("_async")):
            try:
                getattr(tel, name)(2.0)
                results[name] = "SUCCESS"
            except Exception as exc:  # noqa: BLE001 - the binding raises one type per result
                results[name] = str(exc).split(";")[0]
        failed = {k: v for k, v in results.items() if v != "SUCCESS"}
        assert set(failed) == DENIED_BY_ARDUCOPTER, failed
        assert set(failed.values()) == {"COMMAND_DENIED"}, failed
        assert until(tel.health_all_ok, 60.0), f"health never all ok: {tel.health()}"

        count = [0]
        lock = threading.Lock()

        def on_position(*_):
            with lock:
                count[0] += 1
        tel.set_rate_position(10.0)
        tel.subscribe_position(on_position)
        time.sleep(1.0)
        with lock:
            count[0] = 0
        window = 3.0
        time.sleep(window)
        with lock:
            n = count[0]
        scale = ARDUCOPTER_SPEEDUP if kind == "arducopter" else ap.v.speed
        hz = n / window / scale
        assert 5.0 <= hz <= 20.0, f"position at {hz:.1f} Hz (own clock), asked 10"
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        if m is not None:
            m.destroy()
        ap.stop()
