"""The scenario's setpoints, forwarded to a foreign autopilot as a companion computer would.

Our FC reads SETPOINT records (roll, pitch, yaw, altitude) from the ring; ArduCopter and
PX4 take the same commands over MAVLink. A forwarder turns the scenario's profile
(bridge/setpoints.py, compiled the same way the Simulator compiles it) into
SET_ATTITUDE_TARGET messages, in the physics thread, once per physics step, so every
command reaches the autopilot at the physics step it is due (in lockstep the autopilot waits
for our reply before it runs its next frame, and the bytes written before that reply are in
its socket when it does).

Clock: the profile's time 0 is the take-off command (`start_at`), the same origin as the
run log (log_sink.py), so S4's doublets fall at the same flight times as for our FC, whose
AutoFlight takes off at 0.

Phases:
- take-off: the autopilot climbs on its own take-off; nothing is sent (an attitude target
  would end the climb).
- forwarding, from the first of: the autopilot reports an altitude within ENGAGE_MARGIN_M
  of the commanded one; the profile commands anything else than its first value;
  ENGAGE_AFTER_S of flight time. From then on every change is sent at once and the current
  command is resent every 1/`resend_hz` of sim time (each autopilot drops a target that
  stops coming: ArduCopter's GUID_TIMEOUT, PX4's COM_OF_LOSS_T).

The message: quaternion [w, x, y, z] of the commanded roll, pitch, yaw; type_mask = the
three body-rate IGNORE bits (the rates must be all given or all ignored); thrust is never
ignored, and what it means is each autopilot's own: `thrust_for` (ardupilot/setpoints.py:
a climb rate; px4/setpoints.py: collective thrust from an altitude loop).

The commanded attitude the run log writes (att_target_rad, which tools/benchmark/metrics.py
compares with the true attitude) is `command`: what we asked for, exact in physics time.
"""

from __future__ import annotations

from silbridge.bridge.frames import quat_from_euler
from silbridge.bridge.setpoints import SetpointProgram
from silbridge.shm.records import NS_PER_S as _NS

ENGAGE_MARGIN_M = 0.5       # take-off counts as done this close to the commanded altitude
ENGAGE_AFTER_S = 10.0       # forward anyway after this long (a take-off that never reports)
# ATTITUDE_TARGET_TYPEMASK_BODY_{ROLL,PITCH,YAW}_RATE_IGNORE (bits 0, 1, 2).
TYPE_MASK_RATES_IGNORED = 0b0000_0111


class SetpointForwarder:
    """Scenario profile -> SET_ATTITUDE_TARGET, driven by the physics steps.

    send(time_boot_ms, q_wxyz, thrust, type_mask) -> bool: writes the message (the driver's
    send_attitude_target); False when the link is not up yet.
    reported_alt_m() -> float | None: the autopilot's altitude above home.
    Subclasses set `resend_hz` and define thrust_for(); `_before_send` is their hook for
    what goes with each message.
    """

    resend_hz: float

    def __init__(self, scenario, dt_ns: int, heading_rad: float, *, send, reported_alt_m,
                 thrust: float):
        program = SetpointProgram(scenario, dt_ns, heading_rad)
        self._events = program.events       # (step, roll, pitch, yaw, alt, mask), step >= 1
        self._dt_ns = dt_ns
        self._send = send
        self._reported_alt_m = reported_alt_m
        self._resend_ns = int(round(_NS / self.resend_hz))
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
        self.last_thrust = thrust           # the thrust field last sent (logged per step)
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

    def _before_send(self) -> None:
        """What goes with each message (PX4: ask for OFFBOARD); nothing by default."""

    def thrust_for(self, alt_cmd: float, roll: float, pitch: float, flight_ns: int) -> float:
        """The message's thrust field for this command, in the autopilot's meaning."""
        raise NotImplementedError

    def _send_now(self, flight_ns: int) -> bool:
        self._before_send()
        roll, pitch, yaw, alt = self.command
        thrust = self.thrust_for(alt, roll, pitch, flight_ns)
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
                "resend_hz": self.resend_hz}
