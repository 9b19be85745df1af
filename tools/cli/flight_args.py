"""Command-line options shared by `silbridge bridge`, `fc` and `fly`."""

from __future__ import annotations

import argparse

from silbridge.fc_sil.params import FEATURES

from silbridge.tools.loop.flight import FlightOptions


class OptionError(ValueError):
    user_facing = True


def add_flight_arguments(p: argparse.ArgumentParser, *, processes: bool) -> None:
    p.add_argument("--scenario", default="S1",
                   help="built-in scenario name (S1..S5) or a TOML file (default S1)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="simulated seconds (default: the scenario's duration)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--lockstep", action="store_true",
                      help="deterministic, as fast as possible (default)")
    mode.add_argument("--realtime", action="store_true", help="pace to the wall clock")
    mode.add_argument("--speed", type=float, default=None, metavar="X",
                      help="real time at X times the wall clock")
    p.add_argument("--busy-wait", action="store_true",
                   help="real time: spin between steps instead of sleeping (one core at 100 %%; "
                        "a sleeping core's caches go cold: loop jitter p99 ~2x lower here)")
    if processes:
        p.add_argument("--processes", type=int, choices=(1, 2), default=2,
                       help="FC in its own process (2, default) or in the bridge's (1)")
    p.add_argument("--imu-hz", type=float, default=None, metavar="N",
                   help="IMU rate (a whole multiple of the 1 kHz physics rate)")
    p.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    p.add_argument("--instance", default=None,
                   help="shared-memory instance name (several runs can coexist)")
    add_transport_arguments(p, listen=True)
    add_fc_arguments(p)
    if processes:
        p.add_argument("--log", default=None, metavar="FILE.mcap",
                       help="write the run's MCAP log (open it in Foxglove; `silbridge analyze`)")
        add_view_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_view_arguments(p: argparse.ArgumentParser) -> None:
    """--viz-hz and --live: the log's viewable channels (tools/logs/viz_log.py, docs/logs.md)."""
    p.add_argument("--viz-hz", type=float, default=None, metavar="N",
                   help="viewable per-sample log channels (/viz/...: Foxglove plots and 3D) "
                        "at most N messages per second each (default 1000: every sample; "
                        "3D at most 100, scene 10; 0: none)")
    p.add_argument("--live", nargs="?", const="", default=None, metavar="HOST:PORT",
                   help="serve the viewable channels live over Foxglove's WebSocket protocol "
                        "(default 127.0.0.1:8765; port 0: a free one)")


def add_transport_arguments(p: argparse.ArgumentParser, *, listen: bool) -> None:
    """--transport shm|udp|tcp and --hil-addr (docs/hil_transport.md)."""
    p.add_argument("--transport", choices=("shm", "udp", "tcp"), default="shm",
                   help="bridge <-> FC link: shared memory (default) or MAVLink 2 HIL messages "
                        "over UDP or TCP (PX4 convention: the simulator listens)")
    where = ("listen on HOST:PORT (bridge default 127.0.0.1:4560; `fly` picks a free port)"
             if listen else "the simulator's HOST:PORT (default 127.0.0.1:4560)")
    p.add_argument("--hil-addr", default=None, metavar="HOST:PORT|serial:DEV:BAUD",
                   help=f"udp/tcp only: {where}; or a serial line, e.g. "
                        f"serial:/dev/ttyACM0:921600")


def add_fc_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="set an FC parameter (repeatable), e.g. ATC_RAT_RLL_D=0.004")
    p.add_argument("--feature-off", action="append", default=[], metavar="FEATURE",
                   choices=list(FEATURES),
                   help="switch a stabilisation feature off (ablation), repeatable: "
                        + ", ".join(FEATURES))


def add_mavlink_arguments(p: argparse.ArgumentParser) -> None:
    """The MAVLink vehicle's options (`silbridge fly` and `silbridge fc`)."""
    from silbridge.mavlink.endpoints import add_gcs_arguments

    onoff = p.add_mutually_exclusive_group()
    onoff.add_argument("--mavlink", dest="mavlink", action="store_true", default=None,
                       help="fly the MAVLink vehicle: disarmed on the ground, GCS control only "
                            "(default in real time; off in lockstep so benchmarks never depend "
                            "on a GCS)")
    onoff.add_argument("--no-mavlink", dest="mavlink", action="store_false",
                       help="no MAVLink: the scenario's scripted take-off and setpoints")
    add_gcs_arguments(p)
    p.add_argument("--params", dest="param_file", default=None, metavar="FILE",
                   help="ArduPilot .parm file: loaded at start, saved atomically after "
                        "every PARAM_SET (created if missing)")
    p.add_argument("--mission", dest="mission_file", default=None, metavar="FILE",
                   help="QGC WPL 110 mission: loaded at start, saved after every upload")
    p.add_argument("--tlog", default=None, metavar="FILE.tlog",
                   help="MAVLink telemetry log of the GCS traffic, both directions (MAVProxy's "
                        "format: mavlogdump.py, MAVExplorer)")


def mavlink_wanted(args, realtime: bool) -> bool:
    """--mavlink / --no-mavlink, else on in real time and off in lockstep."""
    m = getattr(args, "mavlink", None)
    return realtime if m is None else bool(m)


def parse_params(items: list[str]) -> dict:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise OptionError(f"--param wants NAME=VALUE, got {item!r}")
        try:
            out[name.strip().upper()] = float(value)
        except ValueError:
            raise OptionError(f"--param {name}: {value!r} is not a number") from None
    return out


def options_from_args(args) -> FlightOptions:
    if args.speed is not None and args.speed <= 0:
        raise OptionError("--speed must be > 0")
    if args.duration is not None and args.duration <= 0:
        raise OptionError("--duration must be > 0")
    if args.imu_hz is not None and args.imu_hz <= 0:
        raise OptionError("--imu-hz must be > 0")
    if getattr(args, "viz_hz", None) is not None and args.viz_hz < 0:
        raise OptionError("--viz-hz must be >= 0 (0: no viewable channels)")
    realtime = bool(args.realtime or args.speed is not None)
    mav_extra = {}
    if hasattr(args, "no_default_gcs"):
        mav_extra = dict(mavlink=mavlink_wanted(args, realtime), gcs_urls=tuple(args.gcs),
                         no_default_gcs=args.no_default_gcs, param_file=args.param_file,
                         mission_file=args.mission_file, tlog=args.tlog)
        if args.tlog and not mav_extra["mavlink"]:
            raise OptionError("--tlog logs the MAVLink GCS traffic: fly the MAVLink vehicle "
                              "(--mavlink, the default in real time) or leave --tlog out")
    return FlightOptions(
        scenario=args.scenario, duration_s=args.duration, lockstep=not realtime,
        speed=args.speed if args.speed is not None else 1.0,
        busy_wait=bool(getattr(args, "busy_wait", False)),
        processes=getattr(args, "processes", 2), imu_hz=args.imu_hz, seed=args.seed,
        instance=args.instance, params=parse_params(args.param),
        transport=getattr(args, "transport", "shm"), hil_addr=getattr(args, "hil_addr", None),
        log_path=getattr(args, "log", None), viz_hz=getattr(args, "viz_hz", None),
        live=getattr(args, "live", None),
        features_off=tuple(args.feature_off), **mav_extra)
