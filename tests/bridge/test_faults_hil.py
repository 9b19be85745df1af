"""A GNSS glitch reaches the FC over shared memory and over MAVLink HIL (--transport udp):
the ring, and HIL_GPS, carry the GNSS record the fault engine changed; the FC, in its own
process, logs the fixes it received (decoded from HIL_GPS over udp; tools/loop/run_log.py
logs sensor records as the FC consumed them).
Real processes, real JSBSim; the glitch falls while the vehicle still stands on the ground,
so the flight with and without it differ only by the glitch.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from silbridge.bridge.scenario import SCENARIO_DIR, load_scenario
from silbridge.tools.logs.mcap_log import read_log
from silbridge.tools.loop.flight import FlightOptions, fly_two_processes

_GLITCH = '\n[[failure]]\nunit = "gnss"\ntype = "glitch"\nat_s = 0.5\nduration_s = 0.5\n' \
          'offset_m = [20.0, -10.0, 0.0]\n'
_LATENCY_NS = 110_000_000


def _fly(tmp_path, transport: str, name: str, extra: str):
    path = tmp_path / f"{name}.toml"
    path.write_text((SCENARIO_DIR / "S1.toml").read_text() + extra)
    log = tmp_path / f"{name}.mcap"
    s = fly_two_processes(FlightOptions(scenario=str(path), duration_s=1.5, processes=2,
                                        transport=transport,
                                        instance=f"fault-hil-{transport}-{name}",
                                        log_path=str(log)), out=lambda *_: None)
    return s, read_log(log, ["/gnss"]).channels["/gnss"]


@pytest.mark.parametrize("transport", ["shm", "udp"])
def test_a_gnss_glitch_reaches_the_fc(tmp_path, transport):
    s, g = _fly(tmp_path, transport, "glitch", _GLITCH)
    _, ref = _fly(tmp_path, transport, "clean", "")
    assert not s["crashed"] and len(g) == len(ref) >= 12
    t = g["sim_ns"] - _LATENCY_NS                     # the epoch each fix was made at
    w = (t > 500_000_000) & (t <= 1_000_000_000)
    assert w.sum() == 5
    sc = load_scenario("S1")
    m_per_deg_lat = 111_132.954 - 559.822 * math.cos(2 * math.radians(sc.home.lat_deg))
    dn = (g["lat_e7"] - ref["lat_e7"]) * 1e-7 * m_per_deg_lat
    de = (g["lon_e7"] - ref["lon_e7"]) * 1e-7 * m_per_deg_lat * math.cos(
        math.radians(sc.home.lat_deg))
    np.testing.assert_allclose(dn[w], 20.0, atol=0.2)
    np.testing.assert_allclose(de[w], -10.0, atol=0.2)
    assert (dn[~w] == 0).all() and (de[~w] == 0).all()
