"""The vibration, mount and IMU-chip constants of one run, and the IMU's mounting rotation,
by the names of the sensor stage's table (bridge/src/sensor_stage.c SB_STAGE_CONST_FIELDS:
vib_*, chip_*, imu_rot_on, imu_r*); and the chip's AAF gain for Python (tests, docs).

The models live in C (bridge/src/vibration.h, imu_chip.h); this module only turns the
scenario's [vibration], [mount] and [imu_chip] tables, the JSBSim model's geometry and
mass and the vehicle draw (CG offset, IMU misalignment) into those numbers. The stage's
vib_imbalance*_kg_m and vib_ripple*_frac carry vibration.frame_gain already (effective
forcing of a rigid frame that shakes the FC as the real frame does). With
vibration.enabled false and no IMU misalignment every constant is 0 and the stage runs
the IMU of before. bridge/vibration_checks.py checks the scenario's keys.
"""

from __future__ import annotations

import math

from silbridge.bridge.fdm import ROTOR_HUBS_FRD_M
from silbridge.bridge.imu import SPIN_CW
from silbridge.bridge.scenario import draw_rng

_SLUG_FT2_KG_M2 = 1.3558179483314003                     # slug ft^2 -> kg m^2
_N_RIPPLES = 5                                           # sensor_stage.h SB_VIB_RIPPLES
_AXES = "xyz"


def names() -> list[str]:
    """Every constant this module fills, in the stage's table order."""
    out = ["vib_on"]
    for m in range(1, 5):
        out += [f"vib_hub{m}_{a}_m" for a in _AXES] + [f"vib_spin{m}", f"vib_imbalance{m}_kg_m"]
    out.append("vib_kt_n_s2")
    for h in range(1, _N_RIPPLES + 1):
        out += [f"vib_ripple{h}_order", f"vib_ripple{h}_frac"]
    out += ["vib_mass_kg", "vib_ixx_kg_m2", "vib_iyy_kg_m2", "vib_izz_kg_m2"]
    out += [f"vib_lever_{a}_m" for a in _AXES]
    out += ["vib_frame_hz", "vib_frame_damping", "vib_mount_hz", "vib_mount_damping",
            "vib_mount_rot_hz", "vib_mount_rot_damping", "vib_wash_frac", "vib_wash_seed",
            "chip_odr_hz", "chip_aaf_hz", "chip_aaf_order"]
    out += ["imu_rot_on"] + [f"imu_r{i}{j}" for i in range(3) for j in range(3)]
    return out


def enabled(sc) -> bool:
    return bool(sc.vibration.enabled)


def stage_consts(sc, fdm, vehicle) -> dict:
    """The stage's vib_*, chip_*, imu_rot_on and imu_r* constants (all 0 when vibration is
    off and the vehicle draw's IMU rotation is the identity)."""
    c = dict.fromkeys(names(), 0.0)
    # The mounting misalignment is the vehicle's, applied with or without vibration; an
    # identity draw leaves the stage's path (and S1..S4's bytes) as before.
    if not vehicle.imu_identity:
        c["imu_rot_on"] = 1.0
        for i in range(3):
            for j in range(3):
                c[f"imu_r{i}{j}"] = float(vehicle.imu_rot[i][j])
    if not enabled(sc):
        return c
    vib, mount, chip = sc.vibration, sc.mount, sc.imu_chip
    cg = vehicle.cg_offset_frd_m
    c["vib_on"] = 1.0
    # Every stage after the forcing is linear, so the frame's lumped gain (frame_gain: what a
    # real frame passes to the FC over what the rigid body does) scales the forcing itself:
    # the accelerometer and the gyro keep reading one motion.
    gain = vib.frame_gain
    u_kg_m = vib.imbalance_g_mm * 1e-6 * gain        # g*mm -> kg*m
    for m in range(4):
        hub = ROTOR_HUBS_FRD_M[m]
        for i, a in enumerate(_AXES):
            c[f"vib_hub{m + 1}_{a}_m"] = hub[i] - cg[i]
        c[f"vib_spin{m + 1}"] = SPIN_CW[m]
        c[f"vib_imbalance{m + 1}_kg_m"] = u_kg_m * vib.imbalance_scale[m]
    c["vib_kt_n_s2"] = fdm.model_constant("quadx/kt-n-per-rad_s2")
    ripples = [(float(vib.blades), vib.blade_pass_ripple)]
    ripples += list(zip(vib.harmonic_orders, vib.harmonic_ripple))
    for h, (order, frac) in enumerate(ripples, start=1):
        c[f"vib_ripple{h}_order"] = float(order)
        c[f"vib_ripple{h}_frac"] = float(frac) * gain if order > 0 else 0.0
    c["vib_mass_kg"] = fdm.mass_kg
    for a in _AXES:
        c[f"vib_i{a}{a}_kg_m2"] = fdm.fdm[f"inertia/i{a}{a}-slugs_ft2"] * _SLUG_FT2_KG_M2
    for i, a in enumerate(_AXES):
        c[f"vib_lever_{a}_m"] = mount.imu_offset_frd_m[i] - cg[i]
    soft = mount.type == "soft"
    c["vib_frame_hz"] = vib.frame_mode_hz
    c["vib_frame_damping"] = vib.frame_mode_damping
    c["vib_mount_hz"] = mount.resonance_hz if soft else 0.0
    c["vib_mount_damping"] = mount.damping
    c["vib_mount_rot_hz"] = mount.rot_resonance_hz if soft else 0.0
    c["vib_mount_rot_damping"] = mount.rot_damping
    # Prop wash: the frame gain scales its forcing as it does the lines'; its generator's
    # seed is the run's own named stream (same seed, same draws; a 53-bit whole number,
    # exact as a double).
    c["vib_wash_frac"] = vib.prop_wash * gain
    c["vib_wash_seed"] = float(draw_rng(sc.seed, "vibration:prop_wash").integers(0, 2 ** 53))
    c["chip_odr_hz"] = float(chip.odr_hz)
    c["chip_aaf_hz"] = chip.aaf_hz
    c["chip_aaf_order"] = float(chip.aaf_order)
    return c


def aaf_gain(f_hz: float, aaf_hz: float, odr_hz: float, order: int = 2) -> float:
    """|H| at f_hz of the chip's AAF (bridge/src/imu_chip.c: bilinear 2nd-order
    Butterworth pre-warped to aaf_hz at odr_hz); order 0: 1."""
    if order == 0:
        return 1.0
    k = math.tan(math.pi * aaf_hz / odr_hz)
    q = math.sqrt(0.5)
    norm = 1.0 / (1.0 + k / q + k * k)
    b = (k * k * norm, 2.0 * k * k * norm, k * k * norm)
    a = (1.0, 2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm)
    z = complex(math.cos(2 * math.pi * f_hz / odr_hz), -math.sin(2 * math.pi * f_hz / odr_hz))
    return abs((b[0] + b[1] * z + b[2] * z * z) / (a[0] + a[1] * z + a[2] * z * z))
