"""Fixtures shared by the tools tests.

`pitch_push_scenario`: the flight the viewable-channel tests fly (the log's /viz channels,
test_viz_log.py, and the same channels served live, test_live_view.py): a 10 deg pitch
step and, half a second later, a 0.2 g push north for one second, so the command channel
changes and the scene shows a disturbance arrow. Each test picks its own times and seed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

_SCENARIO = """
name = "{name}"
description = "{description}"
seed = {seed}
duration_s = {duration_s}
takeoff_alt_m = 10.0

[windows]
warmup_s = 1.0
transient_end_s = 2.0

[[setpoint]]
type = "tilt"
axis = "pitch"
shape = "step"
amplitude_deg = 10.0
hold_s = 1.0
start_s = {step_s}
repeat = 1
period_s = 10.0

[[disturbance]]
type = "force"
frame = "ned"
axis = "x"
amplitude_g = 0.2
start_s = {push_on_s}
stop_s = {push_off_s}
"""


def _write_pitch_push(folder: Path, name: str, description: str, *, seed: int,
                      duration_s: float, step_s: float) -> Path:
    """Write <folder>/<name>.toml: the pitch step at step_s, the push from step_s + 0.5 s
    to step_s + 1.5 s; returns its path."""
    path = Path(folder) / f"{name}.toml"
    path.write_text(_SCENARIO.format(name=name, description=description, seed=seed,
                                     duration_s=float(duration_s), step_s=float(step_s),
                                     push_on_s=step_s + 0.5, push_off_s=step_s + 1.5))
    return path


@pytest.fixture(scope="session")
def pitch_push_scenario():
    """_write_pitch_push(folder, name, description, seed=, duration_s=, step_s=) -> path.
    Session-scoped (it holds nothing) so module-scoped fixtures can use it."""
    return _write_pitch_push
