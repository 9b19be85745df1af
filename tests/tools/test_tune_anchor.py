"""The anchor: the real ArduCopter 4.6 AUTOTUNE flies on our physics, finishes, saves
its gains on disarming, and those gains go into our FC (clipped to our declared ranges
where AUTOTUNE goes past them, and said so). Needs SILBRIDGE_ARDUCOPTER."""

from __future__ import annotations

import os

import pytest

from silbridge.fc_sil.flight_core import FlightCore
from silbridge.tools.tune.tune_anchor import for_our_fc, run_autotune

BINARY = os.environ.get("SILBRIDGE_ARDUCOPTER")


@pytest.mark.skipif(not BINARY, reason="set SILBRIDGE_ARDUCOPTER to an ArduCopter SITL binary "
                                       "(../shared/peers/arducopter-4.6.0/arducopter)")
def test_arducopter_autotune_on_our_physics_saves_roll_gains():
    res = run_autotune(BINARY, axes_mask=1, budget_sim_s=900.0)
    assert any("saved gains" in t.lower() for t in res["statustext"]), res["statustext"]
    g = res["gains"]
    assert 0.02 < g["ATC_RAT_RLL_P"] < 0.5 and g["ATC_RAT_RLL_P"] != pytest.approx(0.135)
    assert 0.0005 < g["ATC_RAT_RLL_D"] < 0.02
    assert res["tune_sim_s"] > 20.0
    applied, clipped = for_our_fc(g, ("roll",))
    core = FlightCore(applied)               # our FC takes every value as given
    for name, value in applied.items():
        assert core.get_param(name) == pytest.approx(value, rel=1e-6)
    for name, (theirs, ours) in clipped.items():
        assert theirs != ours and applied[name] == ours
