"""The bridge's start-up checks, as the paper's procedure lists them (section 4.2).

Before the first step: the simulation step is consistent (a whole number of IMU samples per
physics step) and the FC attaches. Over the first check window: the counters move, IMU and
PWM rates are within +-5 %, and drops/overwrites stay below 0.5 %. Each check is one
`CheckResult` line; the driver (bridge/bridge_driver.py) prints them and stops the run on a
failure, except a real-time rate shortfall, which is a measurement of the host: warned and
counted while the run goes on (bridge/rate_watch.py), unless `strict_rates` refuses it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

from silbridge.shm import lockstep as ls

from .errors import PeerLost, StartupCheckFailed

if TYPE_CHECKING:       # annotations only: the driver imports this module
    from .bridge_driver import BridgeRunConfig
    from .bridge_loop import BridgeLoop
    from .rate_watch import RateWatch

_NS = 1_000_000_000


@dataclass
class CheckResult:
    name: str
    ok: bool
    detail: str
    warn_only: bool = False     # failed, but the run goes on (a real-time rate shortfall)

    def line(self) -> str:
        verdict = "ok" if self.ok else ("SHORT" if self.warn_only else "FAILED")
        return f"check {self.name:<10} {verdict}  {self.detail}"


def check_sim_step(sim) -> CheckResult:
    dt_ns = sim.dt_ns
    per_step = sim.imu_hz * dt_ns / _NS
    ok = dt_ns > 0 and abs(per_step - round(per_step)) < 1e-9 and round(per_step) >= 1
    return CheckResult("sim step", ok,
                       f"physics dt {dt_ns / 1e6:g} ms, {per_step:g} IMU samples per step")


def wait_attach(seg, cfg: BridgeRunConfig, peer_check, stop) -> CheckResult | None:
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


def first_window_checks(loop: BridgeLoop, cfg: BridgeRunConfig, wall_ns: int, out,
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
