"""The scenario's setpoints, forwarded to PX4 in OFFBOARD as attitude targets with thrust.

The profile, clock and engagement every autopilot shares (tools/autopilots/common/setpoints.py:
time 0 = the take-off command; forwarding starts once PX4 reports the commanded altitude,
the profile moves, or 10 s have passed), with PX4's own two parts:

- Thrust. In OFFBOARD attitude control PX4 takes SET_ATTITUDE_TARGET's thrust as the
  normalised collective thrust (0..1), with no altitude control of its own. A companion
  computer closes the altitude loop: thrust = (hover + kp e + kd (climb_cmd - climb) + ki
  integral e) / (cos roll cos pitch), on PX4's own altitude estimate (LOCAL_POSITION_NED),
  with hover = MPC_THR_HOVER (set from our vehicle, tools/autopilots/px4/sitl.py). The integral runs
  only while PX4 is in OFFBOARD (before that PX4 ignores the thrust).
- Mode. Once forwarding starts the driver is asked to switch PX4 to OFFBOARD; PX4 only
  accepts while targets stream, so they are sent at SEND_HZ (> 2 Hz, COM_OF_LOSS_T 1 s).
"""

from __future__ import annotations

import math

from silbridge.tools.autopilots.common.setpoints import SetpointForwarder
from silbridge.shm.records import NS_PER_S as _NS

SEND_HZ = 50.0
ALT_KP = 0.03          # thrust per metre (hover 0.35: 1 unit of thrust ~ 28 m/s^2)
ALT_KD = 0.09          # thrust per m/s of climb-rate error
ALT_KI = 0.02          # thrust per metre-second
CLIMB_GAIN_1_S = 1.0   # climb-rate command per metre of altitude error, limited below
CLIMB_MAX_M_S = 1.5
THRUST_MIN, THRUST_MAX = 0.05, 0.9


class Px4SetpointForwarder(SetpointForwarder):
    """send: Px4Driver.send_attitude_target; driver: its altitude, climb and mode."""

    resend_hz = SEND_HZ

    def __init__(self, scenario, dt_ns: int, heading_rad: float, *, send, driver,
                 hover_thrust: float):
        super().__init__(scenario, dt_ns, heading_rad, send=send,
                         reported_alt_m=lambda: driver.alt_m, thrust=hover_thrust)
        self.driver = driver
        self.hover = hover_thrust
        self.integral = 0.0
        self._last_ns: int | None = None

    def _before_send(self) -> None:
        self.driver.want_offboard()

    def thrust_for(self, alt_cmd: float, roll: float, pitch: float, flight_ns: int) -> float:
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
