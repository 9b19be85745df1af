"""Barometer, magnetometer and GNSS models (the 10-100 Hz sensors).

Each model is sampled on the first physics step at or after its due time
t_m = round(m * 1e9 / rate_hz) ns, m = 1, 2, ... (`Schedule`; the step kernel
keeps the baro's and magnetometer's schedules in C, and the GNSS's from the second fix on:
bridge/src/gnss_model.c makes the same fixes, bridge/gnss_kernel.py hands Gnss's state
over and back).
Noise comes from one named stream per sensor (noise.NormalRows).

- Baro: static pressure from JSBSim's standard atmosphere (ISA, `atmosphere.py`
  has the closed form the tests compare with) through a first-order lag run at
  the physics rate, plus an offset and white noise. Temperature: air temperature.
- Mag: the configured Earth field (NED, gauss) rotated into body FRD, plus a
  hard-iron offset and white noise.
- GNSS: truth at each epoch plus a first-order Gauss-Markov position error
  (sigma_h, sigma_v, tau) and white velocity noise; the fix is published
  `latency_s` after its epoch (the first step at or after epoch + latency), as
  a receiver's message arrives late. The record's sim_ns is the arrival time;
  the position is the one of the epoch. A GNSS fault (bridge/faults/gnss.py) replaces the
  fix made at an epoch while it is on; the noise stream runs on as without it.
"""

from __future__ import annotations

import math
from collections import deque

from silbridge.bridge.noise import NormalRows
from silbridge.mavlink.hil import hil_quant


def due_ns(m: int, rate_hz: float) -> int:
    """Sample m (1, 2, ...) of a periodic sensor is due at round(m * 1e9 / rate_hz) ns."""
    return int(round(m * 1e9 / rate_hz))


class Schedule:
    """Due times of a periodic sensor in integer nanoseconds."""

    def __init__(self, rate_hz: float):
        self.rate_hz = rate_hz
        self.m = 1
        self.next_ns = due_ns(1, rate_hz)

    def advance(self) -> None:
        self.m += 1
        self.next_ns = due_ns(self.m, self.rate_hz)


class Baro:
    """Configuration, schedule and noise stream of the barometer. The step kernel's
    sensor stage (bridge/src/sensor_stage.c) runs the lag once per physics
    step, filtered_pa += alpha * (pressure_pa - filtered_pa), alpha = 1 - exp(-dt /
    lag_s), and samples pa = filtered + offset + noise_pa * n, put on the grid
    HIL_SENSOR (float32 hPa) carries exactly, so the FC reads the same pressure over
    shared memory and over MAVLink."""

    def __init__(self, cfg, seed: int, dt_s: float, pressure0_pa: float):
        self.cfg = cfg
        self.schedule = Schedule(cfg.rate_hz)
        self.noise = NormalRows(seed, "baro", 1)
        self.alpha = 1.0 if cfg.lag_s <= 0 else 1.0 - math.exp(-dt_s / cfg.lag_s)
        self.filtered_pa = pressure0_pa


class Mag:
    """Configuration, schedule and noise stream of the magnetometer; the step kernel
    samples field_frd = R(phi, theta, psi) field_ned + offset + noise_gauss * n."""

    def __init__(self, cfg, seed: int):
        self.cfg = cfg
        self.schedule = Schedule(cfg.rate_hz)
        self.noise = NormalRows(seed, "mag", 3)


class Gnss:
    """Epochs at rate_hz, each released latency_s later."""

    def __init__(self, cfg, seed: int, m_per_rad_lat: float, m_per_rad_lon: float):
        self.cfg = cfg
        self.schedule = Schedule(cfg.rate_hz)
        self.noise = NormalRows(seed, "gnss", 6)
        self.latency_ns = int(round(cfg.latency_s * 1e9))
        self.m_per_rad_lat = m_per_rad_lat
        self.m_per_rad_lon = m_per_rad_lon
        self.err_ned_m = None   # Gauss-Markov state, started from its stationary law
        self.last_epoch_ns = 0
        self.pending: deque = deque()
        self._fault = None
        # Called when the fault changes: the model may have to come back from C to Python,
        # whatever switched it (the fault engine's schedule, a poll, a script's inject).
        self.on_fault_change = None

    @property
    def fault(self):
        """bridge/faults/gnss.py GnssFault while a GNSS fault is on, else None."""
        return self._fault

    @fault.setter
    def fault(self, fault) -> None:
        self._fault = fault
        if self.on_fault_change is not None:
            self.on_fault_change()

    def epoch(self, sim_ns: int, lat_rad: float, lon_rad: float, alt_msl_m: float,
              vel_ned_m_s) -> None:
        """Measure at an epoch; queue the fix for release after the latency."""
        c = self.cfg
        n = self.noise.next_row()
        sig = (c.pos_sigma_h_m, c.pos_sigma_h_m, c.pos_sigma_v_m)
        if self.err_ned_m is None:
            self.err_ned_m = [sig[i] * n[i] for i in range(3)]
        else:
            a = math.exp(-(sim_ns - self.last_epoch_ns) * 1e-9 / c.pos_tau_s)
            q = math.sqrt(1.0 - a * a)
            self.err_ned_m = [a * self.err_ned_m[i] + q * sig[i] * n[i] for i in range(3)]
        self.last_epoch_ns = sim_ns
        v = c.vel_sigma_m_s
        vel = (vel_ned_m_s[0] + v * n[3], vel_ned_m_s[1] + v * n[4], vel_ned_m_s[2] + v * n[5])
        if self.fault is None:
            fix = self.fix(lat_rad, lon_rad, alt_msl_m, self.err_ned_m, vel, c.pos_sigma_h_m,
                           c.pos_sigma_v_m, c.fix_type, c.satellites)
        else:
            fix = self.fault.fix(self, sim_ns, lat_rad, lon_rad, alt_msl_m, vel)
            if fix is None:    # the receiver is silent
                return
        self.pending.append((sim_ns + self.latency_ns, sim_ns, fix))

    def fix(self, lat_rad: float, lon_rad: float, alt_msl_m: float, e, vel, sigma_h_m: float,
            sigma_v_m: float, fix_type: int, satellites: int) -> tuple:
        """The record's fields of a fix at the true position plus the error e (NED, m) with
        velocity vel (NED, m/s) and the stated accuracy."""
        lat_deg = math.degrees(lat_rad + e[0] / self.m_per_rad_lat)
        lon_deg = math.degrees(lon_rad + e[1] / self.m_per_rad_lon)
        alt_m = alt_msl_m - e[2]
        # Whole cm/s, as HIL_GPS carries it (same fix over shared memory and MAVLink).
        q = hil_quant.velocity_m_s
        return (int(round(lat_deg * 1e7)), int(round(lon_deg * 1e7)),
                int(round(alt_m * 1000.0)), q(vel[0]), q(vel[1]), q(vel[2]),
                min(65535, int(round(sigma_h_m * 100.0))),
                min(65535, int(round(sigma_v_m * 100.0))), fix_type, satellites)
