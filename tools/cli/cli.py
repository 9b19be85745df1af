"""The `silbridge` command line: one command, one module per subcommand.

Each subcommand lives in ``silbridge.tools.cmd_<name>`` and exposes
``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``.
Modules are imported only when their subcommand runs, so `silbridge fc`
does not pay for JSBSim and `silbridge --help` is instant.

Errors meant for the user (a missing segment, a bad scenario file, ...) are
exceptions whose class sets ``user_facing = True``: they are printed as one
line that says what to do, exit status 2. Anything else is a bug and keeps
its traceback.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys

from silbridge.tools.version import package_version

# name -> module; the order is the order of `silbridge --help`.
COMMANDS = {
    "bridge": "cmd_bridge",
    "fc": "cmd_fc",
    "fly": "cmd_fly",
    "sitl": "cmd_sitl",
    "soak": "cmd_soak",
    "bench": "cmd_bench",
    "ablate": "cmd_ablate",
    "transport": "cmd_transport",
    "analyze": "cmd_analyze",
    "params": "cmd_params",
    "shm-bench": "cmd_shm_bench",
    "fc-bench": "cmd_fc_bench",
    "speed": "cmd_speed",
    "clean": "cmd_clean",
    "tune": "cmd_tune",
}


def _module_name(mod: str) -> str:
    return f"{__package__}.{mod}"


def available_commands() -> dict[str, str]:
    """Subcommands whose module exists in this build."""
    return {name: mod for name, mod in COMMANDS.items()
            if importlib.util.find_spec(_module_name(mod)) is not None}


def build_parser(commands: dict[str, str]) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="silbridge",
        description="High-rate software-in-the-loop toolkit for multirotor flight control.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {package_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, mod in commands.items():
        module = importlib.import_module(_module_name(mod))
        p = sub.add_parser(name, help=getattr(module, "HELP", ""),
                           description=getattr(module, "HELP", None))
        module.add_arguments(p)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    commands = available_commands()
    # Import only the module asked for when we can tell which one it is.
    wanted = next((a for a in argv if not a.startswith("-")), None)
    if wanted in commands:
        commands = {wanted: commands[wanted]}
    parser = build_parser(commands)
    args = parser.parse_args(argv)
    from silbridge.tools.loop.stop_signals import install
    stop = install()   # Ctrl-C / SIGTERM: stop at the next step (tools/loop/stop_signals.py)
    try:
        return int(args._run(args) or 0)
    except KeyboardInterrupt:
        print("silbridge: interrupted", file=sys.stderr)
        return stop.exit_code(130)
    except Exception as exc:  # noqa: BLE001 - only user-facing errors are shortened
        if getattr(exc, "user_facing", False):
            print(f"silbridge {args.command}: error: {exc}", file=sys.stderr)
            return 2
        raise


if __name__ == "__main__":
    sys.exit(main())
