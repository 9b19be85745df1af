"""The FC loop: sensor records -> FlightCore -> PWM records, one poll at a time.

`FcLoop.poll()` consumes whatever the sensor stream holds in one batch, runs the
C core over it (estimator and rate loop per IMU sample, PWM every 2.5 ms of sim
time), publishes the PWM, and acknowledges the lockstep step. The same poll
serves `silbridge fc` (its own process, `run_fc`) and `silbridge fly
--processes 1` (polled by the bridge right after each publish).

Two polls, each needed in production, chosen once when the loop is built from its
transport (fc_sil/fc_transport.py): over shared memory the record router does the
whole poll in C (`Core.poll_io`, fc_sil/ext/record_router.c: pop, core, push, lockstep
acknowledgement, statistics, log queues), and Python runs only the supervisor; over
the MAVLink HIL links (UDP, TCP), whose records are decoded in Python, `_poll_py`
does the same steps with the same clock readings.

The FC never blocks on input (paper 3.4): when the ring is empty it returns,
and the process driver (`run_fc`) waits: in lockstep with the hand-off of
shm/include/sb_handoff.h (spin while a core is free, else block on the futex),
in C together with the C polls (shm serve_polls); in real time spin -> yield ->
sleep, so two processes on two cores do not starve each other. It watches the bridge through the segment
and leaves with a clear message when the bridge dies.
"""

from __future__ import annotations

import functools
import math
import time
from time import monotonic_ns
from typing import Callable

import numpy as np

from silbridge.fc_sil.fc_transport import FcTransport
from silbridge.fc_sil.status import STATUS_DTYPE
from silbridge.shm import lockstep as ls
from silbridge.shm.segment import serve_polls
from silbridge.shm.records import (FLAG_STEP_END, PWM_DTYPE, RECORD_DTYPE, RECORD_SIZE, Kind,
                                   word_index)
from silbridge.shm.timer_slack import set_timer_slack_ns
from silbridge.shm.records import NS_PER_S as _NS


class FcLost(Exception):
    """The bridge died or vanished while the FC was running."""

    user_facing = True


class _Series:
    """Bounded int64 sample store (keeps the newest `cap` samples, cap a power of two).

    Its count lives in a slot of the loop's counter array (words[index]), which the C
    poll updates too. A memoryview over a numpy array: storing a Python int through it
    costs ~30 ns against ~90 ns for a numpy element. With `touch` the pages are touched
    once here: np.zeros maps them lazily, and a real-time session then grew by the
    store's 8 MB over its first half hour, which the soak benchmark reads as a leak. A
    flight that ends by itself leaves them lazy, its 120,000 samples touching 1 MB: a
    bench worker's loop took ~6 ms to start with the three stores touched, and 55-85 ms
    for one run in three, whose stores the allocator mapped afresh."""

    def __init__(self, words, index: int, cap: int = 1 << 20, touch: bool = True):
        self.arr = np.zeros(cap, dtype=np.int64)    # the C poll writes here too
        if touch:
            self.arr.fill(0)
        self.buf = memoryview(self.arr)
        self.mask = cap - 1
        self._words, self._index = words, index

    def add(self, v: int) -> None:
        w, i = self._words, self._index
        self.buf[w[i] & self.mask] = v
        w[i] += 1

    @property
    def n(self) -> int:
        return self._words[self._index]

    def values(self) -> np.ndarray:
        return self.arr[: min(self.n, len(self.arr))].copy()

    def percentiles_us(self, qs=(50, 99)) -> dict:
        v = self.values()
        if len(v) == 0:
            return {f"p{q}": None for q in qs}
        p = np.percentile(v, qs) / 1e3
        return {f"p{q}": float(x) for q, x in zip(qs, p)}


# The loop's counters, kept by either poll (the C poll's FC_IO_*, fc_sil/ext/core_object.h);
# _IO_TIMING.. holds the C poll's last /timing row (sim, imu wall, consume, pwm wall, period).
# The last two are Python's inputs to the C poll's FC_SYNC_NS (shm/lockstep.py): the sim time
# of the next poll Python follows (0: every poll), and the kinds whose polls it follows.
(_IO_LAST_SIM_NS, _IO_LAST_K, _IO_POLLS, _IO_RECORDS, _IO_PWM_PUBLISHED, _IO_N_LATENCY,
 _IO_N_PERIOD, _IO_N_E2E, _IO_TIMING) = range(9)
_IO_TIMING_END = _IO_TIMING + 5
_IO_SYNC_UNTIL, _IO_HAND_ON_KINDS = _IO_TIMING_END, _IO_TIMING_END + 1
_IO_WORDS = _IO_HAND_ON_KINDS + 1
# FC_IO_SYNC_UNTIL for "no due poll" (an int64 word)
_NEVER_NS = (1 << 63) - 1
# With the C poll, the log's batch boundaries are cut every this many polls.
_FLUSH_POLLS = 128

# python_due's poll count when no log cuts batches.
_NO_LIMIT = 1 << 30

# Batches up to this size use views made once (a numpy slice costs ~150 ns per poll).
_SMALL = 64

# Header fields of the newest record, read through memoryviews of the batch as Python
# ints (~30 ns, no numpy scalar): slot n-1 starts at word (n-1) * words-per-slot.
_I64_SLOT = RECORD_SIZE // 8
_I64_SIM = word_index(Kind.NONE, "sim_ns", 8)
_I64_WALL = word_index(Kind.NONE, "wall_ns", 8)
_U16_SLOT = RECORD_SIZE // 2
_U16_FLAGS = word_index(Kind.NONE, "flags", 2)


def _small_views(arr: np.ndarray) -> list:
    return [arr[:i] for i in range(_SMALL)]


def _counter(index: int, doc: str) -> property:
    """A read-only FcLoop attribute for one of the counters either poll keeps."""
    return property(lambda self: self._iow[index], doc=doc)


class FcLoop:
    """One FC poll at a time: `poll()` -> records consumed (0: nothing waiting).

    Which poll runs is chosen once, here, from the transport (fc_sil/fc_transport.py):
    over a shared-memory segment the C record router does the whole poll (`_poll_c`);
    over a link whose records cross in Python (the MAVLink HIL links; or a core whose
    attach_router says no) `_poll_py` does. Both keep the same counters and statistics
    and serve every sink (capturing or per-cycle) and the supervisor."""

    poll: Callable[[], int]

    def __init__(self, core, transport: FcTransport, *, supervisor=None, sink=None,
                 batch: int = 8192, schedule=None, bounded: bool = False):
        self.core = core
        self.seg = transport
        self.supervisor = supervisor
        # Timed parameter changes (fc_sil/param_schedule.py), or None.
        self.schedule = schedule
        self.buf = np.zeros(batch, dtype=RECORD_DTYPE)
        # Outputs preallocated for the largest batch and bound to the C core once:
        # the step then parses, slices and allocates nothing.
        self._pwm_out = np.zeros(batch, dtype=PWM_DTYPE)
        self._status_out = np.zeros(batch, dtype=STATUS_DTYPE)
        self._step = core.bind_batch(self.buf, self._pwm_out, self._status_out)
        self._recs = _small_views(self.buf)
        self._pwms = _small_views(self._pwm_out)
        self._stats = _small_views(self._status_out)
        raw = memoryview(self.buf.view(np.uint8))
        self._i64 = raw.cast("q")
        self._u16 = raw.cast("H")
        # Bound methods of the links, looked up once.
        self._pop_into = transport.sensors.pop_into
        self._push_pwm = transport.actuators.push_batch
        self._set_word = transport.set_word
        # Counters (_IO_* slots) shared by both polls; the C poll writes them in place.
        self._io = np.zeros(_IO_WORDS, dtype=np.int64)
        self._iow = memoryview(self._io)
        # bounded: the flight ends by itself (a lockstep run of a set duration), so its
        # statistics' stores need not be touched up front (_Series).
        self.latency_ns = _Series(self._iow, _IO_N_LATENCY, touch=not bounded)
        self.period_ns = _Series(self._iow, _IO_N_PERIOD, touch=not bounded)
        self.e2e_ns = _Series(self._iow, _IO_N_E2E, touch=not bounded)
        self._prev_consume = 0
        self._sink = self._tick = self._flush = self._fc_batch = None
        self._flush_in = 0
        self._due = []      # batch_poll(): the next_due_ns of the supervisor and schedule
        self._cpoll = self._attach_router(transport.c_capsule())
        self.poll = self._poll_py if self._cpoll is None else self._poll_c
        self.sink = sink

    def _attach_router(self, capsule):
        """The C record router's poll over the segment, or None (records cross in Python)."""
        if capsule is None:
            return None
        self._iow[_IO_HAND_ON_KINDS] = ls.HAND_ON_KINDS
        return self.core.attach_router(
            capsule, fc_sim_word=ls.FC_SIM_NS, latency_ns=self.latency_ns.arr,
            period_ns=self.period_ns.arr, e2e_ns=self.e2e_ns.arr, words=self._io)

    @property
    def polls_in_c(self) -> bool:
        """True when the C record router does the whole poll (shared memory)."""
        return self._cpoll is not None

    last_sim_ns = _counter(_IO_LAST_SIM_NS, "sim time [ns] of the last step the FC answered")
    polls = _counter(_IO_POLLS, "polls that consumed records")
    records = _counter(_IO_RECORDS, "records consumed")
    pwm_published = _counter(_IO_PWM_PUBLISHED, "PWM records published")

    @property
    def sink(self):
        """Where each cycle is logged. A sink with capture_fc(core) has the C core append
        the cycle's records itself (and, under the C poll, the /timing rows: Python then
        only cuts batches every _FLUSH_POLLS polls; under the Python poll one tick(timing...)
        call per cycle); any other sink gets fc_batch(records, pwm, status, timing)."""
        return self._sink

    @sink.setter
    def sink(self, sink) -> None:
        if self._tick is not None or self._flush is not None:
            self.core.bind_log(None)
        self._sink = sink
        self._tick = self._flush = self._fc_batch = None
        capture = getattr(sink, "capture_fc", None)
        if capture is None:
            self._fc_batch = sink.fc_batch if sink is not None else None
        elif self._cpoll is not None:
            self._flush = capture(self.core, timing=True)
            self._flush_in = _FLUSH_POLLS
        else:
            self._tick = capture(self.core)

    def _poll_c(self) -> int:
        n = self._cpoll()
        if n:
            if self.schedule is not None:
                self.schedule.after_batch(self)
            if self._flush is not None:
                self._flush_in -= 1
                if self._flush_in <= 0:
                    self._flush_in = _FLUSH_POLLS
                    self._flush()
            if self._fc_batch is not None:
                self._hand_on(n, self._iow[_IO_LAST_K], None)
            elif self.supervisor is not None:
                # _hand_on inlined: this is every poll of `fly`, and a Python frame costs
                # ~40 ns of a ~1.7 us poll.
                k = self._iow[_IO_LAST_K]
                if n < _SMALL and k < _SMALL:
                    self.supervisor.after_batch(self, self._recs[n], self._pwms[k],
                                                self._stats[k])
                else:
                    self.supervisor.after_batch(self, self.buf[:n], self._pwm_out[:k],
                                                self._status_out[:k])
        return n

    # -- polls made in C by the bridge's batch (`fly --processes 1` in lockstep) ----------
    def batch_poll(self):
        """The C poll for a caller that polls many steps in C without Python in between
        (BridgeLoop.bind_in_process_fc), or None when this loop's per-poll Python cannot be
        scheduled: no C poll, a per-cycle sink, or a supervisor or schedule without
        `next_due_ns()` (the sim time of the next poll whose after_batch acts)."""
        if self._cpoll is None or self._fc_batch is not None:
            return None
        parts = [p for p in (self.supervisor, self.schedule) if p is not None]
        self._due = [p.next_due_ns for p in parts if hasattr(p, "next_due_ns")]
        return self._cpoll if len(self._due) == len(parts) else None

    def python_due(self) -> tuple[float, int]:
        """(sim ns of the first step whose poll Python must follow, C polls allowed before
        the log's next batch cut): the caller ends its batch at the step that reaches either."""
        due = math.inf
        for next_due in self._due:
            t = next_due()
            if t < due:
                due = t
        return due, (self._flush_in if self._flush is not None else _NO_LIMIT)

    def promise_until(self, due_ns: float) -> None:
        """The C poll's FC_SYNC_NS (shm/lockstep.py) goes no later than due_ns, the sim time
        of the next poll Python follows; 0: every poll is followed (nothing promised), as
        outside the serve loop, where Python runs after each poll."""
        self._iow[_IO_SYNC_UNTIL] = _NEVER_NS if due_ns >= _NEVER_NS else max(0, math.ceil(due_ns))

    def after_c_polls(self, polls: int, last_n: int) -> None:
        """A caller made `polls` C polls (batch_poll) since the last call, the newest just now
        (it consumed last_n records): what _poll_c does after each, for the newest. The
        earlier ones owed Python nothing (python_due): the supervisor and schedule act only
        when due, and the log cuts its batches by count."""
        if polls <= 0:
            return
        if self.schedule is not None:
            self.schedule.after_batch(self)
        if self._flush is not None:
            self._flush_in -= polls
            if self._flush_in <= 0:
                self._flush_in = _FLUSH_POLLS
                self._flush()
        if self.supervisor is not None:
            self._hand_on(last_n, self._iow[_IO_LAST_K], None)

    def _hand_on(self, n: int, k: int, timing: tuple | None) -> None:
        """The per-cycle sink and the supervisor, on the batch just polled (n records in,
        k PWM out). timing: the /timing row, or None for the C poll's (in its words)."""
        if n < _SMALL and k < _SMALL:
            recs, pwm, status = self._recs[n], self._pwms[k], self._stats[k]
        else:
            recs, pwm, status = self.buf[:n], self._pwm_out[:k], self._status_out[:k]
        if self._fc_batch is not None:
            if timing is None:
                timing = tuple(self._iow[_IO_TIMING:_IO_TIMING_END])
            self._fc_batch(recs, pwm, status, timing)
        if self.supervisor is not None:
            self.supervisor.after_batch(self, recs, pwm, status)

    def _poll_py(self) -> int:
        n = self._pop_into(self.buf)
        if n == 0:
            return 0
        consume = monotonic_ns()
        k = self._step(n)
        i = (n - 1) * _I64_SLOT
        newest_sim = self._i64[i + _I64_SIM]
        newest_wall = self._i64[i + _I64_WALL]
        w = self._iow
        pwm_wall = 0
        if k:
            self._push_pwm(self._pwms[k] if k < _SMALL else self._pwm_out[:k])
            pwm_wall = monotonic_ns()
            w[_IO_PWM_PUBLISHED] += k
            self.e2e_ns.add(pwm_wall - newest_wall)
        if self._u16[(n - 1) * _U16_SLOT + _U16_FLAGS] & FLAG_STEP_END:
            w[_IO_LAST_SIM_NS] = newest_sim
            self._set_word(ls.FC_SIM_NS, newest_sim)
        self.latency_ns.add(consume - newest_wall)
        period = 0
        if self._prev_consume:
            period = consume - self._prev_consume
            self.period_ns.add(period)
        self._prev_consume = consume
        w[_IO_POLLS] += 1
        w[_IO_RECORDS] += n
        if self._tick is not None:
            self._tick(newest_sim, newest_wall, consume, pwm_wall, period)
        if self.schedule is not None:
            self.schedule.after_batch(self)
        if self._fc_batch is not None or self.supervisor is not None:
            self._hand_on(n, k, (newest_sim, newest_wall, consume, pwm_wall, period))
        return n

    def push_records(self, recs: np.ndarray) -> int:
        """Records of another kind the FC sends the bridge beside its PWM (FAULT, from the
        supervisor between polls): on the same actuator link, after the PWM published so far,
        so the bridge reads them at its next collection, in order."""
        return self._push_pwm(recs)

    def close(self) -> None:
        """Detach the C record router from the segment (before the segment closes); a
        poll after this raises."""
        if self._cpoll is not None:
            self.core.detach_router()

    def summary(self, nominal_period_ns: float | None = None) -> dict:
        """Latency and jitter figures (us) for the run summary."""
        periods = self.period_ns.values()
        if nominal_period_ns is None and len(periods):
            nominal_period_ns = float(np.median(periods))
        if len(periods) and nominal_period_ns:
            dev = np.abs(periods - nominal_period_ns) / 1e3
            jitter = {"p50": float(np.percentile(dev, 50)), "p99": float(np.percentile(dev, 99))}
        else:
            jitter = {"p50": None, "p99": None}
        return {
            "latency_us": self.latency_ns.percentiles_us(),
            "e2e_us": self.e2e_ns.percentiles_us(),
            "jitter_us": jitter,
            "polls": self.polls,
            "records": self.records,
            "pwm_published": self.pwm_published,
        }


class _NeverStop:
    requested = False
    name = None


# After its own Ctrl-C the FC keeps answering this long for the bridge's STOP (a terminal
# signals both processes; the bridge ends the run at its next step, so the last step is
# answered and the log is whole); alone (the bridge was not signalled) it then leaves.
STOP_GRACE_S = 1.0


def _served_in_c(loop: FcLoop):
    """serve(timeout_s) -> (polls, timed_out): in lockstep over shared memory, the FC's
    waits and C polls in one C loop (shm serve_polls), handing Python only the polls
    FcLoop.python_due names; None where the loop has no such poll (a HIL link, a per-cycle
    sink): run_fc then polls from Python. timed_out: no record came within timeout_s."""
    poll = loop.batch_poll()
    capsule = loop.seg.c_capsule() if poll is not None else None
    if capsule is None:
        return None

    def serve(timeout_s: float) -> tuple[int, bool]:
        due_ns, polls_left = loop.python_due()
        loop.promise_until(due_ns)
        polls, last_n, timed_out = serve_polls(capsule, poll, due_ns, polls_left, timeout_s,
                                               ls.HAND_ON_KINDS, loop.buf)
        loop.promise_until(0)
        loop.after_c_polls(polls, last_n)
        return polls, timed_out
    return serve


def run_fc(loop: FcLoop, *, wait_slice_s: float = 0.02, out=print, stop=_NeverStop,
           notices=None) -> dict:
    """Drive an FcLoop in its own process until the bridge says STOP.

    Returns the FC summary (with "interrupted": the signal that stopped this process, or
    "bridge" when the bridge's run was interrupted, else None). Raises FcLost when the
    bridge dies mid-run. stop: anything with `requested` and `name` (tools/loop/stop_signals.py).
    notices: a fc_sil.sim_notice.NoticeReader (the bridge's rate reports), polled when idle.
    """
    seg = loop.seg
    dt_ns = seg.word(ls.PHYSICS_DT_NS) or 1_000_000
    lockstep = seg.word(ls.RUN_MODE) == ls.MODE_LOCKSTEP
    if not lockstep:
        set_timer_slack_ns(1)   # wake on time when the ring wait sleeps

    # In lockstep the waits are the hand-off (shm/include/sb_handoff.h). In real time the
    # shm ring yields about two physics periods before it sleeps; HIL links block.
    wait = functools.partial(seg.sensors.wait, yield_s=max(2e-4, 2.0 * dt_ns / _NS))
    serve = _served_in_c(loop) if lockstep else None
    seg.set_word(ls.FC_STATE, ls.FC_STATE_READY)
    interrupted = None
    stop_deadline = None
    try:
        while True:
            if serve is not None:
                polls, timed_out = serve(wait_slice_s)
                if polls and not stop.requested:
                    continue
            elif loop.poll():
                seg.beat()
                if not stop.requested:
                    continue
            else:
                timed_out = None
            if stop.requested and stop_deadline is None:
                interrupted = stop.name
                stop_deadline = time.monotonic() + STOP_GRACE_S
            stop_word = seg.word(ls.STOP)
            if stop_word:
                # Drain what is left so the last step is answered.
                while loop.poll():
                    pass
                if notices is not None:     # the end figures, written before STOP
                    notices.poll(force=True)
                if stop_word == ls.STOP_INTERRUPTED and interrupted is None:
                    interrupted = "bridge"
                break
            if stop_deadline is not None and (time.monotonic() > stop_deadline
                                              or not seg.peer_alive()):
                while loop.poll():
                    pass
                seg.set_word(ls.FC_STOP, 1)   # the bridge stops too (PeerWatch)
                break
            if notices is not None:
                notices.poll()
            # Yield (not sleep) through about a physics period: a sleeping FC wakes
            # up to ~1 ms after its data, a yielding one within a microsecond or two.
            if serve is not None and not timed_out:
                continue
            if timed_out or not wait(wait_slice_s):
                seg.beat()
                if seg.word(ls.STOP):
                    continue
                if not seg.peer_alive():
                    raise FcLost("the bridge process is gone; the FC stops. Restart "
                                 "`silbridge bridge` (or use `silbridge fly`)")
        seg.set_word(ls.FC_STATE, ls.FC_STATE_DONE)
    except BaseException:
        seg.set_word(ls.FC_STOP, 1)
        seg.set_word(ls.FC_STATE, ls.FC_STATE_FAILED)
        raise
    # Jitter is judged against the median cycle: the nominal period in real time
    # (dt / speed), and the natural pace of the pair in lockstep.
    summary = loop.summary()
    summary["interrupted"] = interrupted
    return summary
