"""Vibration from the rotors, through frame and mount, read through the IMU chip (real
JSBSim, the C sensor stage): gyro peaks sit at k x the rotor frequency and follow a
throttle change; the accelerometer's vibration is what the gyro's motion and the lever
arm predict; an alias appears where a chip shows one; same seed, same bytes; bad keys."""

import hashlib
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.bridge.vibration_consts import aaf_gain
from silbridge.shm.records import Kind

from bridge_test_helpers import QUIET_IMU, of_kind

FC_HZ = 1000.0


def fly(overrides, pwm_us, steps, name="S1", seed=None):
    """IMU records and the rotor frequency [Hz] at the end, at a constant PWM from the
    ground (below hover: the vehicle stays down, the rotors spin)."""
    sim = Simulator(load_scenario(name, seed=seed, overrides=overrides))
    recs = np.concatenate([sim.step((pwm_us,) * 4).copy() for _ in range(steps)])
    return sim, of_kind(recs, Kind.IMU), sim.rotor_rad_s()[0] / (2 * math.pi)


def peak_near(x, f_hz):
    """Interpolated spectrum peak within +-8 % of f_hz, and its height over the median."""
    x = x - x.mean(axis=0)
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x))[:, None], axis=0)).sum(axis=1)
    freqs = np.fft.rfftfreq(len(x), 1.0 / FC_HZ)
    band = np.flatnonzero((freqs > 0.92 * f_hz) & (freqs < 1.08 * f_hz))
    i = band[np.argmax(spec[band])]
    a, b, c = np.log(spec[i - 1:i + 2])
    shift = 0.5 * (a - c) / (a - 2 * b + c)
    return freqs[i] + shift * (freqs[1] - freqs[0]), spec[i] / np.median(spec)


def phasors(x, freqs_hz):
    """Complex amplitude P of each column at each frequency: x = Re(P exp(j 2 pi f t))."""
    t = np.arange(len(x)) / FC_HZ
    cols = [np.ones_like(t)]
    for f in freqs_hz:
        cols += [np.cos(2 * np.pi * f * t), np.sin(2 * np.pi * f * t)]
    coef = np.linalg.lstsq(np.column_stack(cols), x, rcond=None)[0]
    return [coef[1 + 2 * k] - 1j * coef[2 + 2 * k] for k in range(len(freqs_hz))]


def test_gyro_peaks_sit_at_k_times_the_rotor_frequency_and_follow_the_throttle():
    # Noise off: at 0.5 % of thrust the 3rd-order line sits near the chip's noise floor at
    # low throttle; this test is about where the lines are.
    sim = Simulator(load_scenario("S1", overrides={**QUIET_IMU, "vibration.enabled": True}))
    seen = []
    for pwm in (sim.hover_pwm_us - 250.0, sim.hover_pwm_us - 60.0):
        recs = [sim.step((pwm,) * 4).copy() for _ in range(3000)]
        gyro = of_kind(np.concatenate(recs[1000:]), Kind.IMU)["gyro_frd_rad_s"].astype(float)
        f_rot = sim.rotor_rad_s()[0] / (2 * math.pi)
        for k in (1, 2, 3):
            f_peak, height = peak_near(gyro, k * f_rot)
            assert height > 30.0, (k, height)               # a peak, not the noise floor
            assert f_peak == pytest.approx(k * f_rot, rel=0.01), (k, f_peak, f_rot)
        seen.append(f_rot)
    assert seen[1] > 1.1 * seen[0]                           # the throttle moved the peaks


@pytest.mark.parametrize("mount", [{"mount.type": "hard"},
                                   {"mount.type": "soft", "mount.resonance_hz": 35.0,
                                    "mount.rot_resonance_hz": 35.0, "mount.damping": 0.2,
                                    "mount.rot_damping": 0.2}])
def test_accel_vibration_is_what_the_gyro_motion_and_the_lever_arm_predict(mount):
    """Two IMU places (noise off: it would blur the gyro phasors): the accelerometers differ by
    alpha x dr, alpha = j 2 pi f x the gyro's phasor, at every rotor harmonic."""
    base = {**QUIET_IMU, "vibration.enabled": True, **mount}
    dr = np.array((0.08, -0.05, -0.04))
    _, imu0, f_rot = fly({**base, "mount.imu_offset_frd_m": [0.0, 0.0, 0.0]}, 1400.0, 3000)
    _, imu1, _ = fly({**base, "mount.imu_offset_frd_m": dr.tolist()}, 1400.0, 3000)
    freqs = [k * f_rot for k in (1, 2, 3, 4)]
    tail = slice(1000, None)
    gyro = phasors(imu0["gyro_frd_rad_s"][tail].astype(float), freqs)
    d_acc = phasors((imu1["accel_frd_m_s2"][tail].astype(float)
                     - imu0["accel_frd_m_s2"][tail].astype(float)), freqs)
    assert np.abs(imu1["gyro_frd_rad_s"] - imu0["gyro_frd_rad_s"]).max() == 0.0
    checked = 0
    for f, w, da in zip(freqs, gyro, d_acc):
        predicted = np.cross(1j * 2 * np.pi * f * w, dr)
        if np.linalg.norm(predicted) < 1e-4:     # m/s^2: a harmonic the soft mount removed
            continue
        assert np.linalg.norm(da - predicted) < 0.02 * np.linalg.norm(predicted), f
        checked += 1
    assert checked >= 2


def _second_order_gain(f_n_hz, zeta, f_hz):
    """|H| of the declared 2nd-order stage (vibration.h sb_vib_second_order)."""
    r = f_hz / f_n_hz
    return 1.0 / math.hypot(1.0 - r * r, 2.0 * zeta * r)


@pytest.mark.parametrize("stage", ["frame mode", "soft mount"])
def test_frame_mode_and_soft_mount_scale_the_blade_pass_line_by_their_declared_gain(stage):
    """The blade-pass line of the vertical accelerometer (IMU at the CG: translation only),
    with the stage against without it: the ratio is the stage's gain at 2 x rotor frequency
    (V4 puts the frame mode there and amplifies it; V1's soft mount attenuates it)."""
    base = {**QUIET_IMU, "vibration.enabled": True, "mount.imu_offset_frd_m": [0.0, 0.0, 0.0]}
    if stage == "frame mode":
        extra = {"vibration.frame_mode_hz": 150.0, "vibration.frame_mode_damping": 0.05}
    else:
        extra = {"mount.type": "soft", "mount.resonance_hz": 30.0, "mount.damping": 0.15}
    _, plain, f_rot = fly(base, 1450.0, 3000)
    _, shaped, _ = fly({**base, **extra}, 1450.0, 3000)
    f_bp = 2 * f_rot
    amp = [abs(phasors(imu["accel_frd_m_s2"][1000:, 2].astype(float), [f_bp])[0])
           for imu in (plain, shaped)]
    if stage == "frame mode":
        declared = _second_order_gain(150.0, 0.05, f_bp)
        assert declared > 2.0                       # near resonance: amplified
    else:
        declared = _second_order_gain(30.0, 0.15, f_bp)
        assert declared < 0.1                       # far above resonance: isolated
    assert amp[1] / amp[0] == pytest.approx(declared, rel=0.01)


def _only_order(order):
    """Only one thrust-ripple order: its alias is the one line in the gyro."""
    return {**QUIET_IMU, "vibration.enabled": True, "vibration.imbalance_g_mm": 0.0,
            "vibration.blade_pass_ripple": 0.0, "vibration.harmonic_orders": [order, 0, 0, 0],
            "vibration.harmonic_ripple": [0.02, 0, 0, 0], "imu_chip.odr_hz": 32000}


def test_a_1300_hz_line_aliases_to_its_folded_frequency_with_the_aaf_off_and_shrinks_with_it_on():
    base = _only_order(16)              # 16 x ~81 Hz ~ 1.3 kHz at this throttle
    _, off, f_rot = fly({**base, "imu_chip.aaf_order": 0}, 1500.0, 3000)
    _, on, _ = fly({**base, "imu_chip.aaf_order": 2, "imu_chip.aaf_hz": 585.0}, 1500.0, 3000)
    f_vib = 16 * f_rot
    assert 1250.0 < f_vib < 1350.0
    alias = abs(f_vib - FC_HZ)
    g_off = off["gyro_frd_rad_s"][1000:].astype(float)
    g_on = on["gyro_frd_rad_s"][1000:].astype(float)
    f_peak, height = peak_near(g_off, alias)
    assert f_peak == pytest.approx(alias, rel=0.01) and height > 100.0
    a_off = np.abs(phasors(g_off, [alias])[0])
    a_on = np.abs(phasors(g_on, [alias])[0])
    assert np.linalg.norm(a_on) / np.linalg.norm(a_off) == pytest.approx(
        aaf_gain(f_vib, 585.0, 32000.0), rel=0.02)


@pytest.mark.parametrize("vibration", [False, True])
def test_the_imu_reads_through_the_vehicles_mounting_misalignment(vibration):
    """[vehicle] draws an IMU misalignment R (E); the stage applies it to the IMU's signal,
    with or without vibration: at rest, with every error source off, accel = R f_true."""
    only_imu_tilt = {"vehicle.imperfect": True, "vehicle.cg_tol_xy_m": 0.0,
                     "vehicle.cg_tol_z_m": 0.0, "vehicle.kt_tol": 0.0, "vehicle.kq_tol": 0.0,
                     "vehicle.tilt_tol_deg": 0.0, "vehicle.imu_tilt_tol_deg": 1.0,
                     "mount.imu_offset_frd_m": [0.0, 0.0, 0.0], **QUIET_IMU}
    if vibration:
        only_imu_tilt.update({"vibration.enabled": True, "vibration.imbalance_g_mm": 0.0,
                              "vibration.blade_pass_ripple": 0.0,
                              "vibration.harmonic_ripple": [0.0, 0.0, 0.0, 0.0]})
    sim, imu, _ = fly(only_imu_tilt, 1000.0, 300)
    rot = np.array(sim.vehicle.imu_rot)
    assert not sim.vehicle.imu_identity
    f_true = np.array(sim.truth()["specific_force_frd_m_s2"])
    accel = imu["accel_frd_m_s2"][-1].astype(float)
    assert np.allclose(accel, rot @ f_true, atol=1e-5)
    assert not np.allclose(accel, f_true, atol=1e-3)       # 1 deg of tilt shows


def _hash(name, seed, steps=1500):
    sim = Simulator(load_scenario(name, seed=seed))
    h = hashlib.md5()
    pwm = (sim.hover_pwm_us + 40.0,) * 4
    for _ in range(steps):
        h.update(sim.step(pwm).tobytes())
    return h.hexdigest()


def test_same_seed_same_bytes_with_vibration_on():
    assert _hash("V2", 3) == _hash("V2", 3)
    assert _hash("V2", 3) != _hash("V2", 4)             # the rotor phases are drawn


def _fly_hash(name, seed):
    out = subprocess.run([sys.executable, "-m", "silbridge.tools", "fly", "--processes", "1",
                          "--scenario", name, "--seed", str(seed), "--duration", "3", "--json"],
                         capture_output=True, text=True, check=True, timeout=120).stdout
    summary = json.loads(out)
    assert not summary["crashed"]
    return summary["trace_hash"]


def test_a_closed_loop_flight_with_vibration_has_one_trace_hash_per_seed():
    """Real processes, our FC in the loop: V2 (a bent prop) twice with one seed, once with
    another."""
    assert _fly_hash("V2", 5) == _fly_hash("V2", 5) != _fly_hash("V2", 6)


@pytest.mark.parametrize("name", ["V1", "V2", "V3", "V4"])
def test_the_v_scenarios_load_with_vibration_on(name):
    sc = load_scenario(name)
    assert sc.vibration.enabled


BAD = {
    "unknown key": ({"vibration.wobble": 1.0}, "vibration.wobble"),
    "negative amplitude": ({"vibration.imbalance_g_mm": -1.0}, "vibration.imbalance_g_mm"),
    "negative frame gain": ({"vibration.frame_gain": -1.0}, "vibration.frame_gain"),
    "negative prop wash": ({"vibration.prop_wash": -0.01}, "vibration.prop_wash"),
    "prop wash above the thrust": ({"vibration.prop_wash": 1.5}, "vibration.prop_wash"),
    "negative ripple": ({"vibration.harmonic_ripple": [0.01, -0.1, 0, 0]},
                        "vibration.harmonic_ripple[1]"),
    "mount above Nyquist": ({"mount.resonance_hz": 5000.0}, "mount.resonance_hz"),
    "frame above Nyquist": ({"imu_chip.odr_hz": 1000, "vibration.frame_mode_hz": 600.0},
                            "vibration.frame_mode_hz"),
    "AAF above Nyquist": ({"imu_chip.aaf_hz": 4500.0}, "imu_chip.aaf_hz"),
    "not a chip rate": ({"imu_chip.odr_hz": 5000}, "imu_chip.odr_hz"),
    "fractional order": ({"vibration.harmonic_orders": [2.5, 0, 0, 0]},
                         "vibration.harmonic_orders[0]"),
    "bad mount": ({"mount.type": "rubber"}, "mount.type"),
    "AAF order": ({"imu_chip.aaf_order": 1}, "imu_chip.aaf_order"),
}


@pytest.mark.parametrize("case", BAD)
def test_bad_vibration_input_is_a_scenario_error_naming_the_key(case):
    overrides, key = BAD[case]
    with pytest.raises(ScenarioError, match=key.replace("[", r"\[").replace("]", r"\]")):
        load_scenario("V1", overrides=overrides)


def test_the_chip_needs_one_imu_sample_per_physics_step():
    with pytest.raises(ScenarioError, match="vibration.enabled"):
        load_scenario("V1", overrides={"imu.rate_hz": 2000})
