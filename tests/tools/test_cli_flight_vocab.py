"""The flight commands speak the one flag vocabulary (issue 22, notes VOCAB): `--link-addr`
with its old spellings as hidden aliases that say they are deprecated, `-I/--sitl-instance`,
help texts whose defaults are the real ones, and `silbridge --version`."""

from __future__ import annotations

import argparse
import subprocess
import sys
from importlib.metadata import version

import pytest

from silbridge.tools.cli.aliases import add_deprecated_alias
from silbridge.tools.cli.cli import build_parser

SB = [sys.executable, "-m", "silbridge.tools"]


def _parser(command):
    return build_parser({command: f"cmd_{command}"})


@pytest.mark.parametrize("command, old", [("fly", "--hil-addr"), ("fc", "--hil-addr"),
                                          ("bridge", "--hil-addr"),
                                          ("bridge", "--sitl-address")])
def test_old_address_spellings_are_hidden_deprecated_aliases(capsys, command, old):
    p = _parser(command)
    new = p.parse_args([command, "--link-addr", "127.0.0.1:4570"])
    assert capsys.readouterr().err == ""
    aliased = p.parse_args([command, old, "127.0.0.1:4570"])
    assert aliased.link_addr == new.link_addr == "127.0.0.1:4570"
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{old} is deprecated, use --link-addr" in err
    sub = p._subparsers._group_actions[0].choices[command]
    assert old not in sub.format_help() and "--link-addr" in sub.format_help()


def test_an_alias_copies_the_new_flags_action(capsys):
    p = argparse.ArgumentParser(prog="silbridge x")
    p.add_argument("--param", action="append", default=[])
    p.add_argument("--on", action="store_true")
    p.add_argument("--speed", type=float, default=1.0)
    add_deprecated_alias(p, "--p", "--param")
    add_deprecated_alias(p, "--turn-on", "on")           # by dest
    add_deprecated_alias(p, "--sitl-speedup", "--speed")
    assert vars(p.parse_args([])) == {"param": [], "on": False, "speed": 1.0}
    a = p.parse_args(["--p", "A=1", "--param", "B=2", "--turn-on", "--sitl-speedup", "3"])
    assert vars(a) == {"param": ["A=1", "B=2"], "on": True, "speed": 3.0}
    assert "--turn-on is deprecated, use --on" in capsys.readouterr().err
    with pytest.raises(ValueError):
        add_deprecated_alias(p, "--old", "--not-there")


def test_link_addr_with_shared_memory_is_refused():
    p = subprocess.run(SB + ["fly", "--link-addr", "127.0.0.1:4570"], capture_output=True,
                       text=True, timeout=60)
    assert p.returncode == 2 and "--transport udp" in p.stderr


@pytest.mark.parametrize("argv, says", [
    (["bridge", "-I", "1"], "with shared memory there is none"),
    (["bridge", "--fc", "ardupilot", "-I", "1", "--link-addr", "127.0.0.1:9002"], "not both"),
    (["sitl", "-I", "10"], "give 0..9"),
])
def test_instance_misuse_is_refused(argv, says):
    p = subprocess.run(SB + argv, capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and says in p.stderr, p.stderr


def test_sitl_instance_moves_the_default_endpoints():
    from silbridge.tools.cli.cmd_sitl import gcs_urls
    assert gcs_urls(0, False, []) == ["udpout:127.0.0.1:14550", "udpout:127.0.0.1:14540"]
    assert gcs_urls(2, False, ["udpin:0.0.0.0:14600"]) == [
        "udpout:127.0.0.1:14570", "udpout:127.0.0.1:14542", "udpin:0.0.0.0:14600"]
    assert gcs_urls(2, True, ["udpin:0.0.0.0:14600"]) == ["udpin:0.0.0.0:14600"]


@pytest.mark.parametrize("command", ["fly", "bridge", "fc", "sitl"])
def test_help_defaults_are_the_parsers_defaults(command):
    p = _parser(command)
    sub = p._subparsers._group_actions[0].choices[command]
    text = " ".join(sub.format_help().split())
    for action in sub._actions:
        if action.help in (None, argparse.SUPPRESS) or "%(default)s" not in action.help:
            continue
        assert f"default {action.default}" in text, action.dest
    flags = {s for a in sub._actions for s in a.option_strings}
    if command in ("fly", "sitl", "fc"):
        assert {"--params", "--save-params", "--param"} <= flags
    if command in ("bridge", "sitl"):
        assert {"-I", "--sitl-instance"} <= flags
    if command != "sitl":
        assert "--link-addr" in flags


def test_version():
    p = subprocess.run(SB + ["--version"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0
    assert p.stdout.strip() == f"silbridge {version('silbridge')}"


@pytest.mark.parametrize("flag", [["--gcs", "udpin:127.0.0.1:14999"], ["--mission", "m.txt"],
                                  ["--tlog", "x.tlog"]])
def test_ground_station_options_without_mavlink_are_refused(tmp_path, flag):
    p = subprocess.run(SB + ["fly", *flag], capture_output=True, text=True, timeout=60,
                       cwd=tmp_path)
    assert p.returncode == 2 and f"{flag[0]} " in p.stderr and "--mavlink" in p.stderr
    assert list(tmp_path.iterdir()) == []
