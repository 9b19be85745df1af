"""The chip's raw samples at its data rate (bridge/src/imu_raw.h), with real JSBSim and the
C sensor stage: they never change what the FC reads; their last tick of each step is the
FC's read; their spectrum shows the rotor lines at k x the rotor frequency, and a line
above the FC's Nyquist frequency at its true frequency where the FC's samples alias it;
log_raw without the chip is refused, naming the key.

The vehicle sits on the ground with its rotors spinning below hover (a constant PWM):
steady rotor speed, steady lines."""

import math

import numpy as np
import pytest

from silbridge.bridge.bridge_loop import BATCH_MAX_STEPS
from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind
from silbridge.tools.logs.imu_raw_log import RAW_DTYPE, ImuRawLog
from silbridge.tools.logs.spectrum import welch
from silbridge.tools.logs.spectrum_peaks import refine

from bridge_test_helpers import QUIET_IMU, of_kind

FC_HZ = 1000.0


def spin(name, overrides, steps, raw: bool, below_hover_us=60.0):
    """(step records, raw rows or None, rotor frequency [Hz] at the end)."""
    sim = Simulator(load_scenario(name, overrides=overrides))
    n = int(sim.scenario.imu_chip.odr_hz // FC_HZ)
    buf = np.zeros(2 * n, RAW_DTYPE)
    if raw:
        sim.kernel.bind_imu_raw(buf)
    pwm = (sim.hover_pwm_us - below_hover_us,) * 4
    recs, rows = [], []
    for _ in range(steps):
        recs.append(sim.step(pwm).copy())
        if raw:
            got, dropped = sim.kernel.take_imu_raw()
            assert got == n and dropped == 0
            rows.append(buf[:got].copy())
    f_rot = sim.rotor_rad_s()[0] / (2 * math.pi)
    return np.concatenate(recs), (np.concatenate(rows) if raw else None), f_rot


def peak_near(x, rate_hz, f_hz, rel=0.05):
    """(frequency, amplitude, height over the median) of the largest bin within +-rel of
    f_hz in the Welch spectrum (1 s segments) of the three axes' sum of squares."""
    sp = welch(x.astype(float), rate_hz, int(rate_hz))
    amp = np.sqrt((sp.amp ** 2).sum(axis=1))
    band = np.flatnonzero(np.abs(sp.freq_hz - f_hz) <= rel * f_hz)
    i = int(band[np.argmax(amp[band])])
    d, gain = refine(amp, i)
    df = sp.freq_hz[1] - sp.freq_hz[0]
    return sp.freq_hz[i] + d * df, amp[i] * gain, amp[i] / np.median(amp[1:])


WASH = {"vibration.prop_wash": 0.02}


@pytest.mark.parametrize("name, over", [("V1", {}), ("V2", {}), ("V3", {}), ("V4", {}),
                                        ("V2", WASH)])
def test_fc_reads_are_bit_identical_with_raw_logging_on_and_off(name, over):
    off, _, _ = spin(name, over, 800, raw=False)
    on, rows, _ = spin(name, over, 800, raw=True)
    assert off.tobytes() == on.tobytes()
    assert len(rows) == 800 * 8 and np.all(np.diff(rows["sim_ns"]) == 125_000)


@pytest.mark.parametrize("odr_hz, over", [(2000, {}), (8000, {}), (32000, {}), (8000, WASH)])
def test_the_last_tick_of_each_step_is_what_the_fc_reads(odr_hz, over):
    """Noise off: the FC's sample is the chip's register at the step's end (the stage's
    one-shot ramp map and analytic lines against the tick-by-tick filter and turning
    phasors; the prop wash, when on, from the same draws)."""
    recs, rows, _ = spin("V2", {**QUIET_IMU, **over, "imu_chip.odr_hz": odr_hz}, 600,
                         raw=True)
    imu = of_kind(recs, Kind.IMU)
    n = odr_hz // 1000
    assert len(rows) == 600 * n
    last = rows[n - 1::n]
    assert np.array_equal(last["sim_ns"], imu["sim_ns"])
    for col in ("gyro_frd_rad_s", "accel_frd_m_s2"):
        scale = np.abs(imu[col]).max()
        np.testing.assert_allclose(last[col], imu[col], rtol=0, atol=1e-5 * scale + 1e-6)


@pytest.mark.parametrize("odr_hz", [8000, 32000])
def test_raw_spectrum_shows_the_rotor_lines_at_k_times_the_rotor_frequency(odr_hz):
    _, rows, f_rot = spin("V2", {**QUIET_IMU, "imu_chip.odr_hz": odr_hz}, 3000, raw=True)
    gyro = rows["gyro_frd_rad_s"][odr_hz:]          # past the spin-up
    for k in (1, 2, 3):
        f, _, height = peak_near(gyro, float(odr_hz), k * f_rot)
        assert height > 30.0, (k, height)
        assert f == pytest.approx(k * f_rot, rel=0.01), (k, f, f_rot)


def test_a_line_above_the_fc_nyquist_is_true_in_the_raw_spectrum_and_aliased_at_fc_rate():
    """A 17th-order thrust ripple (~1.26 kHz) with the AAF on: the 8 kHz chip samples show
    it at 17 f_rot, the FC's 1 kHz samples at its alias 1000 - ... Hz, with one amplitude."""
    over = {**QUIET_IMU, "vibration.harmonic_orders": [17.0, 0.0, 0.0, 0.0],
            "vibration.harmonic_ripple": [0.02, 0.0, 0.0, 0.0]}
    recs, rows, f_rot = spin("V2", over, 3000, raw=True)
    f_line = 17 * f_rot
    assert FC_HZ / 2 < f_line < 1.5 * FC_HZ
    alias = abs(f_line - round(f_line / FC_HZ) * FC_HZ)
    raw_f, raw_a, raw_h = peak_near(rows["gyro_frd_rad_s"][8000:], 8000.0, f_line, rel=0.01)
    gyro_fc = of_kind(recs, Kind.IMU)["gyro_frd_rad_s"][1000:]
    fc_f, fc_a, fc_h = peak_near(gyro_fc, FC_HZ, alias, rel=0.03)
    assert raw_h > 30.0 and fc_h > 30.0, (raw_h, fc_h)
    assert raw_f == pytest.approx(f_line, rel=0.01)
    assert fc_f == pytest.approx(alias, rel=0.01)
    assert fc_a == pytest.approx(raw_a, rel=0.05)
    # and the chip's own samples do not fold it: nothing at the alias frequency there
    _, _, raw_at_alias = peak_near(rows["gyro_frd_rad_s"][8000:], 8000.0, alias, rel=0.01)
    assert raw_at_alias < 0.01 * raw_h


def test_log_raw_without_the_chip_is_refused_naming_the_key():
    with pytest.raises(ScenarioError, match="imu_chip.log_raw"):
        load_scenario("S1", overrides={"imu_chip.log_raw": True})
    assert load_scenario("V2", overrides={"imu_chip.log_raw": True}).imu_chip.log_raw


def test_binding_raw_rows_without_the_chip_is_refused():
    sim = Simulator(load_scenario("S1"))
    with pytest.raises(ValueError, match="vibration on"):
        sim.kernel.bind_imu_raw(np.zeros(64, RAW_DTYPE))


class _Writer:
    """The log writer's two calls ImuRawLog makes; it keeps the rows."""

    def __init__(self):
        self.rows = []

    def declare(self, channel, dtype):
        pass

    def write(self, channel, rows):
        self.rows.append(rows.copy())


def test_the_logs_raw_buffer_holds_a_whole_batch_of_steps():
    """ImuRawLog takes the chip's rows once per batch (bridge_loop's write_rows): its buffer
    holds the longest batch's rows, so none is dropped, at the chip's highest data rate."""
    sim = Simulator(load_scenario("V2", overrides={"imu_chip.odr_hz": 32000}))
    n = int(sim.scenario.imu_chip.odr_hz // FC_HZ)
    writer = _Writer()
    raw = ImuRawLog(writer, sim.kernel, n, rotor_hook=lambda *a: None)
    pwm = (sim.hover_pwm_us - 60.0,) * 4
    for _ in range(BATCH_MAX_STEPS):
        sim.step(pwm)
    raw.take()
    raw.close()
    rows = np.concatenate(writer.rows)
    assert raw.dropped == 0
    assert len(rows) == n * BATCH_MAX_STEPS
    assert np.all(np.diff(rows["sim_ns"]) == 1_000_000_000 // 32000)
