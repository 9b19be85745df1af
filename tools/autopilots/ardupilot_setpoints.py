"""The scenario's setpoints, forwarded to ArduCopter in GUIDED as a companion computer would.

Our FC reads SETPOINT records (roll, pitch, yaw, altitude) from the ring;
ArduCopter takes the same commands over MAVLink. This object turns the
scenario's profile (bridge/setpoints.py, compiled the same way the Simulator
compiles it) into SET_ATTITUDE_TARGET messages, in the physics thread, once
per servo packet, so every command reaches ArduCopter at the physics step it
is due (SITL waits for our reply before it runs its next frame, and the TCP
bytes written before that reply are in its socket when it does).

Clock: the profile's time 0 is the take-off command (`start_at`), the same
origin as the run log, so S4's doublets fall at the same flight times as for
our FC, whose AutoFlight takes off at 0.

Phases:
- take-off: ArduCopter climbs in GUIDED's take-off submode (MAV_CMD_NAV_TAKEOFF
  from tools/autopilots/sitl_ardupilot.py); nothing is sent, a SET_ATTITUDE_TARGET would
  end the climb.
- forwarding, from the first of: ArduCopter reports (GLOBAL_POSITION_INT
  relative_alt) an altitude within ENGAGE_MARGIN_M of the commanded one; the
  profile commands anything else than its first value; ENGAGE_AFTER_S of flight
  time. From then on every change is sent at once and the current command is
  resent every 1/RESEND_HZ of sim time: ArduCopter drops an angle target that
  is GUID_TIMEOUT old (3 s by default, ArduCopter/Parameters.cpp) back to level.

The message (ArduCopter/GCS_Mavlink.cpp, handle_message_set_attitude_target):
quaternion [w, x, y, z] of the commanded roll, pitch, yaw (unit length within
1e-3 or it is refused); type_mask = the three body-rate IGNORE bits (the rates
must be all given or all ignored); thrust is NOT ignored (ignoring it makes
ArduCopter leave angle control). With the default GUID_OPTIONS (bit 3,
SetAttitudeTarget_ThrustAsThrust, clear) thrust is a climb-rate command:
exactly 0.5 = climb rate 0 (hold the altitude), 0.5..1 = up to WPNAV_SPEED_UP,
0..0.5 = down to WPNAV_SPEED_DN. Altitude setpoints are flown through that
field: climb = ALT_GAIN_1_S x (commanded - reported altitude) outside a
ALT_DEADBAND_M band, else exactly 0.5. (SET_POSITION_TARGET_LOCAL_NED would
switch GUIDED to its position controller and drop the attitude target.)

The commanded attitude the run log writes (att_target_rad, which
tools/benchmark/metrics.py compares with the true attitude) is `command`: what we asked
ArduCopter for, exact in physics time. ArduCopter's own shaped target
(ATTITUDE_TARGET) is logged next to it (tools/autopilots/ardupilot_log.py).
"""

from __future__ import annotations

from silbridge.bridge.frames import quat_from_euler
from silbridge.bridge.setpoints import SetpointProgram

RESEND_HZ = 20.0            # >= 10 Hz asked; ArduCopter's GUID_TIMEOUT is 3 s by default
ENGAGE_MARGIN_M = 0.5       # take-off counts as done this close to the commanded altitude
ENGAGE_AFTER_S = 10.0       # forward anyway after this long (a take-off that never reports)
ALT_GAIN_1_S = 0.5          # climb-rate command per metre of altitude error [1/s]
ALT_DEADBAND_M = 0.3        # inside it thrust is exactly 0.5: ArduCopter holds its altitude
SPEED_UP_M_S = 2.5          # WPNAV_SPEED_UP default, 250 cm/s: thrust 1.0
SPEED_DN_M_S = 1.5          # WPNAV_SPEED_DN default, 150 cm/s: thrust 0.0
# ATTITUDE_TARGET_TYPEMASK_BODY_{ROLL,PITCH,YAW}_RATE_IGNORE (bits 0, 1, 2).
TYPE_MASK_RATES_IGNORED = 0b0000_0111
_NS = 1_000_000_000


def thrust_for_climb(climb_m_s: float) -> float:
    """ArduCopter's thrust field (GUID_OPTIONS bit 3 clear) for a climb-rate command [m/s]."""
    if climb_m_s > 0.0:
        return min(1.0, 0.5 + 0.5 * climb_m_s / SPEED_UP_M_S)
    if climb_m_s < 0.0:
        return max(0.0, 0.5 + 0.5 * climb_m_s / SPEED_DN_M_S)
    return 0.5


class SetpointForwarder:
    """Scenario profile -> SET_ATTITUDE_TARGET, driven by the physics steps.

    send(time_boot_ms, q_wxyz, thrust, type_mask) -> bool: writes the message
    (MavlinkDriver.send_attitude_target); False when the link is not up yet.
    reported_alt_m() -> float | None: ArduCopter's altitude above home.
    """

    def __init__(self, scenario, dt_ns: int, heading_rad: float, *, send, reported_alt_m):
        program = SetpointProgram(scenario, dt_ns, heading_rad)
        self._events = program.events       # (step, roll, pitch, yaw, alt, mask), step >= 1
        self._dt_ns = dt_ns
        self._send = send
        self._reported_alt_m = reported_alt_m
        self._resend_ns = int(round(_NS / RESEND_HZ))
        first = self._events[0] if self._events else (1, 0.0, 0.0, heading_rad,
                                                      scenario.takeoff_alt_m, 0)
        self.command = tuple(first[1:5])    # (roll_rad, pitch_rad, yaw_rad, alt_m)
        self._initial = self.command
        self._next = 1 if self._events else 0
        self.t0_ns: int | None = None
        self.engaged_ns: int | None = None  # flight time forwarding began
        self.engaged_by = ""
        self.sent = 0
        self.refused = 0                    # send() returned False (link not up)
        self.last_thrust = 0.5
        self._next_send_ns = 0
        self._dirty = False

    def start_at(self, sim_ns: int) -> None:
        """The take-off command's physics time: the profile's time 0."""
        if self.t0_ns is None:
            self.t0_ns = int(sim_ns)

    @property
    def engaged(self) -> bool:
        return self.engaged_ns is not None

    def step(self, sim_ns: int) -> None:
        """Once per physics step (sim_ns: the time this step's PWM took effect)."""
        if self.t0_ns is None:
            return
        flight_ns = sim_ns - self.t0_ns
        # The profile's value after this step: events whose step k is due by its end.
        events = self._events
        due_ns = flight_ns + self._dt_ns
        while self._next < len(events) and events[self._next][0] * self._dt_ns <= due_ns:
            self.command = tuple(events[self._next][1:5])
            self._next += 1
            self._dirty = True
        if self.engaged_ns is None:
            reason = self._engage_reason(flight_ns)
            if not reason:
                return
            self.engaged_ns, self.engaged_by = flight_ns, reason
            self._dirty = True
        if self._dirty or flight_ns >= self._next_send_ns:
            if self._send_now(flight_ns):
                self._dirty = False
                self._next_send_ns = flight_ns + self._resend_ns

    def _engage_reason(self, flight_ns: int) -> str:
        if self.command != self._initial:
            return "profile"
        alt = self._reported_alt_m()
        if alt is not None and abs(alt - self.command[3]) <= ENGAGE_MARGIN_M:
            return "altitude"
        if flight_ns >= ENGAGE_AFTER_S * _NS:
            return "timeout"
        return ""

    def _send_now(self, flight_ns: int) -> bool:
        roll, pitch, yaw, alt = self.command
        climb = 0.0
        reported = self._reported_alt_m()
        if reported is not None and abs(alt - reported) > ALT_DEADBAND_M:
            climb = ALT_GAIN_1_S * (alt - reported)
        thrust = thrust_for_climb(climb)
        q = quat_from_euler(roll, pitch, yaw)
        ok = self._send(max(flight_ns, 0) // 1_000_000, q, thrust, TYPE_MASK_RATES_IGNORED)
        if ok:
            self.sent += 1
            self.last_thrust = thrust
        else:
            self.refused += 1
        return ok

    def summary(self) -> dict:
        return {"setpoints_sent": self.sent, "setpoints_refused": self.refused,
                "forwarding_from_s": (None if self.engaged_ns is None
                                      else self.engaged_ns / _NS),
                "forwarding_started_by": self.engaged_by,
                "resend_hz": RESEND_HZ}
