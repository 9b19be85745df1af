"""Entry of the transport comparison's child processes (tools/transport_bench.py).

    python -m silbridge.tools.transport_child variant NAME --steps 1000,2000 --duration S
    python -m silbridge.tools.transport_child fc --transport T --instance N [--hil-addr A]
    ... [--no-fastcrc]

--no-fastcrc makes `import fastcrc` fail in this process before anything imports pymavlink,
which then falls back to its pure-Python CRC (the paper's RPC figures match that case). The
switch lives only in this entry point: no module of ours keeps it.
"""

from __future__ import annotations

import argparse
import json
import sys


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--no-fastcrc" in argv:
        if "pymavlink.dialects.v20.common" in sys.modules:
            raise RuntimeError("pymavlink was imported before --no-fastcrc could take effect")
        sys.modules["fastcrc"] = None        # `import fastcrc` now raises ImportError
    p = argparse.ArgumentParser(prog="transport_child")
    sub = p.add_subparsers(dest="role", required=True)
    v = sub.add_parser("variant")
    v.add_argument("name")
    v.add_argument("--steps", required=True)
    v.add_argument("--duration", type=float, required=True)
    v.add_argument("--no-fastcrc", action="store_true")
    f = sub.add_parser("fc")
    f.add_argument("--transport", required=True)
    f.add_argument("--instance", required=True)
    f.add_argument("--hil-addr", default=None)
    f.add_argument("--no-fastcrc", action="store_true")
    args = p.parse_args(argv)

    from . import transport_bench as tb
    if args.role == "variant":
        steps = [int(x) for x in args.steps.split(",") if x]
        result = tb.run_variant(args.name, steps, args.duration)
    else:
        result = tb.fc_child(args.transport, args.instance, args.hil_addr)
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
