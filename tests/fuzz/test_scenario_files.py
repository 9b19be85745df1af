"""Scenario TOML files, perturbed from the built-ins: each loads, or fails with a
ScenarioError that names the file and either the line (bad TOML) or the key."""

from __future__ import annotations

import re
import tempfile
import tomllib
from pathlib import Path

from hypothesis import event, given

from silbridge.bridge import scenario_schema as S
from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import SCENARIO_DIR, Scenario, load_scenario

from fuzz_mutate import perturbed

VALID = tuple(p.read_text() for p in sorted(SCENARIO_DIR.glob("*.toml")))
# TOML-shaped edits: keys that do not exist, tables twice, values of the wrong type or size.
_TOKENS = (
    "=", "seed = 1", "seed = -1", "seed = \"one\"", "unknown_key = 1", "[imu]", "[physics]",
    "[[disturbance]]", "[[setpoint]]", "[[fc_param]]", "type = \"tilt\"", "type = [1]",
    "type = {a = 1}", "repeat = 1000000000000", "repeat = 0", "period_s = 1e-300",
    "duration_s = 1e300", "rate_hz = 3", "rate_hz = 0", "rate_hz = 1e9",
    "axis = [0, 0, 0]", "axis = \"w\"", "axis = [1e308, 1e308, 1e308]",
    "amplitude_g = {uniform = [1e308, -1e308]}", "amplitude_g = {uniform = [-1e308, 1e308]}",
    "amplitude_deg = {choice = []}", "amplitude_deg = {choice = [true]}",
    "start_s = {normal = [0, 1]}", "thrust_scale = [1, 1, 1]", "thrust_scale = [nan, 1, 1, 1]",
    "lat_deg = inf", "lat_deg = nan", "x = 1979-05-27", "x = 07:32:00", "x = '''a\nb'''",
    "name = 1", "doublet = 1", "\"\" = 1", "\"a.b\" = 2", "a.b.c = 3",
)
_DIR = Path(tempfile.mkdtemp(prefix="silbridge-fuzz-scenario-"))
_KNOWN = set(S.TOP) | set(S.SECTIONS) | {"disturbance", "setpoint", "fc_param"}


@given(perturbed(VALID, _TOKENS))
def test_a_perturbed_scenario_loads_or_names_file_and_line_or_key(data: bytes):
    path = _DIR / "mine.toml"
    path.write_bytes(data)
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        assert getattr(exc, "user_facing", False)
        event("refused")
        msg = str(exc)
        assert msg.startswith(f"{path.name}: "), msg
        rest = msg[len(path.name) + 2:]
        try:
            raw = tomllib.loads(data.decode("utf-8"))
        except ValueError:    # not UTF-8, not TOML, or a number Python will not read
            assert re.search(r"line \d+", rest), msg          # the line it is on
            return
        # Otherwise the message starts with the key: a key of the file (a quoted one may hold
        # a dot: "a.b"), or a required one.
        assert any(re.match(re.escape(k) + r"[.\[:]", rest) for k in _KNOWN | set(raw)), msg
        return
    event("loaded")
    assert isinstance(sc, Scenario)
    assert sc.duration_s > 0 and sc.physics_hz > 0
