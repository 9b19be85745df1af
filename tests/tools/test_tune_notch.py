"""`tune notch` without flying: the filter model against scipy.signal, the proposal on a
synthetic gyro spectrum with known lines, the .parm it writes, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from silbridge.mavlink.gcs.params_file import load_parm
from silbridge.tools.logs.spectrum import welch
from silbridge.tools.tune.tune_notch_cmd import check_declared, declared_default
from silbridge.tools.tune.tune_notch_filters import (NotchDesign, lpf_response,
                                                     notch_response, phase_lag_deg)
from silbridge.tools.tune.tune_notch_log import gyro_lines
from silbridge.tools.tune.tune_notch_propose import (NotchEvidence, NotchProposalError,
                                                     predicted_rms, propose)
from silbridge.tools.tune.tune_parm import write_parm
from silbridge.tools.tune.tune_sysid import TuneError

signal = pytest.importorskip("scipy.signal")

RATE = 1000.0


def _ardupilot_notch_ba(f0, bw, att_db, fs):
    """ArduPilot's NotchFilter biquad (pre-warped bilinear of its prototype), written
    out independently of the model under test."""
    octaves = np.log2(f0 / (f0 - bw / 2.0)) * 2.0
    q = np.sqrt(2.0 ** octaves) / (2.0 ** octaves - 1.0)
    a = 10.0 ** (-att_db / 40.0)
    omega = 2.0 * np.pi * f0 / fs
    alpha = np.sin(omega) / (2.0 * q)
    b = [1.0 + alpha * a * a, -2.0 * np.cos(omega), 1.0 - alpha * a * a]
    den = [1.0 + alpha, -2.0 * np.cos(omega), 1.0 - alpha]
    return b, den


def test_notch_and_low_pass_match_scipy():
    f = np.linspace(1.0, 480.0, 600)
    d = NotchDesign(center_hz=81.0, bw_hz=40.5, att_db=40.0, harmonics=0b11)
    h = notch_response(f, d, RATE)
    ref = np.ones_like(f, dtype=complex)
    for fc, bw in ((81.0, 40.5), (162.0, 81.0)):      # constant Q: BW scales with the centre
        b, a = _ardupilot_notch_ba(fc, bw, 40.0, RATE)
        ref *= signal.freqz(b, a, worN=f, fs=RATE)[1]
    assert np.allclose(h, ref, rtol=1e-9, atol=1e-12)
    one = NotchDesign(center_hz=81.0, bw_hz=40.5, att_db=40.0, harmonics=0b1)
    assert 20 * np.log10(abs(notch_response(81.0, one, RATE))) == pytest.approx(-40.0, abs=1e-6)
    b, a = signal.butter(2, 20.0, fs=RATE)
    assert np.allclose(lpf_response(f, 20.0, RATE), signal.freqz(b, a, worN=f, fs=RATE)[1],
                       rtol=1e-9, atol=1e-12)
    # a notch far above the loop costs a little phase at 5 Hz, never a lead
    assert phase_lag_deg(5.0, d, 20.0, RATE) > phase_lag_deg(5.0, None, 20.0, RATE) > 0


def _synthetic(lines, seconds=20.0, noise=1e-4, seed=3):
    """Three gyro axes at RATE: sinusoids (freq, amp per axis) over white noise."""
    t = np.arange(int(seconds * RATE)) / RATE
    rng = np.random.default_rng(seed)
    x = noise * rng.standard_normal((len(t), 3))
    for f, amps in lines:
        x += np.outer(np.sin(2 * np.pi * f * t), amps)
    return welch(x, RATE, int(RATE))


def _evidence(sp, f1, **kw):
    base = dict(imu_rate_hz=RATE, fundamental_hz=f1, fundamental_source="/rotor",
                spread_hz=0.0, lowest_hz=0.8 * f1, hover_throttle=0.42, esc=False,
                lines=gyro_lines(sp, f1, 0.0), gyro_filter_hz=20.0)
    base.update(kw)
    return NotchEvidence(**base)


def test_known_lines_give_known_notch():
    # 1x strong on x and z, 2x (blade pass) on z, 3x far below 1x's residual after a notch
    sp = _synthetic([(100.0, [0.05, 0.01, 0.08]), (200.0, [0.0, 0.0, 0.02]),
                     (300.0, [0.0, 0.0, 0.002])])
    ev = _evidence(sp, 100.0)
    assert [ln.harmonic for ln in ev.lines] == [1, 2, 3]
    p = propose(ev, att_db=40.0)
    v = p.values
    assert v["INS_HNTCH_MODE"] == 1 and v["INS_HNTCH_ENABLE"] == 1
    assert v["INS_HNTCH_FREQ"] == 100.0 and v["INS_HNTCH_BW"] == 50.0
    assert v["INS_HNTCH_REF"] == 0.42 and v["INS_HNTCH_ATT"] == 40.0
    # 2x after the 20 Hz low-pass: 0.02/100 = 2e-4 against 1x's 0.08/25 * 1e-2 = 3.2e-5:
    # kept; 3x: 0.002/225 = 9e-6: not worth a notch
    assert v["INS_HNTCH_HMNCS"] == 0b011
    assert v["INS_GYRO_FILTER"] == 20
    # the proposal removes what it predicts: >= 20 dB less filtered noise in 20-200 Hz
    before = predicted_rms(sp.freq_hz, sp.psd, lpf_response(sp.freq_hz, 20.0, RATE), (20, 200))
    after = predicted_rms(sp.freq_hz, sp.psd, notch_response(sp.freq_hz, p.design, RATE)
                          * lpf_response(sp.freq_hz, 20.0, RATE), (20, 200))
    assert 20 * np.log10(np.linalg.norm(after) / np.linalg.norm(before)) < -20.0


def test_esc_telemetry_gives_mode_3_with_the_floor_at_the_lowest_rotor_speed():
    sp = _synthetic([(90.0, [0.05, 0.05, 0.05])])
    p = propose(_evidence(sp, 90.0, esc=True, lowest_hz=72.0), att_db=40.0)
    v = p.values
    assert (v["INS_HNTCH_MODE"], v["INS_HNTCH_REF"]) == (3, 1.0)
    assert (v["INS_HNTCH_FREQ"], v["INS_HNTCH_BW"]) == (72.0, 36.0)
    assert v["INS_HNTCH_HMNCS"] == 1
    # forced back to throttle: FREQ is the hover frequency again
    assert propose(_evidence(sp, 90.0, esc=True), 40.0, mode=1).values["INS_HNTCH_FREQ"] == 90.0


def test_gyro_filter_comes_below_the_notch_and_spread_widens_it():
    sp = _synthetic([(100.0, [0.05, 0.05, 0.05])])
    v = propose(_evidence(sp, 100.0, gyro_filter_hz=90.0), 40.0).values
    assert v["INS_GYRO_FILTER"] == 75       # FREQ - BW/2
    v = propose(_evidence(sp, 100.0, spread_hz=40.0), 40.0).values
    assert v["INS_HNTCH_BW"] == 80.0


def test_refusals():
    quiet = _synthetic([])
    with pytest.raises(NotchProposalError, match="no rotor line"):
        propose(_evidence(quiet, 100.0), 40.0)
    sp = _synthetic([(100.0, [0.05, 0.05, 0.05])])
    with pytest.raises(NotchProposalError, match="ESC telemetry"):
        propose(_evidence(sp, 100.0), 40.0, mode=3)
    with pytest.raises(NotchProposalError, match="hover throttle"):
        propose(_evidence(sp, 100.0, hover_throttle=None), 40.0)
    with pytest.raises(TuneError, match="declares no INS_HNTCH_NOPE"):
        check_declared({"INS_HNTCH_FREQ": 80, "INS_HNTCH_NOPE": 1})
    with pytest.raises(TuneError, match="declares no"):
        declared_default("INS_HNTC9_ATT")


def test_parm_written_loads_back(tmp_path):
    sp = _synthetic([(100.0, [0.05, 0.01, 0.08]), (200.0, [0.0, 0.0, 0.02])])
    p = propose(_evidence(sp, 100.0), att_db=declared_default("INS_HNTCH_ATT"))
    path = write_parm(tmp_path / "notch.parm", p.values, header="test")
    back = dict(load_parm(path))
    assert set(back) == set(p.values)
    for name, value in p.values.items():
        assert back[name] == pytest.approx(value, rel=1e-6)
