"""`silbridge sitl`: the vehicle for a ground station, as ArduPilot's sim_vehicle.py gives it.

Real time, the MAVLink vehicle (ArduCopter-like: disarmed on the ground, flown from the GCS)
on UDP 14550 (QGroundControl) and 14540 (MAVSDK), running until Ctrl-C. `-I N` moves the
ground-station port by 10 N, as sim_vehicle.py -I N does, and the MAVSDK port by N, as PX4's
-i N does: moving 14540 by 10 N too would land instance 1's MAVSDK stream on instance 0's
QGroundControl port (14550), so several vehicles could not run side by side.
It is `silbridge fly --realtime --mavlink` with a GCS user's defaults; `fly` stays the
lockstep benchmark flight.
"""

from __future__ import annotations

import argparse

from silbridge.tools.cli.flight_args import (
    OptionError,
    add_duration_argument,
    add_fc_arguments,
    add_log_argument,
    add_mavlink_arguments,
    add_processes_argument,
    add_scenario_argument,
    add_strict_rates_argument,
    check_param_file,
    flight_duration,
    parse_params,
)

HELP = "a real-time vehicle for QGroundControl/MAVSDK (like sim_vehicle.py), until Ctrl-C"

# Port offset per instance: sim_vehicle.py -I N moves its GCS outputs by 10 N; PX4 -i N moves
# its MAVSDK (offboard) port 14540 by N. Keyed by the default endpoint's port.
QGC_PORT, MAVSDK_PORT = 14550, 14540       # mavlink.endpoints.DEFAULT_GCS_URLS' ports
PORT_STRIDE = {QGC_PORT: 10, MAVSDK_PORT: 1}


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scenario_argument(p)
    add_duration_argument(p, realtime_only=True)
    p.add_argument("--speed", type=float, default=1.0, metavar="X",
                   help="X times real time (default %(default)s)")
    p.add_argument("-I", "--sitl-instance", type=int, default=0, metavar="N",
                   help=f"instance number: the ground-station port {QGC_PORT} moves by "
                        f"{PORT_STRIDE[QGC_PORT]} N (sim_vehicle.py -I N), the MAVSDK port "
                        f"{MAVSDK_PORT} by N (PX4 -i N) (default %(default)s)")
    add_strict_rates_argument(p)
    add_processes_argument(p)
    add_fc_arguments(p)
    add_mavlink_arguments(p, switch=False)
    add_log_argument(p)
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")


def gcs_urls(instance: int, no_default: bool, extra) -> list[str]:
    """The vehicle's MAVLink endpoints: the defaults moved for instance N, then --gcs ones."""
    from silbridge.mavlink.endpoints import DEFAULT_GCS_URLS, parse_endpoint

    urls = [] if no_default else [
        f"{e.kind}:{e.host}:{e.port + PORT_STRIDE[e.port] * instance}"
        for e in map(parse_endpoint, DEFAULT_GCS_URLS)]
    return urls + [u for u in extra if u not in urls]


def options_from_args(args):
    from silbridge.tools.loop.flight import FlightOptions

    if args.speed <= 0:
        raise OptionError("--speed must be > 0")
    if not 0 <= args.sitl_instance < QGC_PORT - MAVSDK_PORT:
        # from 10 on, the MAVSDK port 14540 + N would reach instance 0's 14550
        raise OptionError(f"-I/--sitl-instance: give 0..{QGC_PORT - MAVSDK_PORT - 1}")
    check_param_file(args.param_file, save=args.save_params, mavlink=True)
    urls = gcs_urls(args.sitl_instance, args.no_default_gcs, args.gcs)
    if not urls:
        raise OptionError("--no-default-gcs leaves no MAVLink endpoint: add --gcs URL")
    return FlightOptions(
        scenario=args.scenario, duration_s=flight_duration(args.duration, True),
        lockstep=False, speed=args.speed, processes=args.processes,
        strict_rates=args.strict_rates,
        params=parse_params(args.param), features_off=tuple(args.feature_off),
        mavlink=True, gcs_urls=tuple(urls), no_default_gcs=True,
        param_file=args.param_file, save_params=args.save_params,
        mission_file=args.mission_file, tlog=args.tlog, log_path=args.log)


def run(args) -> int:
    from silbridge.tools.cli.cmd_fly import fly_and_report, progress_printer

    opts = options_from_args(args)
    until = "until stopped (Ctrl-C)" if opts.duration_s == float("inf") else \
        f"for {opts.duration_s:g} s of sim time"
    progress_printer(args.json)(f"sitl: MAVLink vehicle on {', '.join(opts.gcs_urls)}; "
                                f"real time x{opts.speed:g} {until}")
    # Ctrl-C is how a sitl session ends: the shell's 130, as sim_vehicle.py's.
    return fly_and_report(opts, json_out=args.json)
