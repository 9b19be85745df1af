"""The paper's campaign (section 4.5): N lockstep runs per scenario, metrics per run.

A run is fully described by a `RunSpec` (scenario, seed, duration, FC
parameters, features switched off), so the same spec gives the same log bit
for bit wherever it runs: in a local process pool (default) or on a Ray
cluster. Each run writes its MCAP log and its metrics are computed from that
log alone (tools/benchmark/metrics.py), exactly as `silbridge analyze` would.

Ctrl-C / SIGTERM (tools/loop/stop_signals.py): no new run starts; the runs in
flight stop at their next step and close their logs marked interrupted (the
workers take the signal from the terminal, or from the parent when only it was
signalled); the campaign returns the finished runs, and the interrupted ones
with `summary["interrupted"]` set, which callers leave out of the table.
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field, replace
from multiprocessing import get_context
from pathlib import Path

from silbridge.bridge.link_spin import spin_budget_us


class CampaignError(Exception):
    user_facing = True


@dataclass(frozen=True)
class RunSpec:
    scenario: str
    run_index: int
    seed: int
    duration_s: float
    log_path: str
    imu_hz: float | None = None
    params: tuple = ()            # ((name, value), ...) FC parameter overrides
    features_off: tuple = ()      # FC stabilisation features switched off
    variant: str = "full"         # ablation label
    keep_log: bool = True         # False: delete the log once its metrics are computed
    windows: tuple = ((0.0, 10.0), (10.0, 30.0), (30.0, 120.0), (90.0, 120.0))
    fc: str = "ours"              # ours | ardupilot (ArduCopter SITL, JSON) | px4 (MAVLink HIL)
    sitl: str | None = None       # fc == ardupilot: the arducopter binary
    sitl_speedup: float = 50.0    # fc == ardupilot: SITL --speedup
    viz_hz: float = 0.0           # the log's viewable channels (off in campaigns: their cost)
    px4: str | None = None        # fc == px4: the px4 SITL binary (etc/ beside its bin/)
    link_spin_us: float = 0.0     # fc != ours: spin on the lockstep link (bridge/link_spin.py)


@dataclass
class RunResult:
    spec: RunSpec
    metrics: dict = field(default_factory=dict)
    summary: dict = field(default_factory=dict)
    problems: list = field(default_factory=list)
    wall_s: float = 0.0


def make_specs(scenarios, runs: int, duration_s: float, out_dir: Path, *, base_seed: int = 1,
               imu_hz=None, params=(), features_off=(), variant="full", windows=None,
               keep_logs: str = "all", fc: str = "ours", sitl: str | None = None,
               sitl_speedup: float = 50.0, viz_hz: float = 0.0, px4: str | None = None):
    """One RunSpec per (scenario, run). keep_logs: all | first (run 0 of each
    scenario, enough for the report's traces) | none. A 120 s log is ~45 MB."""
    if keep_logs not in ("all", "first", "none"):
        raise CampaignError(f"keep_logs must be all, first or none, not {keep_logs!r}")
    specs = []
    for sc in scenarios:
        for i in range(runs):
            name = Path(sc).stem if sc.endswith(".toml") else sc
            log = out_dir / "logs" / variant / f"{name}_run{i:02d}.mcap"
            specs.append(RunSpec(scenario=sc, run_index=i, seed=base_seed + i,
                                 duration_s=duration_s, log_path=str(log), imu_hz=imu_hz,
                                 params=tuple(params), features_off=tuple(features_off),
                                 variant=variant, fc=fc, sitl=sitl,
                                 sitl_speedup=sitl_speedup, viz_hz=viz_hz, px4=px4,
                                 windows=windows or RunSpec.windows,
                                 keep_log=keep_logs == "all" or (keep_logs == "first"
                                                                 and i == 0)))
    return specs


def run_one(spec: RunSpec) -> RunResult:
    """Fly one run in this process, log it, and compute its metrics from the log."""
    from silbridge.tools.loop.stop_signals import STOP

    if STOP.requested:   # queued before the stop reached this worker: never started
        return RunResult(spec=spec, summary={"interrupted": STOP.name, "skipped": True})
    try:
        return _fly_and_score(spec)
    except Exception:
        # A stop that arrives during start-up (nothing polls yet) raises KeyboardInterrupt
        # where the worker is; native code such as JSBSim's model loader can turn that into
        # another exception (SystemError). Either way the run never began.
        if STOP.requested:
            return RunResult(spec=spec, summary={"interrupted": STOP.name, "skipped": True})
        raise


def _fly_and_score(spec: RunSpec) -> RunResult:
    from silbridge.tools.loop.flight import FlightOptions, fly_one_process

    Path(spec.log_path).parent.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if spec.fc == "ardupilot":
        from silbridge.tools.autopilots.ardupilot.flight import fly_ardupilot
        summary = fly_ardupilot(scenario=spec.scenario, seed=spec.seed,
                                duration_s=spec.duration_s, log_path=spec.log_path,
                                binary=spec.sitl, imu_hz=spec.imu_hz, params=dict(spec.params),
                                speedup=spec.sitl_speedup, spin_us=spec.link_spin_us)
        return _result_from_log(spec, summary, t0)
    if spec.fc == "px4":
        from silbridge.tools.autopilots.px4.flight import fly_px4
        from silbridge.tools.autopilots.px4.sitl import find_px4
        binary, etc = find_px4(spec.px4)
        summary = fly_px4(scenario=spec.scenario, seed=spec.seed, duration_s=spec.duration_s,
                          log_path=spec.log_path, binary=binary, etc=etc, imu_hz=spec.imu_hz,
                          params=dict(spec.params), spin_us=spec.link_spin_us)
        return _result_from_log(spec, summary, t0)
    opts = FlightOptions(scenario=spec.scenario, duration_s=spec.duration_s, lockstep=True,
                         processes=1, imu_hz=spec.imu_hz, seed=spec.seed,
                         instance=f"bench-{os.getpid()}-{spec.variant}-{spec.run_index}",
                         log_path=spec.log_path, params=dict(spec.params),
                         features_off=spec.features_off, viz_hz=spec.viz_hz)
    summary = fly_one_process(opts, out=lambda s: None)
    return _result_from_log(spec, summary, t0)


def _result_from_log(spec: RunSpec, summary: dict, t0: float) -> RunResult:
    """Integrity check and metrics of a run's log (the same for every FC)."""
    from silbridge.tools.logs.integrity import check_log
    from silbridge.tools.logs.mcap_log import read_log
    from silbridge.tools.benchmark.metrics import Windows, compute_metrics

    log = read_log(spec.log_path)
    problems = check_log(log)
    w = spec.windows
    metrics = compute_metrics(log, Windows(warmup=w[0], transient=w[1], analysis=w[2], yaw=w[3]))
    # Not from the log: how fast the run went (table1.json's realtime_factor, mean per row).
    metrics["realtime_factor"] = float(summary.get("realtime_factor", float("nan")))
    del log
    if not spec.keep_log:
        os.unlink(spec.log_path)
    return RunResult(spec=spec, metrics=metrics, summary=summary, problems=problems,
                     wall_s=time.perf_counter() - t0)


class Progress:
    """A one-line progress bar on stderr (a line per 10 % when not a terminal)."""

    def __init__(self, total: int, label: str, enabled: bool = True):
        self.total = max(total, 1)
        self.label = label
        self.done = 0
        self.enabled = enabled
        self.tty = sys.stderr.isatty()
        self.t0 = time.monotonic()
        self._last_decile = -1

    def step(self, note: str = "") -> None:
        self.done += 1
        if not self.enabled:
            return
        frac = self.done / self.total
        elapsed = time.monotonic() - self.t0
        eta = elapsed / frac - elapsed if frac > 0 else 0.0
        bar = "#" * int(frac * 30)
        line = (f"{self.label} [{bar:<30}] {self.done}/{self.total} runs, "
                f"{elapsed:5.1f} s, eta {eta:4.0f} s {note}")
        if self.tty:
            print("\r" + line[:120], end="" if self.done < self.total else "\n",
                  file=sys.stderr, flush=True)
        elif int(frac * 10) != self._last_decile:
            self._last_decile = int(frac * 10)
            print(line, file=sys.stderr, flush=True)


def check_executor(executor: str, jobs: int | None, ray_address: str | None) -> None:
    """--executor, --jobs and --ray-address together: what would be ignored is refused,
    and the Ray extra is checked before anything runs."""
    if executor not in ("local", "ray"):
        raise CampaignError(f"unknown executor {executor!r}: use local or ray")
    if jobs is not None and jobs < 1:
        raise CampaignError("--jobs must be >= 1")
    if ray_address and executor != "ray":
        raise CampaignError("--ray-address is for --executor ray: add it, or leave "
                            "--ray-address out")
    if executor == "ray":
        from silbridge.tools.optional_deps import require
        require(["ray"], "ray", "--executor ray")
        if ray_address and jobs is not None:
            raise CampaignError("--jobs sizes the local pool or the Ray started here; a Ray "
                                "cluster at --ray-address uses its own CPUs: leave --jobs out")


def run_campaign(specs, *, jobs: int | None = None, executor: str = "local",
                 ray_address: str | None = None, progress: bool = True,
                 label: str = "bench") -> list[RunResult]:
    """Run every spec; results come back in spec order whatever finished first."""
    if executor == "ray":
        results = _run_ray(specs, ray_address, progress, label, jobs)
    elif executor == "local":
        results = _run_local(specs, jobs or os.cpu_count() or 1, progress, label)
    else:
        raise CampaignError(f"unknown executor {executor!r}: use local or ray")
    bad = [r for r in results if r.problems and not r.summary.get("interrupted")]
    if bad:
        r = bad[0]
        raise CampaignError(f"run {r.spec.scenario} #{r.spec.run_index} produced a log that "
                            f"fails the integrity check: {r.problems[0]} ({r.spec.log_path})")
    return results


def _worker_init() -> None:
    """Pool workers answer Ctrl-C / SIGTERM like the command line does."""
    from silbridge.tools.loop.stop_signals import install_worker
    install_worker()


# Each pool worker flies one run at a time on one core: numpy's OpenBLAS (and any OpenMP)
# thread pool in every worker can only compete with the other workers' lockstep loops (perf
# once showed `blas_thread_server` spinning in a campaign). The BLAS calls in a run (the
# metrics) are small; the log is written by the loop and does not depend on them.
_ONE_THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


@contextmanager
def _worker_env():
    """The thread limits in the environment the spawned workers inherit (they are read when
    numpy loads, before any initializer could act); a limit the user set is kept."""
    added = {k: v for k, v in _ONE_THREAD_ENV.items() if k not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for k in added:
            os.environ.pop(k, None)


def _cost(spec: RunSpec) -> float:
    """A run's expected wall time, for the order of submission only: foreign autopilots
    fly several times slower than our FC per simulated second."""
    return spec.duration_s * (1.0 if spec.fc == "ours" else 4.0)


def _run_local(specs, jobs: int, progress: bool, label: str) -> list[RunResult]:
    from silbridge.tools.loop.stop_signals import PARENT_STOP_SIGNAL, STOP

    bar = Progress(len(specs), label, progress)
    # A foreign autopilot's lockstep link spins only where each concurrent run has two cores.
    spin = spin_budget_us(min(jobs, len(specs)))
    specs = [replace(s, link_spin_us=spin) if s.fc != "ours" else s for s in specs]
    if jobs <= 1:
        out = []
        with STOP.polling():
            for s in specs:
                if STOP.requested:
                    break
                out.append(run_one(s))
                bar.step(s.scenario)
        return out
    results: dict[int, RunResult] = {}
    # spawn: every worker starts clean (no inherited JSBSim or shared-memory state).
    # Longest first (sorted is stable: equal runs keep their order), so the campaign does not
    # end with one long run on one core while the others idle; results stay in spec order.
    order = sorted(range(len(specs)), key=lambda i: -_cost(specs[i]))
    with STOP.polling(), _worker_env(), \
            ProcessPoolExecutor(max_workers=min(jobs, len(specs)),
                                mp_context=get_context("spawn"), initializer=_worker_init) as pool:
        futures = {pool.submit(run_one, specs[i]): i for i in order}
        pending = set(futures)
        forwarded = False
        while pending:
            done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
            for fut in done:
                i = futures[fut]
                try:
                    results[i] = fut.result()
                except (BrokenProcessPool, KeyboardInterrupt):
                    if not STOP.requested:
                        raise
                    continue        # a worker stopped by the signal before its run began
                bar.step(specs[i].scenario)
            if STOP.requested and not forwarded:
                forwarded = True
                for fut in pending:
                    fut.cancel()
                # The parent alone may have been signalled (kill PID): pass the stop on
                # (a soft one: a worker that also got the terminal's Ctrl-C must not take
                # it for a second Ctrl-C), so the runs in flight close their logs.
                for proc in list(getattr(pool, "_processes", {}).values()):
                    try:
                        os.kill(proc.pid, PARENT_STOP_SIGNAL)
                    except ProcessLookupError:
                        pass
                pending = {f for f in pending if not f.cancelled()}
    return [results[i] for i in sorted(results)]


def _run_ray(specs, address: str | None, progress: bool, label: str,
             jobs: int | None = None) -> list[RunResult]:
    from silbridge.tools.optional_deps import require
    require(["ray"], "ray", "--executor ray")
    import ray
    started_here = not ray.is_initialized()
    if started_here:
        if address:
            ray.init(address=address, log_to_driver=False)
        else:
            ray.init(num_cpus=jobs or os.cpu_count(), include_dashboard=False,
                     log_to_driver=False)
    try:
        remote = ray.remote(num_cpus=1)(run_one)
        refs = [remote.remote(s) for s in specs]
        index = {ref: i for i, ref in enumerate(refs)}
        bar = Progress(len(specs), label, progress)
        results: dict[int, RunResult] = {}
        pending = list(refs)
        from silbridge.tools.loop.stop_signals import STOP
        with STOP.polling():
            while pending and not STOP.requested:
                ready, pending = ray.wait(pending, num_returns=1, timeout=0.2)
                if not ready:
                    continue
                i = index[ready[0]]
                results[i] = ray.get(ready[0])
                bar.step(specs[i].scenario)
            for ref in pending:   # stopped: the runs in flight are cancelled, not waited for
                ray.cancel(ref)
        return [results[i] for i in sorted(results)]
    finally:
        if started_here:
            ray.shutdown()


def spec_dict(spec: RunSpec) -> dict:
    return asdict(spec)
