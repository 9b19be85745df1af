"""`silbridge params`: the flight controller's parameters, from the one declaration.

    silbridge params list [--file F.parm] [--match TEXT]   names, values, units, ranges
    silbridge params show NAME [--file F.parm]              one parameter in full
    silbridge params diff FILE [FILE2]                      FILE against the defaults, or FILE2
    silbridge params export [--format parm|json|md] [--file F.parm] [--out PATH]

Values are the declared defaults unless `--file` gives an ArduPilot .parm file (as `silbridge
fc --params FILE` saves it); a file's values are validated exactly as the FC would apply them,
and refused entries are reported. Every form takes --json (one JSON object on stdout).
"""

from __future__ import annotations

import argparse
import json
import os
import sys

from silbridge.tools.cli.aliases import add_deprecated_alias

HELP = "list, show, diff and export the flight-controller parameters"


class ParamsCommandError(Exception):
    user_facing = True


def _json_flag(p) -> None:
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS,
                   help="one JSON object on stdout")


def add_arguments(p) -> None:
    p.add_argument("--json", action="store_true", default=False,
                   help="one JSON object on stdout")
    sub = p.add_subparsers(dest="action", metavar="ACTION")
    sub.required = True
    lp = sub.add_parser("list", help="every parameter: name, value, unit, range")
    lp.add_argument("--file", help="values from this .parm file (default: the defaults)")
    lp.add_argument("--match", default=None, help="only names containing TEXT")
    _json_flag(lp)
    sp = sub.add_parser("show", help="one parameter in full")
    sp.add_argument("name")
    sp.add_argument("--file", help="value from this .parm file")
    _json_flag(sp)
    dp = sub.add_parser("diff", help="a .parm file against the defaults or another file")
    dp.add_argument("file")
    dp.add_argument("file2", nargs="?")
    _json_flag(dp)
    ep = sub.add_parser("export", help="write the parameter set as .parm, JSON or Markdown")
    ep.add_argument("--format", choices=("parm", "json", "md"), default="parm",
                    help="file format (default %(default)s)")
    ep.add_argument("--file", help="values from this .parm file (default: the defaults)")
    ep.add_argument("--out", "-o", metavar="FILE",
                    help="write here (atomically for .parm) (default: stdout)")
    add_deprecated_alias(ep, "--output", "--out")
    _json_flag(ep)


# ---- values ------------------------------------------------------------------------------------

def _values(path: str | None) -> tuple[dict[str, float], list[str]]:
    """name -> value (defaults, then the file's valid entries) and the refusals."""
    from silbridge.fc_sil import params as P
    from silbridge.fc_sil.flight_core import FlightCore
    from silbridge.fc_sil.param_store import CoreParamStore
    from silbridge.mavlink.errors import ParamFileError
    from silbridge.mavlink.gcs.params_file import apply_parm, load_parm

    store = CoreParamStore(FlightCore())
    problems: list[str] = []
    if path:
        if not os.path.exists(path):
            raise ParamsCommandError(f"no such parameter file {path!r}; give a .parm file "
                                     f"(`silbridge fc --params FILE` writes one)")
        try:
            problems = apply_parm(store, load_parm(path))
        except ParamFileError as exc:
            raise ParamsCommandError(str(exc)) from None
    return {p.name: store.get(p.name)[0] for p in P.PARAMS}, problems


def _fmt(v: float, typ: str) -> str:
    return str(int(v)) if typ != "FLOAT" else f"{v:g}"


def _row(p, value) -> dict:
    return {"index": p.index, "name": p.name, "type": p.type, "value": value,
            "default": p.default, "min": p.min, "max": p.max, "unit": p.unit,
            "where": "host" if p.host else "core", "text": p.text}


# ---- actions -----------------------------------------------------------------------------------

def _list(args) -> int:
    from silbridge.fc_sil import params as P
    values, problems = _values(args.file)
    defaults, _ = _values(None)
    rows = [_row(p, values[p.name]) for p in P.PARAMS
            if args.match is None or args.match.upper() in p.name]
    if args.json:
        print(json.dumps({"count": len(rows), "params": rows, "problems": problems}))
        return 0
    for r in rows:
        p = P.BY_NAME[r["name"]]
        mark = "*" if r["value"] != defaults[p.name] else " "
        rng = f"[{_fmt(p.min, p.type)}, {_fmt(p.max, p.type)}]"
        print(f"{p.name:<16} {mark}{_fmt(r['value'], p.type):>10} {p.unit:<7} {rng:<18} "
              f"{r['where']}")
    print(f"{len(rows)} parameters" + (" (* differs from the default)" if args.file else ""))
    for msg in problems:
        print(f"refused: {msg}", file=sys.stderr)
    return 0


def _show(args) -> int:
    from silbridge.fc_sil import params as P
    from silbridge.fc_sil.errors import ParamError
    try:
        p = P.lookup(args.name)
    except ParamError as exc:
        raise ParamsCommandError(str(exc)) from None
    values, _ = _values(args.file)
    row = _row(p, values[p.name])
    if args.json:
        print(json.dumps(row))
        return 0
    print(f"{p.name} = {_fmt(row['value'], p.type)} {p.unit}".rstrip())
    print(f"  {p.text}")
    print(f"  type {p.type}, default {_fmt(p.default, p.type)}, range "
          f"[{_fmt(p.min, p.type)}, {_fmt(p.max, p.type)}], index {p.index}, "
          f"{'host (Python runtime)' if p.host else 'core (C struct)'}")
    return 0


def _diff(args) -> int:
    from silbridge.fc_sil import params as P
    a, prob_a = _values(args.file)
    if args.file2:
        b, prob_b = _values(args.file2)
        label_a, label_b = args.file, args.file2
    else:
        b, prob_b = a, []
        a, _ = _values(None)          # the defaults as stored (float32), like the file's
        label_a, label_b = "default", args.file
    rows = [{"name": p.name, "a": a[p.name], "b": b[p.name]} for p in P.PARAMS
            if a[p.name] != b[p.name]]
    problems = prob_a + prob_b
    if args.json:
        print(json.dumps({"a": label_a, "b": label_b, "differences": rows,
                          "problems": problems}))
        return 0
    print(f"{'NAME':<16} {label_a:>14} {label_b:>14}")
    for r in rows:
        t = P.BY_NAME[r["name"]].type
        print(f"{r['name']:<16} {_fmt(r['a'], t):>14} {_fmt(r['b'], t):>14}")
    print(f"{len(rows)} differ")
    for msg in problems:
        print(f"refused: {msg}", file=sys.stderr)
    return 0


def _export(args) -> int:
    from silbridge.fc_sil import params as P
    from silbridge.mavlink.gcs.params_file import format_parm, save_parm

    values, problems = _values(args.file)
    if args.format == "parm":
        entries = [(p.name, values[p.name], p.mav_type) for p in P.PARAMS]
        if args.out:
            save_parm(args.out, entries)
            text = None
        else:
            text = format_parm(entries)
    elif args.format == "json":
        text = json.dumps({p.name: values[p.name] for p in P.PARAMS}, indent=1) + "\n"
    else:
        text = _markdown(values)
    if text is not None and args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            f.write(text)
    if args.json:
        print(json.dumps({"format": args.format, "output": args.out, "count": len(values),
                          "problems": problems,
                          **({} if args.out else {"text": text})}))
    elif text is not None and not args.out:
        sys.stdout.write(text)
    for msg in problems:
        print(f"refused: {msg}", file=sys.stderr)
    return 0


def _markdown(values: dict[str, float]) -> str:
    from silbridge.fc_sil import params as P
    out = ["| Name | Value | Default | Min | Max | Unit | Description |",
           "|---|---:|---:|---:|---:|---|---|"]
    for p in P.PARAMS:
        out.append(f"| `{p.name}` | {_fmt(values[p.name], p.type)} | {_fmt(p.default, p.type)}"
                   f" | {_fmt(p.min, p.type)} | {_fmt(p.max, p.type)} | {p.unit} | "
                   f"{p.text.replace('|', chr(92) + '|')} |")
    return "\n".join(out) + "\n"


def run(args) -> int:
    return {"list": _list, "show": _show, "diff": _diff, "export": _export}[args.action](args)
