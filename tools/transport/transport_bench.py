"""The transport stress test (paper Table 2): shared memory against MAVLink HIL, in one run.

For each transport the IMU rate steps up from 1 kHz (1-2-5 per decade up to the cap) while
baro and mag stay at 100 Hz and the FC returns PWM at 400 Hz; every step is a real-time closed
loop (the rate is a wall-clock rate) with the real FC in its own process. Per step: achieved
rate per stream at the FC (count over the publish-time span of what arrived), sensor -> FC
latency and FC loop jitter p50/p95/p99, drop and overwrite ratios, and whether PWM held
400 Hz within 0.5 %, plus the CPU other processes took meanwhile. A transport stops at its
first failed step; a failure that may not be the transport's (a narrow miss, or a busy
machine: see retry_reason) is run once more first, and must fail twice to end the series.
A step that fails while other processes held the CPU is marked degraded (host_degraded): its
miss says the machine was busy, not where the transport's ceiling is, so the table shows
the series as ended by a busy host and never takes that step for the transport's limit.

Process layout (tools/transport/transport_procs.py): the parent starts, all at once before anything
is measured, one *runner* per CRC setting (it owns the bridge side), and each runner one *FC
child* that serves all its steps (a fresh FlightCore and segment per step, the interpreter
reused, so a step costs about its measured second); the parent then has the transports
measured one after the other. Both are `python -m silbridge.tools.transport.transport_child`, which can
hide the `fastcrc` package before pymavlink loads (--no-fastcrc): pymavlink picks its CRC at
import time, so the switch is per process and nothing in our own code paths holds it.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass

import numpy as np
from silbridge.shm.records import NS_PER_S as _NS

PWM_HZ = 400.0
PWM_TOLERANCE = 0.005        # PWM within 0.5 % of 400 Hz
IMU_TOLERANCE = 0.005        # the IMU must also arrive at >= 99.5 % of the requested rate
# A failed step is run again (once; it must fail twice to end the series) only when the miss
# may not be the transport's: it missed narrowly, as a scheduler hiccup does (measured: udp at
# 50 kHz, IMU 99.8 %, PWM 397.9 Hz), or other processes held a noticeable share of the two
# cores meanwhile (tools/transport/transport_load.py). On an idle machine a transport past its ceiling
# misses by more (tcp at 50 kHz: IMU 94.8 %, PWM 377 Hz); a second second would only confirm it.
RETRY_IMU_FRACTION = 0.97    # IMU at >= 97 % of the requested rate
RETRY_PWM_TOLERANCE = 0.03   # PWM within 3 % of 400 Hz
RETRY_DROP_RATIO = 0.01      # fewer than 1 % of the records lost
RETRY_OTHERS_CORES = 0.25    # others used a quarter of a core or more during the step
STEP_ANSWER_S = 30.0         # the FC child answers within this once the bridge has stopped

# name -> (transport, fastcrc)
VARIANTS = {
    "shm": ("shm", True),
    "udp": ("udp", True),
    "tcp": ("tcp", True),
    "udp-nofastcrc": ("udp", False),
    "tcp-nofastcrc": ("tcp", False),
}
DEFAULT_TRANSPORTS = ("shm", "udp", "tcp", "tcp-nofastcrc")
DEFAULT_IMU_MAX_HZ = 2_000_000
DEFAULT_DURATION_S = 1.0


class TransportBenchError(Exception):
    user_facing = True


def imu_steps(cap_hz: int, start_hz: int = 1000) -> list[int]:
    """1k, 2k, 5k, 10k, 20k, 50k, ... up to and including cap_hz."""
    out, decade = [], start_hz
    while True:
        for m in (1, 2, 5):
            hz = m * decade
            if hz > cap_hz:
                return out
            out.append(hz)
        decade *= 10


def _pct(values: np.ndarray, scale: float = 1e-3) -> dict:
    if len(values) == 0:
        return {"p50": None, "p95": None, "p99": None}
    p = np.percentile(values, (50, 95, 99)) * scale
    return {"p50": float(p[0]), "p95": float(p[1]), "p99": float(p[2])}


# -- the FC child ---------------------------------------------------------------------------
class StreamCounter:
    """FcLoop sink: per-stream counts and publish-time spans of what reached the FC."""

    KINDS = {"imu": 1, "baro": 2, "mag": 3}

    def __init__(self):
        self.count = {k: 0 for k in self.KINDS}
        self.first = {k: None for k in self.KINDS}
        self.last = {k: None for k in self.KINDS}
        self.pwm_walls: list = []

    def fc_batch(self, recs, pwm, status, timing) -> None:
        pwm_wall = timing[3]
        kinds = recs["kind"]
        walls = recs["wall_ns"]
        for name, k in self.KINDS.items():
            idx = np.flatnonzero(kinds == k)
            if len(idx):
                self.count[name] += len(idx)
                if self.first[name] is None:
                    self.first[name] = int(walls[idx[0]])
                self.last[name] = int(walls[idx[-1]])
        if len(pwm):
            self.pwm_walls.append(pwm_wall)

    def event(self, *args) -> None:
        pass

    def rates_hz(self) -> dict:
        out = {}
        for name in self.KINDS:
            n, a, b = self.count[name], self.first[name], self.last[name]
            out[name] = (n - 1) / ((b - a) / _NS) if n > 1 and b > a else 0.0
        return out


class PwmClock:
    """Bridge sink: counts the PWM records the bridge received.

    The PWM rate of a step is that count over the run's wall time (the pacer's absolute
    deadlines make a run that kept up last exactly its duration): a loop that falls behind
    delivers fewer than 400 per wall second; short hiccups it recovers from show in the late
    steps and the jitter instead of bending the rate."""

    def __init__(self):
        self.count = 0

    def pwm_records(self, pwm) -> None:
        self.count += len(pwm)

    def event(self, *args) -> None:
        pass


def fc_child(transport: str, instance: str, hil_addr: str | None,
             attach_timeout_s: float = 15.0) -> dict:
    """One step on the FC side (in the FC child): attach, run the real FC until STOP, measure."""
    from silbridge.fc_sil.fc_loop import run_fc
    from silbridge.shm import lockstep as ls

    from silbridge.tools.loop.flight import make_fc_loop
    from silbridge.tools.loop.transport_wiring import fc_segment, guard_fc

    counter = StreamCounter()
    with fc_segment(transport, instance, hil_addr=hil_addr, timeout_s=attach_timeout_s) as seg:
        loop = make_fc_loop(seg, sink=counter)
        guard_fc(loop)
        run_fc(loop, out=lambda s: print(s, file=sys.stderr))
        dt_ns = seg.word(ls.PHYSICS_DT_NS) or 1_000_000
        counters = seg.counters() if hasattr(seg, "counters") else {}
    lat = loop.latency_ns.values()
    periods = loop.period_ns.values()
    return {
        "records": loop.records,
        "pwm_published": loop.pwm_published,
        "rates_hz": counter.rates_hz(),
        "latency_us": _pct(lat),
        "latency_cdf_us": (np.percentile(lat, np.arange(0, 101)) / 1e3).tolist() if len(lat) else [],
        "jitter_us": _pct(np.abs(periods - dt_ns)),
        # The FC child imports pymavlink for every transport; over shm no CRC is computed.
        "fastcrc": _fastcrc_loaded() if transport != "shm" else False,
        "link": counters,
    }


def _fastcrc_loaded() -> bool:
    """True when pymavlink (if loaded) computes CRCs with fastcrc."""
    mod = sys.modules.get("pymavlink.dialects.v20.ardupilotmega")   # the dialect we use
    return bool(mod is not None and getattr(mod, "mcrf4xx", None) is not None)


# -- one step, bridge side --------------------------------------------------------------------
def run_step(transport: str, imu_hz: int, duration_s: float, fc,
             step_no: int | None = None) -> dict:
    """One IMU step: a fresh simulator and segment here, the FC in the FcChild `fc`.
    step_no (default: the child's next) names the step in the protocol and the segment."""
    from silbridge.bridge.errors import BridgeError
    from silbridge.bridge.bridge_driver import BridgeRunConfig, prepare_segment, run_bridge
    from silbridge.shm import Segment

    from silbridge.tools.loop.flight import FlightOptions, make_simulator
    from silbridge.tools.transport.transport_load import OthersCpu
    from silbridge.tools.transport.transport_procs import ChildLost
    from silbridge.tools.loop.transport_wiring import bridge_address, bridge_segment

    if step_no is None:
        step_no = fc.steps_started + 1
    opts = FlightOptions(scenario="S1", duration_s=duration_s, lockstep=False, imu_hz=imu_hz,
                         transport=transport)
    sc, sim = make_simulator(opts)
    # No start-up checks inside the window: this run measures, it does not gate.
    cfg = BridgeRunConfig(duration_s=duration_s, lockstep=False, check_window_s=duration_s * 10,
                          settle_s=duration_s, trace_hash=False)
    name = f"tbench-{os.getpid()}-{step_no}"
    if transport == "shm":   # 8 MiB of sensor ring: up to ~60 ms of 2 MHz IMU in flight
        seg_cm = Segment.create(name, sensor_slots=1 << 17)
    else:
        seg_cm = bridge_segment(transport, name, sim, default_port=0)
    clock = PwmClock()
    with seg_cm as seg:
        prepare_segment(seg, sim, cfg)
        fc.start_step(step_no, transport, name,
                      None if transport == "shm" else bridge_address(seg),
                      attach_timeout_s=cfg.attach_timeout_s)
        others = OthersCpu([os.getpid(), fc.pid])
        others.start()
        try:
            res = run_bridge(sim, seg, cfg, peer_check=fc.busy, sink=clock, out=lambda s: None)
            others_cores = others.cores()
        except BridgeError as e:
            # The child's own account (its error, or that it died) says more than "the FC
            # left"; it answers at once once the bridge has stopped.
            try:
                fc.step_result(step_no, timeout_s=5.0)
            except ChildLost as lost:
                raise lost from e
            raise
        fc_res = fc.step_result(step_no, timeout_s=STEP_ANSWER_S)
    r = step_figures(imu_hz, res, clock, fc_res)
    r["others_cpu_cores"] = others_cores
    r["degraded"] = host_degraded(r)
    return r


def host_degraded(r: dict) -> bool:
    """A failed step measured while other processes used the CPU (retry_reason's threshold):
    a busy host's figures, kept apart from the transport's (docs/reference/metrics.md)."""
    return bool(not r["ok"] and r.get("others_cpu_cores", 0.0) >= RETRY_OTHERS_CORES)


def step_figures(imu_hz: int, res, clock: PwmClock, fc: dict) -> dict:
    """A step's result from what the bridge (res, clock) and the FC child (fc) measured."""
    written = res.ring["sensors"]["written"]
    received = fc.get("records", 0)
    overwritten = res.ring["sensors"]["overwritten"] + res.ring["sensors"]["rejected"]
    drop = max(0, written - received) / max(written, 1)
    rates = dict(fc.get("rates_hz", {}))
    rates["pwm"] = clock.count / max(res.wall_s, 1e-9)
    pwm_ok = bool(abs(rates["pwm"] / PWM_HZ - 1.0) <= PWM_TOLERANCE)
    imu_ok = bool(rates.get("imu", 0.0) >= imu_hz * (1.0 - IMU_TOLERANCE))
    return {
        "imu_hz_requested": imu_hz,
        "achieved_hz": rates,
        "latency_us": fc.get("latency_us", _pct(np.array([]))),
        "latency_cdf_us": fc.get("latency_cdf_us", []),
        "jitter_us": fc.get("jitter_us", _pct(np.array([]))),
        "drop_ratio": drop,
        "overwrite_ratio": overwritten / max(written, 1),
        "pwm_ok": pwm_ok,
        "ok": bool(pwm_ok and imu_ok and drop == 0.0),
        "late_steps": res.late_steps,
        # The bridge's own account (bridge/bridge_driver.rates_summary): what the simulator
        # published, its late steps and worst late stretch, and its rate watch's verdict.
        "sim_rates": res.rates,
        "wall_s": res.wall_s,
        "records_published": written,
        "records_received": received,
        "fastcrc": fc.get("fastcrc"),
        "link": fc.get("link", {}),
    }


def retry_reason(r: dict) -> str | None:
    """Why a failed step deserves a second run (None: it does not, or it passed)."""
    if r["ok"]:
        return None
    imu = r["achieved_hz"].get("imu", 0.0) or 0.0
    pwm = r["achieved_hz"].get("pwm", 0.0) or 0.0
    if (imu >= r["imu_hz_requested"] * RETRY_IMU_FRACTION
            and abs(pwm / PWM_HZ - 1.0) <= RETRY_PWM_TOLERANCE
            and r["drop_ratio"] <= RETRY_DROP_RATIO):
        return "narrow miss"
    others = r.get("others_cpu_cores", 0.0)
    if others >= RETRY_OTHERS_CORES:
        return f"other processes used {others:.2f} cores"
    return None


def codec_cost_us(imu_hz: int = 50_000, steps: int = 100) -> dict:
    """Per-message cost of the HIL codec in this process (its CRC choice), on a real
    simulator's records: bridge encode, FC parse (pymavlink), FC record rebuild. Explains
    where MAVLink's ceiling comes from."""
    from silbridge.bridge.scenario import load_scenario
    from silbridge.bridge.simulator import Simulator
    from silbridge.mavlink.framing import FrameDecoder, RxCounters
    from silbridge.mavlink.hil.hil_channel import make_codec
    from silbridge.mavlink.hil.hil_codec import SensorDecoder, SensorEncoder

    sim = Simulator(load_scenario("S1", seed=1), imu_hz=imu_hz)
    batches = [sim.step((1000.0,) * 4).copy() for _ in range(steps)]
    enc = SensorEncoder(make_codec(1, 51), (0, 0, 0))
    dec = SensorDecoder((0, 0, 0))
    dec.imu_hz = imu_hz
    parse = FrameDecoder(make_codec(1, 1), RxCounters())
    t0 = time.perf_counter()
    blobs = []
    for recs in batches:
        frames: list = []
        enc.encode(recs, 0, frames)
        blobs.append(b"".join(frames))
    t1 = time.perf_counter()
    msgs = [parse.feed(b, True) for b in blobs]
    t2 = time.perf_counter()
    for ms in msgs:
        for m in ms:
            dec.feed(m, 0)
    t3 = time.perf_counter()
    n = max(1, sum(len(ms) for ms in msgs))
    return {"encode": (t1 - t0) / n * 1e6, "parse": (t2 - t1) / n * 1e6,
            "to_records": (t3 - t2) / n * 1e6, "messages": n, "fastcrc": _fastcrc_loaded()}


def run_variant(variant: str, steps: list[int], duration_s: float, fc) -> dict:
    """All steps of one transport, bridge side in this (runner) process, the FC in the FcChild
    `fc` (whose CRC setting must be the variant's: pymavlink fixes it per process)."""
    transport, _ = VARIANTS[variant]
    # Here, not at start-up: the other children's start-up would share the CPU with it.
    codec = codec_cost_us() if transport != "shm" else None
    results = []
    for hz in steps:
        r = run_step(transport, hz, duration_s, fc)
        why = retry_reason(r)
        if why:
            again = run_step(transport, hz, duration_s, fc)
            again["first_attempt"] = {k: r[k] for k in ("achieved_hz", "drop_ratio", "late_steps",
                                                         "ok", "others_cpu_cores", "degraded")}
            again["first_attempt"]["retried_because"] = why
            r = again
        results.append(r)
        print(_step_line(variant, r), file=sys.stderr, flush=True)
        if not r["ok"]:
            break
    summary = summarise_variant(variant, results)
    summary["codec_us_per_message"] = codec
    return summary


def _step_line(variant: str, r: dict) -> str:
    a = r["achieved_hz"]
    retried = r.get("first_attempt", {}).get("retried_because")
    return (f"  {variant:<14} IMU {r['imu_hz_requested']:>9,} Hz -> {a.get('imu', 0):>12,.0f} Hz  "
            f"PWM {a['pwm']:6.1f} Hz  drop {r['drop_ratio'] * 100:6.3f} %  "
            f"latency p50 {r['latency_us']['p50'] or 0:8.1f} us  "
            f"others {r['others_cpu_cores']:4.2f} cores  {step_verdict(r)}"
            + (f" (second run; first failed: {retried})" if retried else ""))


def step_verdict(r: dict) -> str:
    if r["ok"]:
        return "ok"
    return "DEGRADED (busy host)" if r.get("degraded") else "FAILED"


def summarise_variant(variant: str, results: list[dict]) -> dict:
    passed = [r for r in results if r["ok"]]
    best = passed[-1] if passed else (results[0] if results else None)
    transport, fastcrc = VARIANTS[variant]
    last = results[-1] if results else None
    # What ended the series: every step passed (the IMU cap), the transport, or a busy host.
    ended_by = ("cap" if last is None or last["ok"] else
                "busy host" if last.get("degraded") else "transport")
    return {
        "transport": transport,
        "fastcrc": fastcrc if transport != "shm" else None,
        "max_imu_hz": passed[-1]["imu_hz_requested"] if passed else 0,
        "ended_by": ended_by,
        "degraded_steps": sum(1 for r in results if r.get("degraded")),
        "pwm_hz": best["achieved_hz"]["pwm"] if best else 0.0,
        "latency_us": best["latency_us"] if best else _pct(np.array([])),
        "jitter_us": best["jitter_us"] if best else _pct(np.array([])),
        "drop_ratio": best["drop_ratio"] if best else 1.0,
        "achieved_hz": best["achieved_hz"] if best else {},
        "steps": results,
    }


# -- the comparison (parent) -----------------------------------------------------------------
@dataclass
class TransportBenchConfig:
    transports: tuple = DEFAULT_TRANSPORTS
    imu_max_hz: int = DEFAULT_IMU_MAX_HZ
    duration_s: float = DEFAULT_DURATION_S
    out_dir: str | None = None


class _NeverStop:
    requested = False
    name = None


def run_comparison(cfg: TransportBenchConfig, out=print, stop=_NeverStop) -> dict:
    """stop (tools/loop/stop_signals.py): once requested, the transport being measured is
    abandoned, its runner stopped, and the report holds the transports measured so far."""
    unknown = [t for t in cfg.transports if t not in VARIANTS]
    if unknown:
        raise TransportBenchError(f"unknown transport(s) {', '.join(unknown)}: choose from "
                                  f"{', '.join(VARIANTS)}")
    steps = imu_steps(int(cfg.imu_max_hz))
    if not steps:
        raise TransportBenchError("--imu-max must be at least 1000 Hz")
    from silbridge.tools.transport.transport_procs import JsonChild

    t0 = time.monotonic()
    report = {"config": {"transports": list(cfg.transports), "imu_steps_hz": steps,
                         "duration_s": cfg.duration_s, "baro_hz": 100, "mag_hz": 100,
                         "pwm_hz": PWM_HZ, "pwm_tolerance": PWM_TOLERANCE},
              "transports": {}}
    # One runner per CRC setting (pymavlink fixes it per process), each with its FC child,
    # all started now, side by side, while nothing is measured; then the transports are
    # measured strictly one after the other, the idle processes blocked on a pipe.
    runners: dict = {}
    try:
        for variant in cfg.transports:
            fastcrc = VARIANTS[variant][1]
            if fastcrc not in runners:
                cmd = [sys.executable, "-m", "silbridge.tools.transport.transport_child", "runner",
                       "--steps", ",".join(map(str, steps)),
                       "--seconds-per-rate", str(cfg.duration_s)]
                if not fastcrc:
                    cmd.append("--no-fastcrc")
                crc = "fastcrc" if fastcrc else "pure-Python-CRC"
                runners[fastcrc] = JsonChild(cmd, f"the {crc} runner")
        if cfg.out_dir:
            from silbridge.tools.transport.transport_report import preload
            preload()
        for runner in runners.values():
            runner.read_msg(120.0, "starting")
        # Bound on one transport's series: every step and its retry, answered late.
        series_s = 2 * len(steps) * (cfg.duration_s + STEP_ANSWER_S) + 60.0
        for variant in cfg.transports:
            if stop.requested:
                break
            out(f"transport {variant}: IMU steps up to {steps[-1]:,} Hz, "
                f"{cfg.duration_s:g} s each")
            runner = runners[VARIANTS[variant][1]]
            runner.send({"go": variant}, f"being sent {variant}")
            t_end = time.monotonic() + series_s
            while not runner.has_message() and not stop.requested and time.monotonic() < t_end:
                time.sleep(0.05)
            if stop.requested:
                break
            report["transports"][variant] = runner.read_msg(
                max(t_end - time.monotonic(), 1.0), f"measuring {variant}")
    finally:
        for runner in runners.values():
            if stop.requested and runner.alive():
                # A soft stop (the runner may have had the terminal's Ctrl-C already): it
                # unwinds, its step's segment unlinked, and exits.
                from silbridge.tools.loop.stop_signals import PARENT_STOP_SIGNAL
                runner.proc.send_signal(PARENT_STOP_SIGNAL)
            runner.close()
    if stop.requested:
        report["interrupted"] = stop.name
    report["wall_s"] = time.monotonic() - t0
    if cfg.out_dir and report["transports"]:
        from silbridge.tools.transport.transport_report import write_outputs
        report["outputs"] = write_outputs(report, cfg.out_dir)
    return report
