"""Record builders shared by the FlightCore tests (real shm record dtypes); this folder on
sys.path, so its tests import the block bindings (fc_blocks.py) by name (--import-mode=importlib)."""

import sys
from pathlib import Path

import numpy as np
import pytest

from silbridge.shm import records as R

if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))

G = 9.80665


class Stream:
    """Builds time-ordered batches of sensor records for a vehicle at rest, level."""

    def __init__(self, imu_hz=1000.0, baro_hz=100.0, mag_hz=100.0, gt=False):
        self.imu_period_ns = int(round(1e9 / imu_hz))
        self.baro_every = max(1, int(round(imu_hz / baro_hz))) if baro_hz else 0
        self.mag_every = max(1, int(round(imu_hz / mag_hz))) if mag_hz else 0
        self.gt = gt
        self.k = 0
        self.seq = {}

    def _record(self, kind, sim_ns, **fields):
        """One record of `kind` at sim_ns with the next sequence number, as RECORD_DTYPE."""
        seq = self.seq.get(kind, 0)
        self.seq[kind] = seq + 1
        r = R.empty(kind, 1)
        r["sim_ns"] = sim_ns
        r["seq"] = seq
        for name, value in fields.items():
            r[name] = value
        return R.as_generic(r)

    def batch(self, n_imu, accel=(0.0, 0.0, -G), gyro=(0.0, 0.0, 0.0), pressure_pa=101325.0,
              field=(0.2, 0.0, 0.4), q_gt=(1.0, 0.0, 0.0, 0.0)):
        rows = []
        for _ in range(n_imu):
            t = self.k * self.imu_period_ns
            rows.append(self._record(R.Kind.IMU, t, accel_frd_m_s2=accel, gyro_frd_rad_s=gyro))
            if self.baro_every and self.k % self.baro_every == 0:
                rows.append(self._record(R.Kind.BARO, t, pressure_pa=pressure_pa))
            if self.mag_every and self.k % self.mag_every == 0:
                rows.append(self._record(R.Kind.MAG, t, field_frd_gauss=field))
            if self.gt and self.k % 10 == 0:
                rows.append(self._record(R.Kind.GT_ATT, t, q_wxyz=q_gt))
            self.k += 1
        return np.concatenate(rows)


@pytest.fixture
def stream():
    return Stream


def setpoint(sim_ns, roll=0.0, pitch=0.0, yaw=0.0, alt=float("nan"), mask=0):
    sp = R.empty(R.Kind.SETPOINT, 1)
    sp["sim_ns"] = sim_ns
    sp["roll_rad"], sp["pitch_rad"], sp["yaw_rad"], sp["altitude_m"] = roll, pitch, yaw, alt
    sp["mask"] = mask
    return R.as_generic(sp)


@pytest.fixture
def make_setpoint():
    return setpoint
