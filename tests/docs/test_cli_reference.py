"""docs/reference/cli.md is the parsers' own description: current, complete, free of hidden
aliases and of whatever machine generated it."""

from __future__ import annotations

import argparse
import html
import re
import subprocess
import sys

from silbridge.tools.docs import cli_reference
from silbridge.tools.docs.cli_reference import build_cli_parser, render

REGENERATE = "python -m silbridge.tools.docs.cli_reference"


def _commands(parser: argparse.ArgumentParser, path: tuple[str, ...] = ("silbridge",)):
    """(path, parser) of every command and subcommand, the root included."""
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from _commands(child, (*path, name))


def test_the_checked_in_page_matches_the_parsers():
    done = subprocess.run([sys.executable, "-m", "silbridge.tools.docs.cli_reference", "--check"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, (f"docs/reference/cli.md is stale; regenerate it with "
                                  f"`{REGENERATE}`:\n{done.stderr[-3000:]}")


def test_check_fails_on_a_stale_page_and_says_how_to_fix_it(tmp_path):
    page = tmp_path / "cli.md"
    assert cli_reference.main(["--out", str(page)]) == 0
    assert cli_reference.main(["--out", str(page), "--check"]) == 0
    page.write_text(page.read_text().replace("## silbridge fly", "## silbridge fly-old"))
    done = subprocess.run([sys.executable, "-m", "silbridge.tools.docs.cli_reference", "--check",
                           "--out", str(page)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert REGENERATE in done.stderr and "fly-old" in done.stderr


_ROW = re.compile(r"^\| <code[^>]*>(.*?)</code> \| (.*?) \| ", re.M)


def _rows(section: str) -> dict[str, str]:
    """flag -> default cell, for each option row of one command's section."""
    out = {}
    for name, default in _ROW.findall(section):
        for flag in re.findall(r"(?:^|, )(-[-\w]+)", html.unescape(name)):
            out[flag] = default
    return out


def _section(text: str, path: tuple[str, ...]) -> str:
    head = f"{'#' * min(len(path), 4) if len(path) > 1 else '##'} {' '.join(path)}\n"
    assert head in text, f"no section for {' '.join(path)}"
    return text.split(head, 1)[1].split("\n#", 1)[0]


def test_every_command_and_visible_option_is_on_the_page_and_no_hidden_one():
    text = render()
    for path, parser in _commands(build_cli_parser()):
        rows = _rows(_section(text, path))
        for action in parser._actions:
            if not action.option_strings or isinstance(action, argparse._HelpAction):
                continue
            for flag in action.option_strings:
                if action.help == argparse.SUPPRESS:
                    assert flag not in rows, f"hidden {flag} of {' '.join(path)} listed"
                else:
                    assert flag in rows, f"{flag} of {' '.join(path)} not listed"


def test_defaults_on_the_page_are_the_parsers_defaults():
    """`bench --runs` and `--scenarios`: the default column shows the value argparse uses."""
    rows = _rows(_section(render(), ("silbridge", "bench")))
    args = build_cli_parser().parse_args(["bench"])
    assert rows["--runs"] == str(args.runs)
    assert rows["--scenarios"] == args.scenarios


def test_the_page_does_not_depend_on_the_environment(monkeypatch):
    plain = render()
    monkeypatch.setenv("SILBRIDGE_ARDUCOPTER", "/home/someone/ardupilot/build/arducopter")
    monkeypatch.setenv("SILBRIDGE_PX4", "/home/someone/px4/bin/px4")
    monkeypatch.setenv("COLUMNS", "37")
    assert render() == plain
    assert "/home/someone" not in plain
