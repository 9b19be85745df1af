"""The crashes the property tests found, kept as plain examples so they stay fixed even when
Hypothesis draws other files: each was an unhandled exception (or a hang) in a loader."""

from __future__ import annotations

import re

import pytest

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import SCENARIO_DIR, load_scenario
from silbridge.mavlink.errors import MissionFileError
from silbridge.mavlink.gcs.wpl import load_wpl, parse_wpl

_ROW = "1\t0\t3\t16\t0\t0\t0\t0\t{lat}\t149.1652374\t10\t{ac}\n"
_HEAD = "QGC WPL 110\n0\t0\t0\t16\t0\t0\t0\t0\t-35.3632621\t149.1652374\t584\t1\n"


@pytest.mark.parametrize("lat, ac, says", [
    ("inf", 1, "x/latitude inf is out of range"),            # was OverflowError
    ("nan", 1, "x/latitude nan is out of range"),            # was ValueError from round()
    ("1e300", 1, "x/latitude 1e+300 is out of range"),       # was an int no message can carry
    ("-35.36", "inf", "autocontinue must be 0 or 1"),        # was OverflowError
])
def test_wpl_values_that_crashed_the_loader_name_the_line(lat, ac, says):
    with pytest.raises(MissionFileError, match=r"^m\.waypoints:3: " + re.escape(says)):
        parse_wpl(_HEAD + _ROW.format(lat=lat, ac=ac), "m.waypoints")


def test_wpl_that_is_not_utf8_names_the_line(tmp_path):
    path = tmp_path / "m.waypoints"
    path.write_bytes(_HEAD.encode() + b"1\t0\t3\t16\t0\t0\t0\t0\t-35.3\xff\t149\t10\t1\n")
    says = re.escape(f"{path}:3: byte 0xff is not UTF-8")
    with pytest.raises(MissionFileError, match="^" + says):
        load_wpl(path)          # was UnicodeDecodeError


def _s4_with(tmp_path, old: str, new: str):
    path = tmp_path / "mine.toml"
    path.write_bytes((SCENARIO_DIR / "S4.toml").read_bytes().replace(old.encode(), new, 1))
    return path


def test_scenario_that_is_not_utf8_names_the_line(tmp_path):
    path = _s4_with(tmp_path, "seed", b"\xffseed")
    with pytest.raises(ScenarioError, match=r"^mine\.toml: byte 0xff at line \d+ is not UTF-8"):
        load_scenario(path)     # was UnicodeDecodeError


def test_scenario_setpoint_type_of_the_wrong_kind_names_the_key(tmp_path):
    path = _s4_with(tmp_path, 'type = "tilt"', b"type = [1]")
    with pytest.raises(ScenarioError, match=r"^mine\.toml: setpoint\[0\]\.type: unknown type"):
        load_scenario(path)     # was TypeError: unhashable type: 'list'


def test_scenario_repeat_typo_is_refused_before_any_draw(tmp_path):
    path = _s4_with(tmp_path, "repeat = 6", b"repeat = 1000000000000")
    with pytest.raises(ScenarioError, match=r"^mine\.toml: setpoint\[0\]\.repeat: repetition"):
        load_scenario(path)     # was a hang drawing 10**12 amplitudes


def test_scenario_syntax_error_at_the_end_names_the_last_line(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text("seed = 1\nname =")
    with pytest.raises(ScenarioError, match=r"^mine\.toml: not valid TOML \(.*at line 2, end"):
        load_scenario(path)


def test_scenario_number_too_long_for_python_names_the_line(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('name = "x"\nseed = ' + "9" * 5000 + "\n")
    with pytest.raises(ScenarioError, match=r"^mine\.toml: line 2: a number with too many"):
        load_scenario(path)     # was ValueError from int() (4300-digit limit) inside tomllib
