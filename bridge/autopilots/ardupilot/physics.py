"""The Simulator as ArduPilot SITL's JSON physics: one servo packet -> one step -> one reply.

No sockets here (bridge/autopilots/ardupilot/server.py owns the UDP port), so tests can
drive the lockstep rules directly:

- a new frame_count: hold the four motor PWMs for one physics step
  (Simulator.dt_ns, 1 ms) and answer with the state after it. SITL advances
  its clock by the difference of our timestamps, so its clock is ours
  whatever its SIM_RATE_HZ; we pass SIM_RATE_HZ 1000 (tools/autopilots/ardupilot/sitl.py)
  so its scheduler also expects 1 kHz frames, and say so once if a packet
  announces another rate.
- the same frame_count again: SITL resent its servos after a 1 s wait for a
  reply that was lost; answer again with the last state, no step (a step
  would make the two clocks disagree).
- a frame_count that jumps ahead: packets were lost; counted, one step.
- a frame_count that goes back: SITL restarted; the physics restarts too
  (a fresh Simulator from the same scenario and seed), and its timestamp going
  back tells SITL to treat it as a physics reset.

IMU values are the sensor model's (the mean of the step's IMU samples, so an
oversampled IMU is decimated by a boxcar as an IMU FIFO read would be): bias,
noise, vibration and temperature drift of the scenario reach ArduCopter just as
they reach our FC, so Table 1 compares the controllers under the same sensors.
Keep SITL's own SIM_ACC*/SIM_GYR* noise at 0 so it is not added twice.
Position, velocity and attitude are truth: SITL builds its GPS, baro and
compass from them with its own models (our baro/mag/GNSS records are not sent).

Faults of the link (unit "link", bridge/link_faults.py): the servo packet's motors pass
the motor-output direction (a lost or late command: the motors hold the last that
arrived); the reply's sensors, IMU and truth together, pass the sensor direction as one
message per step (a lost or late reply: SITL gets the newest state that arrived, under
this step's timestamp, so its clock still follows ours and lockstep never waits). A fault
switches at the start of a physics step, so the motors of that step's packet were read
before it: the motor direction starts one step (1 ms) late.

Timing: the server passes each packet's arrival time to `handle` and calls
`sent` once the reply is out; the sink then gets one timing(...) call per
stepped packet: PWM time [sim ns], arrival, physics step done and reply sent
[monotonic wall ns], and the wall interval since the previous stepped packet
(SITL's frame period; 0 for the first). Duplicates are answered, not timed.
"""

from __future__ import annotations

import time

import numpy as np

from silbridge.bridge._step import json_reply as _json_reply
from silbridge.bridge.autopilots.ardupilot import json_protocol as apj
from silbridge.bridge.link_faults import PWM_COMMAND, LinkFaults
from silbridge.shm.records import (KIND_PWM, PWM_DTYPE, RECORD_DTYPE, RECORD_SIZE, Kind,
                                   record_struct)
from silbridge.shm.records import NS_PER_S as _NS

# The sink's PWM record, packed in one call from shm/records.py's description of the slot.
_PWM = record_struct(Kind.PWM)


class ArduPilotPhysics:
    """Protocol state around a Simulator.

    make_sim: () -> Simulator, called at start and at every SITL restart.
    sink: optional object with step(records, pwm_record, sim) (the run log) and
    timing(sim_ns, rx_wall_ns, done_wall_ns, tx_wall_ns, period_ns).
    """

    def __init__(self, make_sim, sink=None, note=None):
        self._make_sim = make_sim
        self.sim = make_sim()
        self.link = self._link_faults()
        self.sink = sink
        self._note = note or (lambda text: None)
        self.last_frame: int | None = None
        self.last_reply: bytes | None = None
        self.packets = 0
        self.steps = 0
        self.duplicates = 0
        self.dropped_frames = 0
        self.resets = 0
        self.sitl_rate_hz: int | None = None
        self.channels: int | None = None
        # The step's PWM record for the sink, filled by one struct pack (numpy field
        # stores cost ~1-5 us each); _pwm is a numpy view of the same bytes.
        self._pwm_buf = bytearray(RECORD_SIZE)
        self._pwm = np.frombuffer(self._pwm_buf, dtype=PWM_DTYPE)
        self._rx_ns = 0            # arrival of the packet being handled [wall ns]
        self._prev_rx_ns = 0       # arrival of the previous stepped packet
        self._timing = None        # the last step's timing, until its reply is sent

    @property
    def physics_hz(self) -> float:
        return _NS / self.sim.dt_ns

    def handle(self, data: bytes, source=None, rx_wall_ns: int = 0) -> bytes:
        """One datagram -> the reply to send back to its source (then call `sent`)."""
        pkt = apj.decode_servo_packet(data, source)
        self._rx_ns = rx_wall_ns
        self.packets += 1
        if self.sitl_rate_hz != pkt.frame_rate_hz:
            self.sitl_rate_hz = pkt.frame_rate_hz
            if pkt.frame_rate_hz and abs(pkt.frame_rate_hz - self.physics_hz) > 0.5:
                self._note(f"SITL runs its physics frames at {pkt.frame_rate_hz} Hz, ours at "
                           f"{self.physics_hz:g} Hz: SITL's clock follows our timestamps "
                           f"(1 step per packet); set SIM_RATE_HZ {self.physics_hz:g} so its "
                           "scheduler expects that rate")
        self.channels = pkt.channels
        frame = pkt.frame_count
        last = self.last_frame
        if last is not None and frame == last and self.last_reply is not None:
            self.duplicates += 1
            return self.last_reply
        if last is not None and frame < last:
            self._restart(frame, last)
        elif last is not None and frame > last + 1:
            self.dropped_frames += frame - last - 1
        self.last_frame = frame
        self.last_reply = self._step(pkt)
        return self.last_reply

    def _restart(self, frame: int, last: int) -> None:
        self.resets += 1
        self._note(f"SITL frame count went back ({last} -> {frame}): SITL restarted; "
                   "physics restarted from the scenario's initial state")
        self.sim = self._make_sim()
        self.link = self._link_faults()

    def _link_faults(self) -> LinkFaults:
        sim = self.sim
        link = LinkFaults(sim.scenario.seed,
                          on_event=lambda ns, text: sim.events.append((ns, text)))
        sim.faults.register("link", link)
        self._motors_held = (float(apj.PWM_MIN_US),) * apj.MOTORS
        self._link_rec = np.zeros(1, dtype=PWM_DTYPE)     # a packet's motors as a PWM record
        self._link_rec["kind"] = Kind.PWM
        return link

    def _motors_through_link(self, motors: tuple) -> tuple:
        """The servo packet's motors through a faulty link: the newest command that arrives
        by now, else the last that arrived."""
        rec = self._link_rec
        rec["pwm_us"][0, :apj.MOTORS] = motors     # whole microseconds: a u16 holds them
        arrived = self.link.pwm_in(rec.view(RECORD_DTYPE), self.sim.sim_ns)
        if arrived is not None:
            us = PWM_COMMAND.unpack_from(arrived)[:apj.MOTORS]
            self._motors_held = tuple(float(u) for u in us)
        return self._motors_held

    def _step(self, pkt: apj.ServoPacket) -> bytes:
        sim = self.sim
        motors = apj.motor_pwm_us(pkt)
        if self.link.pwm_engaged:
            motors = self._motors_through_link(motors)
        else:
            self._motors_held = motors
        applied_ns = sim.sim_ns
        recs = sim.step(motors)
        self.steps += 1
        sent = self.link.step_out(recs, sim.sim_ns) if self.link.sensors_engaged else recs
        reply = _json_reply(sent, sim.sim_ns)
        if reply is None:
            raise apj.non_finite(f"at sim time {sim.sim_ns / _NS:.3f} s")
        if self.sink is not None:
            m0, m1, m2, m3 = motors
            _PWM.pack_into(self._pwm_buf, 0, KIND_PWM, 0, self.steps - 1, applied_ns,
                           time.monotonic_ns(), int(m0), int(m1), int(m2), int(m3), 0, 0, 0, 0,
                           apj.MOTORS, 1 if max(motors) > apj.PWM_MIN_US else 0, 0,
                           pkt.frame_count & 0xFFFFFFFF, applied_ns)
            self.sink.step(recs, self._pwm, sim)
            rx = self._rx_ns
            period = rx - self._prev_rx_ns if self._prev_rx_ns and rx else 0
            self._prev_rx_ns = rx
            self._timing = (applied_ns, rx, time.monotonic_ns(), period)
        return reply

    def sent(self, tx_wall_ns: int) -> None:
        """The reply of the last handled packet left at tx_wall_ns: log its timing."""
        t = self._timing
        if t is not None:
            self._timing = None
            self.sink.timing(t[0], t[1], t[2], tx_wall_ns, t[3])

    def stats(self) -> dict:
        return {"packets": self.packets, "steps": self.steps, "duplicates": self.duplicates,
                "dropped_frames": self.dropped_frames, "resets": self.resets,
                "sitl_rate_hz": self.sitl_rate_hz, "channels": self.channels,
                "physics_hz": self.physics_hz, "link": self.link.counts()}
