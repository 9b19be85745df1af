"""The linearised rate plant of our quad about hover: mixer input [us] -> true
body rate [rad/s], from the JSBSim model's own figures (jsbsim_models/quadx:
inertia, motor positions, kT, kQ, omega_max, thrust expo, motor time constant)
and the FC's output timing (PWM grid, physics step). It is the reference the
identification is checked against (tests/tools/test_tune_ident.py), so every
figure is read from the model files, none typed here.

Chain for a roll (pitch) mixer input of c us: each motor moves by +-c us
(fc_mixer.c factors +-1), i.e. throttle by c / 1000 (motors.xml ESC range);
thrust per motor at hover throttle t0 is T = T_max ((1 - e) t + e t^2), so
dT = T_max ((1 - e) + 2 e t0) dt, lagged by the rotor's first-order lag tau
(thrust ~ omega^2 follows omega's lag to first order); the four motors at
+-y_arm (+-x_arm) give a moment 4 y_arm dT, and p' = L / Ixx. Yaw: the
reaction torques kQ/kT dT of four motors, r' = N / Izz.
Timing: the FC's rate loop computes the input at an IMU sample; the PWM tick
that carries it comes on the SB_PWM_HZ grid at the first IMU sample at or after
the tick time, and holds until the next tick; the bridge applies it from that
step on. Its effect is the mean age of the held value (a pure delay, 1.3 ms for
400 Hz PWM and 1 kHz IMU) and the hold's sinc droop.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from silbridge.jsbsim_models import AIRCRAFT_DIR, DEFAULT_MODEL

G0 = 9.80665


@dataclass(frozen=True)
class QuadFigures:
    mass_kg: float
    inertia_kg_m2: tuple      # Ixx, Iyy, Izz
    arm_xy_m: tuple           # |x|, |y| of the motor hubs from the CG
    kt: float                 # N / (rad/s)^2
    kq: float                 # N m / (rad/s)^2
    omega_max: float          # rad/s
    expo: float               # thrust curve expo e
    tau_s: float              # rotor lag time constant

    @property
    def t_max_n(self) -> float:
        return self.kt * self.omega_max ** 2

    def hover_throttle(self) -> float:
        """Throttle t0 at which four motors carry the weight (inverse of the ESC curve)."""
        frac = self.mass_kg * G0 / (4.0 * self.t_max_n)
        e = self.expo
        return ((e - 1.0) + math.sqrt((1.0 - e) ** 2 + 4.0 * e * frac)) / (2.0 * e)

    def thrust_slope_n_per_us(self) -> float:
        """dT/dPWM of one motor at hover [N/us] (1000 us = full throttle range)."""
        e, t0 = self.expo, self.hover_throttle()
        return self.t_max_n * ((1.0 - e) + 2.0 * e * t0) / 1000.0


def _props(path) -> dict:
    root = ET.parse(path).getroot()
    return {p.text.strip(): float(p.get("value")) for p in root.iter("property")
            if p.get("value") is not None and p.text}


def load_figures(model: str = DEFAULT_MODEL) -> QuadFigures:
    """Figures of a model from its XML files (airframe and motors)."""
    folder = AIRCRAFT_DIR / model
    root = ET.parse(folder / f"{model}.xml").getroot()
    mb = root.find("mass_balance")
    inertia = tuple(float(mb.find(k).text) for k in ("ixx", "iyy", "izz"))
    mass = float(mb.find("emptywt").text)
    hubs = []
    for force in root.find("external_reactions").findall("force"):
        if force.get("name", "").startswith("m"):
            loc = force.find("location")
            hubs.append((abs(float(loc.find("x").text)), abs(float(loc.find("y").text))))
    if len(hubs) != 4:
        raise ValueError(f"{model}: expected 4 motor forces, found {len(hubs)}")
    arm = (float(np.mean([h[0] for h in hubs])), float(np.mean([h[1] for h in hubs])))
    props = _props(folder / "motors.xml")
    return QuadFigures(mass_kg=mass, inertia_kg_m2=inertia, arm_xy_m=arm,
                       kt=props["quadx/kt-n-per-rad_s2"], kq=props["quadx/kq-nm-per-rad_s2"],
                       omega_max=props["quadx/omega-max-rad_s"],
                       expo=props["quadx/thrust-expo"], tau_s=props["quadx/motor-tau-s"])


def pwm_hold(pwm_hz: float, imu_hz: float) -> tuple[float, float]:
    """(mean age [s], mean hold [s]) of the value a PWM output carries: ticks on the
    1/pwm_hz grid fire at the first IMU sample at or after their time."""
    n_ticks = 400
    imu_dt = 1.0 / imu_hz
    fire = np.ceil(np.arange(n_ticks) / pwm_hz / imu_dt - 1e-9) * imu_dt
    holds = np.diff(fire)
    mean_age = float(np.sum(holds ** 2 / 2.0) / np.sum(holds))
    return mean_age, float(np.mean(holds))


def plant_gain(fig: QuadFigures, axis: str) -> float:
    """Angular acceleration per us of mixer input [rad/s^2/us]."""
    slope = fig.thrust_slope_n_per_us()
    ixx, iyy, izz = fig.inertia_kg_m2
    if axis == "roll":
        return 4.0 * fig.arm_xy_m[1] * slope / ixx
    if axis == "pitch":
        return 4.0 * fig.arm_xy_m[0] * slope / iyy
    if axis == "yaw":
        return 4.0 * (fig.kq / fig.kt) * slope / izz
    raise ValueError(f"axis must be roll, pitch or yaw, not {axis!r}")


def plant_frf(f_hz, axis: str, *, pwm_hz: float = 400.0, imu_hz: float = 1000.0,
              fig: QuadFigures | None = None) -> np.ndarray:
    """Complex response of the linearised plant (mixer us -> body rate rad/s) at f_hz."""
    fig = fig or load_figures()
    s = 2j * np.pi * np.asarray(f_hz, dtype=float)
    age, hold = pwm_hold(pwm_hz, imu_hz)
    w = np.abs(s)
    droop = np.sinc(w * hold / (2.0 * np.pi))     # |ZOH| of the mean hold
    return plant_gain(fig, axis) / (s * (fig.tau_s * s + 1.0)) * droop * np.exp(-s * age)


def plant_agreement(f_hz, h, coherence, axis: str, *, band_hz: tuple, coh_min: float = 0.9,
                    pwm_hz: float = 400.0, imu_hz: float = 1000.0) -> dict:
    """Largest gain [dB] and phase [deg] difference between an identified plant and
    this model, over the frequencies of the sweep band_hz where coherence >= coh_min
    (outside the sweep a coherence estimate is noise over noise)."""
    f = np.asarray(f_hz, dtype=float)
    m = ((np.asarray(coherence) >= coh_min) & np.isfinite(h) & (f >= band_hz[0])
         & (f <= band_hz[1]))
    if not m.any():
        return {"band_hz": None, "points": 0, "max_gain_err_db": None, "max_phase_err_deg": None}
    model = plant_frf(f[m], axis, pwm_hz=pwm_hz, imu_hz=imu_hz)
    ratio = np.asarray(h)[m] / model
    gain = 20.0 * np.log10(np.abs(ratio))
    phase = np.degrees(np.angle(ratio))          # wrapped: the same branch by construction
    return {"band_hz": [float(f[m].min()), float(f[m].max())], "points": int(m.sum()),
            "max_gain_err_db": float(np.max(np.abs(gain))),
            "max_phase_err_deg": float(np.max(np.abs(phase)))}
