"""The scenario file format: every key, its type, unit, default and the source of the default.

A scenario is a TOML file. Top-level keys name the run; tables configure the
physics, home, analysis windows and each sensor; arrays of tables
``[[disturbance]]`` and ``[[setpoint]]`` script what happens and when. This
module is only the declaration; ``scenario.py`` validates files against it
and draws random values. Any numeric key marked ``drawable`` may instead be a
table ``{uniform = [lo, hi]}`` or ``{choice = [a, b, ...]}``, drawn once per
run from the scenario seed (per repetition for repeated setpoints); list
elements may be drawn the same way.

Sensor defaults, with sources:
- IMU white noise: TDK InvenSense ICM-42688-P datasheet, gyro rate noise
  density 0.0028 dps/sqrt(Hz) = 4.887e-5 rad/s/sqrt(Hz); accel noise density
  70 ug/sqrt(Hz) = 6.865e-4 m/s^2/sqrt(Hz). Turn-on bias: same datasheet's
  zero-rate output +-0.5 dps (8.7e-3 rad/s), used as a one-sigma value (the
  ADIS16448 figure the PX4/RotorS SITL IMU uses). The gyro is re-calibrated
  by the FC at every boot (as ArduPilot's INS_GYR_CAL does); the
  accelerometer is not, it is calibrated once by the user: its turn-on bias
  here is the residual after that calibration, taken as a tenth of the raw
  zero-g offset +-20 mg, i.e. 2 mg = 0.0196 m/s^2 one sigma (raw, an
  uncalibrated +-20 mg would tilt a hovering vehicle by ~1 degree). Temperature
  coefficients +-0.005 dps/K = 8.7e-5 rad/s/K and +-0.15 mg/K = 1.47e-3
  m/s^2/K (ICM-42688-P), drawn per run uniformly within +-. Bias random walk
  3.8785e-5 rad/s^2/sqrt(Hz) and 6.0e-3 m/s^3/sqrt(Hz): RotorS/PX4 SITL IMU
  defaults. Range +-16 g and +-2000 dps (ICM-42688-P full scale).
- Vibration: 1/rev imbalance of 2.0 m/s^2 (accel) and 0.01 rad/s (gyro) per
  motor at full rotor speed, scaling with speed squared; at hover (0.354 of
  full thrust) four motors give ~1 m/s^2 RMS per axis, a well-balanced frame
  with a soft-mounted FC in ArduPilot's vibration guidance (VIBE below
  15 m/s^2 is good). Blade-pass (2/rev) ripple on z at half that amplitude.
- Die temperature: starts at the air temperature and rises 10 K with a 120 s
  time constant (self-heating of an FC board in its enclosure, a typical
  warm-up curve), so temperature-induced bias drifts during a run.
- Baro: TE MS5611 (Pixhawk) at OSR 4096, RMS resolution 0.012 mbar = 1.2 Pa;
  conversion time 9.04 ms, modelled as a 10 ms first-order lag.
- Magnetometer: ST LIS3MDL, RMS noise 3.2 mgauss (ultra-high-performance
  mode). Field: unless the scenario declares mag.field_ned_gauss, the World
  Magnetic Model 2025 (NOAA coefficients WMM_2025.COF, evaluated with the
  pygeomag package) for 2026.0 at the home, read from the committed grid
  silbridge/magfield_grid.py (the table the FC's COMPASS_AUTODEC reads, so
  the FC's declination is the world's). At the default home (PX4's default
  SITL home, Zurich 47.397742 N, 8.545594 E) that is north 0.2159, east
  0.0133, down 0.4324 gauss (declination 3.53 deg; the exact model at 488 m:
  3.55 deg, inclination 63.52 deg, total 0.4836 gauss). Never JSBSim's
  wall-clock WMM, so runs are deterministic.
- GNSS: u-blox M8 class receiver: 2.5 m CEP autonomous -> 2.12 m one-sigma per
  horizontal axis (CEP = 1.1774 sigma), vertical 1.5x horizontal = 3.2 m,
  first-order Gauss-Markov with a 60 s correlation time (the PX4 SITL GPS
  model's), velocity 0.05 m/s; 10 Hz; latency 110 ms (PX4 EKF2_GPS_DELAY
  default); 3D fix with 14 satellites.
"""

from __future__ import annotations

from dataclasses import dataclass

REQUIRED = object()


@dataclass(frozen=True)
class Field:
    """One key: kind is float, int, str, bool, vec3, vec4 or axis."""

    kind: str
    default: object = REQUIRED
    min: float | None = None          # inclusive lower bound
    above: float | None = None        # exclusive lower bound
    max: float | None = None
    choices: tuple | None = None
    drawable: bool = False
    unit: str = ""
    text: str = ""


F = Field

TOP = {
    "name": F("str", text="scenario name (S1..S5 for the built-ins)"),
    "description": F("str", "", text="one line for reports"),
    "seed": F("int", min=0, text="seed of every random draw in the run"),
    "duration_s": F("float", above=0, unit="s", text="run length"),
    "takeoff_alt_m": F("float", 10.0, min=0, unit="m", text="first altitude setpoint above home"),
    "setpoint_rate_hz": F("float", 100.0, above=0, unit="Hz",
                          text="SETPOINT record rate while a ramp is running"),
}

SECTIONS = {
    "physics": {
        "rate_hz": F("int", 1000, above=0, unit="Hz", text="physics step rate; 1e9 must be a multiple"),
        "model": F("str", "quadx", text="JSBSim model under silbridge/jsbsim_models"),
        "crash_descent_m_s": F("float", 3.0, above=0, unit="m/s",
                               text="touchdown descent speed counted as a crash"),
        "crash_tilt_deg": F("float", 60.0, above=0, max=180, unit="deg",
                            text="tilt on the ground counted as a crash (tipped over)"),
    },
    "home": {
        "lat_deg": F("float", 47.397742, min=-89.9, max=89.9, unit="deg"),
        "lon_deg": F("float", 8.545594, min=-180, max=180, unit="deg"),
        "alt_m": F("float", 488.0, min=-400, max=8000, unit="m", text="ground elevation AMSL"),
        "heading_deg": F("float", 0.0, min=-360, max=360, unit="deg"),
        "initial_agl_m": F("float", 0.0, min=0, unit="m",
                           text="feet above ground at start (0 = landed)"),
    },
    "windows": {
        "warmup_s": F("float", 10.0, min=0, unit="s", text="paper protocol: warm-up 0-10 s"),
        "transient_end_s": F("float", 30.0, min=0, unit="s",
                             text="paper protocol: transient to 30 s, analysis after"),
    },
    "imu": {
        "rate_hz": F("int", 1000, above=0, unit="Hz", text="IMU output rate (oversampled above physics)"),
        "gyro_noise_density": F("float", 4.887e-5, min=0, unit="rad/s/sqrt(Hz)"),
        "accel_noise_density": F("float", 6.865e-4, min=0, unit="m/s^2/sqrt(Hz)"),
        "gyro_bias_walk": F("float", 3.8785e-5, min=0, unit="rad/s^2/sqrt(Hz)"),
        "accel_bias_walk": F("float", 6.0e-3, min=0, unit="m/s^3/sqrt(Hz)"),
        "gyro_turn_on_bias": F("float", 8.7e-3, min=0, unit="rad/s", text="one sigma"),
        "accel_turn_on_bias": F("float", 0.0196, min=0, unit="m/s^2",
                                text="one sigma, residual after the user's calibration"),
        "gyro_tempco": F("float", 8.7e-5, min=0, unit="rad/s/K", text="+- bound, drawn"),
        "accel_tempco": F("float", 1.47e-3, min=0, unit="m/s^2/K", text="+- bound, drawn"),
        "temp_rise_k": F("float", 10.0, unit="K"),
        "temp_tau_s": F("float", 120.0, above=0, unit="s"),
        "vib_accel": F("float", 2.0, min=0, unit="m/s^2", text="per motor at full speed"),
        "vib_gyro": F("float", 0.01, min=0, unit="rad/s", text="per motor at full speed"),
        "gyro_bias_rad_s": F("vec3", (0.0, 0.0, 0.0), drawable=True, unit="rad/s",
                             text="constant injected gyro bias, FRD"),
        "accel_range_m_s2": F("float", 156.9, above=0, unit="m/s^2"),
        "gyro_range_rad_s": F("float", 34.91, above=0, unit="rad/s"),
    },
    "baro": {
        "rate_hz": F("float", 100.0, above=0, unit="Hz"),
        "noise_pa": F("float", 1.2, min=0, unit="Pa"),
        "lag_s": F("float", 0.010, min=0, unit="s"),
        "offset_pa": F("float", 0.0, drawable=True, unit="Pa"),
    },
    "mag": {
        "rate_hz": F("float", 100.0, above=0, unit="Hz"),
        "noise_gauss": F("float", 0.0032, min=0, unit="gauss"),
        "field_ned_gauss": F("vec3", None, unit="gauss",
                             text="Earth field; default: the WMM grid at home (silbridge/magfield.py)"),
        "offset_gauss": F("vec3", (0.0, 0.0, 0.0), drawable=True, unit="gauss",
                          text="hard-iron offset, FRD"),
    },
    "gnss": {
        "rate_hz": F("float", 10.0, above=0, unit="Hz"),
        "latency_s": F("float", 0.110, min=0, unit="s"),
        "pos_sigma_h_m": F("float", 2.12, min=0, unit="m"),
        "pos_sigma_v_m": F("float", 3.2, min=0, unit="m"),
        "pos_tau_s": F("float", 60.0, above=0, unit="s"),
        "vel_sigma_m_s": F("float", 0.05, min=0, unit="m/s"),
        "fix_type": F("int", 3, min=0, max=6),
        "satellites": F("int", 14, min=0, max=255),
    },
}

# [[disturbance]] entries: common keys plus per-type keys.
DISTURBANCE_COMMON = {
    "type": F("str", choices=("force", "gyro_bias", "motor_bias", "wind")),
    "start_s": F("float", min=0, drawable=True, unit="s"),
    "stop_s": F("float", None, min=0, drawable=True, unit="s", text="default: end of run"),
}
DISTURBANCE_TYPES = {
    "force": {
        "amplitude_g": F("float", drawable=True, unit="g", text="peak, times vehicle mass"),
        "frequency_hz": F("float", 0.0, min=0, drawable=True, unit="Hz", text="0 = constant"),
        "phase_deg": F("float", 0.0, drawable=True, unit="deg"),
        "axis": F("axis", "x", text="x, y, z or a 3-vector direction"),
        "frame": F("str", "ned", choices=("ned", "frd")),
    },
    "gyro_bias": {
        "amplitude_rad_s": F("float", drawable=True, unit="rad/s"),
        "sign": F("float", 1.0, min=-1, max=1, drawable=True,
                  text="+1 or -1; {choice = [-1, 1]} draws the sign"),
        "axis": F("axis", "x", text="x, y, z or a 3-vector direction (FRD)"),
        "ramp_s": F("float", 0.0, min=0, drawable=True, unit="s", text="0 = step"),
    },
    "motor_bias": {
        "thrust_scale": F("vec4", drawable=True, text="per motor 1..4, 1 = nominal"),
    },
    "wind": {
        "speed_m_s": F("float", drawable=True, min=0, unit="m/s"),
        "from_deg": F("float", 0.0, drawable=True, unit="deg", text="direction it blows from"),
        "turbulence": F("str", "none", choices=("none", "dryden", "tustin")),
        "severity": F("int", 3, min=1, max=7, text="MIL-F-8785C probability of exceedance index"),
    },
}

# [[setpoint]] entries.
SETPOINT_COMMON = {
    "type": F("str", choices=("tilt", "altitude", "yaw")),
    "start_s": F("float", min=0, drawable=True, unit="s"),
}
SETPOINT_TYPES = {
    "tilt": {
        "axis": F("str", "roll", choices=("roll", "pitch")),
        "amplitude_deg": F("float", drawable=True, unit="deg"),
        "shape": F("str", "step", choices=("step", "ramp")),
        "ramp_s": F("float", 0.5, above=0, drawable=True, unit="s", text="for shape = ramp"),
        "hold_s": F("float", 2.0, above=0, drawable=True, unit="s"),
        "doublet": F("bool", True, text="+A, level, -A, level: each step is A, and the vehicle stays near home"),
        "repeat": F("int", 1, min=1),
        "period_s": F("float", 0.0, min=0, unit="s", text="between repetitions (repeat > 1)"),
    },
    "altitude": {
        "altitude_m": F("float", min=0, drawable=True, unit="m"),
        "ramp_s": F("float", 0.0, min=0, unit="s"),
    },
    "yaw": {
        "yaw_deg": F("float", drawable=True, unit="deg"),
        "ramp_s": F("float", 0.0, min=0, unit="s"),
    },
}

# [[fc_param]] entries: set one flight-controller parameter at a sim time. The bridge
# does not know the FC's parameters (bridge/ and fc_sil/ never import each other): the
# caller that joins the two (tools/loop/fc_param_events.py) checks name and value against
# the FC's declaration at load time, and hands the schedule to the FC, which applies it.
FC_PARAM = {
    "name": F("str", text="FC parameter name, e.g. SB_ATT_SRC (`silbridge params list`)"),
    "value": F("float", text="new value, within the parameter's declared range"),
    "at_s": F("float", min=0, drawable=True, unit="s",
              text="sim time; applied after the first physics step that ends at or after it"),
}
