"""GcsCommands: what a GCS may ask of the vehicle (mavlink.vehicle_api.VehicleCommands).

A mixin of fc_sil/vehicle.py's Vehicle. GcsServer.service() runs these on the vehicle
thread between two control-loop batches, so they change state without locks; each returns
(MAV_RESULT, reason or None) worded as ArduCopter's STATUSTEXT, setpoint methods return
nothing. Conventions (ArduCopter 4.5): arming runs the pre-arm checks unless forced; take-off
needs GUIDED, armed and landed. What steers GUIDED (SET_POSITION_TARGET_*, SET_ATTITUDE_TARGET,
DO_REPOSITION, DO_CHANGE_SPEED, CONDITION_YAW) is in guided_commands.py.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode

from .guided_commands import GuidedCommands
from .prearm import prearm_failure

ACCEPTED, FAILED, DENIED = mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_FAILED, mav.MAV_RESULT_DENIED


class GcsCommands(GuidedCommands):

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

    def inject_failure(self, failure_unit: int, failure_type: int, instance: int):
        """MAV_CMD_INJECT_FAILURE as PX4 1.15 answers it (fault_inject.py, fault_map.py)."""
        return self.faults.inject_failure(failure_unit, failure_type, instance,
                                          self.store.host("SYS_FAILURE_EN") == 1,
                                          self.store.host("SB_FI_GCS_S"))

    def manual_control(self, x, y, z, r, buttons) -> None:
        self.pilot.manual_control(x, y, z, r)

    def rc_override(self, channels_us) -> None:
        self.pilot.rc_override(channels_us)
