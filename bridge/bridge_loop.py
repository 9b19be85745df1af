"""The bridge program's loop: physics -> sensor ring, actuator ring -> motors.

`BridgeLoop` owns one physics step at a time (publish_step / collect_pwm) so
the same code serves every way of driving it (bridge/bridge_driver.py): lockstep
or real time, with the FC in another process or interleaved in this one
(`fly --processes 1`). It never imports the FC: they meet only through the
shared-memory segment.

Lockstep follows shm/lockstep.py: publish step k, wait for FC_SIM_NS >= t_k,
take the PWM, step again. Real time paces steps to the wall clock and never
waits for the FC; late PWM simply holds the previous command (zero-order hold),
as an ESC does.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from silbridge.shm import lockstep as ls
from silbridge.shm.records import KIND_PWM, PWM_DTYPE, RECORD_DTYPE, Kind, word_index

from . import _step
from .errors import LockstepBroken, PeerLost
from .fault_records import FaultRecords
from .link_faults import PWM_COMMAND, LinkFaults

_NS = 1_000_000_000

# Where collect_pwm reads a PWM slot, in the word sizes of its views (shm/records.py).
_SLOT_BYTES = RECORD_DTYPE.itemsize
_SLOT_U16 = _SLOT_BYTES // 2
_SLOT_I64 = _SLOT_BYTES // 8
_PWM_US_U16 = word_index(Kind.PWM, "pwm_us", 2)
_ARMED_BYTE = word_index(Kind.PWM, "armed", 1)
_SIM_NS_I64 = word_index(Kind.PWM, "sim_ns", 8)
_WALL_NS_I64 = word_index(Kind.PWM, "wall_ns", 8)
_KIND_U16 = word_index(Kind.NONE, "kind", 2)

# The most steps one run_batch takes: what its trace buffer is sized for. Between two
# batches Python looks at the stop request: 256 steps are ~4 ms of wall time. A batch
# costs ~45k instructions of Python, ~180 a step with 256; a flight's batches end at that
# length or at the IMU's noise refills (1,024 steps), the GNSS epochs being made in C
# (docs/howto/speed.md).
BATCH_MAX_STEPS = 256


@dataclass
class LoopStats:
    """The PWM the bridge received: counts and first/last stamps, for the rates."""

    pwm_received: int = 0
    pwm_first_sim_ns: int = -1
    pwm_last_sim_ns: int = -1
    pwm_first_wall_ns: int = -1
    pwm_last_wall_ns: int = -1
    # steps published without waiting for the FC in its own process: it promised to answer
    # them with nothing (FC_SYNC_NS, shm/lockstep.py) and computed them meanwhile
    steps_overlapped: int = 0


class BridgeLoop:
    """One physics step at a time; see module docstring."""

    # Sample truth for the summary errors every this many physics steps.
    ERROR_SAMPLE_STEPS = 10

    def __init__(self, sim, segment, *, sink=None, settle_s: float = 10.0, trace: bool = True):
        self.sim = sim
        self.seg = segment
        self.sink = sink
        self.pwm_us = (1000.0, 1000.0, 1000.0, 1000.0)   # a tuple: cheapest to unpack per step
        self.armed = False
        self.stats = LoopStats()
        # hashlib's BLAKE2b digest, in an object a batch in C can feed too (step_batch.c)
        self._hash = _step.Blake2b(digest_size=16)
        self._trace = trace
        self._pwm_buf = np.zeros(4096, dtype=RECORD_DTYPE)
        # Column views made once: per-step scalar reads then cost ~100 ns, not a view each.
        view = self._pwm_buf.view(PWM_DTYPE)
        self._pwm_view = view
        self._col_us = view["pwm_us"]
        self._col_armed = view["armed"]
        self._col_sim = view["sim_ns"]
        self._col_wall = view["wall_ns"]
        self.settle_ns = int(settle_s * _NS)
        # Running sums, not lists: a real-time session runs for hours and the lists grew
        # by 100 samples a second (the soak benchmark's memory check found it).
        self._n_err = 0
        self._att_err_sq = 0.0
        self._alt_err_sq = 0.0
        # Bound methods looked up once: `seg.sensors.push_batch` is three lookups a step.
        self._step = sim.step
        self._push = segment.sensors.push_batch
        self._pop_pwm = segment.actuators.pop_into
        self._set_word = segment.set_word
        self._word = segment.word
        self._hash_update = self._hash.update
        self._io_stale = False      # the per-step path changed what the batch's words hold
        self._kernel_hashes = False  # the bound batch feeds the trace hash itself
        self._rotor_rows = None
        # A sink may log the PWM elsewhere (the FC's side) and set pwm_records to None.
        self._log_pwm = getattr(sink, "pwm_records", None) if sink is not None else None
        # A sink may log the rotor speeds after each step (tools/logs/rotor_log.py), or not.
        self._log_rotor = getattr(sink, "rotor", None) if sink is not None else None
        raw = memoryview(self._pwm_buf.view(np.uint8))
        self._pwm_raw = raw
        self._pwm_u16 = raw.cast("H")
        self._pwm_i64 = raw.cast("q")
        # Faults of the link itself (bridge/link_faults.py): while `link.engaged` the records
        # pass through it and the steps run one by one (in_python_next, step_one).
        self.link = LinkFaults(sim.scenario.seed,
                               on_event=lambda ns, text: sim.events.append((ns, text)))
        sim.faults.register("link", self.link)
        # The FC's FAULT records, collected beside its PWM (bridge/fault_records.py).
        self.fault_records = FaultRecords(sim)

    # -- one step ---------------------------------------------------------
    def publish_step(self) -> np.ndarray:
        """Advance physics one step with the held PWM; publish its records."""
        recs = self._step(self.pwm_us)
        self._publish(recs)
        return recs

    def _publish(self, recs: np.ndarray) -> None:
        """The records of the step just taken: hashed, to the FC, and what the step logs."""
        sim = self.sim
        if self._trace:
            self._hash_update(recs)
        sim_ns = sim.sim_ns
        if self.link.sensors_engaged:   # hashed above: what the simulator made, not what arrives
            recs = self.link.sensors_out(recs, sim_ns)
        # A refused push (non-overwriting ring, full) is counted by the ring as
        # rejected and reported by the start-up checks and the summary.
        self._push(recs)
        self._set_word(ls.BRIDGE_SIM_NS, sim_ns)
        if self._log_rotor is not None:
            self._log_rotor(sim_ns)
        self._drain_events()
        if sim.step_index % self.ERROR_SAMPLE_STEPS == 0 and sim_ns >= self.settle_ns:
            self._sample_errors()

    def _drain_events(self) -> None:
        events = self.sim.events
        if events:
            if self.sink is not None:
                for ev_ns, text in events:
                    self.sink.event(ev_ns, "disturbance", text)
            events.clear()

    def collect_pwm(self) -> int:
        """Drain the actuator ring; hold the newest command. Returns records read."""
        n = self._pop_pwm(self._pwm_buf)
        if n and (self._pwm_u16[_KIND_U16] != KIND_PWM or n > 1 and self._others_among(n)):
            n = self._set_others_aside(n)
        if self.link.pwm_engaged:
            self._hold_through_link(n)
        elif n:
            last = n - 1
            # Header and payload fields through memoryviews: Python ints, no numpy scalars.
            u16 = self._pwm_u16
            b = last * _SLOT_U16 + _PWM_US_U16       # pwm_us[0..3]: the four motors
            self.pwm_us = (u16[b], u16[b + 1], u16[b + 2], u16[b + 3])
            self.armed = bool(self._pwm_raw[last * _SLOT_BYTES + _ARMED_BYTE])
        if n == 0:
            return 0
        # Counted, logged and hashed as the FC sent them, whatever the link does to them.
        last = n - 1
        i64 = self._pwm_i64
        st = self.stats
        if st.pwm_first_sim_ns < 0:
            st.pwm_first_sim_ns = i64[_SIM_NS_I64]
            st.pwm_first_wall_ns = i64[_WALL_NS_I64]
        last_row = last * _SLOT_I64
        st.pwm_last_sim_ns = i64[last_row + _SIM_NS_I64]
        st.pwm_last_wall_ns = i64[last_row + _WALL_NS_I64]
        st.pwm_received += n
        self._io_stale = True
        if self._log_pwm is not None:
            self._log_pwm(self._pwm_view[:n])
        # Hash without wall-clock stamps: only what lockstep makes deterministic.
        if self._trace:
            for i in range(n):
                i64[i * _SLOT_I64 + _WALL_NS_I64] = 0
            self._hash_update(self._pwm_raw[:n * _SLOT_BYTES])
        return n

    def _others_among(self, n: int) -> bool:
        """Whether the n records popped hold another kind than PWM (one compare when n == 1)."""
        u16 = self._pwm_u16
        return any(u16[i * _SLOT_U16 + _KIND_U16] != KIND_PWM for i in range(n))

    def _set_others_aside(self, n: int) -> int:
        """A collection with other records than PWM (the FC's FAULTs): those are routed to
        the fault engine, the PWM records moved to the front; returns how many PWM. As the C
        collection does (step_lockstep.c), so the trace holds the PWM alone either way."""
        recs = self._pwm_buf[:n]
        is_pwm = recs["kind"] == KIND_PWM
        self.fault_records.route(recs.copy())
        m = int(is_pwm.sum())
        self._pwm_buf[:m] = recs[is_pwm]
        return m

    def _hold_through_link(self, n: int) -> None:
        """While the link is faulty: the motors take the newest of the n records popped (and
        of earlier ones in flight) that the link lets arrive by now; else they hold their
        command, as an ESC keeps its last pulse."""
        rec = self.link.pwm_in(self._pwm_buf[:n], self.sim.sim_ns)
        if rec is not None:
            us0, us1, us2, us3, _, _, _, _, armed = PWM_COMMAND.unpack_from(rec)
            self.pwm_us = (us0, us1, us2, us3)
            self.armed = bool(armed)
            self._io_stale = True

    # -- many steps: bridge and in-process FC in C -----------------------------
    def bind_in_process_fc(self, fc_poll_c) -> bool:
        """Let run_batch step bridge and FC together in C (`fly --processes 1` in lockstep):
        fc_poll_c is the FC's C poll over this segment (FcLoop.batch_poll). False when this
        run cannot: an oversampled IMU (numpy per step), a sink that logs the PWM here, or
        a rotor hook that cannot take a batch's rows (`write_rows`)."""
        if (fc_poll_c is None or not self.sim.batches or self._log_pwm is not None
                or not self._rotor_takes_rows()):
            return False
        self._bind_batches(self.seg.c_capsule(), fc_poll_c, kernel_hashes=False)
        return True

    def bind_fc_process(self) -> bool:
        """run_batch for an FC in its own process (`fly --processes 2` in lockstep): a step
        waits in C for the FC's answer (the lockstep hand-off, shm/include/sb_handoff.h)
        where the FC's promise (FC_SYNC_NS, shm/lockstep.py) says it may answer with
        records, and at the batch's last; the steps between are published at once and the
        FC computes them while the bridge steps on. A step not answered within a slice ends
        its batch unanswered (`fc_pending`): the caller looks at the FC, then waits on and
        collects the Python way. False when this run cannot: a link without a segment
        (HIL), an oversampled IMU, a PWM-logging sink, a rotor hook that cannot take a
        batch's rows (`write_rows`)."""
        capsule = self.seg.c_capsule()
        if (capsule is None or not self.sim.batches or self._log_pwm is not None
                or not self._rotor_takes_rows()):
            return False
        self._bind_batches(capsule, None)
        return True

    def _rotor_takes_rows(self) -> bool:
        """A batch hands its rotor rows to the log's hook at once (_log_rotor_rows)."""
        return self._log_rotor is None or hasattr(self._log_rotor, "write_rows")

    def _bind_batches(self, capsule, fc_poll_c, kernel_hashes: bool = True) -> None:
        """The batch's buffers, bound to the kernel with the FC's C poll (None: its own
        process). kernel_hashes: the batch feeds the trace hash itself, each step's bytes
        right after its publish, which with the FC in its own process is while the FC
        computes its answer; else run_batch hashes the batch's trace once (one process:
        nothing to overlap, and one call a batch is as cheap; docs/howto/speed.md)."""
        sim = self.sim
        self._kernel_hashes = kernel_hashes and self._trace
        self._fc_own_process = fc_poll_c is None
        self.fc_pending = False
        slots = len(sim.buffer.buf) // _SLOT_BYTES
        self._trace_buf = np.zeros(BATCH_MAX_STEPS * (slots + 16) * _SLOT_BYTES, dtype=np.uint8)
        self._trace_mv = memoryview(self._trace_buf)
        self._io = np.zeros(_step.IO_WORDS, dtype=np.int64)
        self._iow = memoryview(self._io)
        self._iow[_step.IO_ERR_EVERY] = self.ERROR_SAMPLE_STEPS
        self._iow[_step.IO_ERR_FROM_NS] = self.settle_ns
        self._err = np.zeros(_step.ERR_COUNT)
        self._errw = memoryview(self._err)
        self._rotor_rows = (np.zeros((BATCH_MAX_STEPS, 4)) if self._log_rotor is not None
                            else None)
        sim.bind_lockstep(segment=capsule, fc_poll=fc_poll_c,
                          trace=self._trace_buf, pwm=self._pwm_buf, io=self._io,
                          errors=self._err, rotor=self._rotor_rows, bridge_word=ls.BRIDGE_SIM_NS,
                          fc_word=ls.FC_SIM_NS,
                          trace_hash=self._hash if self._kernel_hashes else None,
                          hand_on_kinds=ls.HAND_ON_KINDS if self._fc_own_process else None)
        self._io_stale = True

    def run_batch(self, n: int) -> int:
        """Up to n lockstep steps (at most BATCH_MAX_STEPS), each published, answered by
        the in-process FC and its PWM collected, in C (bridge/src/step_batch.c): the same
        records, hash, stamps, PWM and error samples as n rounds of publish_step, FC poll,
        collect_pwm. Returns the steps done: fewer than n when a step needed Python (its
        part runs in Simulator.step_batch), which then is the batch's last. The caller makes
        every step whose end Python must see (checks, the FC's due polls) the last of one."""
        if self._io_stale:
            self._to_io()
        k0 = self.sim.step_index
        done = self.sim.step_batch(min(n, BATCH_MAX_STEPS))
        w = self._iow
        used = w[_step.IO_TRACE_BYTES]
        if used and self._trace and not self._kernel_hashes:
            self._hash_update(self._trace_mv[:used])
        if w[_step.IO_OTHER_N]:     # the FC's FAULT records, routed before the next step
            at = w[_step.IO_OTHER_AT]
            self.fault_records.route(self._pwm_buf[at:at + w[_step.IO_OTHER_N]].copy())
            w[_step.IO_OTHER_N] = 0
        if w[_step.IO_SYNC_BROKEN]:
            raise LockstepBroken(
                f"the FC in its own process sent {w[_step.IO_SYNC_BROKEN]} PWM record(s) for "
                "steps it had promised to answer with none (FC_SYNC_NS): its motors took them "
                "late. Are the bridge and the FC from the same build? (`make setup` rebuilds "
                "both)")
        if done:
            self.stats.steps_overlapped += w[_step.IO_OVERLAPPED]
            self._from_io()
            if self._rotor_rows is not None:
                self._log_rotor_rows(k0, done)
            if w[_step.IO_FC_MISSED]:
                if not self._fc_own_process:
                    raise PeerLost("the in-process FC did not answer a lockstep step")
                self.fc_pending = True      # its answer is collected the Python way
                self._io_stale = True
        self._drain_events()
        return done

    def _log_rotor_rows(self, k0: int, done: int) -> None:
        """The rotor speeds the batch left after each of its steps k0+1.., to the log's
        /rotor channel in one call (every rotor hook takes a batch's rows: RotorLog,
        RotorSpool, ImuRawLog)."""
        dt = self.sim.dt_ns
        self._log_rotor.write_rows(np.arange(k0 + 1, k0 + 1 + done, dtype=np.int64) * dt,
                                   self._rotor_rows[:done])

    def in_python_next(self) -> bool:
        """True when the next step of a batched run must take the per-step path (step_one):
        the link is faulty or records are in flight, or a fault switches at that step (a
        link fault's first records must already meet the link)."""
        return self.link.engaged or self.sim.faults.next_step == self.sim.step_index + 1

    def step_one(self, answer) -> None:
        """One step of a batched run the per-step way: publish it, answer() (the FC answers
        and the PWM is collected), and the batch's words taken afresh at the next batch."""
        self.publish_step()
        answer()
        self._io_stale = True

    def batch_polls(self) -> tuple[int, int]:
        """FC polls that consumed records in the last run_batch, and the records the newest
        consumed (FcLoop.after_c_polls)."""
        return self._iow[_step.IO_POLLS], self._iow[_step.IO_LAST_POLL]

    def _to_io(self) -> None:
        """The held PWM and the PWM statistics, from the per-step path into the batch's words."""
        w, st = self._iow, self.stats
        for i, us in enumerate(self.pwm_us):
            w[_step.IO_PWM_US + i] = int(us)
        w[_step.IO_ARMED] = int(self.armed)
        w[_step.IO_PWM_RECEIVED] = st.pwm_received
        w[_step.IO_PWM_FIRST_SIM] = st.pwm_first_sim_ns
        w[_step.IO_PWM_FIRST_WALL] = st.pwm_first_wall_ns
        w[_step.IO_PWM_LAST_SIM] = st.pwm_last_sim_ns
        w[_step.IO_PWM_LAST_WALL] = st.pwm_last_wall_ns
        w[_step.IO_ERR_N] = self._n_err
        self._errw[_step.ERR_ATT_SQ] = self._att_err_sq
        self._errw[_step.ERR_ALT_SQ] = self._alt_err_sq
        self._io_stale = False

    def _from_io(self) -> None:
        """The batch's words back into the held PWM, the statistics and the error sums."""
        w, st = self._iow, self.stats
        if w[_step.IO_ERR_N] != self._n_err:
            e = self._errw
            self._n_err = w[_step.IO_ERR_N]
            self._att_err_sq = e[_step.ERR_ATT_SQ]
            self._alt_err_sq = e[_step.ERR_ALT_SQ]
        if w[_step.IO_PWM_RECEIVED] == st.pwm_received:
            return
        b = _step.IO_PWM_US
        self.pwm_us = (w[b], w[b + 1], w[b + 2], w[b + 3])
        self.armed = bool(w[_step.IO_ARMED])
        st.pwm_received = w[_step.IO_PWM_RECEIVED]
        st.pwm_first_sim_ns = w[_step.IO_PWM_FIRST_SIM]
        st.pwm_first_wall_ns = w[_step.IO_PWM_FIRST_WALL]
        st.pwm_last_sim_ns = w[_step.IO_PWM_LAST_SIM]
        st.pwm_last_wall_ns = w[_step.IO_PWM_LAST_WALL]

    def fc_caught_up(self) -> bool:
        return self._word(ls.FC_SIM_NS) >= self.sim.sim_ns

    # -- summary helpers ----------------------------------------------------
    def _sample_errors(self) -> None:
        roll, pitch, alt = self.sim.roll_pitch_alt()
        cmd = self.sim.command
        er = roll - cmd["roll_rad"]
        ep = pitch - cmd["pitch_rad"]
        self._n_err += 1
        self._att_err_sq += er * er + ep * ep
        self._alt_err_sq += (alt - cmd["alt_m"]) ** 2

    def attitude_rms_deg(self) -> float | None:
        if not self._n_err:
            return None
        return math.degrees(math.sqrt(self._att_err_sq / self._n_err))

    def altitude_rms_m(self) -> float | None:
        if not self._n_err:
            return None
        return math.sqrt(self._alt_err_sq / self._n_err)

    def trace_hash(self) -> str:
        return self._hash.hexdigest() if self._trace else ""


class PeerWatch:
    """Detects a dead or stalled FC within ~100 ms while the bridge waits."""

    def __init__(self, segment, *, extra_check=None, stall_s: float = 5.0):
        self.seg = segment
        self.extra_check = extra_check
        self.stall_ns = int(stall_s * _NS)
        self._last_beat = None
        self._last_change = time.monotonic_ns()

    def check(self) -> None:
        if self.seg.word(ls.FC_STOP):
            raise PeerLost("the FC left the run (see its messages above); the bridge stops too")
        if self.extra_check is not None and not self.extra_check():
            raise PeerLost("the FC process exited; the bridge stops. Check the FC's output for why")
        if not self.seg.peer_alive():
            raise PeerLost("the FC process is gone (pid no longer exists); restart `silbridge fc`")
        beat = self.seg.peer_heartbeat()
        now = time.monotonic_ns()
        if beat != self._last_beat:
            self._last_beat = beat
            self._last_change = now
        elif now - self._last_change > self.stall_ns:
            raise PeerLost(f"the FC stopped beating for {(now - self._last_change) / 1e9:.1f} s "
                           "(hung or stopped?); the bridge stops")

