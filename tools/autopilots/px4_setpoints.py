"""The scenario's setpoints, forwarded to PX4 in OFFBOARD as attitude targets with thrust.

The same profile, clock and engagement as for ArduCopter (tools/autopilots/ardupilot_setpoints.py's
SetpointForwarder: time 0 = the take-off command; forwarding starts once PX4 reports the
commanded altitude, the profile moves, or 10 s have passed), with two PX4 differences:

- Thrust. In OFFBOARD attitude control PX4 takes SET_ATTITUDE_TARGET's thrust as the
  normalised collective thrust (0..1), with no altitude control of its own. A companion
  computer closes the altitude loop: thrust = (hover + kp e + kd (climb_cmd - climb) + ki
  integral e) / (cos roll cos pitch), on PX4's own altitude estimate (LOCAL_POSITION_NED),
  with hover = MPC_THR_HOVER (set from our vehicle, tools/autopilots/sitl_px4.py). The integral runs
  only while PX4 is in OFFBOARD (before that PX4 ignores the thrust).
- Mode. Once forwarding starts the driver is asked to switch PX4 to OFFBOARD; PX4 only
  accepts while targets stream, so they are sent at SEND_HZ (> 2 Hz, COM_OF_LOSS_T 1 s).
"""

from __future__ import annotations

import math

from silbridge.bridge.frames import quat_from_euler

from silbridge.tools.autopilots.ardupilot_setpoints import TYPE_MASK_RATES_IGNORED, SetpointForwarder

SEND_HZ = 50.0
ALT_KP = 0.03          # thrust per metre (hover 0.35: 1 unit of thrust ~ 28 m/s^2)
ALT_KD = 0.09          # thrust per m/s of climb-rate error
ALT_KI = 0.02          # thrust per metre-second
CLIMB_GAIN_1_S = 1.0   # climb-rate command per metre of altitude error, limited below
CLIMB_MAX_M_S = 1.5
THRUST_MIN, THRUST_MAX = 0.05, 0.9
_NS = 1_000_000_000


class Px4SetpointForwarder(SetpointForwarder):
    """send: Px4Driver.send_attitude_target; driver: its altitude, climb and mode."""

    def __init__(self, scenario, dt_ns: int, heading_rad: float, *, send, driver,
                 hover_thrust: float):
        super().__init__(scenario, dt_ns, heading_rad, send=send,
                         reported_alt_m=lambda: driver.alt_m)
        self._resend_ns = int(round(_NS / SEND_HZ))
        self.driver = driver
        self.hover = hover_thrust
        self.integral = 0.0
        self._last_ns: int | None = None
        self.last_thrust = hover_thrust

    def _send_now(self, flight_ns: int) -> bool:
        self.driver.want_offboard()
        roll, pitch, yaw, alt = self.command
        thrust = self.thrust(alt, roll, pitch, flight_ns)
        q = quat_from_euler(roll, pitch, yaw)
        ok = self._send(max(flight_ns, 0) // 1_000_000, q, thrust, TYPE_MASK_RATES_IGNORED)
        if ok:
            self.sent += 1
            self.last_thrust = thrust
        else:
            self.refused += 1
        return ok

    def thrust(self, alt_cmd: float, roll: float, pitch: float, flight_ns: int) -> float:
        d = self.driver
        alt, climb = d.alt_m, d.climb_m_s
        dt = 0.0 if self._last_ns is None else (flight_ns - self._last_ns) / _NS
        self._last_ns = flight_ns
        if alt is None or climb is None:
            return self.hover
        e = alt_cmd - alt
        climb_cmd = max(-CLIMB_MAX_M_S, min(CLIMB_MAX_M_S, CLIMB_GAIN_1_S * e))
        if d.offboard and 0.0 < dt < 1.0:
            self.integral = max(-5.0, min(5.0, self.integral + e * dt))
        t = self.hover + ALT_KP * e + ALT_KD * (climb_cmd - climb) + ALT_KI * self.integral
        tilt = max(0.5, math.cos(roll) * math.cos(pitch))
        return max(THRUST_MIN, min(THRUST_MAX, t / tilt))
