"""Entry of the transport comparison's child processes (tools/transport/transport_bench.py).

    python -m silbridge.tools.transport.transport_child runner --steps 1000,2000 \
        --seconds-per-rate S
    python -m silbridge.tools.transport.transport_child fc
    ... [--no-fastcrc]

`runner` is the bridge side: told {"go": "udp"} it runs all IMU steps of that transport and
answers with its summary; `fc` is the FC child a runner keeps for all its steps. Both speak
the line protocol of tools/transport/transport_procs.py.

--no-fastcrc makes `import fastcrc` fail in this process before anything imports pymavlink,
which then falls back to its pure-Python CRC (the paper's RPC figures match that case). The
switch lives only in this entry point: no module of ours keeps it.
"""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--no-fastcrc" in argv:
        if "pymavlink.dialects.v20.common" in sys.modules:
            raise RuntimeError("pymavlink was imported before --no-fastcrc could take effect")
        sys.modules["fastcrc"] = None        # `import fastcrc` now raises ImportError
    p = argparse.ArgumentParser(prog="transport_child")
    sub = p.add_subparsers(dest="role", required=True)
    r = sub.add_parser("runner")
    r.add_argument("--steps", required=True)
    r.add_argument("--seconds-per-rate", type=float, required=True)
    r.add_argument("--no-fastcrc", action="store_true")
    f = sub.add_parser("fc")
    f.add_argument("--no-fastcrc", action="store_true")
    args = p.parse_args(argv)

    from silbridge.tools.loop.stop_signals import install_worker
    from silbridge.tools.transport.transport_procs import protocol_channel, serve_fc, serve_runner
    # Ctrl-C, SIGTERM or the parent's soft stop: KeyboardInterrupt here, so every `with`
    # unwinds (the step's segment is unlinked, sockets closed) before the child exits.
    stop = install_worker()
    proto = protocol_channel()
    try:
        return _serve(args, proto, serve_fc, serve_runner)
    except KeyboardInterrupt:
        return stop.exit_code(130)


def _serve(args, proto, serve_fc, serve_runner) -> int:
    if args.role == "fc":
        return serve_fc(proto=proto)
    steps = [int(x) for x in args.steps.split(",") if x]
    return serve_runner(steps, args.seconds_per_rate, not args.no_fastcrc, proto=proto)


if __name__ == "__main__":
    sys.exit(main())
