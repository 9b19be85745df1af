"""The bridge program's driver: start-up checks, then lockstep or real time.

`run_bridge` is what `silbridge bridge` and `silbridge fly` call. With
`fc_poll` given, the FC lives in this process and is polled right after each
publish (`fly --processes 1`); otherwise it is a separate process watched
through the segment (pid, heartbeat, FC_STOP word).

Start-up follows the paper (section 4.2): the simulation step is consistent,
the FC attaches, the counters move, IMU and PWM rates are within +-5 %, and
drops/overwrites stay below 0.5 %. Each check is reported; a failure stops
the run with the reason.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

from silbridge.shm import lockstep as ls

from .pacing import Pacer
from .runner import BridgeLoop, PeerWatch
from .runner_errors import PeerLost, StartupCheckFailed

_NS = 1_000_000_000


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


@dataclass
class CheckResult:
    name: str
    ok: bool
    detail: str

    def line(self) -> str:
        return f"check {self.name:<10} {'ok' if self.ok else 'FAILED'}  {self.detail}"


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
               out=print, stop=_NeverStop) -> BridgeResult:
    """Run one flight; returns what the bridge measured. Raises a user-facing error on failure.

    stop: anything with a `requested` attribute (and `name`), read once per step; when it
    turns true the run ends at that step as if its duration were over, the FC is told
    (STOP = STOP_INTERRUPTED) and the result says `interrupted` (tools/loop/stop_signals.py).
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
    watch = PeerWatch(seg, extra_check=peer_check) if fc_poll is None else None

    # duration inf: real time until stopped (Ctrl-C / SIGTERM / a crash).
    steps = range(1, int(round(cfg.duration_s * _NS / sim.dt_ns)) + 1) \
        if math.isfinite(cfg.duration_s) else itertools.count(1)
    # The rate checks need a window long on the wall clock too: at --speed 8 one sim
    # second is 125 ms of wall time, where a single scheduler hiccup moves a rate by 5 %.
    window_s = cfg.check_window_s if cfg.lockstep else cfg.check_window_s * max(1.0, cfg.speed)
    check_step = max(1, int(round(window_s * _NS / sim.dt_ns)))
    watch_every = max(1, int(0.02 * _NS / sim.dt_ns))       # ~20 ms of sim time
    pacer = None if cfg.lockstep else Pacer(sim.dt_ns, cfg.speed, busy_wait=cfg.busy_wait)
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
                pacer.wait_for_step(k)
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
                _wait_lockstep(loop, watch)
            else:
                _wait_realtime(loop, pacer, k)
            if watch is not None and k % watch_every == 0:
                watch.check()
                seg.beat()
            if k == check_step:
                new = window_checks(loop, cfg, time.monotonic_ns() - t0, sim.sim_ns)
                for c in new:
                    out(c.line())
                checks.extend(new)
                bad = [c for c in new if not c.ok]
                if bad:
                    raise StartupCheckFailed(f"start-up check '{bad[0].name}' failed: "
                                             f"{bad[0].detail}")
            if sim.crashed:
                out(f"vehicle crashed at t={sim.sim_ns / _NS:.3f} s; run stopped")
                break
    finally:
        seg.set_word(ls.STOP, ls.STOP_INTERRUPTED if interrupted or stop.requested else 1)
    wall_ns = time.monotonic_ns() - t0
    cpu_s = time.thread_time() - cpu0
    if fc_poll is None:
        _wait_fc_done(seg, peer_check)
    res = _result(loop, cfg, checks, wall_ns, pacer)
    res.cpu_s = cpu_s
    res.interrupted = interrupted
    return res


def _wait_lockstep(loop: BridgeLoop, watch: PeerWatch, slice_s: float = 0.02) -> None:
    seg = loop.seg
    target = loop.sim.sim_ns
    while not seg.wait_word(ls.FC_SIM_NS, target, slice_s):
        watch.check()
    loop.collect_pwm()


def _wait_realtime(loop: BridgeLoop, pacer: Pacer, k: int) -> None:
    """Give the FC until shortly before the next deadline to answer; never longer."""
    budget_ns = int(pacer.period_ns * 0.5)
    loop.seg.wait_word(ls.FC_SIM_NS, loop.sim.sim_ns, budget_ns / _NS)
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
