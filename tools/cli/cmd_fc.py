"""`silbridge fc`: the SIL flight-controller program (attaches to a bridge's segment).

The bridge's own --param/--feature-off/--params reach this program through
tools/loop/fc_handover.py; this command line is applied on top of them.
"""

from __future__ import annotations

import json
import sys

from silbridge.tools.loop.flight import FlightOptions, close_fc_loop, make_fc_loop, mavlink_options
from silbridge.tools.cli.flight_args import (
    OptionError,
    add_fc_arguments,
    add_mavlink_arguments,
    add_transport_arguments,
    add_view_arguments,
    check_link_addr,
    check_mavlink_only,
    check_param_file,
    mavlink_wanted,
    parse_params,
)
from silbridge.tools.loop.stop_signals import STOP
from silbridge.tools.loop.transport_wiring import fc_segment, guard_fc

HELP = "the SIL FC program: attach to a running bridge and fly its vehicle"


def add_arguments(p) -> None:
    p.add_argument("--instance", default="silbridge",
                   help="shared-memory instance name of the bridge (default %(default)s)")
    p.add_argument("--attach-timeout", type=float, default=10.0, metavar="S",
                   help="wait this long for the bridge's segment (default %(default)s s)")
    add_transport_arguments(p, listen=False)
    add_fc_arguments(p)
    p.add_argument("--param-at", action="append", default=[], metavar="NAME=VALUE@S",
                   help="set an FC parameter at a sim time (repeatable), e.g. SB_ATT_SRC=1@40; "
                        "`fly` passes a scenario's [[fc_param]] entries this way")
    add_mavlink_arguments(p)
    p.add_argument("--log", default=None, metavar="FILE.mcap",
                   help="write the run's MCAP log from the FC side")
    p.add_argument("--log-meta", default=None, metavar="FILE.json",
                   help="start metadata for --log (config, scenario), as `fly` passes it")
    add_view_arguments(p)
    p.add_argument("--json", action="store_true", help="print the FC summary as JSON")


def run(args) -> int:
    from silbridge.fc_sil.fc_loop import run_fc

    from silbridge.fc_sil.param_schedule import parse_param_at
    from silbridge.tools.loop.fc_handover import take_handover
    from silbridge.tools.loop.fc_param_events import check_fc_param

    params = parse_params(args.param)
    check_link_addr(args.transport, args.link_addr)
    check_param_file(args.param_file, save=args.save_params, mavlink=True)   # before waiting
    try:
        events = [parse_param_at(text) for text in args.param_at]
        for ev in events:
            check_fc_param(ev.name, ev.value)
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    from silbridge.shm import lockstep as ls

    with fc_segment(args.transport, args.instance, hil_addr=args.link_addr,
                    timeout_s=args.attach_timeout) as seg:
        # MAVLink by default when the bridge runs in real time (see add_mavlink_arguments)
        realtime = seg.word(ls.RUN_MODE) != ls.MODE_LOCKSTEP
        # The bridge is up: take what it hands over (its file exists by now).
        given = take_handover(args.instance)
        params = {**given.get("params", {}), **params}
        features_off = tuple(dict.fromkeys([*given.get("features_off", []),
                                            *args.feature_off]))
        param_file = args.param_file or given.get("param_file")
        if given:
            print(f"fc: from the bridge: {_describe(given)}", file=sys.stderr)
        mav_opts = mavlink_options(FlightOptions(
            mavlink=mavlink_wanted(args, realtime), gcs_urls=tuple(args.gcs),
            no_default_gcs=args.no_default_gcs, param_file=param_file,
            save_params=args.save_params, mission_file=args.mission_file, tlog=args.tlog))
        check_param_file(param_file, save=args.save_params, mavlink=mav_opts is not None)
        check_mavlink_only(args, mav_opts is not None)
        loop = make_fc_loop(seg, params=params, features_off=features_off,
                            mavlink=mav_opts, out=out, param_events=events,
                            param_file=param_file)
        guard_fc(loop)
        sink = _open_log(args, loop)
        summary = None
        ended = {}
        from silbridge.fc_sil.sim_notice import NoticeReader    # the bridge's rate reports
        notices = NoticeReader(args.instance, loop) if realtime else None
        try:
            with STOP.polling():
                summary = run_fc(loop, out=out, stop=STOP, notices=notices)
        except BaseException as exc:
            # The log says why it ends early (analyze then checks it up to there).
            ended = {"aborted": f"{type(exc).__name__}: {exc}"}
            raise
        finally:
            close_fc_loop(loop)
            if sink is not None:
                why = (summary or {}).get("interrupted") or STOP.name
                rates = {"rates": notices.final} if notices and notices.final else {}
                sink.close(**({"interrupted": why} if why else ended), **rates)
        if mav_opts is not None:
            summary["mavlink"] = loop.supervisor.summary()
    if args.json:
        print(json.dumps(summary), flush=True)
    else:
        lat, jit = summary["latency_us"], summary["jitter_us"]
        print(f"FC consumed {summary['records']} records in {summary['polls']} polls, "
              f"published {summary['pwm_published']} PWM")
        print(f"sensor->FC latency p50 {lat['p50']} us p99 {lat['p99']} us; "
              f"jitter p50 {jit['p50']} us p99 {jit['p99']} us")
        if summary.get("interrupted"):
            print(f"INTERRUPTED ({summary['interrupted']}): a partial run")
    return STOP.exit_code(0)


def _describe(given: dict) -> str:
    parts = [f"--param {k}={v:g}" for k, v in given.get("params", {}).items()]
    parts += [f"--feature-off {f}" for f in given.get("features_off", [])]
    if given.get("param_file"):
        parts.append(f"--params {given['param_file']}")
    return " ".join(parts)


def _open_log(args, loop):
    """The FC-side MCAP log of `fc --log` (fly --processes 2 --log passes the metadata)."""
    if not args.log and args.live is None:
        return None
    from silbridge.tools.loop.run_log import open_run_sink

    meta = {}
    if args.log_meta:
        with open(args.log_meta) as fh:
            meta = json.load(fh)
    meta["params"] = loop.core.params()
    sink = open_run_sink(args.log, meta, viz_hz=args.viz_hz, live=args.live,
                         out=lambda s: print(s, file=sys.stderr))
    loop.sink = sink
    if getattr(loop.supervisor, "sink", "absent") is None:
        loop.supervisor.sink = sink
    return sink
