"""GuidedCommands: the GCS inputs that steer GUIDED, taken as ArduCopter 4.6 takes them.

A mixin of vehicle_commands.GcsCommands (so of the Vehicle); runs on the vehicle thread.
What ArduCopter does with each (ArduCopter/GCS_MAVLink_Copter.cpp, mode_guided.cpp):

* SET_POSITION_TARGET_LOCAL_NED / _GLOBAL_INT and SET_ATTITUDE_TARGET: ignored outside
  GUIDED; a type_mask, frame or value it cannot use (mavlink/gcs/setpoints.py) stops the
  vehicle (GUIDED's init: velocity 0, hold) without a word (FORCE_SET: dropped, no stop).
  Local frames LOCAL_NED, LOCAL_OFFSET_NED, BODY_NED, BODY_OFFSET_NED (BODY: velocity,
  acceleration and the offset turn with the heading, and the yaw is relative); global
  frames GLOBAL(_INT) above sea level,
  RELATIVE_ALT(_INT) above home, TERRAIN_ALT(_INT) (flat ground here: above home; refused with a
  velocity). A position outside the fence changes nothing.
* SET_ATTITUDE_TARGET's thrust is a climb rate (0.5 hold, 1 WPNAV_SPEED_UP, 0 WPNAV_SPEED_DN)
  unless GUID_OPTIONS bit 3 makes it thrust.
* DO_REPOSITION: in GUIDED, or with the CHANGE_MODE flag (param2 bit 0, MAVSDK sets it) which
  switches to GUIDED; speed (param1) and yaw (param4) are not used; the point is flown as a
  position target. Latitude/longitude 0/0 or a relative altitude of 0 is DENIED.
* DO_CHANGE_SPEED: param2 > 0, else FAILED (what the real ArduCopter 4.6.0 answers; later
  ArduPilot says DENIED); param1 over 2.9 descent, over 1.9 climb, else ground speed; GUIDED
  and AUTO take it, other modes FAILED.
* CONDITION_YAW: ACCEPTED in any mode, acts where the nose is the mode's to point (GUIDED).
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs import setpoints
from silbridge.mavlink.gcs.vehicle_api import CopterMode

from .auto_yaw import YawRequest

ACCEPTED, FAILED, DENIED = mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_FAILED, mav.MAV_RESULT_DENIED
BODY_FRAMES = frozenset({mav.MAV_FRAME_BODY_NED, mav.MAV_FRAME_BODY_OFFSET_NED})
# SET_POSITION_TARGET_GLOBAL_INT altitude frames: "msl", "home", "terrain"
GLOBAL_ALT = {mav.MAV_FRAME_GLOBAL: "msl", mav.MAV_FRAME_GLOBAL_INT: "msl",
              mav.MAV_FRAME_GLOBAL_RELATIVE_ALT: "home",
              mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: "home",
              mav.MAV_FRAME_GLOBAL_TERRAIN_ALT: "terrain",
              mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: "terrain"}
# ArduCopter's sane_vel_or_acc_vector: finite and below 1000 m/s
VEL_SANE_M_S = 1000.0


def latlon_ok(lat_e7: int, lon_e7: int) -> bool:
    return abs(lat_e7) <= 900_000_000 and abs(lon_e7) <= 1_800_000_000


def quat_to_euler(q) -> tuple[float, float, float]:
    w, x, y, z = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


class GuidedCommands:

    # ---- SET_POSITION_TARGET_* ---------------------------------------------------------------
    def set_position_target(self, t) -> None:
        if self.mode.number != CopterMode.GUIDED:
            self.setpoints_ignored += 1
            return
        why = self._guided_position_target(t)
        if why:
            self.setpoints_ignored += 1
            self.mode.init(self)            # ArduCopter: "input is not valid so stop"

    def _body_to_ne(self, x: float, y: float) -> tuple[float, float]:
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        return x * c - y * s, x * s + y * c

    def _guided_position_target(self, t) -> str | None:
        """Hand a target to GUIDED; the reason to stop if ArduCopter would."""
        use = setpoints.position_mask_use(t.type_mask)
        if use.kind is None and not use.stop:
            self.setpoints_ignored += 1
            return None
        if use.kind is None:
            return use.why
        if not t.is_global and t.frame not in setpoints.LOCAL_FRAMES:
            return f"frame {t.frame} not supported"
        body = not t.is_global and t.frame in BODY_FRAMES
        yaw = YawRequest(use.use_yaw, float(t.yaw_rad), use.use_yaw_rate,
                         float(t.yaw_rate_rad_s), body and use.use_yaw)
        if (use.use_yaw and not math.isfinite(t.yaw_rad)) or \
                (use.use_yaw_rate and not math.isfinite(t.yaw_rate_rad_s)):
            return "yaw not a number"
        vel = acc = (0.0, 0.0, 0.0)
        if use.kind in ("velaccel", "posvelaccel"):
            vel = tuple(float(c) for c in t.vel_ned_m_s)
            if not all(math.isfinite(c) and abs(c) < VEL_SANE_M_S for c in vel):
                return "velocity not sane"
            if body:
                vel = (*self._body_to_ne(vel[0], vel[1]), vel[2])
        if use.use_accel and not (t.is_global and use.kind == "posvelaccel"):
            acc = tuple(float(c) for c in t.acc_ned_m_s2)
            if not all(map(math.isfinite, acc)):
                return "acceleration not a number"
            if body:
                acc = (*self._body_to_ne(acc[0], acc[1]), acc[2])
        g = self.mode
        if use.kind == "velaccel":
            g.set_velaccel(self, vel, acc, yaw)
            return None
        if use.kind == "accel":
            g.set_accel(self, acc, yaw)
            return None
        point = self._target_point(t, with_velocity=use.kind == "posvelaccel")
        if isinstance(point, str):
            return point
        ne, alt = point
        if self._outside_fence(ne, alt):
            self.setpoints_ignored += 1     # ArduCopter: set_destination refuses, no change
            return None
        if use.kind == "pos":
            g.set_destination(self, ne, alt, yaw)
        else:
            g.set_posvelaccel(self, ne, alt, vel, acc, yaw)
        return None

    def _target_point(self, t, with_velocity: bool):
        """(ne, alt) of a target's position in the vehicle's frames, or why it is unusable."""
        o = self.est.origin
        if o is None:
            return "no position estimate"
        if t.is_global:
            frame = GLOBAL_ALT.get(t.frame)
            if frame is None:
                return f"frame {t.frame} not supported"
            if frame == "terrain" and with_velocity:
                return "terrain altitude with a velocity"
            lat, lon = int(t.x), int(t.y)
            if not latlon_ok(lat, lon) or not math.isfinite(t.z):
                return "location not valid"
            alt = self.alt_from_msl(t.z) if frame == "msl" else self.alt_from_home(t.z)
            return o.to_ne(lat, lon), alt
        if not all(map(math.isfinite, (t.x, t.y, t.z))):
            return "position not a number"
        if t.frame == mav.MAV_FRAME_LOCAL_NED:
            return (t.x, t.y), self.alt_from_msl(o.alt_msl_m - t.z)
        dx, dy = self._body_to_ne(t.x, t.y) if t.frame in BODY_FRAMES else (t.x, t.y)
        p = self.est.pos_ne_m
        return (p[0] + dx, p[1] + dy), self.alt_m - t.z

    # ---- SET_ATTITUDE_TARGET -----------------------------------------------------------------
    def set_attitude_target(self, t) -> None:
        if self.mode.number != CopterMode.GUIDED:
            self.setpoints_ignored += 1
            return
        use = setpoints.attitude_mask_use(t.type_mask, t.q_wxyz)
        rates = tuple(float(c) for c in t.body_rates_rad_s) if use.use_rates else (0.0,) * 3
        if not use.ok or not all(map(math.isfinite, rates)) or not math.isfinite(t.thrust):
            self.setpoints_ignored += 1
            self.mode.init(self)
            return
        euler = quat_to_euler(t.q_wxyz) if use.use_attitude else None
        if self.mode.thrust_as_thrust:
            self.mode.set_angle(self, euler, rates, max(-1.0, min(1.0, t.thrust)), True)
            return
        th = max(0.0, min(1.0, t.thrust))
        if th > 0.5:
            climb = (th - 0.5) * 2.0 * self.cfg.wp.up_m_s
        elif th < 0.5:
            climb = (th - 0.5) * 2.0 * self.cfg.wp.dn_m_s
        else:
            climb = 0.0
        self.mode.set_angle(self, euler, rates, climb, False)

    # ---- commands ----------------------------------------------------------------------------
    def reposition(self, lat_e7, lon_e7, alt_m, frame, speed_m_s, yaw_deg, change_mode=True):
        guided = self.mode.number == CopterMode.GUIDED
        if not guided and not change_mode:
            return DENIED, None
        relative = frame in (mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                             mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
        if (lat_e7 == 0 and lon_e7 == 0) or (relative and alt_m == 0.0):
            return DENIED, None             # ArduCopter's Location::sanitize changed it
        if self.est.origin is None:
            return FAILED, "Reposition: no position estimate"
        ne = self.est.origin.to_ne(lat_e7, lon_e7)
        alt = self.alt_from_home(alt_m) if relative else self.alt_from_msl(alt_m)
        if self._outside_fence(ne, alt):
            return FAILED, None
        if not guided:
            reason = self._change_mode(CopterMode.GUIDED)
            if reason:
                return FAILED, reason
        self.mode.set_destination(self, ne, alt)
        return ACCEPTED, None

    def change_speed(self, speed_m_s: float, speed_type: float):
        if not speed_m_s > 0.0:
            return FAILED, None
        kind = "descent" if speed_type > 2.9 else "climb" if speed_type > 1.9 else "ground"
        if self.mode.number == CopterMode.GUIDED:
            return (ACCEPTED if self.mode.set_speed(self, kind, float(speed_m_s)) else FAILED,
                    None)
        if self.mode.number == CopterMode.AUTO and kind == "ground":
            self.speed_override_m_s = float(speed_m_s)
            self.wp.sp = self._wp_speeds(self.speed_override_m_s)
            return ACCEPTED, None
        return FAILED, None

    def condition_yaw(self, angle_deg: float, rate_deg_s: float, direction: int,
                      relative: bool):
        if self.mode.number == CopterMode.GUIDED:
            self.mode.condition_yaw(self, angle_deg, rate_deg_s, direction, relative)
        return ACCEPTED, None
