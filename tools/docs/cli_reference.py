"""docs/reference/cli.md, generated from the `silbridge` parsers themselves.

    python -m silbridge.tools.docs.cli_reference            # rewrite the page
    python -m silbridge.tools.docs.cli_reference --check    # exit 1 if the page is stale

The page is never edited by hand: it is whatever tools/cli/cli.py's parser accepts, so a
flag added, renamed or given a new default shows up here the next time this runs, and the
test suite's `--check` fails until it does. Hidden options (help=argparse.SUPPRESS: the
deprecated spellings of tools/cli/aliases.py) are left out, as `--help` leaves them out.

The text must not depend on the machine that generates it: the parser is built with the
SILBRIDGE_* variables unset (a default such as $SILBRIDGE_ARDUCOPTER would otherwise leak a
local path) and the usage lines are wrapped at a fixed width.
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import os
import sys
from collections.abc import Iterator
from pathlib import Path

from silbridge.tools.docs.markdown_text import cell, nowrap_code

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_OUT = REPO_ROOT / "docs" / "reference" / "cli.md"
USAGE_WIDTH = 78           # columns of the usage blocks (the docs theme's text width)
REGENERATE = "python -m silbridge.tools.docs.cli_reference"

# Actions with no value of their own: their default (False, None, 0) says nothing.
_FLAG_ACTIONS = (argparse._StoreTrueAction, argparse._StoreFalseAction,
                 argparse._StoreConstAction, argparse._AppendConstAction,
                 argparse._CountAction, argparse._HelpAction, argparse._VersionAction)


@contextlib.contextmanager
def _neutral_environment() -> Iterator[None]:
    """No SILBRIDGE_* variables and a fixed terminal width while the parser is built."""
    saved = {k: v for k, v in os.environ.items() if k.startswith("SILBRIDGE_")}
    saved_columns = os.environ.get("COLUMNS")
    for k in saved:
        del os.environ[k]
    os.environ["COLUMNS"] = str(USAGE_WIDTH)
    try:
        yield
    finally:
        os.environ.update(saved)
        if saved_columns is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = saved_columns


def build_cli_parser() -> argparse.ArgumentParser:
    """The `silbridge` parser with every subcommand of this build, as `silbridge --help` sees it."""
    from silbridge.tools.cli.cli import available_commands, build_parser
    return build_parser(available_commands())


def _visible(action: argparse.Action) -> bool:
    return action.help != argparse.SUPPRESS and not isinstance(action, argparse._HelpAction)


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction | None:
    return next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)


def _help_text(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The help as `--help` prints it: %(default)s and friends expanded."""
    if not action.help:
        return ""
    return parser._get_formatter()._expand_help(action)   # argparse's own expansion


def _metavar(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    if action.nargs == 0:
        return ""
    formatter = parser._get_formatter()
    default = action.dest.upper() if action.option_strings else action.dest
    return formatter._format_args(action, default)        # "A B" for nargs=2, "[X]" for ?


def _default(action: argparse.Action) -> str:
    if isinstance(action, _FLAG_ACTIONS) or not action.option_strings:
        return ""
    d = action.default
    if d is None or d is argparse.SUPPRESS or d == []:
        return ""
    if isinstance(d, (list, tuple)):
        return " ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in d)
    if isinstance(d, float):
        return f"{d:g}"
    return str(d)


def _options_table(parser: argparse.ArgumentParser) -> list[str]:
    rows = []
    for action in parser._actions:
        if not _visible(action) or isinstance(action, argparse._SubParsersAction):
            continue
        if action.option_strings:
            name = " ".join(filter(None, (", ".join(action.option_strings),
                                          _metavar(parser, action))))
        else:                                   # a positional: its name as usage shows it
            name = _metavar(parser, action)
        choices = ""
        if action.choices is not None and action.metavar is not None:   # else shown as {a,b}
            choices = " (one of " + ", ".join(str(c) for c in action.choices) + ")"
        rows.append(f"| {nowrap_code(name)} | {cell(_default(action))} | "
                    f"{cell(_help_text(parser, action) + choices)} |")
    if not rows:
        return ["No options."]
    return ["| argument | default | meaning |", "|---|---|---|", *rows]


def _section(parser: argparse.ArgumentParser, path: list[str], summary: str,
             level: int = 2) -> list[str]:
    """One command's heading, summary, usage and options, then its own subcommands."""
    out = [f"{'#' * level} {' '.join(path)}", ""]
    text = parser.description or summary
    if text:
        out += [cell(text), ""]
    out += ["```text", parser.format_usage().strip(), "```", ""]
    out += _options_table(parser) + [""]
    sub = _subparsers(parser)
    if sub is None:
        return out
    helps = {a.dest: a.help or "" for a in sub._choices_actions}
    children = _unique_children(sub)
    out += ["| command | what it does |", "|---|---|"]
    out += [f"| [{' '.join([*path, name])}](#{_anchor([*path, name])}) | "
            f"{cell(helps.get(name, ''))} |" for name, _ in children] + [""]
    for name, child in children:
        # `silbridge X` at level 2 beside `silbridge` itself, `silbridge X Y` at 3
        out += _section(child, [*path, name], helps.get(name, ""), min(len(path) + 1, 4))
    return out


def _unique_children(sub: argparse._SubParsersAction) -> list[tuple[str, argparse.ArgumentParser]]:
    """(name, parser) of each subcommand once: an alias maps to a parser already listed."""
    seen: set[int] = set()
    out = []
    for name, child in sub.choices.items():
        if id(child) not in seen:
            seen.add(id(child))
            out.append((name, child))
    return out


def _anchor(path: list[str]) -> str:
    """The id mkdocs' toc extension gives the heading `silbridge X Y` (its default slugify:
    lower case, spaces to '-'); `mkdocs build --strict` fails if it ever differs."""
    return "-".join(path).lower()


def render() -> str:
    with _neutral_environment():
        parser = build_cli_parser()
        top = _section(parser, ["silbridge"], "")
    head = ["# Command-line reference", "",
            "Every `silbridge` subcommand with each of its options, generated from the parsers "
            f"themselves (`{REGENERATE}`); do not edit this page by hand. `silbridge COMMAND "
            "--help` prints the same text in the terminal.", ""]
    return "\n".join(head + top).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog=REGENERATE, description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=str(DEFAULT_OUT), metavar="FILE",
                   help="the page to write or check (default %(default)s)")
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 with a diff if the page differs from the parsers")
    args = p.parse_args(argv)
    text = render()
    out = Path(args.out)
    if args.check:
        current = out.read_text() if out.exists() else ""
        if current == text:
            return 0
        diff = difflib.unified_diff(current.splitlines(), text.splitlines(), str(out),
                                    "from the parsers", lineterm="", n=1)
        print("\n".join(list(diff)[:60]), file=sys.stderr)
        print(f"{out} is stale: regenerate it with `{REGENERATE}`", file=sys.stderr)
        return 1
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(f"wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
