"""Stability margins from frequency-response data (tools/tune_freq.margins) against
python-control's margin() on textbook loops, and the -3 dB bandwidth of a known
closed loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

control = pytest.importorskip("control")

from silbridge.tools.tune.tune_freq import bandwidth_hz, margins  # noqa: E402


def _frf(sys, f):
    return np.asarray(sys(2j * np.pi * f)).reshape(-1)


@pytest.mark.parametrize("num,den,delay", [
    # Ogata's type-1 third-order loop: GM 20 log10(3) = 9.54 dB at sqrt(5) rad/s.
    ([10.0], [1.0, 6.0, 5.0, 0.0], 0.0),
    # A rate-loop-like PI x 1/(s (tau s + 1)) with a 4 ms transport delay (Pade 3rd order).
    ([60.0, 600.0], [0.025, 1.0, 0.0, 0.0], 0.004),
    # Lightly damped: second-order plant with an integrator.
    ([400.0], [1.0, 4.0, 400.0, 0.0], 0.0),
])
def test_margins_match_python_control(num, den, delay):
    sys = control.tf(num, den)
    if delay:
        pn, pd = control.pade(delay, 3)
        sys = sys * control.tf(pn, pd)
    gm, pm, wpc, wgc = control.margin(sys)
    f = np.geomspace(0.01, 500.0, 20000)
    got = margins(f, _frf(sys, f))
    assert got["phase_margin_deg"] == pytest.approx(pm, abs=0.2)
    assert got["crossover_hz"] == pytest.approx(wgc / (2 * math.pi), rel=2e-3)
    assert got["delay_margin_ms"] == pytest.approx(math.radians(pm) / wgc * 1e3, rel=5e-3)
    if math.isfinite(gm):
        assert got["gain_margin_db"] == pytest.approx(20 * math.log10(gm), abs=0.05)
        assert got["phase_crossover_hz"] == pytest.approx(wpc / (2 * math.pi), rel=2e-3)
    else:
        assert got["gain_margin_db"] is None


def test_ogata_loop_known_gain_margin():
    sys = control.tf([10.0], [1.0, 6.0, 5.0, 0.0])
    f = np.geomspace(0.01, 100.0, 20000)
    got = margins(f, _frf(sys, f))
    assert got["gain_margin_db"] == pytest.approx(20 * math.log10(3.0), abs=0.02)
    assert got["phase_crossover_hz"] == pytest.approx(math.sqrt(5.0) / (2 * math.pi), rel=1e-3)


def test_a_crossing_outside_the_data_is_none_not_a_guess():
    sys = control.tf([10.0], [1.0, 6.0, 5.0, 0.0])
    f = np.geomspace(0.01, 0.1, 500)        # below both crossings (0.195, 0.356 Hz)
    got = margins(f, _frf(sys, f))
    assert got["crossover_hz"] is None and got["gain_margin_db"] is None


def test_bandwidth_of_a_first_order_loop():
    # T = 1 / (s / wb + 1): -3 dB at wb exactly (to the dB rounding of 1/sqrt(2)).
    wb = 2 * math.pi * 7.0
    f = np.geomspace(0.1, 200.0, 5000)
    t = 1.0 / (2j * np.pi * f / wb + 1.0)
    assert bandwidth_hz(f, t) == pytest.approx(7.0 * math.sqrt(10 ** 0.3 - 1), rel=1e-3)


def test_auto_search_space_holds_the_shaper_and_autotune_sized_angle_p():
    """The shaper dominates S4's error against the command, so it is searched (tune_auto's
    docstring); ATC_INPUT_TC only on request; ranges within the FC's declared ones."""
    from silbridge.fc_sil import params as P
    from silbridge.tools.tune.tune_auto import _pitch_twin, search_space, tied_twins

    sp = search_space(("roll", "pitch"))
    assert {"ATC_ACCEL_R_MAX", "ATC_ACCEL_P_MAX", "ATC_INPUT_TC"} <= set(sp)
    assert sp["ATC_ANG_RLL_P"][1] >= 22.3          # what ArduCopter's AUTOTUNE saved here
    assert "ATC_INPUT_TC" not in search_space(("roll",), input_tc=False)
    for name, (lo, hi, _log) in sp.items():
        assert P.BY_NAME[name].min <= lo < hi <= P.BY_NAME[name].max
    assert _pitch_twin("ATC_ACCEL_R_MAX") == "ATC_ACCEL_P_MAX"
    assert _pitch_twin("ATC_RAT_RLL_D") == "ATC_RAT_PIT_D"
    twins = tied_twins(sp)       # roll and pitch share one sampled value
    assert twins["ATC_ACCEL_R_MAX"] == "ATC_ACCEL_P_MAX" and twins["ATC_ANG_RLL_P"] == "ATC_ANG_PIT_P"
    assert set(twins.values()) == {n for n in sp if "_PIT_" in n or n == "ATC_ACCEL_P_MAX"}


def test_auto_search_proposes_whole_values_for_integer_parameters():
    """INS_GYRO_FILTER is an INT16 (as in ArduCopter): the FC refuses 34.7 Hz, so every
    trial must propose a whole number, inside the space; floats stay floats."""
    optuna = pytest.importorskip("optuna")
    from silbridge.fc_sil import params as P
    from silbridge.tools.tune.tune_auto import _suggest, search_space

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    sp = search_space(("roll",))
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=1))
    for _ in range(30):
        t = study.ask()
        vals = {n: _suggest(t, n, *sp[n]) for n in ("INS_GYRO_FILTER", "ATC_RAT_RLL_P")}
        lo, hi, _ = sp["INS_GYRO_FILTER"]
        assert isinstance(vals["INS_GYRO_FILTER"], int) and lo <= vals["INS_GYRO_FILTER"] <= hi
        P.BY_NAME["INS_GYRO_FILTER"].validate(vals["INS_GYRO_FILTER"])
        study.tell(t, vals["ATC_RAT_RLL_P"])
    assert len({round(t.params["ATC_RAT_RLL_P"], 6) for t in study.trials}) > 20
