"""The bridge program's driver: start-up checks, then lockstep or real time.

`run_bridge` is what `silbridge bridge` and `silbridge fly` call. It drives the
bridge's loop (bridge/bridge_loop.py) one step at a time. With `fc_poll` given,
the FC lives in this process and is polled right after each publish (`fly
--processes 1`); otherwise it is a separate process watched through the segment
(pid, heartbeat, FC_STOP word).

A run, in named steps: the checks before the first step (`_checks_before_steps`),
the steps (`_Flight.fly`, which runs the checks of the first window, and in real
time judges each later one: `_Flight._judge_window`), then the run's account
(`_Flight.finish`, `_result`). The checks follow the paper's start-up procedure
(section 4.2, bridge/startup_checks.py); each is reported, and a failure stops
the run with the reason, except a real-time rate shortfall: that is a
measurement of the host, reported and counted while the run goes on
(bridge/rate_watch.py), unless `strict_rates` asks for the refusal.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

from silbridge.shm import lockstep as ls

from .bridge_loop import BATCH_MAX_STEPS, BridgeLoop, PeerWatch
from .errors import PeerLost, StartupCheckFailed
from .fault_records import fault_summary
from .pacing import Pacer
from .rate_watch import RateShortfall, RateWatch
from .startup_checks import (
    CheckResult,
    check_sim_step,
    first_window_checks,
    pwm_rate_hz,
    wait_attach,
)

_NS = 1_000_000_000
_MIN_JUDGED_NS = _NS // 4
# Two-process lockstep looks at the FC (alive, beating, not stopped) this often in wall time.
LOOK_WALL_NS = 20_000_000


@dataclass
class BridgeRunConfig:
    duration_s: float
    lockstep: bool = True
    speed: float = 1.0              # real time only: X times real time
    busy_wait: bool = False         # real time only: spin the whole period (bridge/pacing.py)
    attach_timeout_s: float = 15.0
    check_window_s: float = 1.0     # sim seconds observed by the start-up checks
    settle_s: float = 10.0          # summary errors are taken after this sim time
    rate_tolerance: float = 0.05    # +-5 % (paper 4.2 step 5)
    drop_tolerance: float = 0.005   # 0.5 % (paper 4.2 step 4)
    pwm_hz: float = 400.0
    trace_hash: bool = True         # off only for stress tests: hashing 2 MHz IMU costs ~100 us/step
    strict_rates: bool = False      # real time: a rate shortfall refuses the run (--strict-rates)
    report_every_s: float = 10.0    # wall seconds between two reports of a lasting shortfall


@dataclass
class BridgeResult:
    sim_s: float
    wall_s: float
    steps: int
    published: dict
    pwm_received: int
    pwm_hz: float
    ring: dict
    checks: list = field(default_factory=list)
    attitude_rms_deg: float | None = None
    altitude_rms_m: float | None = None
    trace_hash: str = ""
    crashed: bool = False
    late_steps: int = 0
    max_late_us: float = 0.0
    cpu_s: float = 0.0     # the bridge thread's CPU time in the loop (with an in-process FC: both)
    interrupted: str | None = None  # "SIGINT"/"SIGTERM" when a signal stopped the run early
    rates: dict = field(default_factory=dict)   # rates_summary(): achieved, late, degraded
    steps_in_c: int = 0    # steps run in C batches with the in-process FC (the rest per step)
    steps_overlapped: int = 0  # LoopStats.steps_overlapped: published without waiting for the FC
    link: dict = field(default_factory=dict)    # link faults' records delayed / dropped
    faults: dict = field(default_factory=dict)  # per unit: switches, FAULT records ({}: none)


class _NeverStop:
    requested = False
    name = None


def prepare_segment(seg, sim, cfg: BridgeRunConfig) -> None:
    """Words the FC reads at attach time; written before it can attach."""
    seg.set_word(ls.RUN_MODE, ls.MODE_LOCKSTEP if cfg.lockstep else ls.MODE_REALTIME)
    seg.set_word(ls.PHYSICS_DT_NS, sim.dt_ns)
    seg.set_word(ls.IMU_HZ, int(round(sim.imu_hz)))
    seg.set_word(ls.STOP, 0)


def run_bridge(sim, seg, cfg: BridgeRunConfig, *, fc_poll=None, peer_check=None, sink=None,
               out=print, stop=_NeverStop, notify=None, fc_loop=None) -> BridgeResult:
    """Run one flight; returns what the bridge measured. Raises a user-facing error on failure.

    stop: anything with a `requested` attribute (and `name`), read once per step; when it
    turns true the run ends at that step as if its duration were over, the FC is told
    (STOP = STOP_INTERRUPTED) and the result says `interrupted` (tools/loop/stop_signals.py).

    notify(text, fields): real time only, for the ground station: called with the
    STATUSTEXT of each reported rate shortfall and its figures, and once at the end with
    text None and the run's final figures (rates_summary). The bridge has no MAVLink: the
    caller passes them to the FC's vehicle.

    fc_loop: the in-process FcLoop whose poll fc_poll is: in lockstep its C poll then runs
    inside the bridge's batches of steps in C (_Flight.fly_batched), same trace.
    """
    loop = BridgeLoop(sim, seg, sink=sink, settle_s=cfg.settle_s,
                      trace=cfg.trace_hash)
    checks, attached = _checks_before_steps(loop, cfg, fc_poll, peer_check, out, stop)
    if not attached:
        seg.set_word(ls.STOP, ls.STOP_INTERRUPTED)
        res = _result(loop, cfg, checks, 0, None)
        res.interrupted = stop.name
        return res
    flight = _Flight(loop, cfg, checks, fc_poll=fc_poll, peer_check=peer_check, sink=sink,
                     out=out, stop=stop, notify=notify)
    batched = (fc_loop is not None and cfg.lockstep
               and loop.bind_in_process_fc(fc_loop.batch_poll()))
    batched_p2 = (not batched and fc_poll is None and cfg.lockstep
                  and loop.bind_fc_process())
    try:
        if batched:
            flight.fly_batched(fc_loop)
        elif batched_p2:
            flight.fly_batched_own_fc()
        else:
            flight.fly()
        rates = flight.finish()
    finally:
        seg.set_word(ls.STOP, ls.STOP_INTERRUPTED if flight.interrupted or stop.requested
                     else 1)
    cpu_s = time.thread_time() - flight.cpu0
    if fc_poll is None:
        _wait_fc_done(seg, peer_check)
    res = _result(loop, cfg, checks, flight.wall_ns, flight.pacer)
    res.cpu_s = cpu_s
    res.interrupted = flight.interrupted
    res.rates = rates
    res.steps_in_c = flight.steps_in_c
    res.steps_overlapped = loop.stats.steps_overlapped
    return res


def _checks_before_steps(loop: BridgeLoop, cfg: BridgeRunConfig, fc_poll, peer_check, out,
                         stop) -> tuple[list[CheckResult], bool]:
    """The sim-step check, then (an FC in another process) the wait for it to attach.
    Returns the checks so far and whether the run goes on (False: a stop came first)."""
    checks = [check_sim_step(loop.sim)]
    out(checks[-1].line())
    if not checks[-1].ok:
        raise StartupCheckFailed(f"{checks[-1].detail}: choose an IMU rate that is a whole "
                                 f"multiple of the physics rate")
    if fc_poll is None:
        attached = wait_attach(loop.seg, cfg, peer_check, stop)
        if attached is None:
            return checks, False
        checks.append(attached)
        out(checks[-1].line())
    return checks, True


class _Flight:
    """The steps of one run after start-up, and what they share: how many steps, when to
    look at the FC and the rates, the pacer and rate watch of real time, the first window's
    checks. `fly` is the per-step loop; `finish` its account."""

    def __init__(self, loop: BridgeLoop, cfg: BridgeRunConfig, checks: list, *, fc_poll,
                 peer_check, sink, out, stop, notify):
        sim, seg = loop.sim, loop.seg
        self.loop, self.cfg, self.checks = loop, cfg, checks
        self.fc_poll, self.sink, self.out, self.stop, self.notify = (fc_poll, sink, out, stop,
                                                                     notify)
        self.peer = PeerWatch(seg, extra_check=peer_check) if fc_poll is None else None
        # duration inf: real time until stopped (Ctrl-C / SIGTERM / a crash).
        self.steps = range(1, int(round(cfg.duration_s * _NS / sim.dt_ns)) + 1) \
            if math.isfinite(cfg.duration_s) else itertools.count(1)
        # The rate checks need a window long on the wall clock too: at --speed 8 one sim
        # second is 125 ms of wall time, where a single scheduler hiccup moves a rate by 5 %.
        window_s = cfg.check_window_s * (1.0 if cfg.lockstep else max(1.0, cfg.speed))
        self.check_step = max(1, int(round(window_s * _NS / sim.dt_ns)))
        self.watch_every = max(1, int(0.02 * _NS / sim.dt_ns))       # ~20 ms of sim time
        self.pacer = None if cfg.lockstep else Pacer(sim.dt_ns, cfg.speed,
                                                     busy_wait=cfg.busy_wait)
        # Real time judges its windows on the wall clock: on a host too slow for --speed the
        # sim-time window above would take far longer than the one wall second it stands for.
        self.window_wall_ns = int(window_s / max(cfg.speed, 1e-9) * _NS)
        self.watch = None if cfg.lockstep else RateWatch(sim.imu_hz, cfg.pwm_hz,
                                                         cfg.rate_tolerance, cfg.report_every_s)
        self.window = None      # real time: (wall_ns, imu count, pwm count) at the last window
        self.lag_ns = late_lag_ns(seg, sim)
        self.interrupted = None     # the stop's name when a stop ended the run
        self.steps_in_c = 0         # fly_batched: steps the C batches finished
        self.t0 = 0
        self.cpu0 = 0.0
        self.wall_ns = 0

    def fly(self) -> None:
        """Every step until the duration, a stop or a crash. The FC answers each step in
        this process (fc_poll), or in its own: waited for in lockstep, given until shortly
        before the next deadline in real time."""
        loop, cfg, sim, seg = self.loop, self.cfg, self.loop.sim, self.loop.seg
        stop, out, fc_poll, pacer, peer = self.stop, self.out, self.fc_poll, self.pacer, self.peer
        watch_every, check_step, lag_ns = self.watch_every, self.check_step, self.lag_ns
        self.t0 = time.monotonic_ns()
        self.cpu0 = time.thread_time()
        if pacer is not None:
            pacer.start_ns = self.t0
        # Locals, not attribute lookups, in the per-step loop (a few hundred ns a step).
        publish, collect, word = loop.publish_step, loop.collect_pwm, seg.word
        in_process_lockstep = fc_poll is not None and cfg.lockstep
        for k in self.steps:
            if stop.requested:
                self._stopped()
                break
            if pacer is not None:
                late_ns = pacer.wait_for_step(k)
            publish()
            if in_process_lockstep:
                fc_poll()
                collect()
                if word(ls.FC_SIM_NS) < sim.sim_ns:
                    raise PeerLost("the in-process FC did not answer a lockstep step")
            elif fc_poll is not None:
                fc_poll()
                collect()
            elif cfg.lockstep:
                _wait_lockstep(loop, peer)
            else:
                _wait_realtime(loop, pacer, late_ns, lag_ns)
            if k % watch_every == 0:
                self._look()
            if cfg.lockstep and k == check_step:
                self.checks.extend(first_window_checks(loop, cfg, time.monotonic_ns() - self.t0,
                                                       out, None))
            if sim.crashed and sim.end_on_crash:
                out(f"vehicle crashed at t={sim.sim_ns / _NS:.3f} s; run stopped")
                break

    def fly_batched(self, fc) -> None:
        """fly() for an FC in this process in lockstep: the steps run in batches in C
        (BridgeLoop.run_batch), each batch ending where Python has work: a step the kernel
        flags (Python's part of it done in Simulator.step_batch), the FC's due polls
        (fc.python_due), the first window's checks, the duration. A stop is seen between
        batches (at most BATCH_MAX_STEPS steps, ~1 ms); a crash is flagged by the kernel, so
        it ends its batch and the run at the crashing step."""
        loop, sim, fc_poll = self.loop, self.loop.sim, self.fc_poll

        def answer() -> None:
            fc_poll()
            loop.collect_pwm()
            if loop.seg.word(ls.FC_SIM_NS) < sim.sim_ns:
                raise PeerLost("the in-process FC did not answer a lockstep step")

        def batch(k, last) -> None:
            if loop.in_python_next():       # a link fault (bridge/link_faults.py)
                loop.step_one(answer)
                return
            self.steps_in_c += loop.run_batch(self._batch_len(k, last, fc))
            fc.after_c_polls(*loop.batch_polls())
        self._fly_batches(batch)

    def fly_batched_own_fc(self) -> None:
        """fly() for an FC in its own process in lockstep: the steps run in batches in C, each
        step waiting there for the FC's answer (BridgeLoop.bind_fc_process), each batch ending
        at the first window's checks or the duration, or after BATCH_MAX_STEPS. The FC is
        looked at (PeerWatch) after the batch that ends LOOK_WALL_NS of wall time after the
        last look: a look every 20 ms of sim time, as the per-step loop does, would end a
        batch every 20 steps, a quarter of a millisecond at 80x real time, and its Python
        cost ~1 us a step. A dead FC is still found within a wait's slice: a step it does not
        answer ends the batch, and _wait_lockstep looks at it while it waits. The FC's own
        Python is its process's business."""
        loop, sim, every = self.loop, self.loop.sim, self.watch_every

        def batch(k, last) -> None:
            if loop.in_python_next():       # a link fault (bridge/link_faults.py), step by step
                loop.step_one(lambda: _wait_lockstep(loop, self.peer))
                if sim.step_index % every == 0:
                    self._look()
                return
            n = min(BATCH_MAX_STEPS, last - k + 1)
            if k <= self.check_step:
                n = min(n, self.check_step - k + 1)
            self.steps_in_c += loop.run_batch(n)
            if loop.fc_pending:
                loop.fc_pending = False
                _wait_lockstep(loop, self.peer)
            now = time.monotonic_ns()
            if now - self._looked_ns >= LOOK_WALL_NS:
                self._looked_ns = now
                self._look()
        self._looked_ns = time.monotonic_ns()
        self._fly_batches(batch)

    def _fly_batches(self, batch) -> None:
        """The batched loop of both FC placements: `batch(k, last)` runs one batch from step
        k; between batches a stop request, the first window's checks and a crash are seen."""
        loop, cfg, sim, stop = self.loop, self.cfg, self.loop.sim, self.stop
        last = self.steps[-1] if isinstance(self.steps, range) else math.inf
        self.t0 = time.monotonic_ns()
        self.cpu0 = time.thread_time()
        k = 1
        while k <= last:
            if stop.requested:
                self._stopped()
                break
            batch(k, last)
            k = sim.step_index + 1
            if sim.step_index == self.check_step:
                self.checks.extend(first_window_checks(loop, cfg, time.monotonic_ns() - self.t0,
                                                       self.out, None))
            if sim.crashed and sim.end_on_crash:
                self.out(f"vehicle crashed at t={sim.sim_ns / _NS:.3f} s; run stopped")
                break

    def _batch_len(self, k: int, last, fc) -> int:
        """Steps from step k the next batch may take: it ends at the first step whose end
        Python must see. (In-process lockstep has no peer to watch nor rates to judge:
        fly()'s 20 ms look is empty here.)"""
        dt = self.loop.sim.dt_ns
        n = min(BATCH_MAX_STEPS, last - k + 1)
        if k <= self.check_step:
            n = min(n, self.check_step - k + 1)
        due_ns, polls = fc.python_due()
        if due_ns < (k + n - 1) * dt:
            n = max(1, min(n, -(-int(due_ns) // dt) - k + 1))
        return max(1, min(n, polls))

    def _stopped(self) -> None:
        """A stop was requested: say where, in the output and the log."""
        sim_ns = self.loop.sim.sim_ns
        self.interrupted = self.stop.name
        self.out(f"{self.interrupted or 'stop'}: run stopped at t={sim_ns / _NS:.3f} s")
        if self.sink is not None:
            self.sink.event(sim_ns, "stop", f"interrupted by {self.interrupted}")

    def _look(self) -> None:
        """Every ~20 ms of sim time: is the FC in its own process alive (and we beat for it);
        in real time, has a rate window ended."""
        if self.peer is not None:
            self.peer.check()
            self.loop.seg.beat()
        if self.watch is not None:
            self._judge_window(time.monotonic_ns())

    def _judge_window(self, now: int) -> None:
        """Real time: the start-up checks at the end of the first window, then each later
        window judged by the rate watch."""
        loop, t0 = self.loop, self.t0
        if self.window is None and now - t0 >= self.window_wall_ns:
            self.checks.extend(first_window_checks(loop, self.cfg, now - t0, self.out,
                                                   self.watch))
            self.window = _window_mark(loop, now)
            if not self.checks[-2].ok:       # rates: say it now, to all
                self._report(now - t0, self.window, None, first=True)
        elif self.window is not None and now - self.window[0] >= self.window_wall_ns:
            mark = _window_mark(loop, now)
            self._report(now - t0, mark, self.window)
            self.window = mark

    def _report(self, wall_ns: int, mark, prev, first: bool = False) -> None:
        """Judge the window prev -> mark (or, first, report the start-up window's shortfall)
        and report a shortfall when the watch says one is due."""
        loop, cfg, sink, notify = self.loop, self.cfg, self.sink, self.notify
        if first:       # the start-up window: the figures its check printed
            span_s = max(wall_ns, 1) / _NS * cfg.speed
            imu_hz, pwm_hz = mark[1] / span_s, pwm_rate_hz(loop, cfg)
        else:
            span_s = max(mark[0] - prev[0], 1) / _NS * cfg.speed
            imu_hz, pwm_hz = (mark[1] - prev[1]) / span_s, (mark[2] - prev[2]) / span_s
        short = self.watch.judge(imu_hz, pwm_hz, wall_ns / _NS)
        if short is None:
            return
        fields = _short_fields(short, self.pacer)
        if not first:       # the start-up check's own line already said it
            self.out(short.line())
        if sink is not None and hasattr(sink, "event"):     # a bare PWM sink has no events
            sink.event(loop.sim.sim_ns, "rates", short.line(), **fields)
        if notify is not None:
            notify(short.statustext(), fields)

    def finish(self) -> dict:
        """After the last step: the wall time, the pacer's last late stretch closed, and the
        run's rates (rates_summary), handed to notify before the FC is told to stop."""
        wall_ns = self.wall_ns = time.monotonic_ns() - self.t0
        if self.pacer is not None:
            self.pacer.finish(self.t0 + wall_ns)
        # A run shorter than the window is judged whole once it lasted long enough that a
        # scheduler hiccup (~10 ms) cannot make a 5 % shortfall.
        rates = rates_summary(self.loop, self.cfg, wall_ns, self.pacer, self.watch,
                              judged=self.window is not None or wall_ns >= _MIN_JUDGED_NS)
        if self.notify is not None and self.watch is not None:
            self.notify(None, rates)     # before STOP: the FC logs them before it closes its log
        return rates


def _window_mark(loop: BridgeLoop, now_ns: int) -> tuple[int, int, int]:
    return now_ns, loop.sim.published_counts()["imu"], loop.stats.pwm_received


def _short_fields(short: RateShortfall, pacer) -> dict:
    return {"imu_hz": short.imu_hz, "pwm_hz": short.pwm_hz, "want_imu_hz": short.imu_want_hz,
            "want_pwm_hz": short.pwm_want_hz,
            "late_steps": pacer.late_steps if pacer is not None else 0}


def rates_summary(loop: BridgeLoop, cfg: BridgeRunConfig, wall_ns: int, pacer,
                  watch: RateWatch | None, judged: bool = True) -> dict:
    """The run's "rates" (summary, log, soak): achieved IMU and PWM in sim-time Hz over the
    whole run, late steps, the worst late stretch (wall seconds, from sim time ..._at_s) and
    whether it was degraded: a window, or the whole run once it lasted a window, short."""
    scale = 1.0 if cfg.lockstep else cfg.speed
    span_s = max(loop.sim.sim_ns if cfg.lockstep else wall_ns, 1) / _NS * scale
    imu_hz = loop.sim.published_counts()["imu"] / span_s
    pwm_hz = pwm_rate_hz(loop, cfg)
    degraded = False
    if watch is not None:
        if judged and watch.shortfall(imu_hz, pwm_hz) is not None:
            watch.degraded = True
        degraded = watch.degraded
    dt_s = loop.sim.dt_ns / _NS
    return {
        "imu_hz": imu_hz, "pwm_hz": pwm_hz,
        "want_imu_hz": loop.sim.imu_hz, "want_pwm_hz": cfg.pwm_hz,
        "late_steps": pacer.late_steps if pacer is not None else 0,
        "max_late_us": pacer.max_late_ns / 1e3 if pacer is not None else 0.0,
        "worst_stretch_s": pacer.worst_stretch_ns / _NS if pacer is not None else 0.0,
        "worst_stretch_at_s": pacer.worst_stretch_step * dt_s if pacer is not None else 0.0,
        "degraded": degraded,
        "reports": watch.reports if watch is not None else 0,
    }


def _wait_lockstep(loop: BridgeLoop, watch: PeerWatch, slice_s: float = 0.02) -> None:
    seg = loop.seg
    target = loop.sim.sim_ns
    while not seg.wait_word(ls.FC_SIM_NS, target, slice_s):
        watch.check()
    loop.collect_pwm()


# Behind schedule, the bridge lets the FC lag by up to this share of the sensor ring before it
# waits for it (at most LATE_WAIT_S a step; links without a ring: LATE_LAG_MIN_STEPS).
LATE_LAG_RING_SHARE = 8
LATE_LAG_MIN_STEPS = 8
LATE_WAIT_S = 0.02


def late_lag_ns(seg, sim) -> int:
    """How far (sim ns) the FC may trail a bridge that is behind schedule: an eighth of the
    sensor ring at this run's records per step, so the ring never overflows."""
    per_step = sim.imu_hz * sim.dt_ns / _NS + 4        # IMU samples + baro/mag/GNSS/truth
    slots = getattr(seg.sensors, "capacity", 0) or 0
    steps = max(LATE_LAG_MIN_STEPS, int(slots / LATE_LAG_RING_SHARE / per_step))
    return steps * sim.dt_ns


def _wait_realtime(loop: BridgeLoop, pacer: Pacer, late_ns: int, lag_ns: int) -> None:
    """On time: give the FC until shortly before the next deadline to answer; never longer.
    Already a period behind (a host too slow for --speed): no deadline is left to keep, so
    the bridge keeps the FC within lag_ns (late_lag_ns) instead of letting it fall a ring
    behind (the drops check): a slow host then flies slower, as ArduCopter SITL does, not
    lossy."""
    if late_ns <= pacer.period_ns:
        loop.seg.wait_word(ls.FC_SIM_NS, loop.sim.sim_ns, pacer.period_ns * 0.5 / _NS)
    else:
        loop.seg.wait_word(ls.FC_SIM_NS, max(0, loop.sim.sim_ns - lag_ns), LATE_WAIT_S)
    loop.collect_pwm()


def _wait_fc_done(seg, peer_check, timeout_s: float = 3.0) -> None:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        if seg.word(ls.FC_STATE) in (ls.FC_STATE_DONE, ls.FC_STATE_FAILED):
            return
        if peer_check is not None and not peer_check():
            return
        time.sleep(0.005)


def _result(loop: BridgeLoop, cfg: BridgeRunConfig, checks, wall_ns: int, pacer) -> BridgeResult:
    sim = loop.sim
    st = loop.stats
    sim_s = sim.sim_ns / _NS
    wall_s = wall_ns / _NS
    pwm_hz = pwm_rate_hz(loop, cfg)
    ring = {"sensors": loop.seg.sensors.stats(), "actuators": loop.seg.actuators.stats()}
    return BridgeResult(
        sim_s=sim_s, wall_s=wall_s, steps=sim.step_index, published=sim.published_counts(),
        pwm_received=st.pwm_received, pwm_hz=pwm_hz, ring=ring, checks=checks,
        attitude_rms_deg=loop.attitude_rms_deg(), altitude_rms_m=loop.altitude_rms_m(),
        trace_hash=loop.trace_hash(), crashed=bool(sim.crashed),
        late_steps=pacer.late_steps if pacer else 0,
        max_late_us=pacer.max_late_ns / 1e3 if pacer else 0.0, link=loop.link.counts(),
        faults=fault_summary(sim.faults, loop.fault_records))
