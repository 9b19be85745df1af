"""One closed-loop flight, wired from its parts: the glue under `silbridge
bridge`, `silbridge fc` and `silbridge fly` (and the campaign runner).

bridge/ and fc_sil/ never import each other; this module (tools/ may use
everything) builds each side and hands them the shared segment. The summary
joins what the bridge measured with what the FC measured into the keys the
issue fixes for `fly --json`.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass

from silbridge.bridge.bridge_driver import BridgeRunConfig, prepare_segment, run_bridge
from silbridge.bridge.simulator import Simulator
from silbridge.fc_sil.sim_notice import NoticeWriter

from silbridge.tools.loop.fc_param_events import load_flight_scenario, param_at_args, param_events
from silbridge.tools.loop.stop_signals import STOP
from silbridge.tools.version import package_version
from silbridge.tools.loop.transport_wiring import (
    bridge_address,
    bridge_segment,
    fc_cli_args,
    fc_segment,
    guard_fc,
    in_process_poll,
)

_NS = 1_000_000_000


@dataclass
class FlightOptions:
    scenario: str = "S1"
    duration_s: float | None = None     # None: the scenario's duration; inf: until stopped
    lockstep: bool = True
    speed: float = 1.0
    busy_wait: bool = False             # real time: spin between steps, never sleep
    strict_rates: bool = False          # real time: refuse a rate shortfall (--strict-rates)
    processes: int = 2
    imu_hz: float | None = None
    seed: int | None = None
    instance: str | None = None
    log_path: str | None = None
    params: dict | None = None          # parameter overrides for the FC
    features_off: tuple = ()            # FC stabilisation features switched off (ablation)
    mavlink: bool = False               # the MAVLink vehicle (GCS control) instead of AutoFlight
    gcs_urls: tuple = ()                # extra --gcs endpoints
    no_default_gcs: bool = False        # leave out udpout 127.0.0.1:14550 and :14540
    param_file: str | None = None       # --params FILE (.parm), read at start in every mode
    save_params: bool = False           # --save-params: GCS PARAM_SETs written back to it
    mission_file: str | None = None     # --mission FILE (QGC WPL 110)
    transport: str = "shm"              # shm | udp | tcp (MAVLink HIL, tools/loop/transport_wiring.py)
    hil_addr: str | None = None         # udp/tcp: the bridge's listen address (default: any port)
    viz_hz: float | None = None         # viewable log channels [Hz]; None: VIZ_HZ_DEFAULT; 0: none
    live: str | None = None             # --live HOST:PORT: serve the viewable channels (Foxglove)
    tlog: str | None = None             # --tlog FILE: the MAVLink GCS traffic


def default_instance() -> str:
    return f"fly-{os.getpid()}"


def make_simulator(opts: FlightOptions):
    sc = load_flight_scenario(opts.scenario, seed=opts.seed)
    sim = Simulator(sc, imu_hz=opts.imu_hz)
    return sc, sim


def bridge_config(opts: FlightOptions, sc) -> BridgeRunConfig:
    duration = opts.duration_s if opts.duration_s is not None else sc.duration_s
    return BridgeRunConfig(duration_s=duration, lockstep=opts.lockstep, speed=opts.speed,
                           busy_wait=opts.busy_wait, strict_rates=opts.strict_rates,
                           settle_s=min(10.0, duration / 2))


def make_fc_loop(seg, *, params: dict | None = None, features_off=(), sink=None,
                 mavlink=None, out=None, param_events=(), param_file: str | None = None,
                 bounded: bool = False):
    """The FC side: FlightCore with parameters applied, wrapped in an FcLoop.

    Parameters: the declared defaults, then param_file (--params, read-only), then params
    (--param), then the features switched off; the same with or without MAVLink.

    param_events: fc_sil.param_schedule.ParamEvent changes due at sim times (a scenario's
    [[fc_param]] entries).

    mavlink: None for the pre-MAVLink AutoFlight (scenario setpoints, auto-arm), or a
    fc_sil.vehicle_server.MavlinkOptions: the MAVLink vehicle (disarmed, GCS control only);
    close it with close_fc_loop(loop).

    bounded: the flight ends by itself, in lockstep (fc_sil/fc_loop.py FcLoop)."""
    from silbridge.fc_sil.autoflight import AutoFlight
    from silbridge.fc_sil.flight_core import FlightCore
    from silbridge.fc_sil.param_schedule import ParamSchedule
    from silbridge.fc_sil.params import feature_params
    from silbridge.fc_sil.fc_loop import FcLoop

    core = FlightCore()
    overrides = {**(params or {}), **feature_params(features_off)}
    schedule = ParamSchedule(core, param_events) if param_events else None
    if mavlink is not None:
        from silbridge.fc_sil.vehicle_server import start_mavlink_vehicle
        vehicle = start_mavlink_vehicle(core, mavlink, overrides=overrides, sink=sink, out=out)
        # through the vehicle's store, which its host parameters (SIM_*, the FC-side
        # [[failure]] switches: fc_param_events.py) are read from
        schedule = ParamSchedule(vehicle.store, param_events) if param_events else None
        return FcLoop(core, seg, supervisor=vehicle, sink=sink, schedule=schedule,
                      bounded=bounded)
    if param_file:
        from silbridge.fc_sil.vehicle_server import load_start_params
        _, problems = load_start_params(core, param_file)
        for p in problems:
            (out or print)(f"parameter file: {p}")
    for name, value in overrides.items():
        core.set_param(name, value)
    return FcLoop(core, seg, supervisor=AutoFlight(core, sink=sink), sink=sink,
                  schedule=schedule, bounded=bounded)


def mavlink_options(opts: FlightOptions):
    """The MavlinkOptions of a flight, or None when the MAVLink vehicle is off."""
    if not opts.mavlink:
        return None
    from silbridge.fc_sil.vehicle_server import MavlinkOptions
    from silbridge.mavlink.endpoints import DEFAULT_GCS_URLS, parse_endpoint
    urls = [] if opts.no_default_gcs else list(DEFAULT_GCS_URLS)
    urls += [u for u in opts.gcs_urls if u not in urls]
    return MavlinkOptions(endpoints=[parse_endpoint(u) for u in urls],
                          param_file=opts.param_file, save_params=opts.save_params,
                          mission_file=opts.mission_file, tlog=opts.tlog)


def mavlink_cli_args(opts: FlightOptions) -> list[str]:
    """The same MAVLink options for a `silbridge fc` subprocess."""
    if not opts.mavlink:
        return []
    args = ["--mavlink"]
    for url in opts.gcs_urls:
        args += ["--gcs", url]
    if opts.no_default_gcs:
        args.append("--no-default-gcs")
    if opts.save_params:
        args.append("--save-params")
    if opts.mission_file:
        args += ["--mission", opts.mission_file]
    if opts.tlog:
        args += ["--tlog", opts.tlog]
    return args


def close_fc_loop(loop) -> None:
    """Stop the MAVLink server of a make_fc_loop(..., mavlink=...) loop (no-op otherwise)."""
    close = getattr(loop.supervisor, "server", None)
    if close is not None:
        from silbridge.fc_sil.vehicle_server import vehicle_close
        vehicle_close(loop.supervisor)


def run_metadata(opts: FlightOptions, sc, sim, cfg, core) -> dict:
    """What a log records at start: config, scenario, the full parameter set."""
    return {
        "config": {
            "imu_hz": sim.imu_hz, "pwm_hz": cfg.pwm_hz, "physics_hz": _NS / sim.dt_ns,
            "baro_hz": sc.baro_hz, "mag_hz": sc.mag_hz, "gnss_hz": sc.gnss_hz,
            # null: until stopped (real time); the log's end says where it stopped
            "duration_s": cfg.duration_s if math.isfinite(cfg.duration_s) else None,
            "seed": sc.seed, "transport": opts.transport,
            "processes": opts.processes,
            "mode": "lockstep" if opts.lockstep else f"realtime x{opts.speed:g}",
            "features_off": list(opts.features_off),
        },
        "scenario": sc.to_dict(),
        # The drawn imperfections ([vehicle]), when the scenario asks for them.
        **({"vehicle": sim.vehicle.to_dict()} if sim.vehicle.imperfect else {}),
        "params": core.params() if core is not None else {},
        "software": {"silbridge": package_version()},
    }


def fly_one_process(opts: FlightOptions, out=print) -> dict:
    """Bridge and FC interleaved in this process, through the same ring API."""
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    name = opts.instance or default_instance()
    sink = None
    with bridge_segment(opts.transport, name, sim, hil_addr=opts.hil_addr, default_port=0) as seg:
        prepare_segment(seg, sim, cfg)
        fc_addr = None if opts.transport == "shm" else bridge_address(seg)
        with fc_segment(opts.transport, name, hil_addr=fc_addr, wait_config=False) as fc_seg:
            fc = make_fc_loop(fc_seg, params=opts.params, features_off=opts.features_off,
                              mavlink=mavlink_options(opts), out=out,
                              param_events=param_events(sc), param_file=opts.param_file,
                              bounded=opts.lockstep and math.isfinite(cfg.duration_s))
            guard_fc(fc)
            if opts.log_path or opts.live is not None:
                from silbridge.tools.loop.run_log import open_run_sink
                # The FC's C core logs the PWM it computes (the same records the
                # bridge receives in lockstep): one memcpy instead of a Python call.
                # sim: this process steps the physics, so the log gets /rotor too.
                sink = open_run_sink(opts.log_path, run_metadata(opts, sc, sim, cfg, fc.core),
                                     viz_hz=opts.viz_hz, live=opts.live, out=out, sim=sim)
                fc.sink = sink
                fc.supervisor.sink = sink
            res = None
            ended = {}
            try:
                with STOP.polling(), STOP.emergency(segment_unlinker(seg)):
                    res = run_bridge(sim, seg, cfg, sink=sink, out=_tee(out, sink, sim),
                                     fc_poll=in_process_poll(fc, fc_seg, seg, sim, opts.lockstep),
                                     stop=STOP, notify=_in_process_notify(fc), fc_loop=fc)
            except BaseException as exc:
                ended = {"aborted": f"{type(exc).__name__}: {exc}"}
                raise
            finally:
                close_fc_loop(fc)
                if sink is not None:
                    sink.close(**(_end_fields(res) or ended))
            fc_summary = fc.summary()
    summary = summarise(opts, sc, sim, res, fc_summary)
    if sink is not None:
        summary["log"] = opts.log_path
    return summary


def segment_unlinker(seg):
    """The emergency clean-up of a segment this process owns (a second Ctrl-C)."""
    unlink = getattr(seg, "unlink", None)
    return unlink if unlink is not None and getattr(seg, "is_owner", False) else (lambda: None)


def _end_fields(res) -> dict:
    """What the log's closing summary says about how the run ended (and, in real time, the
    achieved rates: bridge/bridge_driver.rates_summary)."""
    if res is None:
        return {"interrupted": STOP.name} if STOP.requested else {}
    rates = {"rates": res.rates} if res.rates else {}
    link = {"link": res.link} if any(res.link.values()) else {}
    return {**({"interrupted": res.interrupted} if res.interrupted else {}), **rates, **link}


def _in_process_notify(fc):
    """run_bridge's notify with the FC in this process: the STATUSTEXT straight to its
    vehicle (the bridge logs the figures itself, and the end ones go in the log's end)."""
    from silbridge.fc_sil.sim_notice import deliver

    def notify(text, fields):
        if text is not None:
            deliver(fc, text, fields, log=False)
    return notify


def _tee(out, sink, sim):
    """Print a progress line and, with a log, record it as a check event."""
    if sink is None:
        return out

    def both(line: str) -> None:
        out(line)
        if line.startswith("check "):
            sink.event(sim.sim_ns, "check", line[6:].strip())
    return both


def fly_two_processes(opts: FlightOptions, out=print, sink=None) -> dict:
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    name = opts.instance or default_instance()
    with bridge_segment(opts.transport, name, sim, hil_addr=opts.hil_addr, default_port=0) as seg:
        prepare_segment(seg, sim, cfg)
        cmd = [sys.executable, "-m", "silbridge.tools", "fc", "--instance", name, "--json"]
        cmd += fc_cli_args(opts.transport, seg)
        if opts.param_file:
            cmd += ["--params", opts.param_file]
        for pname, value in (opts.params or {}).items():
            cmd += ["--param", f"{pname}={value}"]
        for feature in opts.features_off:
            cmd += ["--feature-off", feature]
        cmd += param_at_args(param_events(sc))
        cmd += mavlink_cli_args(opts)
        meta_path = spool = None
        if opts.log_path or opts.live is not None:
            # The FC process writes the log (it sees every record and its own PWM);
            # it adds the parameter set to the metadata the bridge side knows.
            meta_path = f"{opts.log_path}.meta.json" if opts.log_path else \
                os.path.join(tempfile.gettempdir(), f"{name}.meta.json")
            meta = run_metadata(opts, sc, sim, cfg, None)
            spool = _rotor_spool(opts, sim) if sink is None else None
            if sc.imu_chip.log_raw:     # the FC process writes the log: no chip rows there
                out("note: imu_chip.log_raw: /imu_raw is logged by --processes 1 only")
            # /rotor's rate is not declared here: the bridge appends the spooled rows only
            # to a log the FC finished, so a killed run's log would miss a declared channel.
            if spool is not None:
                sink = spool
            with open(meta_path, "w") as fh:
                json.dump(meta, fh)
            cmd += ["--log-meta", meta_path] + (["--log", opts.log_path] if opts.log_path else [])
            if opts.viz_hz is not None:
                cmd += ["--viz-hz", str(opts.viz_hz)]
            if opts.live is not None:
                cmd += ["--live", opts.live]
        # Real time: the rate reports reach the FC's vehicle (STATUSTEXT) and log through
        # a file (fc_sil/sim_notice.py), written before the FC can start.
        notices = None if opts.lockstep else NoticeWriter(name)
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
        try:
            with STOP.polling(), STOP.emergency(segment_unlinker(seg)), \
                    STOP.emergency(proc.terminate):
                res = run_bridge(sim, seg, cfg, peer_check=lambda: proc.poll() is None,
                                 sink=sink, out=out, stop=STOP, notify=notices)
                # The FC finishes and indexes the log before it prints its summary.
                stdout, _ = proc.communicate(timeout=30)
            if spool is not None:
                _append_rotor(spool, opts.log_path, out)
        finally:
            stop_child(proc)
            if notices is not None:
                notices.remove()
            if spool is not None:
                spool.discard()
    fc_summary = last_json_line(stdout)
    summary = summarise(opts, sc, sim, res, fc_summary)
    if meta_path:
        os.unlink(meta_path)
    if opts.log_path:
        summary["log"] = opts.log_path
    return summary


def _rotor_spool(opts: FlightOptions, sim):
    """The bridge's /rotor rows of a two-process flight with a log file: spooled beside the
    log while the FC process writes it (tools/logs/rotor_log.py RotorSpool)."""
    if not opts.log_path:
        return None
    from silbridge.tools.logs.rotor_log import RotorSpool
    return RotorSpool(f"{opts.log_path}.rotor.spool", sim.rotor_rad_s)


def _append_rotor(spool, log_path: str, out) -> None:
    """Append the spooled /rotor rows to the log the FC process finished; a log it did not
    finish (killed, cut short) is left as it is, and said so."""
    try:
        spool.append_into(log_path)
    except (OSError, ValueError) as exc:
        out(f"note: could not add /rotor to {log_path}: {exc}")


def stop_child(proc, timeout_s: float = 10.0) -> None:
    """Stop a child still running: SIGTERM first (it closes its log), SIGKILL if it hangs."""
    if proc.poll() is not None:
        return
    proc.terminate()
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def last_json_line(text: str) -> dict:
    """The last JSON object a `silbridge ... --json` child printed ({} if none)."""
    for line in reversed((text or "").strip().splitlines()):
        line = line.strip()
        if line.startswith("{"):
            return json.loads(line)
    return {}


def summarise(opts: FlightOptions, sc, sim, res, fc_summary: dict) -> dict:
    """The `fly --json` object (keys fixed by the closed-loop issue) plus context."""
    scale_s = res.sim_s if opts.lockstep else res.wall_s * opts.speed
    scale_s = max(scale_s, 1e-9)
    pub = res.published
    rates = {k: pub.get(k, 0) / scale_s for k in ("imu", "baro", "mag", "gnss")}
    rates["pwm"] = res.pwm_hz
    overwritten = sum(r["overwritten"] for r in res.ring.values())
    rejected = sum(r["rejected"] for r in res.ring.values())
    return {
        "sim_s": res.sim_s,
        "wall_s": res.wall_s,
        "realtime_factor": res.sim_s / max(res.wall_s, 1e-9),
        # CPU seconds of the bridge's loop thread (with --processes 1 the FC's too): the
        # speed figure that other processes on the machine do not inflate.
        "loop_cpu_s": res.cpu_s,
        # Steps the bridge published without waiting for an FC in its own process, which
        # had promised to answer them with nothing (shm/lockstep.py FC_SYNC_NS).
        "steps_overlapped": res.steps_overlapped,
        # "c": the step read and wrote JSBSim's nodes from C; "python: why not" (the same
        # values, slower: bridge/src/jsbsim_native.h).
        "jsbsim_nodes": sim.jsbsim_nodes,
        "rates_hz": rates,
        "overwritten": overwritten,
        "rejected": rejected,
        "latency_us": fc_summary.get("latency_us", {"p50": None, "p99": None}),
        "jitter_us": fc_summary.get("jitter_us", {"p50": None, "p99": None}),
        "e2e_us": fc_summary.get("e2e_us", {"p50": None, "p99": None}),
        "attitude_rms_deg": res.attitude_rms_deg,
        "altitude_rms_m": res.altitude_rms_m,
        # The sim-time span those two RMS cover: after the settle time to the end of the run
        # (not the paper's analysis window that `silbridge analyze` scores).
        "rms_window_s": [bridge_config(opts, sc).settle_s, res.sim_s],
        # A ground station flies the MAVLink vehicle: the scenario's setpoints are not its
        # command, so errors against them mean nothing and are not printed.
        "gcs_flown": bool(opts.mavlink),
        "trace_hash": res.trace_hash,
        "crashed": res.crashed,
        "scenario": sc.name,
        "seed": sc.seed,
        "imu_hz": sim.imu_hz,
        "mode": "lockstep" if opts.lockstep else f"realtime x{opts.speed:g}",
        "processes": opts.processes,
        "checks": [{"name": c.name, "ok": c.ok, "detail": c.detail} for c in res.checks],
        "late_steps": res.late_steps,
        # Achieved rates, late steps, the worst late stretch and whether the host kept up
        # (bridge/bridge_driver.rates_summary); real-time benchmarks leave "degraded" runs out.
        "rates": res.rates,
        # The signal that ended the run early ("SIGINT"/"SIGTERM"), else None.
        "interrupted": res.interrupted,
        # Records the SIL link's faults delayed and dropped (bridge/link_faults.py).
        "link": res.link,
        # Per fault unit: switches on/off and FAULT records from the FC, only when the run had
        # faults (bridge/fault_records.py fault_summary), so a user sees the entries acted.
        **({"faults": res.faults} if res.faults else {}),
        **({"mavlink": fc_summary["mavlink"]} if "mavlink" in fc_summary else {}),
    }


def print_summary(s: dict, out=print) -> None:
    lat, jit = s["latency_us"], s["jitter_us"]
    r = s["rates_hz"]

    def f(v, fmt="{:.2f}"):
        return "n/a" if v is None else fmt.format(v)

    out(f"scenario {s['scenario']} seed {s['seed']}  {s['mode']}, {s['processes']} process(es)")
    out(f"sim {s['sim_s']:.2f} s in {s['wall_s']:.2f} s wall  ({s['realtime_factor']:.1f}x real time)")
    out(f"rates  IMU {r['imu']:.1f}  baro {r['baro']:.1f}  mag {r['mag']:.1f}  "
        f"GNSS {r['gnss']:.1f}  PWM {r['pwm']:.1f} Hz")
    out(f"ring   overwritten {s['overwritten']}  rejected {s['rejected']}")
    out(f"sensor->FC latency p50 {f(lat['p50'])} us  p99 {f(lat['p99'])} us;  "
        f"loop jitter p50 {f(jit['p50'])} us  p99 {f(jit['p99'])} us")
    a, b = s["rms_window_s"]
    if s.get("gcs_flown"):
        out(f"error RMS n/a: a ground station flew the vehicle (no scenario command to score)"
            f"  crashed {s['crashed']}")
    elif b <= a:
        out(f"error RMS n/a: the run ended at {b:.2f} s, before the {a:g} s settling time"
            f"  crashed {s['crashed']}")
    else:
        out(f"error RMS over {a:g}-{round(b, 3):g} s (whole run after settling): attitude "
            f"{f(s['attitude_rms_deg'], '{:.3f}')} deg  altitude "
            f"{f(s['altitude_rms_m'], '{:.3f}')} m  crashed {s['crashed']}")
    out(f"trace hash {s['trace_hash']}")
    link = s.get("link") or {}
    if any(link.values()):
        out(f"link faults: sensor records delayed {link['sensor_delayed']}, dropped "
            f"{link['sensor_dropped']}; PWM records delayed {link['pwm_delayed']}, dropped "
            f"{link['pwm_dropped']}")
    faults = s.get("faults") or {}
    if faults:
        out("faults: " + "; ".join(f"{u} on {c['on']} off {c['off']}, FAULT records "
                                   f"{c['fault_records']}" for u, c in faults.items()))
    rt = s.get("rates") or {}
    if rt.get("degraded"):
        out(f"DEGRADED real time (slow host): IMU {rt['imu_hz']:.1f} Hz (want "
            f"{rt['want_imu_hz']:g}), PWM {rt['pwm_hz']:.1f} Hz (want {rt['want_pwm_hz']:g}), "
            f"{rt['late_steps']} late steps, worst stretch {rt['worst_stretch_s']:.2f} s from "
            f"t={rt['worst_stretch_at_s']:.2f} s")
    if s.get("interrupted"):
        out(f"INTERRUPTED by {s['interrupted']} at {s['sim_s']:.2f} s of sim time: a partial run")
