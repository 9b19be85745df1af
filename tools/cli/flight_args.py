"""Command-line options shared by `silbridge bridge`, `fc`, `fly` and `sitl`.

The flag vocabulary is one across subcommands (notes: issue 22): `--link-addr` for
the simulator link, `--params FILE` read-only with `--save-params` to write GCS
changes back, `--duration` in simulated seconds ("until stopped" in real time).
Old spellings are hidden aliases (tools/cli/aliases.py).
"""

from __future__ import annotations

import argparse
import math
import os

from silbridge.fc_sil.params import FEATURES

from silbridge.tools.cli.aliases import add_deprecated_alias
from silbridge.tools.loop.flight import FlightOptions


class OptionError(ValueError):
    user_facing = True


def duration_s(text: str) -> float:
    """--duration: simulated seconds > 0, or inf (until stopped; real time only)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds (or inf)") \
            from None
    if not value > 0:       # also refuses nan
        raise argparse.ArgumentTypeError(f"{text!r}: want seconds > 0, or inf")
    return value


def add_duration_argument(p: argparse.ArgumentParser, *, realtime_only: bool = False) -> None:
    default = ("until stopped (Ctrl-C)" if realtime_only else
               "the scenario's duration in lockstep; until stopped (Ctrl-C) in real time")
    p.add_argument("--duration", type=duration_s, default=None, metavar="S",
                   help=f"simulated seconds, or inf (default: {default})")


def add_scenario_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scenario", default="S1",
                   help="built-in scenario name (S1..S5) or a TOML file (default %(default)s)")


def add_processes_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--processes", type=int, choices=(1, 2), default=2,
                   help="FC in its own process (2) or in the simulator's (1) "
                        "(default %(default)s)")


def add_log_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--log", default=None, metavar="FILE.mcap",
                   help="write the run's MCAP log (open it in Foxglove; `silbridge analyze`)")


def add_flight_arguments(p: argparse.ArgumentParser, *, processes: bool,
                         link_help: str = "") -> None:
    add_scenario_argument(p)
    add_duration_argument(p)
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--lockstep", action="store_true",
                      help="deterministic, as fast as possible (default)")
    mode.add_argument("--realtime", action="store_true", help="pace to the wall clock")
    mode.add_argument("--speed", type=float, default=None, metavar="X",
                      help="real time at X times the wall clock")
    p.add_argument("--busy-wait", action="store_true",
                   help="real time: spin between steps instead of sleeping (one core at 100 %%; "
                        "a sleeping core's caches go cold: loop jitter p99 ~2x lower here)")
    add_strict_rates_argument(p)
    if processes:
        add_processes_argument(p)
    p.add_argument("--imu-hz", type=float, default=None, metavar="N",
                   help="IMU rate (a whole multiple of the 1 kHz physics rate; "
                        "default: the scenario's)")
    p.add_argument("--seed", type=int, default=None,
                   help="override the scenario's seed (default: the scenario's)")
    p.add_argument("--instance", default=None,
                   help="shared-memory instance name (several runs can coexist)")
    add_transport_arguments(p, listen=True, extra_help=link_help)
    add_fc_arguments(p)
    if processes:
        add_log_argument(p)
        add_view_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_strict_rates_argument(p: argparse.ArgumentParser) -> None:
    """--strict-rates: the real-time rate check refuses instead of reporting (`fly`, `sitl`)."""
    from silbridge.bridge.bridge_driver import BridgeRunConfig

    tol = BridgeRunConfig.rate_tolerance * 100
    p.add_argument("--strict-rates", action="store_true",
                   help=f"real time: stop at start-up (exit 2) when IMU or PWM miss their rate "
                        f"by more than {tol:g} %%, as benchmarks need; by default a slow host "
                        f"is reported (console, summary, log, STATUSTEXT) and the run goes on")


def add_view_arguments(p: argparse.ArgumentParser) -> None:
    """--viz-hz and --live: the log's viewable channels (tools/logs/viz_log.py, docs/logs.md)."""
    from silbridge.tools.logs.live_view import DEFAULT_HOST, DEFAULT_PORT
    from silbridge.tools.logs.viz_log import SCENE_HZ, VIEW3D_HZ, VIZ_HZ_DEFAULT

    p.add_argument("--viz-hz", type=float, default=None, metavar="N",
                   help="viewable per-sample log channels (/viz/...: Foxglove plots and 3D) "
                        f"at most N messages per second each (default {VIZ_HZ_DEFAULT:g}: every "
                        f"sample; 3D at most {VIEW3D_HZ:g}, scene {SCENE_HZ:g}; 0: none)")
    p.add_argument("--live", nargs="?", const="", default=None, metavar="HOST:PORT",
                   help="serve the viewable channels live over Foxglove's WebSocket protocol "
                        f"(default {DEFAULT_HOST}:{DEFAULT_PORT}; port 0: a free one)")


def add_transport_arguments(p: argparse.ArgumentParser, *, listen: bool,
                            extra_help: str = "") -> None:
    """--transport shm|udp|tcp and --link-addr (docs/hil_transport.md)."""
    from silbridge.tools.loop.transport_wiring import HIL_PORT

    p.add_argument("--transport", choices=("shm", "udp", "tcp"), default="shm",
                   help="bridge <-> FC link: shared memory, or MAVLink 2 HIL messages "
                        "over UDP or TCP (PX4 convention: the simulator listens) "
                        "(default %(default)s)")
    where = (f"listen on HOST:PORT (bridge default 127.0.0.1:{HIL_PORT}; `fly` picks a free "
             f"port)" if listen else f"the simulator's HOST:PORT (default 127.0.0.1:{HIL_PORT})")
    p.add_argument("--link-addr", default=None, metavar="HOST:PORT|serial:DEV:BAUD",
                   help=f"udp/tcp only: {where}; or a serial line, e.g. "
                        f"serial:/dev/ttyACM0:921600{extra_help}")
    add_deprecated_alias(p, "--hil-addr", "--link-addr")


def add_fc_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="set an FC parameter (repeatable; applied after --params), "
                        "e.g. ATC_RAT_RLL_D=0.004")
    p.add_argument("--feature-off", action="append", default=[], metavar="FEATURE",
                   choices=list(FEATURES),
                   help="switch a stabilisation feature off (ablation), repeatable: "
                        + ", ".join(FEATURES))
    p.add_argument("--params", dest="param_file", default=None, metavar="FILE",
                   help="ArduPilot .parm file loaded at start, in every mode; read-only "
                        "unless --save-params")


def add_mavlink_arguments(p: argparse.ArgumentParser, *, switch: bool = True) -> None:
    """The MAVLink vehicle's options (`silbridge fly`, `fc`, `sitl`; sitl has no on/off)."""
    from silbridge.mavlink.endpoints import add_gcs_arguments

    if switch:
        onoff = p.add_mutually_exclusive_group()
        onoff.add_argument("--mavlink", dest="mavlink", action="store_true", default=None,
                           help="fly the MAVLink vehicle: disarmed on the ground, GCS control "
                                "only (default in real time; off in lockstep so benchmarks "
                                "never depend on a GCS)")
        onoff.add_argument("--no-mavlink", dest="mavlink", action="store_false",
                           help="no MAVLink: the scenario's scripted take-off and setpoints")
    add_gcs_arguments(p)
    p.add_argument("--save-params", action="store_true",
                   help="write PARAM_SET changes back to the --params FILE (atomically; "
                        "a missing FILE is created)")
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


def check_param_file(path: str | None, *, save: bool, mavlink: bool) -> None:
    """--params FILE is read-only and must exist; --save-params writes GCS changes back."""
    if save and not path:
        raise OptionError("--save-params writes PARAM_SET changes to the --params FILE: "
                          "add --params FILE")
    if save and not mavlink:
        raise OptionError("--save-params saves what a GCS changes: fly the MAVLink vehicle "
                          "(--mavlink, real time, or `silbridge sitl`) or leave it out")
    if path is None:
        return
    if os.path.isdir(path):
        raise OptionError(f"--params {path}: is a folder; give a .parm file")
    if not save and not os.path.exists(path):
        raise OptionError(f"--params {path}: no such file; check the path (with "
                          f"--save-params a missing file is created)")


def check_mavlink_only(args, mavlink: bool) -> None:
    """--tlog, --gcs and --mission serve a ground station: without MAVLink they are refused."""
    if mavlink:
        return
    for flag, given, what in (("--tlog", args.tlog, "logs the MAVLink GCS traffic"),
                              ("--gcs", args.gcs, "adds a MAVLink GCS endpoint"),
                              ("--mission", args.mission_file, "is the MAVLink vehicle's")):
        if given:
            raise OptionError(f"{flag} {what}: fly the MAVLink vehicle (--mavlink, the default "
                              f"in real time; `silbridge sitl`) or leave {flag} out")


def check_link_addr(transport: str, link_addr: str | None) -> None:
    """Our FC's link: an address means something only over udp/tcp (or a serial line)."""
    if link_addr is not None and transport == "shm":
        raise OptionError("--link-addr is the udp/tcp link's address: add --transport udp "
                          "(or tcp), or leave it out for shared memory")


def flight_duration(duration: float | None, realtime: bool) -> float | None:
    """None (the scenario's) in lockstep; inf (until stopped) in real time by default."""
    if duration is not None and math.isinf(duration) and not realtime:
        raise OptionError("--duration inf runs until stopped, which lockstep cannot: give "
                          "seconds, or fly in real time (--realtime, --speed X, `silbridge sitl`)")
    if duration is None and realtime:
        return math.inf
    return duration


def options_from_args(args) -> FlightOptions:
    if args.speed is not None and args.speed <= 0:
        raise OptionError("--speed must be > 0")
    if args.imu_hz is not None and args.imu_hz <= 0:
        raise OptionError("--imu-hz must be > 0")
    if getattr(args, "viz_hz", None) is not None and args.viz_hz < 0:
        raise OptionError("--viz-hz must be >= 0 (0: no viewable channels)")
    # --lockstep, --realtime and --speed are one mutually exclusive group: an explicit
    # --lockstep states the default (sitl has no such flag: it is real time by nature).
    realtime = (not getattr(args, "lockstep", False)
                and bool(getattr(args, "realtime", False) or args.speed is not None))
    mav_extra = {}
    mavlink = False
    if hasattr(args, "no_default_gcs"):
        mavlink = mavlink_wanted(args, realtime)
        mav_extra = dict(mavlink=mavlink, gcs_urls=tuple(args.gcs),
                         no_default_gcs=args.no_default_gcs, mission_file=args.mission_file,
                         tlog=args.tlog, save_params=args.save_params)
        check_mavlink_only(args, mavlink)
    check_param_file(args.param_file, save=getattr(args, "save_params", False), mavlink=mavlink)
    return FlightOptions(
        scenario=args.scenario, duration_s=flight_duration(args.duration, realtime),
        lockstep=not realtime, speed=args.speed if args.speed is not None else 1.0,
        busy_wait=bool(getattr(args, "busy_wait", False)),
        strict_rates=bool(getattr(args, "strict_rates", False)),
        processes=getattr(args, "processes", 2), imu_hz=args.imu_hz, seed=args.seed,
        instance=args.instance, params=parse_params(args.param),
        transport=getattr(args, "transport", "shm"), hil_addr=getattr(args, "link_addr", None),
        log_path=getattr(args, "log", None), viz_hz=getattr(args, "viz_hz", None),
        live=getattr(args, "live", None), param_file=args.param_file,
        features_off=tuple(args.feature_off), **mav_extra)
