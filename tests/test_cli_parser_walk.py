"""Every flag `silbridge` accepts reaches the code that uses it, and says its real default.

The whole parser is built (tools/cli/cli.py build_parser over every subcommand) and walked:
each subcommand, each sub-subcommand (`tune sysid`, `params export`, ...), each option. Each
option's dest must be read as `args.<dest>` or `getattr(args, "<dest>")` in the command's
module or in a silbridge.tools module the command hands `args` to (`options_from_args(args)`,
`run_sysid(args, ...)`), transitively. A flag added to a parser and read nowhere fails here;
`test_the_walk_catches_an_unused_flag` proves it on a synthetic parser. Hidden aliases
(tools/cli/aliases.py) share their new flag's dest and are checked to be hidden.

Help texts: a "(default X)" must say the action's real default (argparse's %(default)s, or
a constant formatted into the text): a hand-typed number that drifted fails. A default of
None may be described in words, "(default: the scenario's)", but not with a value.
"""

from __future__ import annotations

import argparse
import ast
import importlib.util
import re
from pathlib import Path

import pytest

from silbridge.tools.cli import cli
from silbridge.tools.cli.aliases import _DeprecatedAlias

# Names a command's code uses for the parsed namespace.
ARGS_NAMES = {"args", "ns", "namespace", "opts_args"}
SKIP_ACTIONS = (argparse._HelpAction, argparse._VersionAction, _DeprecatedAlias)


# ---- what a command's code reads ----------------------------------------------------------

def _is_module(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, AttributeError):    # a.b.c where a.b is a module, not a package
        return False


def _source(module: str) -> tuple[Path, ast.Module] | None:
    spec = importlib.util.find_spec(module) if _is_module(module) else None
    if spec is None or not spec.origin or not spec.origin.endswith(".py"):
        return None
    path = Path(spec.origin)
    return path, ast.parse(path.read_text(), str(path))


def _imported_names(tree: ast.Module) -> dict[str, str]:
    """Local name -> the silbridge.tools module it comes from (imports anywhere in the file,
    function bodies included): `from M import f` gives f -> M, `import M as m` gives m -> M."""
    out = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("silbridge.tools"):
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                out[alias.asname or alias.name] = sub if _is_module(sub) else node.module
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("silbridge.tools"):
                    out[alias.asname or alias.name] = alias.name
    return out


def _helpers(tree: ast.Module) -> set[str]:
    """The modules whose functions this file hands the namespace to: f(args, ...) with f
    imported from M, or m.f(args) with m a module; their reads count as the command's."""
    names = _imported_names(tree)
    out = set()
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        passed = [a for a in node.args + [k.value for k in node.keywords]
                  if isinstance(a, ast.Name) and a.id in ARGS_NAMES]
        if not passed:
            continue
        f = node.func
        if isinstance(f, ast.Name) and f.id in names:
            out.add(names[f.id])
        elif isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) \
                and f.value.id in names:
            out.add(names[f.value.id])
    return out


def reads_of(tree: ast.AST) -> set[str]:
    """Attributes read from the namespace: args.x, getattr(args, "x"[, default])."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) \
                and node.value.id in ARGS_NAMES:
            out.add(node.attr)
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
                and node.func.id in ("getattr", "hasattr") and len(node.args) >= 2 \
                and isinstance(node.args[0], ast.Name) and node.args[0].id in ARGS_NAMES \
                and isinstance(node.args[1], ast.Constant) and isinstance(node.args[1].value, str):
            out.add(node.args[1].value)
    return out


def command_reads(module: str) -> set[str]:
    """What the command module reads from the namespace, and the modules it hands the
    namespace to (transitively): a flag passed on to a helper is read there."""
    seen, todo, reads = set(), [module], set()
    while todo:
        mod = todo.pop()
        if mod in seen:
            continue
        seen.add(mod)
        src = _source(mod)
        if src is None:
            continue
        _, tree = src
        reads |= reads_of(tree)
        todo += sorted(_helpers(tree) - seen)
    return reads


# ---- the parser ---------------------------------------------------------------------------

def walk(parser: argparse.ArgumentParser, path=()):
    """(command path, parser) for the parser and every sub-parser below it."""
    yield path, parser
    for action in parser._actions:       # argparse keeps no public list of a parser's actions
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from walk(sub, path + (name,))


def checked_actions(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, SKIP_ACTIONS):
            continue
        yield action


def unused_dests(parser: argparse.ArgumentParser, reads: set[str]) -> list[str]:
    """Dests of the parser's own actions (subparser choice dests included) read nowhere."""
    out = []
    for action in checked_actions(parser):
        if action.dest in (argparse.SUPPRESS, None) or action.dest.startswith("_"):
            continue
        if action.dest not in reads:
            out.append("/".join(action.option_strings) or action.dest)
    return out


def _fmt_number(x) -> float | None:
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def default_mismatch(parser: argparse.ArgumentParser, action: argparse.Action) -> str | None:
    """Why the "(default ...)" in the action's help does not say its default, or None."""
    if not action.help or action.help == argparse.SUPPRESS:
        return None
    text = parser._get_formatter()._expand_help(action)
    m = re.search(r"\(default(:?)\s*([^)]*)\)", text)
    if m is None:
        return None
    prose, said = m.group(1) == ":", m.group(2).strip()
    d = action.default
    if d is None or d is argparse.SUPPRESS:
        if prose:
            return None          # "(default: the scenario's)": what None means, in words
        first = said.split()[0].rstrip(",;") if said else ""
        if _fmt_number(first) is not None:
            return f"default is None but the help says {said!r}"
        return None
    if isinstance(d, bool) or d == []:
        return None              # store_true / append: nothing to say
    if prose:
        return f"default {d!r} described in words: {said!r}"
    tokens = re.split(r"[\s,;:]+", said)
    if isinstance(d, (tuple, list)):
        got = [_fmt_number(t) for t in tokens[:len(d)]]
        want = [_fmt_number(x) for x in d]
        return None if got == want else f"default {d!r} but the help says {said!r}"
    if isinstance(d, (int, float)):
        got = _fmt_number(tokens[0].replace("_", ""))
        return None if got is not None and got == float(d) else \
            f"default {d!r} but the help says {said!r}"
    return None if said.startswith(str(d)) else f"default {d!r} but the help says {said!r}"


# ---- the tests ----------------------------------------------------------------------------

def _commands():
    return cli.available_commands()


@pytest.fixture(scope="module")
def parser():
    return cli.build_parser(_commands())


def _module_for(path) -> str:
    return cli._module_name(_commands()[path[0]])


def test_the_whole_parser_has_every_subcommand(parser):
    names = {path[0] for path, _ in walk(parser) if path}
    assert names == set(_commands()) and {"bench", "ablate", "tune", "fly"} <= names
    tune = {path for path, _ in walk(parser) if path[:1] == ("tune",)}
    assert {("tune", a) for a in ("sysid", "step", "auto", "anchor")} <= tune


@pytest.mark.parametrize("command", sorted(cli.COMMANDS))
def test_every_flag_reaches_the_code(parser, command):
    if command not in _commands():
        pytest.skip(f"{command}: module not in this build")
    reads = command_reads(_module_for((command,))) | reads_of(
        ast.parse(Path(cli.__file__).read_text()))
    unused = {}
    for path, sub in walk(parser):
        if path[:1] != (command,):
            continue
        missing = unused_dests(sub, reads)
        if missing:
            unused[" ".join(path)] = missing
    assert not unused, f"flags accepted but read nowhere: {unused}"


@pytest.mark.parametrize("command", sorted(cli.COMMANDS))
def test_every_stated_default_is_the_real_one(parser, command):
    if command not in _commands():
        pytest.skip(f"{command}: module not in this build")
    wrong = {}
    for path, sub in walk(parser):
        if path[:1] != (command,):
            continue
        for action in checked_actions(sub):
            why = default_mismatch(sub, action)
            if why:
                wrong[" ".join(path) + " " + "/".join(action.option_strings)] = why
    assert not wrong, wrong


def test_hidden_aliases_are_hidden_and_share_the_new_dest(parser):
    aliases = []
    for path, sub in walk(parser):
        for action in sub._actions:
            if isinstance(action, _DeprecatedAlias):
                aliases.append((path, action))
                assert action.help == argparse.SUPPRESS
                assert any(a.dest == action.dest for a in checked_actions(sub)), action.dest
                usage = set(re.findall(r"-[-\w]+", sub.format_usage()))
                assert not usage & set(action.option_strings), action.option_strings
    by_flag = {(p[0], a.option_strings[0]) for p, a in aliases}
    assert ("bench", "--sitl") in by_flag and ("transport", "--duration") in by_flag


# ---- the walk, on a synthetic parser ------------------------------------------------------

_SYNTHETIC = '''
def run(args):
    total = args.used + getattr(args, "also_used", 0)
    return helper(args) + total
'''


def test_the_walk_catches_an_unused_flag():
    p = argparse.ArgumentParser()
    p.add_argument("--used", type=int, default=1, help="read as args.used (default %(default)s)")
    p.add_argument("--also-used", type=int, default=0)
    p.add_argument("--forgotten", action="store_true", help="accepted, read nowhere")
    sub = p.add_subparsers(dest="action")
    s = sub.add_parser("go")
    s.add_argument("--deep", default="x")
    reads = reads_of(ast.parse(_SYNTHETIC))
    assert reads == {"used", "also_used"}
    assert unused_dests(p, reads) == ["--forgotten", "action"]
    assert unused_dests(s, reads) == ["--deep"]
    assert unused_dests(p, reads | {"forgotten", "action"}) == []


def test_a_flag_handed_to_a_helper_counts_as_read_there():
    tree = ast.parse("from silbridge.tools.cli.flight_args import options_from_args\n"
                     "from silbridge.tools.cli import flight_args as fa\n"
                     "def run(args):\n"
                     "    return options_from_args(args), fa.parse_params(args.param)\n")
    assert _helpers(tree) == {"silbridge.tools.cli.flight_args"}
    assert {"scenario", "param_file", "speed"} <= command_reads("silbridge.tools.cli.cmd_fly")
    # bench reads its own flags: flight_args, which it imports, is not its helper.
    assert "instance" not in command_reads("silbridge.tools.cli.cmd_bench")


def test_the_walk_catches_a_hand_typed_default():
    p = argparse.ArgumentParser()
    good = p.add_argument("--runs", type=int, default=5, help="runs (default %(default)s)")
    stale = p.add_argument("--n", type=int, default=5, help="runs (default 20)")
    stale_out = p.add_argument("--out", default="ablate-out", help="folder (default bench-out)")
    none_num = p.add_argument("--f", type=float, default=None, help="Hz (default 0.5)")
    none_words = p.add_argument("--imu", default=None, help="rate (default: the scenario's)")
    win = p.add_argument("--w", nargs=2, type=float, default=(30.0, 120.0),
                         help="window (default 30 120)")
    assert default_mismatch(p, good) is None and default_mismatch(p, win) is None
    assert default_mismatch(p, none_words) is None
    for action in (stale, stale_out, none_num):
        assert default_mismatch(p, action), action.dest
    # set_defaults changes what %(default)s shows: ablate's runs and out.
    p.set_defaults(runs=7)
    assert "(default 7)" in p.format_help()
