"""Record builders shared by the FlightCore tests (real shm record dtypes)."""

import numpy as np
import pytest

from silbridge.shm import records as R

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

    def _next_seq(self, kind):
        s = self.seq.get(kind, 0)
        self.seq[kind] = s + 1
        return s

    def batch(self, n_imu, accel=(0.0, 0.0, -G), gyro=(0.0, 0.0, 0.0), pressure_pa=101325.0,
              field=(0.2, 0.0, 0.4), q_gt=(1.0, 0.0, 0.0, 0.0)):
        rows = []
        for _ in range(n_imu):
            t = self.k * self.imu_period_ns
            imu = R.empty(R.Kind.IMU, 1)
            imu["sim_ns"] = t
            imu["seq"] = self._next_seq(R.Kind.IMU)
            imu["accel_frd_m_s2"] = accel
            imu["gyro_frd_rad_s"] = gyro
            rows.append(R.as_generic(imu))
            if self.baro_every and self.k % self.baro_every == 0:
                b = R.empty(R.Kind.BARO, 1)
                b["sim_ns"] = t
                b["seq"] = self._next_seq(R.Kind.BARO)
                b["pressure_pa"] = pressure_pa
                rows.append(R.as_generic(b))
            if self.mag_every and self.k % self.mag_every == 0:
                m = R.empty(R.Kind.MAG, 1)
                m["sim_ns"] = t
                m["seq"] = self._next_seq(R.Kind.MAG)
                m["field_frd_gauss"] = field
                rows.append(R.as_generic(m))
            if self.gt and self.k % 10 == 0:
                g = R.empty(R.Kind.GT_ATT, 1)
                g["sim_ns"] = t
                g["seq"] = self._next_seq(R.Kind.GT_ATT)
                g["q_wxyz"] = q_gt
                rows.append(R.as_generic(g))
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
