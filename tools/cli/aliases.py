"""Old flag spellings kept for one release as hidden, deprecated aliases.

The flag vocabulary was made one across subcommands (issue 22); a renamed flag
keeps its old spelling so existing scripts still run, but the old spelling is
hidden from `--help` and says once on stderr what to type instead. The alias
copies the new flag's action (type, nargs, choices, store/append/store_true) so
both spellings land in the same ``dest`` in exactly the same way.

Usage, after the new flag has been added to the same parser::

    add_deprecated_alias(p, "--hil-addr", "--link-addr")
    add_deprecated_alias(p, "--output", "out")        # or name the new flag's dest
"""

from __future__ import annotations

import argparse
import sys


class _DeprecatedAlias(argparse.Action):
    """Says the flag is deprecated, then does exactly what the new flag's action does."""

    def __init__(self, option_strings, dest, *, target: argparse.Action, new_flag: str,
                 **_ignored):
        # default=SUPPRESS: the alias must never overwrite the new flag's default.
        super().__init__(option_strings, dest, nargs=target.nargs, const=target.const,
                         default=argparse.SUPPRESS, type=target.type, choices=target.choices,
                         metavar=target.metavar, help=argparse.SUPPRESS)
        self._target = target
        self._new_flag = new_flag

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"{parser.prog}: {option_string} is deprecated, use {self._new_flag}",
              file=sys.stderr)
        self._target(parser, namespace, values, self._new_flag)


def _find_action(parser: argparse.ArgumentParser, new: str) -> argparse.Action:
    for action in parser._actions:   # argparse keeps no public list of a parser's actions
        if new.startswith("-") and new in action.option_strings:
            return action
        if not new.startswith("-") and action.dest == new and action.option_strings:
            return action
    raise ValueError(f"add_deprecated_alias: add {new!r} to the parser before its alias")


def _long_flag(action: argparse.Action) -> str:
    longs = [s for s in action.option_strings if s.startswith("--")]
    return (longs or action.option_strings)[0]


def add_deprecated_alias(parser: argparse.ArgumentParser, old: str, new: str) -> argparse.Action:
    """Add ``old`` as a hidden alias of the already-added flag ``new`` (a flag or its dest).

    Using ``old`` prints "<prog>: <old> is deprecated, use <new>" on stderr and stores
    into the new flag's dest as the new flag would.
    """
    target = _find_action(parser, new)
    new_flag = new if new.startswith("-") else _long_flag(target)
    return parser.add_argument(old, dest=target.dest, action=_DeprecatedAlias,
                               target=target, new_flag=new_flag)
