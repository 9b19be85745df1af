"""The Simulator as PX4's MAVLink simulator: one HIL_ACTUATOR_CONTROLS -> one PX4 step.

No sockets here (bridge/autopilots/px4/server.py owns the link), so tests drive the rules directly.

A PX4 step is 1/STEP_HZ (4 ms at PX4's 250 Hz IMU_INTEG_RATE) = `substeps` physics steps of
the Simulator (1 ms each) under the same motor outputs (zero-order hold); the step's frames
(hil_messages.py) carry time_usec = the sim time at its end, which becomes PX4's clock.

Lockstep accounting, per reply (HIL_ACTUATOR_CONTROLS): PX4 stamps it with its clock, which
the newest HIL_SENSOR set, so a reply whose time_usec is the last step sent answers that
step (`answered`); one older than that was sent before PX4 read the newest step (`stale`:
its motors are taken, no step is made). `unanswered` counts steps the server made without an
answer (a reply that never came within the stall limit; lockstep broken, reported).

The sink (the run log, tools/autopilots/common/log_sink.py's AutopilotLogSink serves both foreign
autopilots) gets step(records, pwm_record, sim) for every physics step and timing(...) once
per PX4 step: PWM time [sim ns], reply arrival, physics done, frames sent [monotonic wall ns]
and the wall interval since the previous reply. Both come after the step's frames are sent
(`sent`): in lockstep PX4 computes its reply meanwhile, so the bridge's critical path per
step is the physics and one write. The truth frame (HIL_STATE_QUATERNION, when PX4's
interval is due) rides in that write after HIL_SENSOR, the order PX4 always got it in: a
second write of its own woke PX4's link thread a second time per step, which cost more than
packing it before the write (~3 us; `python -m silbridge.tools.autopilots.px4.speed`,
2026-11-25, five runs each on otherwise the same code: 15.1-16.4x, mean 15.8x, with two
writes; 15.2-16.9x, mean 16.3x, with one).
"""

from __future__ import annotations

import time

import numpy as np

from silbridge.bridge.autopilots.px4.hil_messages import (
    MODE_ARMED,
    MOTORS,
    STEP_HZ,
    Px4SensorEncoder,
    StepAccumulator,
    controls_to_pwm_us,
)
from silbridge.bridge.link_faults import PWM_COMMAND, LinkFaults
from silbridge.shm.records import PWM_DTYPE, RECORD_DTYPE, Kind

from silbridge.bridge.errors import BridgeError

PWM_STOPPED_US = 1000


class Px4Physics:
    """Protocol state around a Simulator. make_sim: () -> Simulator; codec: pymavlink codec."""

    def __init__(self, make_sim, codec, *, sink=None, step_hz: int = STEP_HZ, origin=None):
        self.sim = make_sim()
        sim = self.sim
        if sim.physics_hz % step_hz:
            raise BridgeError(f"PX4 step rate {step_hz} Hz must divide the physics rate "
                              f"{sim.physics_hz} Hz")
        self.step_hz = step_hz
        self.substeps = sim.physics_hz // step_hz
        if origin is None:
            h = sim.scenario.home
            origin = (round(h.lat_deg * 1e7), round(h.lon_deg * 1e7), round(h.alt_m * 1000))
        self.encoder = Px4SensorEncoder(codec, origin)
        self.acc = StepAccumulator()
        self.sink = sink
        self.motors_us = [PWM_STOPPED_US] * MOTORS
        self.armed = False
        self.last_sent_us = -1
        self.steps = 0               # PX4 steps made
        self.freewheel_steps = 0     # before PX4's first reply
        self.replies = 0
        self.answered = 0
        self.stale = 0
        self.unanswered = 0
        self.lockstep_flag = None    # PX4's flags bit 0, from its replies
        self.first_reply_us = None   # sim time of PX4's first reply
        self._pwm = np.zeros(1, dtype=PWM_DTYPE)
        self._pwm["kind"] = Kind.PWM
        self._pwm["channel_count"] = MOTORS
        self._pwm_seq = 0
        # Faults of the link (bridge/link_faults.py): PX4's motors through the motor-output
        # direction, each physics step's sensor records through the sensor direction (truth
        # is never late: HIL_STATE_QUATERNION is PX4's ground truth, not a sensor).
        self.link = LinkFaults(sim.scenario.seed,
                               on_event=lambda ns, text: sim.events.append((ns, text)))
        sim.faults.register("link", self.link)
        self._motors_sent = list(self.motors_us)     # what reached the motors last
        self._held: list = []        # (sim_ns, records, rotor row) of the step's physics steps, for the log
        self._timing = None
        self._rx_ns = 0
        self._prev_rx_ns = 0

    @property
    def sim_us(self) -> int:
        return self.sim.sim_ns // 1000

    def on_controls(self, m, rx_wall_ns: int = 0) -> bool:
        """A HIL_ACTUATOR_CONTROLS: take its motors; True if it answers the last step sent."""
        self.replies += 1
        self._rx_ns = rx_wall_ns
        self.motors_us = controls_to_pwm_us(m.controls)
        self.armed = bool(m.mode & MODE_ARMED)
        self.lockstep_flag = bool(m.flags & 1)
        if self.first_reply_us is None:
            self.first_reply_us = self.last_sent_us
        if m.time_usec >= self.last_sent_us:
            self.answered += 1
            return True
        self.stale += 1
        return False

    def step(self, out: list, *, answered: bool = True, freewheel: bool = False) -> None:
        """One PX4 step under the current motors; its frames (HIL_GPS when a fix came,
        HIL_SENSOR, HIL_STATE_QUATERNION when due) are appended to out. Send them, then call
        `sent`."""
        sim = self.sim
        acc = self.acc
        acc.reset()
        applied_ns = sim.sim_ns
        link = self.link
        motors = self._motors_through_link() if link.pwm_engaged else self.motors_us
        self._motors_sent = motors
        held = self._held
        for _ in range(self.substeps):
            t_ns = sim.sim_ns
            recs = sim.step(motors)
            acc.add(link.sensors_out(recs, sim.sim_ns) if link.sensors_engaged else recs)
            if self.sink is not None:     # the Simulator reuses its buffer: keep a copy
                # The rotor speeds too: the sink writes these steps later, at `sent`.
                held.append((t_ns, recs.copy(), (sim.sim_ns, tuple(sim.rotor_rad_s()))))
        self.steps += 1
        if freewheel:
            self.freewheel_steps += 1
        elif not answered:
            self.unanswered += 1
        step_us = sim.sim_ns // 1000
        self.encoder.encode(acc, step_us, out)
        self.encoder.encode_truth(acc, step_us, out)
        self.last_sent_us = step_us
        self._timing = (applied_ns, self._rx_ns, time.monotonic_ns())

    def _motors_through_link(self) -> list:
        """PX4's newest motors through a faulty link: the newest command that arrives by now,
        else the last that arrived."""
        p = self._pwm
        p["pwm_us"][0, :MOTORS] = self.motors_us
        arrived = self.link.pwm_in(p.view(RECORD_DTYPE), self.sim.sim_ns)
        return (list(PWM_COMMAND.unpack_from(arrived)[:MOTORS]) if arrived is not None
                else self._motors_sent)

    def sent(self, tx_wall_ns: int) -> None:
        """The step's frames left at tx_wall_ns: what PX4 does not wait for happens now,
        while PX4 computes its reply: the run log's rows and the step's timing."""
        sink = self.sink
        t = self._timing
        if sink is None or t is None:
            return
        self._timing = None
        applied, rx, done = t
        p = self._pwm
        p["wall_ns"] = done
        p["pwm_us"][0, :MOTORS] = self.motors_us
        p["armed"] = 1 if self.armed else 0
        p["fc_step_seq"] = self.replies
        p["imu_sim_ns"] = applied
        for t_ns, recs, rotor in self._held:
            p["seq"] = self._pwm_seq    # one PWM record per physics step (held outputs)
            self._pwm_seq += 1
            p["sim_ns"] = t_ns
            sink.step(recs, p, self.sim, rotor=rotor)
        self._held.clear()
        period = rx - self._prev_rx_ns if self._prev_rx_ns and rx else 0
        if rx:
            self._prev_rx_ns = rx
        sink.timing(applied, rx, done, tx_wall_ns, period)

    def stats(self) -> dict:
        return {"px4_steps": self.steps, "freewheel_steps": self.freewheel_steps,
                "replies": self.replies, "answered": self.answered, "stale_replies": self.stale,
                "unanswered_steps": self.unanswered, "step_hz": self.step_hz,
                "physics_hz": self.sim.physics_hz, "px4_lockstep_flag": self.lockstep_flag,
                "first_reply_sim_s": (None if self.first_reply_us is None
                                      else self.first_reply_us / 1e6),
                "state_interval_us": self.encoder.state_interval_us,
                "sent": dict(self.encoder.sent), "link": self.link.counts()}
