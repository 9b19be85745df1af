"""The C step kernel (bridge/src/: the shim and its pure-C sensor stage) against its
readable Python oracle (step_kernel_oracle.py, beside this file).

Both must write byte-identical records for the same scenario, seed and PWM sequence,
through take-off, disturbances, oversampling and a crash; that is what lets the
oracle document the C code and keeps trace hashes stable across the switch. The
constants and the FDM getters reach the C stage by name: a missing or unknown name
is refused, never taken by position.
"""

import numpy as np
import pytest
import step_kernel_oracle
from bridge_test_helpers import profile_digest

from silbridge.bridge import _step
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator


def _run(kernel_cls, scenario, imu_hz, steps):
    sim = Simulator(load_scenario(scenario), imu_hz=imu_hz, kernel_cls=kernel_cls)
    return profile_digest(sim, steps), sim


@pytest.mark.parametrize("scenario,imu_hz", [("S1", None), ("S2", None), ("S3", None),
                                             ("S4", None), ("S1", 8000), ("S3", 1500)])
def test_c_kernel_writes_the_reference_records(scenario, imu_hz):
    steps = 4000 if imu_hz is None else 1500
    c_hash, c_sim = _run(_step.Kernel, scenario, imu_hz, steps)
    py_hash, py_sim = _run(step_kernel_oracle.Kernel, scenario, imu_hz, steps)
    assert c_hash == py_hash
    assert c_sim.published_counts() == py_sim.published_counts()
    assert (c_sim.crashed, c_sim.crash_reason) == (py_sim.crashed, py_sim.crash_reason)
    assert c_sim.truth() == py_sim.truth()
    if imu_hz is None and scenario == "S1":
        assert c_sim.crashed, "the profile should end in a crash (exercises the flags)"


def test_injected_gyro_bias_reaches_the_kernel():
    over = {"imu.gyro_noise_density": 0.0, "imu.gyro_turn_on_bias": 0.0,
            "imu.gyro_bias_walk": 0.0, "imu.gyro_tempco": 0.0, "imu.vib_gyro": 0.0,
            "imu.gyro_bias_rad_s": [0.03, -0.02, 0.01]}
    sim = Simulator(load_scenario("S1", overrides=over))
    recs = sim.step((1000.0,) * 4)
    gyro = recs[recs["kind"] == 1].view(np.dtype([("h", "V24"), ("a", "<f4", 3),
                                                  ("g", "<f4", 3), ("r", "V16")]))["g"][0]
    truth = sim.truth()["rates_frd_rad_s"]
    np.testing.assert_allclose(gyro - np.array(truth, dtype=np.float32),
                               [0.03, -0.02, 0.01], atol=1e-6)


def test_nan_pwm_is_refused_with_the_step_number():
    sim = Simulator(load_scenario("S1"))
    sim.step((1000.0,) * 4)
    with pytest.raises(ValueError, match="NaN at step 2"):
        sim.step((1000.0, float("nan"), 1000.0, 1000.0))


def test_wrong_pwm_shape_is_refused():
    sim = Simulator(load_scenario("S1"))
    with pytest.raises(TypeError, match="4 pulse widths"):
        sim.step((1000.0,) * 3)


def _kernel_args(sim, **change):
    """The arguments the simulator gives its kernel, with some replaced."""
    args = {"buffer": bytearray(64 * 8), "setters": [h.set_double_value for h in sim.fdm.h_pwm],
            "run": sim.fdm.fdm.run, "getters": sim.fdm.sample_getters(),
            "state": np.zeros(_step.ST_COUNT), "consts": sim._stage_consts(),
            "phase": np.zeros(4), "dt_ns": sim.dt_ns, "flip_steps": 1000, "scalar_imu": True,
            "on_ground": True}
    args.update(change)
    return args


@pytest.mark.parametrize("kernel_cls", [_step.Kernel, step_kernel_oracle.Kernel])
def test_constants_and_getters_are_taken_by_name(kernel_cls):
    sim = Simulator(load_scenario("S1"))
    consts = sim._stage_consts()
    missing = {k: v for k, v in consts.items() if k != "baro_alpha"}
    with pytest.raises(KeyError, match="baro_alpha"):
        kernel_cls(**_kernel_args(sim, consts=missing))
    with pytest.raises(KeyError, match="baro_lag"):
        kernel_cls(**_kernel_args(sim, consts={**consts, "baro_lag": 0.5}))
    getters = sim.fdm.sample_getters()
    del getters["temperature_r"]
    with pytest.raises(KeyError, match="temperature_r"):
        kernel_cls(**_kernel_args(sim, getters=getters))
    # Names, not insertion order, place each value: a reversed dict is accepted.
    kernel_cls(**_kernel_args(sim, consts=dict(reversed(consts.items()))))


def test_the_stage_tables_match_the_fdm_properties():
    """Every field of the C FDM sample has a JSBSim property bound by the same name."""
    from silbridge.bridge.fdm import SAMPLE_PROPERTIES
    assert tuple(SAMPLE_PROPERTIES) == _step.SAMPLE_FIELDS
    assert set(Simulator(load_scenario("S1"))._stage_consts()) == set(_step.CONST_FIELDS)
