"""The radio failsafe as ArduCopter 4.6 (ArduCopter/radio.cpp read_radio, events.cpp
failsafe_radio_on_event): pilot input lost for RC_FS_TIMEOUT, or the throttle channel below
FS_THR_VALUE, while armed and flying -> "Radio Failsafe" (WARNING) and FS_THR_ENABLE's
action (rc_input.py), in every mode, unless FS_OPTIONS lets this one go on (fs_options.py:
bit 0 AUTO, bit 2 GUIDED, bit 3 a landing; by default none). Latched until input is back
("Radio Failsafe Cleared"); the mode stays what the failsafe made it.

Our pilot input is a ground station's MANUAL_CONTROL / RC override, aged on the wall clock as
the link's own (pilot.py). When it stops, only a mode the pilot flies (fs_options.PILOT_MODES)
takes the failsafe (a throttle below FS_THR_VALUE in it still acts in any mode): in
ArduCopter SITL an override that stops hands back to its simulated receiver, which never
fails, so a MAVSDK script that sent manual control and then flies AUTO or GUIDED must not
be sent home. An injected receiver loss (SIM_RC_FAIL, MAV_CMD_INJECT_FAILURE,
a scenario's rc unit) is timed on sim time from the step that first sees it, as ArduCopter
SITL's SIM_RC_FAIL, whose RC_FS_TIMEOUT runs on its simulated clock: the failsafe then
comes RC_FS_TIMEOUT of sim time after the loss at any --speed.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode
from silbridge.shm.records import NS_PER_S

from .fs_options import PILOT_MODES, continuing


class RadioFailsafe:
    def __init__(self):
        self.active = False
        self._lost_ns: int | None = None     # sim time the injected loss was first seen

    def age_s(self, v) -> float | None:
        """Seconds without pilot input: sim time during an injected loss, else the link's."""
        if v.pilot.lost:
            if self._lost_ns is None:
                self._lost_ns = v.sim_ns
            return (v.sim_ns - self._lost_ns) / NS_PER_S
        self._lost_ns = None
        return v.pilot.age_s()

    def check(self, v) -> None:
        pilot = v.pilot
        age = self.age_s(v)
        thr_us = pilot.throttle_pwm()
        low = not pilot.lost and thr_us is not None and thr_us < pilot.rc.fs_thr_value_us
        if age is None or (age <= v.cfg.rc_fs_timeout_s and not low):
            if self.active:
                v.statustext(mav.MAV_SEVERITY_WARNING, "Radio Failsafe Cleared")
            self.active = False
            return
        if self.active:
            return
        self.active = True
        action = pilot.rc.fs_thr_action()
        if action is None or not (v.armed and v.airborne):
            return
        if not pilot.lost and not low and v.mode.number not in PILOT_MODES:
            return          # a ground station's sticks went quiet, not a receiver (above)
        going_on = continuing("Radio", v.mode.number, int(v.store.host("FS_OPTIONS")))
        v.statustext(mav.MAV_SEVERITY_WARNING,
                     "Radio Failsafe" + (f" - {going_on}" if going_on else ""))
        if going_on:
            return
        if action == CopterMode.RTL and not (v.home_set and v.position_ok()):
            action = CopterMode.LAND
        if v.mode.number != action:
            v.set_mode_internal(action, "radio failsafe")
