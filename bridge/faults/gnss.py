"""GNSS faults: what the receiver reports while a gnss fault is on (the model is
bridge/lowrate.py's Gnss; the engine switches, this module makes each epoch's fix).

At each epoch the receiver's error and noise are drawn as without a fault (the stream runs
on, so the fixes after the fault are the fault-free run's), then:
- off: no fix at all (no GNSS record, no HIL_GPS);
- fix_lost: fixes keep coming with fix type 1 (no fix), 0 satellites, no position or
  velocity (0) and unknown accuracy (eph/epv 65535 cm, MAVLink's "unknown");
- sats_drop: the satellite count falls linearly from the configured one to `satellites`
  over ramp_s. Accuracy follows the geometry: a dilution of precision grows roughly as
  1/sqrt(n) with n satellites spread over the sky, so the position error and the reported
  eph/epv are scaled by sqrt(n0 / n). Below 4 satellites there is no 3D solution: with 3 the
  fix is 2D (type 2), below 3 it is lost as above (with the count still reported);
- glitch: the position jumps by offset_m (NED) while on;
- drift: the position walks off at rate_m_s (NED) from the moment it switched on;
- vel_error: the velocity is off by error_m_s (NED).
Faults of different types add up (a drift during a satellite drop).
"""

from __future__ import annotations

import math

_UNKNOWN_CM = 65535   # eph/epv "unknown" (MAVLink GPS_RAW_INT / HIL_GPS)


def satellites_at(f, n0: int, sim_ns: int) -> int:
    """The satellite count of a sats_drop fault at sim_ns."""
    ramp_s = f.params["ramp_s"]
    frac = 1.0 if ramp_s <= 0 else min(1.0, (sim_ns - f.t_on_ns) * 1e-9 / ramp_s)
    return int(round(n0 + (f.params["satellites"] - n0) * frac))


class GnssFault:
    """The active gnss faults, folded; Gnss.epoch calls fix() instead of its own."""

    def __init__(self, faults):
        self.by_type = {f.type: f for f in faults}

    def fix(self, gnss, sim_ns: int, lat_rad: float, lon_rad: float, alt_msl_m: float, vel):
        c, t = gnss.cfg, self.by_type
        if "off" in t:
            return None
        sats, fix_type, scale = c.satellites, c.fix_type, 1.0
        if "sats_drop" in t:
            sats = satellites_at(t["sats_drop"], c.satellites, sim_ns)
            scale = math.sqrt(c.satellites / max(sats, 1)) if c.satellites > 0 else 1.0
            if sats < 4:
                fix_type = min(fix_type, 2)
        if "fix_lost" in t or sats < 3:
            return (0, 0, 0, 0.0, 0.0, 0.0, _UNKNOWN_CM, _UNKNOWN_CM, min(fix_type, 1),
                    0 if "fix_lost" in t else sats)
        off = [0.0, 0.0, 0.0]
        if "glitch" in t:
            off = list(t["glitch"].params["offset_m"])
        if "drift" in t:
            f = t["drift"]
            dt_s = (sim_ns - f.t_on_ns) * 1e-9
            off = [o + r * dt_s for o, r in zip(off, f.params["rate_m_s"])]
        if "vel_error" in t:
            vel = [v + d for v, d in zip(vel, t["vel_error"].params["error_m_s"])]
        e = [scale * gnss.err_ned_m[i] + off[i] for i in range(3)]
        return gnss.fix(lat_rad, lon_rad, alt_msl_m, e, vel, scale * c.pos_sigma_h_m,
                        scale * c.pos_sigma_v_m, fix_type, sats)


class GnssApplier:
    """Keeps the Gnss model's fault in step with the engine's active gnss faults."""

    def __init__(self, engine, gnss):
        self.engine = engine
        self.gnss = gnss

    def on(self, fault, sim_ns: int) -> None:
        active = self.engine.active("gnss")
        self.gnss.fault = GnssFault(active) if active else None

    off = on
