"""The height above ground the sensor stage computes is JSBSim's own, to the bit.

The kernel reads the geodetic altitude (position/geod-alt-ft) and subtracts the terrain
elevation the bridge gave JSBSim (Fdm.terrain_ft), instead of calling position/h-agl-ft,
whose getter goes through the ground callback each time (bridge/fdm.py). That is only right
while JSBSim's flat-earth ground callback computes h-agl-ft as exactly that difference: a
JSBSim upgrade that changed it would fail here, before any trace hash moves.
"""

import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator


@pytest.mark.parametrize("scenario, home", [("S1", None), ("S3", None),
                                            ("S1", {"home.alt_m": 0.0}),
                                            ("S1", {"home.alt_m": 2345.6,
                                                    "home.lat_deg": -33.9})])
def test_geodetic_altitude_minus_terrain_is_jsbsims_height_above_ground(scenario, home):
    sim = Simulator(load_scenario(scenario, overrides=home or {}))
    fdm = sim.fdm
    geod = fdm.sample_nodes["geod_alt_ft"].get_double_value
    agl = fdm.h_hagl.get_double_value
    climb = [sim.hover_pwm_us * 1.05] * 4
    heights = []
    for i in range(3000):        # on the legs, spinning up, lifting off, climbing
        sim.step([1000.0] * 4 if i < 500 else climb)
        assert geod() - fdm.terrain_ft == agl(), i
        heights.append(agl())
    assert min(heights) < 1.0 < 5.0 < max(heights)     # both on the ground and well above it
