"""The C core's SYSTEMID sweep (fc_sysid.c): ArduCopter's waveform, its SID_*
parameters, where it is injected, and the refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.errors import InputError
from silbridge.fc_sil.params import BY_NAME

G = 9.80665


def ardu_waveform(t, mag, f0, f1, fade_in, rec, fade_out):
    """ArduCopter SYSTEMID's chirp, in double precision (written from its description)."""
    w0, w1 = 2 * math.pi * f0, 2 * math.pi * f1
    tc = 2.0 / f0
    if t <= 0:
        return 0.0
    if t <= fade_in:
        win = 0.5 - 0.5 * math.cos(math.pi * t / fade_in)
    elif t <= rec - fade_out:
        win = 1.0
    elif t <= rec:
        win = 0.5 - 0.5 * math.cos(math.pi * (t - (rec - fade_out)) / fade_out + math.pi)
    else:
        win = 0.0
    if t <= tc:
        return win * mag * math.sin(w0 * t - w0 * tc)
    if t <= rec:
        b = math.log(w1 / w0)
        return win * mag * math.sin(w0 * (rec - tc) / b * (math.exp(b * (t - tc) / (rec - tc)) - 1))
    return 0.0


def test_sid_parameters_are_declared_with_arducopter_defaults():
    want = {"SID_AXIS": 0, "SID_MAGNITUDE": 15, "SID_F_START_HZ": 0.5, "SID_F_STOP_HZ": 40,
            "SID_T_FADE_IN": 15, "SID_T_REC": 70, "SID_T_FADE_OUT": 2}
    for name, value in want.items():
        d = BY_NAME[name]
        assert 400 <= d.index <= 449 and d.default == pytest.approx(value)
    assert (BY_NAME["SID_AXIS"].min, BY_NAME["SID_AXIS"].max) == (0, 13)


def _step(core, k, dt_ns=1_000_000):
    core.step_imu(k * dt_ns, (0.0, 0.0, -G), (0.0, 0.0, 0.0))


def test_rate_sweep_follows_the_arducopter_waveform_at_the_rate_target():
    sweep = dict(SID_AXIS=7, SID_MAGNITUDE=20, SID_F_START_HZ=2, SID_F_STOP_HZ=30,
                 SID_T_FADE_IN=1, SID_T_REC=4, SID_T_FADE_OUT=0.5)
    core = FlightCore(sweep)
    for k in range(1, 200):
        _step(core, k)
    core.sysid_start()
    start_ns = core.sysid_sample()[0]
    got, want, tgt = [], [], []
    for k in range(200, 200 + 5600):
        _step(core, k)
        s = core.sysid_sample()
        t = (s[0] - start_ns) * 1e-9 - 1.0
        got.append(s[4])
        want.append(ardu_waveform(t, 20, 2, 30, 1, 4, 0.5))
        tgt.append(s[7])
    got, want = np.array(got), np.array(want)
    assert np.max(np.abs(got - want)) < 0.05          # float32 phase over 4 s: < 0.25 %
    assert np.max(np.abs(got)) == pytest.approx(20, abs=0.1)
    # Injected at the rate-loop input: the roll rate target carries it (level, no error).
    assert np.corrcoef(np.radians(got[:4900]), np.array(tgt[:4900]))[0, 1] > 0.999
    assert core.sysid_sample()[1] == 0                 # finished after 1 s + SID_T_REC


def test_mixer_sweep_reaches_the_mixer_not_the_rate_target():
    core = FlightCore(dict(SID_AXIS=11, SID_MAGNITUDE=0.1, SID_F_START_HZ=1, SID_F_STOP_HZ=5,
                           SID_T_FADE_IN=0, SID_T_REC=3, SID_T_FADE_OUT=0))
    for k in range(1, 100):
        _step(core, k)
    core.sysid_start()
    rows = []
    for k in range(100, 2600):
        _step(core, k)
        rows.append(core.sysid_sample())
    r = np.array(rows)
    sample, pid_y, mix_y = r[:, 4], r[:, 14], r[:, 17]
    assert np.max(np.abs(sample)) > 0.09
    np.testing.assert_allclose(mix_y - pid_y, sample * 500.0, atol=1e-3)   # half of 1000 us
    assert np.max(np.abs(r[:, 8])) < 1e-3                                  # pitch rate target


def test_a_sweep_without_an_axis_or_with_bad_times_is_refused():
    core = FlightCore()
    with pytest.raises(InputError, match="SID_AXIS"):
        core.sysid_start()
    core = FlightCore(dict(SID_AXIS=7, SID_F_START_HZ=0.5, SID_T_REC=3))   # 2 cycles = 4 s
    with pytest.raises(InputError):
        core.sysid_start()
    assert core.sysid_sample()[1] == 0
