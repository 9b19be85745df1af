"""fc_notch.c: the harmonic notch against ArduCopter 4.6's design and tracking rules.

The oracle of the response is ArduPilot's NotchFilter biquad written out here from its
documented formulas (A = 10^(-ATT/40), Q from the octave bandwidth, RBJ coefficients) and
evaluated with scipy.signal; the C notch is a state-variable filter with the same transfer
function, driven sample by sample through the cffi bindings of its header.
"""

import numpy as np
import pytest
from scipy import signal

from core_cffi import ffi, lib

FS = 1000.0
TICK_S = 0.0025          # the PWM tick (SB_PWM_HZ 400), ArduCopter's main loop


def ardupilot_notch_ba(f0, bw, att_db, fs):
    """ArduPilot's NotchFilter::calculate_A_and_Q + init_with_A_and_Q, normalised (a0 = 1)."""
    a_att = 10.0 ** (-att_db / 40.0)
    octaves = np.log2(f0 / (f0 - bw / 2.0)) * 2.0
    q = np.sqrt(2.0 ** octaves) / (2.0 ** octaves - 1.0)
    w = 2.0 * np.pi * f0 / fs
    alpha = np.sin(w) / (2.0 * q)
    b = np.array([1.0 + alpha * a_att ** 2, -2.0 * np.cos(w), 1.0 - alpha * a_att ** 2])
    a = np.array([1.0 + alpha, -2.0 * np.cos(w), 1.0 - alpha])
    return b / a[0], a / a[0]


class HarmonicNotch:
    """One fc_notch_t with a configuration by INS_HNTCH_* meaning (ArduCopter defaults)."""

    def __init__(self, fs=FS, **cfg):
        c = dict(enable=True, mode=lib.FC_NOTCH_MODE_FIXED, options=0, harmonics=1,
                 freq_hz=80.0, bw_hz=40.0, att_db=40.0, ref=0.0, fm_ratio=1.0)
        c.update(cfg)
        self.fs = fs
        self.n = ffi.new("fc_notch_t *")
        self.status = lib.fc_notch_init(self.n, ffi.new("fc_notch_config_t *", c), 1.0 / fs)
        self._v = ffi.new("float[3]")

    def step(self, x: float) -> float:
        v = self._v
        v[0], v[1], v[2] = x, -x, 0.5 * x     # three axes, one filter tuning
        lib.fc_notch_apply(self.n, v)
        # one tuning, three independent states: -x and x/2 come out exactly -y and y/2
        # (negation and halving are exact in float arithmetic)
        assert v[1] == -v[0] and v[2] == 0.5 * v[0]
        return v[0]

    def run(self, x, on_sample=None) -> np.ndarray:
        y = np.empty(len(x))
        for i, s in enumerate(np.asarray(x, np.float32).tolist()):
            if on_sample is not None:
                on_sample(i)
            y[i] = self.step(s)
        return y

    def set_centers(self, hz, interval_s=0.005):
        arr = ffi.new("float[]", [float(h) for h in hz])
        lib.fc_notch_set_centers(self.n, len(hz), arr, interval_s)

    def track(self, **inputs):
        esc_hz = inputs.pop("esc_hz", [])
        fft_hz = inputs.pop("fft_hz", [])
        d = dict(throttle=0.0, motors_stopped=False, esc_count=len(esc_hz),
                 esc_hz=list(esc_hz) + [0.0] * (8 - len(esc_hz)),
                 esc_mean_hz=float(np.mean([h for h in esc_hz if h > 0])) if any(esc_hz) else 0.0,
                 fft_count=len(fft_hz), fft_hz=list(fft_hz) + [0.0] * (8 - len(fft_hz)))
        d.update(inputs)
        lib.fc_notch_track(self.n, ffi.new("fc_notch_inputs_t *", d), TICK_S)

    def settle(self, ticks=80, **inputs):
        """Track the same inputs for `ticks` PWM ticks (the 5 %-per-update slew needs time)."""
        for _ in range(ticks):
            self.track(**inputs)
            self.run(np.zeros(int(round(TICK_S * self.fs))))

    def centers(self):
        n = self.n
        return [(round(n.f[i].center_hz, 3), n.f[i].state) for i in range(n.count)]

    def on_centers(self):
        return sorted(c for c, s in self.centers() if s != 0)


def sine_gain_db(make, f, fs=FS, periods=60):
    """Steady-state gain of a fresh filter at f [dB], by least squares over the last half."""
    n = int(periods * fs / f) + 400
    t = np.arange(n) / fs
    x = np.sin(2 * np.pi * f * t)
    x[0] = 0.0
    y = make().run(x)[n // 2:]
    basis = np.stack([np.sin(2 * np.pi * f * t[n // 2:]), np.cos(2 * np.pi * f * t[n // 2:])], 1)
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return 20 * np.log10(np.hypot(*coef))


# ---- the response is the design --------------------------------------------------------------

def test_impulse_response_is_ardupilots_biquad():
    nt = HarmonicNotch()
    x = np.zeros(400, np.float32)
    x[1] = 1.0                       # sample 0 (zero) primes the filter at rest
    b, a = ardupilot_notch_ba(80.0, 40.0, 40.0, FS)
    np.testing.assert_allclose(nt.run(x), signal.lfilter(b, a, x), atol=2e-6)


@pytest.mark.parametrize("f0,bw,att,fs", [(80.0, 40.0, 40.0, 1000.0), (150.0, 50.0, 30.0, 8000.0),
                                           (300.0, 60.0, 20.0, 1000.0)])
def test_attenuation_at_centre_and_edges_matches_scipy(f0, bw, att, fs):
    b, a = ardupilot_notch_ba(f0, bw, att, fs)
    r = f0 / (f0 - bw / 2.0)
    lo, hi = f0 / r, f0 * r                  # the design's -3 dB points (octave bandwidth)
    for f in (f0, lo, hi, 0.3 * f0, 1.7 * f0):
        _, h = signal.freqz(b, a, worN=[f], fs=fs)
        want = 20 * np.log10(abs(h[0]))
        got = sine_gain_db(lambda: HarmonicNotch(fs=fs, freq_hz=f0, bw_hz=bw, att_db=att), f, fs=fs)
        assert got == pytest.approx(want, abs=0.05 if want > -25 else 0.5), f
    assert 20 * np.log10(abs(signal.freqz(b, a, worN=[f0], fs=fs)[1][0])) == pytest.approx(-att)
    if f0 / fs <= 0.1:
        # ArduPilot designs the bandwidth as an analog octave width and pre-warps only the
        # centre, so the edges sit at -3 dB (less the finite depth) only well below Nyquist;
        # at 300 Hz of 1 kHz they are near -1 dB, in ArduCopter and here alike.
        for f in (lo, hi):
            assert -3.0 < 20 * np.log10(abs(signal.freqz(b, a, worN=[f], fs=fs)[1][0])) < -2.6


def test_constant_input_passes_unchanged_and_nan_free():
    nt = HarmonicNotch(harmonics=0b111, options=lib.FC_NOTCH_OPT_TRIPLE)
    y = nt.run(np.full(500, 0.37))
    assert np.all(y == np.float32(0.37))


# ---- the bank: harmonics, composites, budget -------------------------------------------------

def test_harmonics_sit_at_k_times_the_source():
    def bank():
        return HarmonicNotch(fs=2000.0, harmonics=0b1011, freq_hz=60.0, bw_hz=15.0)
    assert bank().on_centers() == [60.0, 120.0, 240.0]
    for f in (60.0, 120.0, 240.0):
        assert sine_gain_db(bank, f, fs=2000.0) < -39.0
    third = sine_gain_db(bank, 180.0, fs=2000.0)
    assert third > -3.0                     # the 3rd harmonic's bit is clear: no notch there


def test_harmonics_at_or_above_048_fs_are_off():
    nt = HarmonicNotch(harmonics=0b11111, freq_hz=100.0, bw_hz=50.0)   # 500 Hz is past 480
    assert nt.on_centers() == [100.0, 200.0, 300.0, 400.0]


def test_double_and_triple_notches_spread_by_bw_over_32_freq():
    s = 40.0 / (32 * 80.0)
    dbl = HarmonicNotch(options=lib.FC_NOTCH_OPT_DOUBLE).on_centers()
    assert dbl == pytest.approx([80 * (1 - s), 80 * (1 + s)], abs=1e-3)
    tri = HarmonicNotch(options=lib.FC_NOTCH_OPT_TRIPLE).on_centers()
    assert tri == pytest.approx([80 * (1 - s), 80.0, 80 * (1 + s)], abs=1e-3)


def test_bank_budget_drops_the_highest_harmonics_first():
    nt = HarmonicNotch(mode=lib.FC_NOTCH_MODE_ESC, ref=1.0, harmonics=0b111,
                       options=lib.FC_NOTCH_OPT_MULTI_SOURCE | lib.FC_NOTCH_OPT_TRIPLE)
    nt.settle(esc_hz=[90.0, 91.0, 92.0, 93.0])
    assert nt.n.count == lib.FC_NOTCH_MAX_FILTERS == 24      # 4 motors x 2 harmonics x 3
    assert max(nt.on_centers()) < 2 * 93.0 * 1.02            # no 3rd harmonic left


# ---- tracking modes --------------------------------------------------------------------------

def test_throttle_mode_centre_follows_throttle():
    nt = HarmonicNotch(mode=lib.FC_NOTCH_MODE_THROTTLE, ref=0.35, fm_ratio=0.7)
    for thr in (0.35, 0.6, 0.2, 0.05):
        nt.settle(throttle=thr)
        want = 80.0 * max(0.7, np.sqrt(thr / 0.35))
        assert nt.on_centers() == pytest.approx([want], rel=1e-4)


def test_ref_zero_keeps_every_mode_at_freq():
    for mode in (lib.FC_NOTCH_MODE_THROTTLE, lib.FC_NOTCH_MODE_ESC, lib.FC_NOTCH_MODE_FFT):
        nt = HarmonicNotch(mode=mode, ref=0.0)
        nt.settle(throttle=0.9, esc_hz=[150.0] * 4, fft_hz=[170.0])
        assert nt.on_centers() == [80.0]


def test_throttle_notch_is_bypassed_while_the_motors_are_stopped():
    nt = HarmonicNotch(mode=lib.FC_NOTCH_MODE_THROTTLE, ref=0.35)
    nt.settle(throttle=0.0, motors_stopped=True)
    x = np.sin(2 * np.pi * 80.0 * np.arange(300) / FS).astype(np.float32)
    np.testing.assert_array_equal(nt.run(x), x)
    nt.settle(ticks=4, throttle=0.35)
    y = nt.run(np.sin(2 * np.pi * 80.0 * np.arange(300, 900) / FS))
    assert np.abs(y[-200:]).max() < 0.02                     # back on, from the input


def test_update_rate_is_200_hz_or_every_loop_tick():
    def moves(options):
        nt = HarmonicNotch(mode=lib.FC_NOTCH_MODE_THROTTLE, ref=0.35, options=options)
        seen = []
        for k in range(8):
            nt.track(throttle=0.35 * (1.0 + 0.01 * (k + 1)) ** 2)
            seen.append(nt.n.f[0].center_hz)
        return len(set(seen))
    assert moves(0) == 4                                     # every other 2.5 ms tick
    assert moves(lib.FC_NOTCH_OPT_LOOP_RATE) == 8


def test_esc_mode_mean_or_per_motor():
    mean = HarmonicNotch(mode=lib.FC_NOTCH_MODE_ESC, ref=1.0)
    mean.settle(esc_hz=[100.0, 110.0, 120.0, 130.0])
    assert mean.on_centers() == pytest.approx([115.0], rel=1e-4)
    per = HarmonicNotch(mode=lib.FC_NOTCH_MODE_ESC, ref=1.0, harmonics=0b11,
                        options=lib.FC_NOTCH_OPT_MULTI_SOURCE)
    per.settle(esc_hz=[100.0, 110.0, 120.0, 0.0])            # motor 4 stale: at the floor
    assert per.on_centers() == pytest.approx([80, 100, 110, 120, 160, 200, 220, 240], rel=1e-4)
    per.settle(esc_hz=[])                                    # no telemetry: throttle fallback
    assert per.n.count == 2


def test_fft_mode_takes_the_fft_centres():
    one = HarmonicNotch(mode=lib.FC_NOTCH_MODE_FFT, ref=1.0)
    one.settle(fft_hz=[140.0, 210.0])
    assert one.on_centers() == pytest.approx([140.0], rel=1e-4)
    per = HarmonicNotch(mode=lib.FC_NOTCH_MODE_FFT, ref=1.0, options=lib.FC_NOTCH_OPT_MULTI_SOURCE)
    per.settle(fft_hz=[140.0, 210.0])
    assert per.on_centers() == pytest.approx([140.0, 210.0], rel=1e-4)


def test_low_centres_fade_then_switch_off():
    nt = HarmonicNotch(mode=lib.FC_NOTCH_MODE_FFT, ref=1.0)
    nt.settle(fft_hz=[40.0])            # half the 80 Hz floor: held at the floor, half faded
    assert nt.on_centers() == [80.0]
    depth_half = nt.n.f[0].m / nt.n.k
    assert 0.3 < depth_half < 0.7       # attenuation fading toward none
    nt.settle(fft_hz=[15.0])            # below a quarter of the floor: off
    assert nt.on_centers() == []


# ---- retune without a jump --------------------------------------------------------------------

def _vibrating_gyro(n, tone_hz, seed=1):
    """A 2 Hz manoeuvre, sensor noise and a unit vibration line at tone_hz (per sample)."""
    t = np.arange(n) / FS
    phase = 2 * np.pi * np.cumsum(np.broadcast_to(tone_hz, (n,))) / FS
    slow = 0.3 * np.sin(2 * np.pi * 2.0 * t)
    noise = 0.002 * np.random.default_rng(seed).standard_normal(n)
    return slow, (slow + noise + np.sin(phase)).astype(np.float32)


@pytest.mark.parametrize("new_hz", [104.0, 140.0])
def test_retune_moves_the_output_monotonically_without_a_step(new_hz):
    """The notch sits on a 100 Hz line and is retuned away: the residual grows to the new
    steady state and never beyond it (a restart or a state mismatch would flash the unit
    line through). 200 Hz updates, 5 % per update."""
    slow, x = _vibrating_gyro(2500, 100.0)
    nt = HarmonicNotch(freq_hz=100.0, bw_hz=50.0)
    n0 = 1000
    y = nt.run(x, on_sample=lambda i: nt.set_centers([new_hz]) if i >= n0 and i % 5 == 0 else None)
    e = np.abs(y - slow)
    before, window, after = e[700:n0].max(), e[n0:n0 + 300].max(), e[2200:].max()
    assert before < 0.02
    # 3 sigma of the sensor noise; a notch leaving a line lets it through with the line's own
    # settling, a few % above its final level at most
    assert window <= 1.03 * max(before, after) + 0.006
    assert np.abs(np.diff(y[n0 - 5:n0 + 300])).max() <= 1.05 * np.abs(np.diff(y[2200:])).max() + 0.01


def test_tracking_a_moving_line_keeps_it_down():
    """A throttle punch: the line sweeps 100 -> 130 Hz in 0.3 s, the centre follows at 200 Hz."""
    n = 3000
    t = np.arange(n) / FS
    tone = np.where(t < 1.0, 100.0, np.where(t < 1.3, 100.0 + 100.0 * (t - 1.0), 130.0))
    slow, x = _vibrating_gyro(n, tone)
    nt = HarmonicNotch(freq_hz=100.0, bw_hz=50.0)
    y = nt.run(x, on_sample=lambda i: nt.set_centers([tone[i]]) if i % 5 == 0 else None)
    assert np.abs(y - slow)[500:].max() < 0.06           # the unit line stays >= 24 dB down


def test_att_and_bw_changes_take_effect_with_states_kept():
    """ATT and BW are set-up values: a change retunes in place (no restart, as ArduCopter's
    init with the filter states kept); a narrower notch needs its own settling time, so the
    line shows briefly (measured, not a jump to the raw line)."""
    slow, x = _vibrating_gyro(3000, 80.0)
    nt = HarmonicNotch()
    cfg = ffi.new("fc_notch_config_t *", dict(enable=True, mode=0, options=0, harmonics=1,
                                               freq_hz=80.0, bw_hz=20.0, att_db=25.0, ref=0.0,
                                               fm_ratio=1.0))
    y = nt.run(x, on_sample=lambda i: lib.fc_notch_configure(nt.n, cfg, 1.0 / FS)
               if i == 1000 else None)
    e = np.abs(y - slow)
    assert e[1000:1100].max() < 0.5                      # never the whole unit line
    assert e[2500:].max() == pytest.approx(10 ** (-25 / 20), abs=0.01)   # 25 dB down now
