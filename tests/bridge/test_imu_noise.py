"""The one-sample-per-step IMU's noise rows summed in C (bridge/src/imu_noise.c,
ImuModel.next_scalar_block) are numpy's sums (ImuModel._next_block, the block path's), to
the bit: the trace hashes of every flight depend on them."""

from __future__ import annotations

import numpy as np
import pytest

from silbridge.bridge import _step
from silbridge.bridge.imu import ImuModel
from silbridge.bridge.scenario import load_scenario


def _model(block_rows: int):
    sc = load_scenario("S1", overrides={"imu.gyro_tempco": 0.002, "imu.accel_tempco": 0.01,
                                        "imu.temp_rise_k": 15.0, "imu.temp_tau_s": 0.5})
    return ImuModel(sc.imu, 7, 1000, 1000, 18.5, 1100.0, block_rows)


@pytest.mark.parametrize("block_rows", [1024, 37])
def test_c_rows_are_numpys_rows(block_rows):
    c_imu, np_imu = _model(block_rows), _model(block_rows)
    for _ in range(4):      # the walk and the temperature carry over from block to block
        out, temps = c_imu.next_scalar_block()
        np_temps = np_imu._next_block()
        expected = np.ascontiguousarray(np_imu._slow + np_imu.white.next_block())
        assert out.tobytes() == expected.tobytes()
        assert temps.tobytes() == np_temps.tobytes()
        assert c_imu._slow.tobytes() == np_imu._slow.tobytes()     # bias6() reads these
        assert c_imu.walk.last.tobytes() == np_imu.walk.last.tobytes()
    assert np.ptp(temps) > 0.0 and np.abs(c_imu.walk.last).max() > 0.0   # not a trivial case


def test_bad_shapes_are_refused():
    z6, z1 = np.zeros((4, 6)), np.zeros(4)
    with pytest.raises(ValueError, match="rows, 6"):
        _step.imu_noise_rows(z6, z6, np.zeros(3), np.zeros(6), np.zeros(6), 25.0, np.zeros(6),
                             z6.copy(), z6.copy())
    with pytest.raises(ValueError, match="float64"):
        _step.imu_noise_rows(z6.astype(np.float32), z6, z1, np.zeros(6), np.zeros(6), 25.0,
                             np.zeros(6), z6.copy(), z6.copy())
