"""The bridge program's driver: start-up checks, then lockstep or real time.

`run_bridge` is what `silbridge bridge` and `silbridge fly` call. With
`fc_poll` given, the FC lives in this process and is polled right after each
publish (`fly --processes 1`); otherwise it is a separate process watched
through the segment (pid, heartbeat, FC_STOP word).

Start-up follows the paper (section 4.2): the simulation step is consistent,
the FC attaches, the counters move, IMU and PWM rates are within +-5 %, and
drops/overwrites stay below 0.5 %. Each check is reported; a failure stops
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

from .pacing import Pacer
from .rate_watch import RateShortfall, RateWatch
from .runner import BridgeLoop, PeerWatch
from .runner_errors import PeerLost, StartupCheckFailed

_NS = 1_000_000_000
_MIN_JUDGED_NS = _NS // 4


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
class CheckResult:
    name: str
    ok: bool
    detail: str
    warn_only: bool = False     # failed, but the run goes on (a real-time rate shortfall)

    def line(self) -> str:
        verdict = "ok" if self.ok else ("SHORT" if self.warn_only else "FAILED")
        return f"check {self.name:<10} {verdict}  {self.detail}"


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


class _NeverStop:
    requested = False
    name = None


def prepare_segment(seg, sim, cfg: BridgeRunConfig) -> None:
    """Words the FC reads at attach time; written before it can attach."""
    seg.set_word(ls.RUN_MODE, ls.MODE_LOCKSTEP if cfg.lockstep else ls.MODE_REALTIME)
    seg.set_word(ls.PHYSICS_DT_NS, sim.dt_ns)
    seg.set_word(ls.IMU_HZ, int(round(sim.imu_hz)))
    seg.set_word(ls.STOP, 0)


def check_sim_step(sim) -> CheckResult:
    dt_ns = sim.dt_ns
    per_step = sim.imu_hz * dt_ns / _NS
    ok = dt_ns > 0 and abs(per_step - round(per_step)) < 1e-9 and round(per_step) >= 1
    return CheckResult("sim step", ok,
                       f"physics dt {dt_ns / 1e6:g} ms, {per_step:g} IMU samples per step")


def wait_attach(seg, cfg: BridgeRunConfig, peer_check=None, out=print,
                stop=_NeverStop) -> CheckResult | None:
    """Wait for the FC; None if a stop was requested meanwhile."""
    t0 = time.monotonic()
    while seg.word(ls.FC_STATE) != ls.FC_STATE_READY:
        if stop.requested:
            return None
        if seg.word(ls.FC_STOP) or seg.word(ls.FC_STATE) == ls.FC_STATE_FAILED:
            raise PeerLost("the FC failed while starting (see its messages)")
        if peer_check is not None and not peer_check():
            raise PeerLost("the FC process exited while starting (see its messages)")
        if time.monotonic() - t0 > cfg.attach_timeout_s:
            raise StartupCheckFailed(
                f"no FC attached within {cfg.attach_timeout_s:g} s: start `silbridge fc "
                f"--instance NAME` with the same instance name, or use `silbridge fly`")
        seg.wait_word(ls.FC_STATE, ls.FC_STATE_READY, 0.02)
    return CheckResult("attach", True, f"FC pid {seg.peer_pid} ready after "
                                       f"{time.monotonic() - t0:.2f} s")


def window_checks(loop: BridgeLoop, cfg: BridgeRunConfig, window_wall_ns: int,
                  window_sim_ns: int) -> list[CheckResult]:
    """Counters, rates and drops over the first check window (paper 4.2 steps 4, 5)."""
    seg = loop.seg
    s_stats = seg.sensors.stats()
    a_stats = seg.actuators.stats()
    checks = [CheckResult(
        "counters", s_stats["read"] > 0 and a_stats["written"] > 0,
        f"sensor ring written {s_stats['written']} read {s_stats['read']}, "
        f"actuator ring written {a_stats['written']} read {a_stats['read']}")]
    # Lockstep runs on sim time by construction; real time is judged on the wall
    # clock, scaled by --speed so every rate reads in sim-time Hz.
    scale = 1.0 if cfg.lockstep else cfg.speed
    span_s = max(window_sim_ns if cfg.lockstep else window_wall_ns, 1) / _NS * scale
    imu_rate = loop.sim.published_counts()["imu"] / span_s
    ok_imu = abs(imu_rate / loop.sim.imu_hz - 1.0) <= cfg.rate_tolerance
    pwm_rate = pwm_rate_hz(loop, cfg)
    ok_pwm = abs(pwm_rate / cfg.pwm_hz - 1.0) <= cfg.rate_tolerance
    checks.append(CheckResult("rates", ok_imu and ok_pwm,
                              f"IMU {imu_rate:.1f} Hz (want {loop.sim.imu_hz:g}), "
                              f"PWM {pwm_rate:.1f} Hz (want {cfg.pwm_hz:g}), +-"
                              f"{cfg.rate_tolerance * 100:g} %"))
    lost = (s_stats["overwritten"] + s_stats["rejected"] + a_stats["overwritten"]
            + a_stats["rejected"])
    total = max(s_stats["written"] + a_stats["written"], 1)
    ratio = lost / total
    checks.append(CheckResult("drops", ratio < cfg.drop_tolerance,
                              f"overwritten+rejected {lost} of {total} ({ratio * 100:.3f} %)"))
    return checks


def pwm_rate_hz(loop: BridgeLoop, cfg: BridgeRunConfig) -> float:
    """PWM rate seen by the bridge in sim-time Hz (timestamps of the PWM records)."""
    st = loop.stats
    if st.pwm_received < 2:
        return 0.0
    if cfg.lockstep:
        span_s = (st.pwm_last_sim_ns - st.pwm_first_sim_ns) / _NS
    else:
        span_s = (st.pwm_last_wall_ns - st.pwm_first_wall_ns) / _NS * cfg.speed
    return (st.pwm_received - 1) / max(span_s, 1e-9)


def run_bridge(sim, seg, cfg: BridgeRunConfig, *, fc_poll=None, peer_check=None, sink=None,
               out=print, stop=_NeverStop, notify=None) -> BridgeResult:
    """Run one flight; returns what the bridge measured. Raises a user-facing error on failure.

    stop: anything with a `requested` attribute (and `name`), read once per step; when it
    turns true the run ends at that step as if its duration were over, the FC is told
    (STOP = STOP_INTERRUPTED) and the result says `interrupted` (tools/loop/stop_signals.py).

    notify(text, fields): real time only, for the ground station: called with the
    STATUSTEXT of each reported rate shortfall and its figures, and once at the end with
    text None and the run's final figures (rates_summary). The bridge has no MAVLink: the
    caller passes them to the FC's vehicle.
    """
    loop = BridgeLoop(sim, seg, sink=sink, settle_s=cfg.settle_s,
                      trace=cfg.trace_hash)
    checks = [check_sim_step(sim)]
    out(checks[-1].line())
    if not checks[-1].ok:
        raise StartupCheckFailed(f"{checks[-1].detail}: choose an IMU rate that is a whole "
                                 f"multiple of the physics rate")
    if fc_poll is None:
        attached = wait_attach(seg, cfg, peer_check, out, stop)
        if attached is None:
            seg.set_word(ls.STOP, ls.STOP_INTERRUPTED)
            res = _result(loop, cfg, checks, 0, None)
            res.interrupted = stop.name
            return res
        checks.append(attached)
        out(checks[-1].line())
    peer = PeerWatch(seg, extra_check=peer_check) if fc_poll is None else None

    # duration inf: real time until stopped (Ctrl-C / SIGTERM / a crash).
    steps = range(1, int(round(cfg.duration_s * _NS / sim.dt_ns)) + 1) \
        if math.isfinite(cfg.duration_s) else itertools.count(1)
    # The rate checks need a window long on the wall clock too: at --speed 8 one sim
    # second is 125 ms of wall time, where a single scheduler hiccup moves a rate by 5 %.
    window_s = cfg.check_window_s if cfg.lockstep else cfg.check_window_s * max(1.0, cfg.speed)
    check_step = max(1, int(round(window_s * _NS / sim.dt_ns)))
    watch_every = max(1, int(0.02 * _NS / sim.dt_ns))       # ~20 ms of sim time
    pacer = None if cfg.lockstep else Pacer(sim.dt_ns, cfg.speed, busy_wait=cfg.busy_wait)
    # Real time judges its windows on the wall clock: on a host too slow for --speed the
    # sim-time window above would take far longer than the one wall second it stands for.
    window_wall_ns = int(window_s / max(cfg.speed, 1e-9) * _NS)
    watch = None if cfg.lockstep else RateWatch(sim.imu_hz, cfg.pwm_hz, cfg.rate_tolerance,
                                                cfg.report_every_s)
    window = None           # real time: (wall_ns, imu count, pwm count) at the last window
    lag_ns = late_lag_ns(seg, sim)
    t0 = time.monotonic_ns()
    cpu0 = time.thread_time()
    if pacer is not None:
        pacer.start_ns = t0
    # Locals, not attribute lookups, in the per-step loop (a few hundred ns a step).
    publish, collect, word = loop.publish_step, loop.collect_pwm, seg.word
    in_process_lockstep = fc_poll is not None and cfg.lockstep
    interrupted = None
    try:
        for k in steps:
            if stop.requested:
                interrupted = stop.name
                out(f"{interrupted or 'stop'}: run stopped at t={sim.sim_ns / _NS:.3f} s")
                if sink is not None:
                    sink.event(sim.sim_ns, "stop", f"interrupted by {interrupted}")
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
                if peer is not None:
                    peer.check()
                    seg.beat()
                if watch is not None:
                    now = time.monotonic_ns()
                    if window is None and now - t0 >= window_wall_ns:
                        checks.extend(_startup_checks(loop, cfg, now - t0, out, watch))
                        window = _window_mark(loop, now)
                        if not checks[-2].ok:       # rates: say it now, to all
                            _report(loop, cfg, now - t0, window, None, watch, out, sink,
                                    notify, pacer, first=True)
                    elif window is not None and now - window[0] >= window_wall_ns:
                        mark = _window_mark(loop, now)
                        _report(loop, cfg, now - t0, mark, window, watch, out, sink, notify,
                                pacer)
                        window = mark
            if cfg.lockstep and k == check_step:
                checks.extend(_startup_checks(loop, cfg, time.monotonic_ns() - t0, out, None))
            if sim.crashed:
                out(f"vehicle crashed at t={sim.sim_ns / _NS:.3f} s; run stopped")
                break
        wall_ns = time.monotonic_ns() - t0
        if pacer is not None:
            pacer.finish(t0 + wall_ns)
        # A run shorter than the window is judged whole once it lasted long enough that a
        # scheduler hiccup (~10 ms) cannot make a 5 % shortfall.
        rates = rates_summary(loop, cfg, wall_ns, pacer, watch,
                              judged=window is not None or wall_ns >= _MIN_JUDGED_NS)
        if notify is not None and watch is not None:
            notify(None, rates)     # before STOP: the FC logs them before it closes its log
    finally:
        seg.set_word(ls.STOP, ls.STOP_INTERRUPTED if interrupted or stop.requested else 1)
    cpu_s = time.thread_time() - cpu0
    if fc_poll is None:
        _wait_fc_done(seg, peer_check)
    res = _result(loop, cfg, checks, wall_ns, pacer)
    res.cpu_s = cpu_s
    res.interrupted = interrupted
    res.rates = rates
    return res


def _startup_checks(loop: BridgeLoop, cfg: BridgeRunConfig, wall_ns: int, out,
                    watch: RateWatch | None) -> list[CheckResult]:
    """The window checks at the end of the first window: printed, and a failure raised,
    but a real-time rate shortfall only warned (unless cfg.strict_rates)."""
    new = window_checks(loop, cfg, wall_ns, loop.sim.sim_ns)
    rates = new[1]
    if not rates.ok and watch is not None and not cfg.strict_rates:
        rates.warn_only = True
    for c in new:
        out(c.line())
    bad = [c for c in new if not c.ok and not c.warn_only]
    if bad:
        raise StartupCheckFailed(f"start-up check '{bad[0].name}' failed: {bad[0].detail}")
    return new


def _window_mark(loop: BridgeLoop, now_ns: int) -> tuple[int, int, int]:
    return now_ns, loop.sim.published_counts()["imu"], loop.stats.pwm_received


def _report(loop, cfg, wall_ns, mark, prev, watch: RateWatch, out, sink, notify, pacer,
            first: bool = False) -> None:
    """Judge the window prev -> mark (or, first, report the start-up window's shortfall)
    and report a shortfall when the watch says one is due."""
    if first:       # the start-up window: the figures its check printed
        span_s = max(wall_ns, 1) / _NS * cfg.speed
        imu_hz, pwm_hz = mark[1] / span_s, pwm_rate_hz(loop, cfg)
    else:
        span_s = max(mark[0] - prev[0], 1) / _NS * cfg.speed
        imu_hz, pwm_hz = (mark[1] - prev[1]) / span_s, (mark[2] - prev[2]) / span_s
    short = watch.judge(imu_hz, pwm_hz, wall_ns / _NS)
    if short is None:
        return
    fields = _short_fields(short, pacer)
    if not first:       # the start-up check's own line already said it
        out(short.line())
    if sink is not None and hasattr(sink, "event"):     # a bare PWM sink has no events
        sink.event(loop.sim.sim_ns, "rates", short.line(), **fields)
    if notify is not None:
        notify(short.statustext(), fields)


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
        max_late_us=pacer.max_late_ns / 1e3 if pacer else 0.0)
