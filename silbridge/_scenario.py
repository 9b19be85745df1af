"""`silbridge.load_scenario`: a scenario file read, overridden, validated and drawn.

The loader is bridge/scenario.py's; its [[fc_param]] entries are checked against the FC's
parameter declaration as `silbridge fly` checks them (tools/loop/fc_param_events.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from silbridge.bridge.scenario import Scenario


def load_scenario(name_or_path: str | Path, seed: int | None = None,
                  **overrides: Any) -> Scenario:
    """A built-in scenario by name ("S1".."S5", "A1".."A4") or a TOML file, validated.

    seed: replaces the file's seed (the random values are drawn from it).
    overrides: keys of the scenario file set before validation; nested keys are dotted,
        so pass them as a dict: ``load_scenario("S1", duration_s=60.0,
        **{"imu.rate_hz": 8000, "disturbance[0].amplitude_g": 0.5})``.

    Raises ScenarioError (``user_facing``) naming the key and file for a missing file,
    an unknown key, a wrong type or an out-of-range value. The file format:
    bridge/scenarios/README.md.
    """
    from silbridge.bridge.scenario import load_scenario as load
    from silbridge.tools.loop.fc_param_events import check_fc_param

    return load(name_or_path, seed=seed, overrides=overrides, check_fc_param=check_fc_param)
