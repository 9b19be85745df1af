"""GcsCommands: what a GCS may ask of the vehicle (mavlink.vehicle_api.VehicleCommands).

A mixin of fc_sil/vehicle.py's Vehicle. GcsServer.service() runs these on the vehicle
thread between two control-loop batches, so they change state without locks; each returns
(MAV_RESULT, reason or None) worded as ArduCopter's STATUSTEXT, setpoint methods return
nothing. Conventions (ArduCopter 4.5): arming runs the pre-arm checks unless forced; take-off
needs GUIDED, armed and landed; GUIDED targets are ignored while landed; SET_POSITION_TARGET
type_mask as in the common dialect (position, velocity, yaw, yaw-rate ignore bits); thrust in
SET_ATTITUDE_TARGET is a climb rate (0.5 = hold), as ArduCopter without GUID_OPTIONS bit 3.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode

from .prearm import prearm_failure

ACCEPTED, FAILED, DENIED = mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_FAILED, mav.MAV_RESULT_DENIED
TYPE_MASK_POS = 0x7
TYPE_MASK_VEL = 0x38
TYPE_MASK_YAW = 0x400
TYPE_MASK_YAW_RATE = 0x800
ATT_MASK_ATTITUDE = 0x80


class GcsCommands:

    def arm(self, force: bool):
        if self.armed:
            return ACCEPTED, None
        if not force and self.cfg.arming_check:
            reason = prearm_failure(self)
            if reason:
                return FAILED, reason
        if self.est.valid:
            self._set_home(announce=True)
        self.reset_vertical()
        self.reset_horizontal()
        self.alt_target_m = self.alt_hold_m = 0.0
        self.yaw_target_rad = self.yaw_rad
        self.yaw_rate_cmd = None
        self.core.set_altitude_target(0.0)
        if self.mode.manual_throttle:
            self.core.set_throttle(0.0)
        self.core.set_attitude_target(0.0, 0.0, yaw_rad=self.yaw_rad)
        self.core.arm()
        self.armed = True
        self._landed_since_ns = self.sim_ns
        self._event("armed")
        return ACCEPTED, None

    def disarm(self, force: bool):
        if not self.armed:
            return ACCEPTED, None
        if self.airborne and not force:
            return DENIED, "Disarm: vehicle is flying (force to disarm in flight)"
        self._disarm(None)
        return ACCEPTED, None

    def set_mode(self, custom_mode: int):
        if custom_mode == self.mode.number:
            return ACCEPTED, None
        reason = self._change_mode(custom_mode)
        return (FAILED, reason) if reason else (ACCEPTED, None)

    def takeoff(self, alt_m: float):
        if not self.armed:
            return FAILED, "Takeoff: vehicle not armed"
        if self.mode.number != CopterMode.GUIDED:
            return FAILED, f"Takeoff: not supported in {self.mode.name}, use GUIDED"
        if self.airborne:
            return FAILED, "Takeoff: already flying"
        if not self.position_ok():
            return FAILED, "Takeoff: need a position estimate (GPS)"
        # above home, as ArduCopter reads it (home is the take-off point unless a GCS moved it)
        self.mode.start_takeoff(self, self.alt_from_home(max(float(alt_m),
                                                             self.cfg.takeoff_min_m)))
        self._landed_since_ns = None
        return ACCEPTED, None

    def land(self):
        return self.set_mode(CopterMode.LAND)

    def rtl(self):
        return self.set_mode(CopterMode.RTL)

    def mission_start(self, first: int, last: int):
        if 0 < first < len(self.mission.items):
            self.mission.current = first
        if self.mode.number == CopterMode.AUTO:
            # MISSION_START in AUTO (MAVSDK sends it after the mode change): (re)start
            reason = self.mission.start(self, first if first > 0 else None)
        else:
            reason = self._change_mode(CopterMode.AUTO)
        return (FAILED, reason) if reason else (ACCEPTED, None)

    def reposition(self, lat_e7, lon_e7, alt_m, frame, speed_m_s, yaw_deg):
        if not self.armed or not self.airborne:
            return DENIED, "Reposition: take off first"
        if self.est.origin is None:
            return FAILED, "Reposition: no position estimate"
        if self.mode.number != CopterMode.GUIDED:
            reason = self._change_mode(CopterMode.GUIDED)
            if reason:
                return FAILED, reason
        ne = self.est.origin.to_ne(lat_e7, lon_e7)
        alt = self.alt_from_home(alt_m) if frame in (mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                                     mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT) \
            else self.alt_from_msl(alt_m)
        speed = speed_m_s if math.isfinite(speed_m_s) and speed_m_s > 0 else None
        if self._outside_fence(ne, alt):
            return FAILED, "Reposition: destination outside fence"
        self.mode.go_to(self, ne, alt, speed)
        if math.isfinite(yaw_deg):
            self.yaw_target_rad = math.radians(yaw_deg)
        else:
            self.face_track(rtl=False)
        return ACCEPTED, None

    def set_home(self, lat_e7, lon_e7, alt_m, relative):
        if self.est.origin is None or not self.est.valid:
            return FAILED, "Set home: no position estimate"
        if lat_e7 is None:              # here, at the vehicle's altitude
            lat_e7, lon_e7 = self.est.latlon_e7()
            alt_msl = self.alt_datum_msl_m + self.alt_m
        else:
            alt_msl = self.home_alt_msl_m + alt_m if relative else alt_m
        self.move_home(lat_e7, lon_e7, alt_msl)
        return ACCEPTED, None

    def change_speed(self, speed_m_s: float, speed_type: int):
        if speed_m_s > 0:
            self.speed_override_m_s = float(speed_m_s)
            self.wp.sp = self._wp_speeds(self.speed_override_m_s)
        elif speed_m_s not in (-1.0, -2.0):
            return DENIED, "Change speed: speed must be > 0 (or -1 for no change)"
        return ACCEPTED, None

    def mission_set_current(self, seq: int):
        reason = self.mission.set_current(seq, self)
        return (DENIED, reason) if reason else (ACCEPTED, None)

    def mission_updated(self, items) -> None:
        self.mission.set_items(items, self)
        if self.mission_file:
            from silbridge.mavlink.errors import MissionFileError
            from silbridge.mavlink.gcs.wpl import save_wpl
            try:
                save_wpl(self.mission_file, items)
            except (MissionFileError, OSError) as exc:
                self.statustext(mav.MAV_SEVERITY_ERROR, f"Mission save failed: {exc}"[:150])

    def geo_updated(self, mission_type: int, items) -> None:
        """A new fence or rally list from the GCS (already validated by the server)."""
        if mission_type == mav.MAV_MISSION_TYPE_FENCE:
            self.fence.set_items(items)
        else:
            self.rally.set_items(items)
        if self.mission_file:
            from silbridge.mavlink.errors import MissionFileError
            from silbridge.mavlink.gcs.wpl import geo_file, save_wpl
            try:
                save_wpl(geo_file(self.mission_file, mission_type), items)
            except (MissionFileError, OSError) as exc:
                self.statustext(mav.MAV_SEVERITY_ERROR, f"Fence/rally save failed: {exc}"[:150])

    def _outside_fence(self, ne, alt_m: float) -> bool:
        return not self.fence.destination_ok(self, ne, alt_m)

    def set_position_target(self, t) -> None:
        if self.mode.number != CopterMode.GUIDED or not self.armed or not self.airborne \
                or self.est.origin is None:
            self.setpoints_ignored += 1     # ArduCopter: take off first
            return
        mask = t.type_mask
        use_pos = (mask & TYPE_MASK_POS) != TYPE_MASK_POS
        use_vel = (mask & TYPE_MASK_VEL) != TYPE_MASK_VEL
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        vel = tuple(t.vel_ned_m_s)
        if t.is_global:
            ne = self.est.origin.to_ne(int(t.x), int(t.y))
            rel = t.frame in (mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                              mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                              mav.MAV_FRAME_GLOBAL_TERRAIN_ALT,
                              mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT)
            alt = self.alt_from_home(t.z) if rel else self.alt_from_msl(t.z)
        elif t.frame == mav.MAV_FRAME_LOCAL_NED:
            ne = (t.x, t.y)
            alt = self.alt_from_msl(self.est.origin.alt_msl_m - t.z)
        else:
            dx, dy = t.x, t.y
            if t.frame in (mav.MAV_FRAME_BODY_NED, mav.MAV_FRAME_BODY_OFFSET_NED):
                dx, dy = dx * c - dy * s, dx * s + dy * c
                vel = (vel[0] * c - vel[1] * s, vel[0] * s + vel[1] * c, vel[2])
            ne = (self.est.pos_ne_m[0] + dx, self.est.pos_ne_m[1] + dy)
            alt = self.alt_m - t.z
        if not (mask & TYPE_MASK_YAW) and math.isfinite(t.yaw_rad):
            self.yaw_target_rad = t.yaw_rad
            self.yaw_rate_cmd = None
        if use_pos and all(map(math.isfinite, (*ne, alt))):
            if self._outside_fence(ne, alt):
                self.setpoints_ignored += 1     # ArduCopter: GUIDED refuses it
                return
            self.mode.go_to(self, ne, alt)
            if mask & TYPE_MASK_YAW:
                self.face_track(rtl=False)
        elif use_vel and all(map(math.isfinite, vel)):
            self.mode.set_velocity(self, vel[:2], -vel[2])
        else:
            self.setpoints_ignored += 1

    def set_attitude_target(self, t) -> None:
        if self.mode.number != CopterMode.GUIDED or not self.armed or not self.airborne:
            self.setpoints_ignored += 1
            return
        if t.type_mask & ATT_MASK_ATTITUDE or not all(map(math.isfinite, t.q_wxyz)):
            self.setpoints_ignored += 1
            return
        w, x, y, z = t.q_wxyz
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        # ArduCopter (GUID_OPTIONS bit 3 clear): thrust 0.5 = hold, 0/1 = full descent/climb
        th = min(1.0, max(0.0, t.thrust)) if math.isfinite(t.thrust) else 0.5
        climb = (th - 0.5) * 2.0 * (self.cfg.wp.up_m_s if th >= 0.5 else self.cfg.wp.dn_m_s)
        self.mode.set_attitude(self, roll, pitch, yaw, climb)

    def manual_control(self, x, y, z, r, buttons) -> None:
        self.pilot.manual_control(x, y, z, r)

    def rc_override(self, channels_us) -> None:
        self.pilot.rc_override(channels_us)
