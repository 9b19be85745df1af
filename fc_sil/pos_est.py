"""Horizontal position and velocity estimate (NED) from the FC's own sensors.

A delayed-measurement complementary filter, per horizontal axis, run at the outer-loop rate:

* prediction: the accelerometer's mean specific force since the last step (raw IMU, FRD),
  rotated to NED with the estimated attitude, plus gravity, gives the NED acceleration;
  velocity and position integrate it (minus a slowly learned acceleration bias, which absorbs
  small attitude-estimate errors: 1 degree of tilt error is 0.17 m/s^2);
* correction: each GNSS fix (10 Hz) describes the vehicle GPS_DELAY_MS ago, so it is compared
  with the estimate stored for that instant (a short history), and the innovation corrects
  position (time constant SB_POS_TC), velocity (SB_VEL_TC) and the bias. The correction is
  added to the stored history as well, so the next fix is not corrected twice.
* gate (gnss_gate.py, EKF3's rules): a fix whose innovation fails its test ratio is not
  fused (a GNSS glitch); after the retry time the estimate resets to GNSS instead.
* reset record: each reset counts (xy_reset_count) and keeps the shift it made to the
  estimate (xy_reset_ne_m), as EKF3's getLastPosNorthEastReset; the position controller
  and the modes' "hold here" points move by it (vehicle_nav.py), so the vehicle does not
  fly the jump (ArduCopter's AC_PosControl::handle_ekf_xy_reset). The first fix starts the
  estimate and is not a reset.

Vertical: the C core's baro + accel filter (alt_est_m, climb_est_m_s, positive up above the
arming point) is already the FC's vertical estimate; this module reports it in NED.

Frames: local NED about the origin = the first 3D fix (the EKF origin in ArduPilot terms);
latitude/longitude conversions use a spherical Earth about that origin (errors of centimetres
within a few kilometres).
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass

from .gnss_gate import GnssGate

EARTH_RADIUS_M = 6378137.0
G_M_S2 = 9.80665
FIX_3D = 3


def quat_rotate_frd_to_ned(q_wxyz, v):
    """Rotate a body FRD vector into NED with the attitude quaternion (body -> NED)."""
    w, x, y, z = q_wxyz
    vx, vy, vz = v
    # v' = q v q*, written out (the standard rotation-matrix form)
    r00 = 1 - 2 * (y * y + z * z)
    r01 = 2 * (x * y - w * z)
    r02 = 2 * (x * z + w * y)
    r10 = 2 * (x * y + w * z)
    r11 = 1 - 2 * (x * x + z * z)
    r12 = 2 * (y * z - w * x)
    r20 = 2 * (x * z - w * y)
    r21 = 2 * (y * z + w * x)
    r22 = 1 - 2 * (x * x + y * y)
    return (r00 * vx + r01 * vy + r02 * vz, r10 * vx + r11 * vy + r12 * vz,
            r20 * vx + r21 * vy + r22 * vz)


@dataclass(frozen=True)
class GeoOrigin:
    lat_e7: int
    lon_e7: int
    alt_msl_m: float

    def to_ne(self, lat_e7: int, lon_e7: int) -> tuple[float, float]:
        """North/east metres of a position from this origin."""
        lat0 = math.radians(self.lat_e7 * 1e-7)
        dn = math.radians((lat_e7 - self.lat_e7) * 1e-7) * EARTH_RADIUS_M
        dlon = (lon_e7 - self.lon_e7) * 1e-7
        if dlon > 180.0:        # across the antimeridian
            dlon -= 360.0
        elif dlon < -180.0:
            dlon += 360.0
        de = math.radians(dlon) * EARTH_RADIUS_M * math.cos(lat0)
        return dn, de

    def to_latlon_e7(self, n_m: float, e_m: float) -> tuple[int, int]:
        lat0 = math.radians(self.lat_e7 * 1e-7)
        lat = self.lat_e7 * 1e-7 + math.degrees(n_m / EARTH_RADIUS_M)
        coslat = max(1e-6, math.cos(lat0))
        lon = self.lon_e7 * 1e-7 + math.degrees(e_m / (EARTH_RADIUS_M * coslat))
        if lon >= 180.0:
            lon -= 360.0
        elif lon < -180.0:
            lon += 360.0
        return int(round(lat * 1e7)), int(round(lon * 1e7))


class PositionEstimator:
    """See module text. ``update`` once per outer-loop step; read pos_ne_m / vel_ne_m_s."""

    HISTORY_S = 1.0

    def __init__(self, pos_tc_s: float = 1.5, vel_tc_s: float = 0.2, delay_s: float = 0.11):
        self.pos_tc_s = pos_tc_s
        self.vel_tc_s = vel_tc_s
        self.delay_s = delay_s
        self.origin: GeoOrigin | None = None
        self.pos_ne_m = [0.0, 0.0]
        self.vel_ne_m_s = [0.0, 0.0]
        self.acc_bias_ne_m_s2 = [0.0, 0.0]
        self.acc_ned_m_s2 = (0.0, 0.0, 0.0)
        self.valid = False                # a 3D fix has been fused
        self.innov_pos_m = 0.0            # size of the last GNSS innovation
        self.innov_vel_m_s = 0.0
        self.last_fix_sim_ns: int | None = None
        self.last_fused_ns: int | None = None
        self.fixes_fused = 0
        self.fixes_rejected = 0
        self.xy_reset_count = 0           # horizontal position resets so far
        self.xy_reset_ne_m = (0.0, 0.0)   # the last reset's shift of the position [m]
        self.xy_reset_vel_ne_m_s = (0.0, 0.0)  # its shift of the velocity (0 unless reset)
        self.gate = GnssGate()
        self._hist: collections.deque = collections.deque()   # (sim_ns, pn, pe, vn, ve)

    def configure(self, pos_tc_s: float, vel_tc_s: float, delay_s: float) -> None:
        self.pos_tc_s, self.vel_tc_s, self.delay_s = pos_tc_s, vel_tc_s, delay_s

    # ---- prediction -----------------------------------------------------------------------

    def predict(self, sim_ns: int, dt_s: float, q_wxyz, accel_frd_m_s2) -> None:
        if accel_frd_m_s2 is not None:
            a = quat_rotate_frd_to_ned(q_wxyz, accel_frd_m_s2)
            # specific force + gravity = kinematic acceleration (NED, gravity down = +g)
            self.acc_ned_m_s2 = (a[0], a[1], a[2] + G_M_S2)
        an = self.acc_ned_m_s2[0] - self.acc_bias_ne_m_s2[0]
        ae = self.acc_ned_m_s2[1] - self.acc_bias_ne_m_s2[1]
        p, v = self.pos_ne_m, self.vel_ne_m_s
        p[0] += v[0] * dt_s + 0.5 * an * dt_s * dt_s
        p[1] += v[1] * dt_s + 0.5 * ae * dt_s * dt_s
        v[0] += an * dt_s
        v[1] += ae * dt_s
        h = self._hist
        h.append((sim_ns, p[0], p[1], v[0], v[1]))
        while h and sim_ns - h[0][0] > self.HISTORY_S * 1e9:
            h.popleft()

    def hold_on_ground(self) -> None:
        """Disarmed on the ground: the vehicle does not move; do not integrate noise."""
        self.vel_ne_m_s[0] = self.vel_ne_m_s[1] = 0.0

    # ---- correction ---------------------------------------------------------------------

    def fuse_gnss(self, fix: dict, vd_est_m_s: float | None = None) -> bool:
        """Fuse a fix (FlightCore.gnss() dict); returns False for no 3D fix, a repeat or a fix
        the gate rejected whole. vd_est_m_s: the vertical estimate's velocity (down), so the
        velocity test covers three axes as EKF3's does."""
        t = int(fix["sim_ns"])
        if t == self.last_fix_sim_ns:
            return False
        self.last_fix_sim_ns = t
        if fix.get("fix_type", 0) < FIX_3D:
            return False
        if self.origin is None:
            self.origin = GeoOrigin(fix["lat_e7"], fix["lon_e7"], fix["alt_mm"] * 1e-3)
        mn, me = self.origin.to_ne(fix["lat_e7"], fix["lon_e7"])
        mvn, mve = fix["vel_ned_m_s"][0], fix["vel_ned_m_s"][1]
        if not self.valid:
            # first fix: start at the measurement instead of converging from zero
            self.pos_ne_m = [mn, me]
            self.vel_ne_m_s = [mvn, mve]
            self._hist.clear()
            self.valid = True
            self.last_fused_ns = t
            self.fixes_fused += 1
            self.gate.start(t)
            return True
        past = self._state_at(t - int(self.delay_s * 1e9))
        dt_fix = 0.1 if self.last_fused_ns is None else \
            min(1.0, max(1e-3, (t - self.last_fused_ns) * 1e-9))
        e_p = (mn - past[0], me - past[1])
        e_v = (mvn - past[2], mve - past[3])
        self.innov_pos_m = math.hypot(*e_p)
        self.innov_vel_m_s = math.hypot(*e_v)
        kp = min(1.0, dt_fix / self.pos_tc_s)
        kv = min(1.0, dt_fix / self.vel_tc_s)
        e_v3 = e_v if vd_est_m_s is None else e_v + (fix["vel_ned_m_s"][2] - vd_est_m_s,)
        a = self.acc_ned_m_s2
        d = self.gate.test(t, e_p, e_v3, fix.get("eph_cm", 0) * 0.01,
                           math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]), kp, kv)
        if not (d.fuse_pos or d.fuse_vel or d.reset_pos or d.reset_vel):
            self.fixes_rejected += 1
            return False
        self.last_fused_ns = t
        kp = 1.0 if d.reset_pos else (kp * d.pos_scale if d.fuse_pos else 0.0)
        kv = 1.0 if d.reset_vel else (kv * d.vel_scale if d.fuse_vel else 0.0)
        # bias learns ~10x slower than the velocity correction (keeps the loop well damped)
        kb = 0.0 if not d.fuse_vel else \
            min(1.0, dt_fix / (10.0 * self.vel_tc_s * self.vel_tc_s)) * d.vel_scale
        dp, dv = (kp * e_p[0], kp * e_p[1]), (kv * e_v[0], kv * e_v[1])
        self._correct(dp, dv, kb, e_v)
        if d.reset_pos:
            self.xy_reset_count += 1
            self.xy_reset_ne_m = dp
            self.xy_reset_vel_ne_m_s = dv if d.reset_vel else (0.0, 0.0)
        self.fixes_fused += 1
        return True

    def _correct(self, dp, dv, kb: float, e_v) -> None:
        """Shift the estimate and its history by (dp, dv); learn the bias from e_v."""
        self.pos_ne_m[0] += dp[0]
        self.pos_ne_m[1] += dp[1]
        self.vel_ne_m_s[0] += dv[0]
        self.vel_ne_m_s[1] += dv[1]
        self.acc_bias_ne_m_s2[0] -= kb * e_v[0]
        self.acc_bias_ne_m_s2[1] -= kb * e_v[1]
        lim = 1.0   # m/s^2: more than this is not an attitude error but a bad fix
        self.acc_bias_ne_m_s2 = [max(-lim, min(lim, b)) for b in self.acc_bias_ne_m_s2]
        self._hist = collections.deque((s, pn + dp[0], pe + dp[1], vn + dv[0], ve + dv[1])
                                       for s, pn, pe, vn, ve in self._hist)

    def has_position(self, sim_ns: int) -> bool:
        """An absolute horizontal position (EKF3 horiz_pos_abs): fixes were fused and GNSS
        aiding has not timed out (gnss_gate.py)."""
        return self.valid and self.gate.has_position(sim_ns)

    def _state_at(self, sim_ns: int) -> tuple[float, float, float, float]:
        best = None
        for s, pn, pe, vn, ve in self._hist:
            if best is None or abs(s - sim_ns) < abs(best[0] - sim_ns):
                best = (s, pn, pe, vn, ve)
            elif s > sim_ns:
                break
        if best is None:
            return (self.pos_ne_m[0], self.pos_ne_m[1], self.vel_ne_m_s[0], self.vel_ne_m_s[1])
        return best[1:]

    # ---- outputs ----------------------------------------------------------------------------

    def latlon_e7(self) -> tuple[int, int]:
        if self.origin is None:
            return 0, 0
        return self.origin.to_latlon_e7(self.pos_ne_m[0], self.pos_ne_m[1])
