"""Faults of the SIL link itself (fault unit "link"): records late or lost between bridge and FC.

The applier the fault engine calls (bridge/faults/engine.py: on / off), and the two filters
the bridge's loop sends records through while a link fault is on or records are still on
their way: `sensors_out` between the simulator and the sensor ring (or the HIL encoder), and
`pwm_in` between the actuator ring (or the HIL decoder) and the held motor command. The
instance is the direction: 0 both, 1 sensors (bridge to FC), 2 motor outputs (FC to bridge).

What a record meets on a faulty link (docs/explanation/sil-link-faults.md):
- latency: it arrives delay_s + U(0, jitter_s) of SIM time after it was sent (a sensor
  record: after its sample time; a PWM record: after the step the bridge popped it). The
  link is a FIFO, as a ring, a TCP stream, a serial line and a UDP socket on one host are: a
  record never overtakes an earlier one, so its arrival is the later of its own draw and the
  previous record's arrival. Per kind, sample times therefore stay in order.
- drop: it is lost with the probability, one draw per record.
- a lost or late PWM record leaves the motors at the last command that arrived, as an ESC
  holds its last pulse.

What the link never touches: the lockstep clock. Ground truth (GT_ATT, GT_NAV) and the
scenario's SETPOINT records are the simulator's instrumentation and script, not sensor
data, and they close each step: the step's last delivered record carries STEP_END at the
step's sim time (shm/lockstep.py), so the FC acknowledges every step even when all its
sensor records are lost, and its sensor failsafe, not a stalled handshake, meets the loss.
Over MAVLink HIL the acknowledgement is the lockstep word, not a PWM record: it is kept.

Draws come from the run's named streams "link.sensors" and "link.pwm" (bridge/scenario.py
draw_rng): the same seed gives the same records delayed and lost, and a fault in one
direction does not change the draws of the other.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from silbridge.bridge.scenario import draw_rng
from silbridge.shm.records import (FLAG_STEP_END, FLAGS_OFFSET, KIND_PWM, RECORD_DTYPE,
                                   RECORD_SIZE, Kind, record_struct)
from silbridge.shm.records import NS_PER_S as _NS

# Kinds that carry the step's clock, not sensor data (truth, setpoints): never on the link.
_CLOCK = frozenset(int(k) for k in (Kind.GT_ATT, Kind.GT_NAV, Kind.SETPOINT))
_SIM_NS = record_struct(Kind.NONE, ["sim_ns"])
# A PWM record's motor command: pwm_us[0..7], armed.
PWM_COMMAND = record_struct(Kind.PWM, ["pwm_us", "armed"])
_KEEP_FLAGS = 0xFF & ~FLAG_STEP_END         # the flags' low byte without STEP_END

SENSORS, PWM = 1, 2                         # the catalog's instances (0: both)

# The filters work on the records' bytes, one Python step per record: a step carries a
# handful, for which numpy's per-call cost (~1 us a call) is what would dominate.


class _Uniforms:
    """U(0, 1) draws of one named stream, taken from blocks: the sequence is the
    generator's own whatever the block size, so a record's draw depends only on how many
    draws came before it."""

    def __init__(self, rng: np.random.Generator, block: int = 4096):
        self.rng, self.block = rng, block
        self.buf: list = []
        self.i = 0

    def take(self, n: int) -> list:
        if self.i + n > len(self.buf):
            self.buf = self.buf[self.i:] + self.rng.random(max(n, self.block)).tolist()
            self.i = 0
        out = self.buf[self.i:self.i + n]
        self.i += n
        return out


@dataclass
class _Direction:
    """One direction of the link: its active faults' combined figures and its queue."""

    draws: _Uniforms
    faults: dict = field(default_factory=dict)  # (type, instance) -> params
    delay_ns: int = 0
    jitter_ns: int = 0
    drop_p: float = 0.0
    queue: deque = field(default_factory=deque)  # FIFO of (due sim ns, item)
    last_due_ns: int = 0
    delayed: int = 0        # records that arrived at least one step after they were sent
    dropped: int = 0        # records lost

    def combine(self) -> None:
        """Two faults on one direction act in series: delays add, survivals multiply."""
        self.delay_ns = self.jitter_ns = 0
        keep = 1.0
        for (ftype, _), p in self.faults.items():
            if ftype == "latency":
                self.delay_ns += int(round(p["delay_s"] * _NS))
                self.jitter_ns += int(round(p["jitter_s"] * _NS))
            else:
                keep *= 1.0 - p["probability"]
        self.drop_p = 1.0 - keep

    @property
    def busy(self) -> bool:
        return bool(self.faults) or bool(self.queue)

    def kept(self, items: list) -> list:
        """The items the link does not lose (one draw each while a drop is on)."""
        if self.drop_p <= 0.0 or not items:
            return items
        p = self.drop_p
        keep = [it for it, u in zip(items, self.draws.take(len(items))) if u >= p]
        self.dropped += len(items) - len(keep)
        return keep

    def holds(self) -> bool:
        """True when records must queue: a delay is on, or earlier ones still travel."""
        return self.delay_ns > 0 or self.jitter_ns > 0 or bool(self.queue)

    def enqueue(self, items: list, sent_ns: list, now_ns: int) -> None:
        """items sent at sent_ns, each due after the delay and its jitter, never before
        the item ahead of it (FIFO)."""
        jitter = self.draws.take(len(items)) if self.jitter_ns else None
        due_last, q = self.last_due_ns, self.queue
        for i, item in enumerate(items):
            due = sent_ns[i] + self.delay_ns
            if jitter is not None:
                due += int(jitter[i] * self.jitter_ns)
            if due > due_last:
                due_last = due
            if due_last > now_ns:
                self.delayed += 1
            q.append((due_last, item))
        self.last_due_ns = due_last

    def release(self, now_ns: int) -> list:
        """The queued items due by now_ns, oldest first."""
        out, q = [], self.queue
        while q and q[0][0] <= now_ns:
            out.append(q.popleft()[1])
        return out


class LinkFaults:
    """The "link" unit's applier and filters; see the module docstring. `engaged` is True
    while the bridge must send records through here (a fault on or records in flight): the
    loop then takes its per-step path, and `sensors_engaged` / `pwm_engaged` say which
    filter; otherwise nothing here runs."""

    def __init__(self, seed: int, on_event=None):
        self.sensors = _Direction(_Uniforms(draw_rng(seed, "link.sensors")))
        self.pwm = _Direction(_Uniforms(draw_rng(seed, "link.pwm")))
        self.engaged = self.sensors_engaged = self.pwm_engaged = False
        self._on_event = on_event       # (sim_ns, text): the run's event list (and log)
        self._held_step = None          # step_out: the newest step that arrived

    # --- the fault engine's applier ---------------------------------------------------------
    def on(self, fault, sim_ns: int) -> None:
        for d in self._directions(fault.instance):
            d.faults[(fault.type, fault.instance)] = dict(fault.params)
            d.combine()
        self._update()

    def off(self, fault, sim_ns: int) -> None:
        for d in self._directions(fault.instance):
            d.faults.pop((fault.type, fault.instance), None)
            d.combine()
        self._update()
        if self._on_event is not None:
            self._on_event(sim_ns, "link so far: " + ", ".join(
                f"{k.replace('_', ' ')} {v}" for k, v in self.counts().items()))

    def _directions(self, instance: int) -> tuple:
        return {0: (self.sensors, self.pwm), SENSORS: (self.sensors,), PWM: (self.pwm,)}[instance]

    def _update(self) -> None:
        self.sensors_engaged = self.sensors.busy
        self.pwm_engaged = self.pwm.busy
        self.engaged = self.sensors_engaged or self.pwm_engaged

    # --- bridge -> FC --------------------------------------------------------------------
    def sensors_out(self, recs: np.ndarray, now_ns: int) -> np.ndarray:
        """What of one step's records (and of earlier ones in flight) reaches the FC now:
        the records due, oldest first, then the step's clock records and the sensor records
        that went straight through, in their order; the last carries STEP_END."""
        d = self.sensors
        raw = recs.tobytes()
        slots = range(0, len(raw), RECORD_SIZE)
        clock = [raw[o] | raw[o + 1] << 8 in _CLOCK for o in slots]
        kept = d.kept([o for o, c in zip(slots, clock) if not c])
        if d.holds():
            if kept:
                d.enqueue([raw[o:o + RECORD_SIZE] for o in kept],
                          [_SIM_NS.unpack_from(raw, o)[0] for o in kept], now_ns)
            straight = [o for o, c in zip(slots, clock) if c]
        else:
            keep = set(kept)
            straight = [o for o, c in zip(slots, clock) if c or o in keep]
        parts = d.release(now_ns) + [raw[o:o + RECORD_SIZE] for o in straight]
        self._update()
        out = bytearray().join(parts)
        for o in range(FLAGS_OFFSET, len(out), RECORD_SIZE):
            out[o] &= _KEEP_FLAGS
        if out:
            out[len(out) - RECORD_SIZE + FLAGS_OFFSET] |= FLAG_STEP_END
        return np.frombuffer(out, dtype=RECORD_DTYPE)

    # --- FC -> bridge ----------------------------------------------------------------------
    def pwm_in(self, recs: np.ndarray, now_ns: int) -> bytes | None:
        """The PWM records the bridge popped now through the link: the newest PWM record
        that arrives by now_ns (its bytes; PWM_COMMAND reads the command), or None when
        none does (the motors hold their last command)."""
        d = self.pwm
        raw = recs.tobytes()
        pwm = d.kept([raw[o:o + RECORD_SIZE] for o in range(0, len(raw), RECORD_SIZE)
                      if raw[o] | raw[o + 1] << 8 == KIND_PWM])
        if d.holds():
            if pwm:
                d.enqueue(pwm, [now_ns] * len(pwm), now_ns)
            pwm = d.release(now_ns)
        self._update()
        return pwm[-1] if pwm else None

    # --- links whose unit is the whole step (ArduPilot SITL's JSON reply) -------------------
    def step_out(self, recs: np.ndarray, now_ns: int) -> np.ndarray:
        """A link that carries each step's sensors as one message: the newest step's records
        that arrive by now_ns, else the last that arrived (the receiver reads its newest
        sample again). The same FIFO, delay and loss rules, one draw per message."""
        d = self.sensors
        sent = d.kept([recs.copy()])
        if d.holds():
            if sent:
                d.enqueue(sent, [now_ns], now_ns)
            sent = d.release(now_ns)
        if sent:
            self._held_step = sent[-1]
        self._update()
        return self._held_step if self._held_step is not None else recs

    # --- the account -------------------------------------------------------------------------
    def counts(self) -> dict:
        """Records delayed and dropped per direction, for the run summary and the log."""
        s, p = self.sensors, self.pwm
        return {"sensor_delayed": s.delayed, "sensor_dropped": s.dropped,
                "pwm_delayed": p.delayed, "pwm_dropped": p.dropped}
