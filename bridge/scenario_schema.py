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
- Vibration (imu.vib_*, the IMU's own terms while vibration.enabled is false): 1/rev
  imbalance of 2.0 m/s^2 (accel) and 0.01 rad/s (gyro) per
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
- Vehicle imperfections ([vehicle], bridge/vehicle_draw.py; off unless imperfect =
  true; each drawn uniformly within +- its tolerance, per seed). No batch
  measurement of these tolerances for this airframe class was found to cite, so
  each default is derived from the parts and the way they are fitted, and the
  derivation is the source:
  - CG: the hand-placed parts of quadx.xml's mass budget, each within a placement
    tolerance: the battery (0.320 kg) and the payload (0.334 kg) strapped within
    +-10 mm along the plate, the avionics stack (0.180 kg) within +-5 mm; worst
    case (0.320 x 10 + 0.334 x 10 + 0.180 x 5) / 1.5 = 5.0 mm along x and y.
    Vertically, the battery's and payload's foam pads +-3 mm: (0.320 + 0.334) x 3
    / 1.5 = 1.3 mm.
  - Thrust and torque coefficients: +-3 %, the issue's "a few %", read as the
    blade-angle error it takes: static CT of a fixed-pitch propeller goes with the
    blade angle above zero lift at 75 % radius, for a 10x4.5 prop atan(4.5 /
    (0.75 pi 10)) = 10.8 deg plus ~3 deg zero-lift angle of a cambered section,
    so +-0.4 deg of moulding or warp is +-3 %; kT and kQ drawn independently.
  - Motor tilt: one 0.2 mm printing layer (or a burr or washer of that size on a
    CNC mount) across the 19 mm bolt spacing of a 2212 motor's 16 x 19 mm mount:
    atan(0.2 / 19) = 0.6 deg, about body x and about body y.
  - IMU mounting: a 0.5 mm difference in the compression of the anti-vibration
    grommets or foam across the 30.5 mm mounting pattern of a flight controller:
    atan(0.5 / 30.5) = 0.94, taken as 1.0 deg in roll, pitch and yaw. ArduPilot's
    AHRS_TRIM_X/Y level trim exists to remove this. For scale, the chip's own axes are
    off by as much: the ICM-42688-P datasheet (DS-000347, Tables 1 and 2) gives a
    cross-axis sensitivity of +-1.25 % (gyro) and +-1 % (accel), i.e. up to 0.7 and
    0.6 deg (not modelled apart: the drawn rotation stands for both).
- ESC telemetry ([esc], bridge/esc_telemetry.py; off unless telemetry_hz is set):
  - kv_rpm_v 920: the 2212 920KV motor jsbsim_models/quadx/motors.xml is built on.
  - winding_ohm 0.134: derived from that file's own figure, the 0.8 ratio of loaded to
    no-load speed at full throttle on 3S (11.1 V). At full throttle the model's shaft torque
    is kQ omega_max^2 = 2.3495e-7 x 855.5^2 = 0.1720 N m, i.e. I = Q / Kt = 16.57 A with
    Kt = 60 / (2 pi 920) = 0.01038 N m/A; the 20 % speed loss is that current across the
    winding: R = 0.2 x 11.1 V / 16.57 A = 0.134 ohm. No-load current is neglected.
  - The pack the ESCs draw from is [battery] (below). (motors.xml sizes the top speed on
    3S; on 4S the ESC never needs full duty: the winding voltage at full throttle, 11.1 V,
    stays below the pack's.)
- Battery ([battery], bridge/battery/; always on, every autopilot reads it):
  - cells 4, capacity_mah 3300, internal_mohm 25, avionics_a 0.6: the pack the FC modelled
    before issue 28 (SB_BATT_CELLS, BATT_CAPACITY, SB_BATT_R_MOHM, SB_BATT_I_IDLE defaults,
    then the [esc] keys battery_cells, battery_mah, battery_mohm, avionics_a): a 4S 3300 mAh
    LiPo of a 450 mm quad, 6.25 mOhm a cell, at 25 degC and full charge.
  - Open-circuit curve and the resistance's rise at low charge: Chen and Rincon-Mora, IEEE
    Trans. Energy Conversion 21(2), 2006 (bridge/src/battery.h).
  - activation_kj_mol 35: the resistance's temperature law is Arrhenius, as PVsyst's Li-ion
    model after Lundgren (2016), whose "usual values are 30 to 40 kJ/mol" (pvsyst.com help,
    Internal resistance): the middle of that range.
  - heat_capacity_j_k 320: the pack's 0.320 kg (quadx.xml's battery mass) at ~1.0 J/(g K),
    the order of a Li-ion pouch cell's specific heat; assumed, no datasheet of this pack.
  - thermal_k_per_w 1.8: a 4S 3300 mAh brick (~135 x 43 x 30 mm, 0.022 m^2 of surface) in
    the prop wash at ~25 W/(m^2 K) (low-speed forced air): 1 / (25 x 0.022) = 1.8 K/W. With
    the heat capacity, tau = 580 s. Assumed figures: set them from a logged pack temperature.
  - rate_hz 10: ArduCopter reads its battery monitor at 10 Hz (its scheduler's
    read_battery task).
  - temp_k_per_w 0.1, temp_tau_s 14: an ESC passes its motor's power at ~95 % efficiency
    (BLHeli_32-class MOSFET stages), so it dissipates 5 % of it; a ~10 g ESC board in the prop
    wash with ~2 K/W to the air rises 0.05 x 2 = 0.1 K per W passed (hover, 37 W a motor:
    +3.7 K; full throttle, 180 W: +18 K). Its heat capacity, ~7 J/K (10 g at ~0.7 J/(g K),
    FR4 and copper), over those 2 K/W gives tau = 14 s. Assumed figures, not a measurement:
    set them from your own ESC log.
- Vibration ([vibration], [mount], [imu_chip]; off unless vibration.enabled): a 450 mm
  quad (quadx.xml: 1.5 kg, hubs 0.225 m from the centre and 0.03 m above the CG) with
  10x4.5 two-blade props; hover at 0.354 of full thrust is omega = 509 rad/s, 81 Hz
  (motors.xml).
  - Imbalance 2.5 g*mm per rotor: a blade 0.05 g heavier than its partner (the
    smallest difference a magnetic prop balancer check is quoted to catch,
    jakubsafar.cz "Propeller balance": "even 0.05 g") at the blade's centre of mass,
    ~0.4 R = 51 mm of a 10-inch prop: 0.05 x 51 = 2.5 g*mm. At hover that is 0.65 N per
    rotor, 0.43 m/s^2 on 1.5 kg. For scale, ISO 21940-11 (was ISO 1940-1) grade G 6.3,
    the grade of fans, allows a mass-centre offset e = G / omega = 6.3 mm/s / 855.5
    rad/s = 7.4 um at full speed: 0.07 to 0.15 g*mm for a 10 to 20 g prop and motor
    bell. Hobby props balanced by hand sit far above fan grade (2.5 g*mm on 10 to 20 g
    is G 100 to G 210). A bent prop (V2) is 5 x that, the issue's definition; a tip
    chipped off (~0.3 g at 120 mm: ~40 g*mm) would be ~15 x.
  - Frame gain 8: what reaches the FC of a real frame over what the rigid frame passes.
    A rigid 1.5 kg body answers the forces above with little motion: balanced props,
    hard mount, hover, the largest axis of ArduPilot's VIBE (the accel's RMS above its
    5 Hz floor, fc_sil/core/fc_vibe.h) reads 1.2 m/s^2 here (seeds 1-3: 1.32, 1.00,
    1.21). Real vehicles read about ten times that: ArduPilot's wiki "Measuring
    Vibration" shows a 3DR IRIS (a quad of this size class) at "normal levels
    below 15 m/s/s", and a hard-mounted MPU9250 on a quad read +-8 m/s^2 (5.7 m/s^2 RMS)
    from its motors alone at half throttle, without props (diydrones.com forum,
    "Vibration analysis"). The gain takes the rigid figure to 10 m/s^2, between the
    two: 10 / 1.2 = 8.3, rounded to 8. It lumps what the rigid model lacks (the arms'
    and plates' flexibility, the motor bells' own imbalance and torque ripple) into one
    frequency-independent factor on every line; the accelerometer and the gyro still
    read one motion. With it, V2 (bent prop, hard mount) reads VIBE 20 m/s^2 on its
    largest axis (seeds 1-3: 21.2, 18.2, 20.2), between the wiki's "normal" (below 15)
    and "may have problems" (above 30); figures: docs/explanation/vibrating-world.md.
  - Prop wash 0 (off): no published RMS thrust fluctuation of a 10-inch prop in hover
    was found to cite; the key exists to be set from a log's broadband floor.
  - Blade pass: 2 % of the rotor's thrust at 2/rev. Assumed, no measurement for this
    airframe found: the order of the arm's share of the circle the blade sweeps at
    0.75 R (a 20 mm arm at 95 mm: 3.4 %), which unloads the blade once per pass. Further
    orders 3 and 4 at a quarter of that (0.5 %), so the spectrum shows the 3rd and 4th
    rotor harmonics that gyro spectra of multirotors show; assumed likewise.
  - Frame mode: none by default (rigid frame); damping 0.05, assumed (a lightly damped
    bolted structure; V4 places the mode at the blade-pass frequency).
  - Mount: hard by default (an FC screwed to the frame). Soft: a resonance well below
    the 1x frequency at hover isolates (above sqrt 2 x resonance the gain is < 1):
    30 Hz translational (gain ~0.16 at 81 Hz), 40 Hz rotational (a board on four
    grommets rocks stiffer than it bounces), damping 0.15 (silicone, loss factor ~0.3
    = 2 zeta): assumed figures, no datasheet of a grommet set found to cite; set them
    from a measured transmissibility. IMU 0.03 m above the CG: the FC on the top plate,
    at hub height.
  - IMU chip: TDK ICM-42688-P (DS-000347 v1.7). ODR 8 kHz, the rate PX4's ICM42688P
    driver runs the gyro at; AAF 585 Hz, 2nd order: the chip's reset configuration
    (GYRO_AAF_DELT 13, DELTSQR 170, BITSHIFT 8 in the datasheet's AAF table, 42 to
    3979 Hz).
"""

from __future__ import annotations

from dataclasses import dataclass

from silbridge.shm import fault_catalog

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
        "end_on_crash": F("bool", True, text="a crash ends the run; false: the physics goes on "
                          "(the autopilot's crash check and disarm on the ground, bench F12)"),
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
    # The vehicle's manufacturing spread (derivations in the module docstring).
    "vehicle": {
        "imperfect": F("bool", False, text="draw the imperfections below from the seed; "
                       "false: the perfect, symmetric quadx"),
        "cg_tol_xy_m": F("float", 0.005, min=0, unit="m",
                         text="CG offset along body x and y, +- bound, drawn"),
        "cg_tol_z_m": F("float", 0.0013, min=0, unit="m", text="CG offset along body z, +-"),
        "kt_tol": F("float", 0.03, min=0, max=0.5, text="each motor's thrust coefficient, "
                    "+- fraction (0.03 = +-3 %)"),
        "kq_tol": F("float", 0.03, min=0, max=0.5, text="each motor's torque coefficient, "
                    "+- fraction, drawn apart from kT"),
        "tilt_tol_deg": F("float", 0.6, min=0, max=10, unit="deg",
                          text="each motor's thrust axis about body x and y, +-"),
        "imu_tilt_tol_deg": F("float", 1.0, min=0, max=10, unit="deg",
                              text="IMU mounting roll, pitch and yaw against the body, +-"),
    },
    # Vibration from the rotors, the IMU's mount and the IMU chip (issue 26; sources in the
    # module docstring; bridge/src/vibration.h and imu_chip.h hold the models).
    "vibration": {
        "enabled": F("bool", False, text="rotor-phase vibration through frame and mount, read "
                     "through the chip below; replaces imu.vib_accel/vib_gyro. false: today's IMU"),
        "imbalance_g_mm": F("float", 2.5, min=0, unit="g*mm",
                            text="static imbalance of each rotor: force U omega^2 at 1x"),
        "imbalance_scale": F("vec4", (1.0, 1.0, 1.0, 1.0), min=0,
                             text="per motor 1..4 multiplier of the imbalance (a bent prop: 5)"),
        "blades": F("int", 2, min=1, max=8, text="blade pass at blades x rotor frequency"),
        "blade_pass_ripple": F("float", 0.02, min=0, max=1, unit="fraction of thrust",
                               text="thrust ripple at blade pass, along the thrust axis"),
        "harmonic_orders": F("vec4", (3.0, 4.0, 0.0, 0.0), min=0, max=64,
                             unit="x rotor frequency",
                             text="further thrust-ripple orders, whole numbers; 0 = unused"),
        "harmonic_ripple": F("vec4", (0.005, 0.005, 0.0, 0.0), min=0, max=1,
                             unit="fraction of thrust", text="their amplitudes"),
        "frame_gain": F("float", 8.0, min=0, unit="ratio",
                        text="the FC's vibration over what a rigid frame transmits, every "
                        "line (the frame's flexibility, lumped; calibrated to measured VIBE)"),
        "prop_wash": F("float", 0.0, min=0, max=1, unit="fraction of thrust",
                       text="broadband thrust fluctuation of each rotor, RMS (prop wash), "
                       "white above 10 Hz; grows with the throttle; 0 = off"),
        "frame_mode_hz": F("float", 0.0, min=0, unit="Hz",
                           text="frame structural resonance between rotors and IMU; 0 = rigid"),
        "frame_mode_damping": F("float", 0.05, above=0, unit="ratio",
                                text="its damping ratio"),
    },
    "mount": {
        "type": F("str", "hard", choices=("hard", "soft"),
                  text="hard: the IMU moves with the frame; soft: 2nd order per axis below"),
        "resonance_hz": F("float", 30.0, above=0, unit="Hz", text="soft mount, translational"),
        "damping": F("float", 0.15, above=0, unit="ratio", text="soft mount, translational"),
        "rot_resonance_hz": F("float", 40.0, above=0, unit="Hz", text="soft mount, rotational"),
        "rot_damping": F("float", 0.15, above=0, unit="ratio", text="soft mount, rotational"),
        "imu_offset_frd_m": F("vec3", (0.0, 0.0, -0.03), unit="m",
                              text="IMU from the structural origin (the nominal CG), body FRD"),
    },
    "imu_chip": {
        "odr_hz": F("int", 8000, above=0, unit="Hz", text="chip output data rate: 1000, 2000, "
                    "4000, 8000, 16000 or 32000, a multiple of imu.rate_hz"),
        "aaf_hz": F("float", 585.0, above=0, unit="Hz", text="anti-alias filter 3 dB bandwidth"),
        "aaf_order": F("int", 2, min=0, max=2, text="0: AAF off; 2: on (2nd order)"),
        "log_raw": F("bool", False, text="log the chip's own samples at odr_hz as /imu_raw "
                     "(needs vibration.enabled; 1.3 MB of log per s at 32 kHz)"),
    },
    # ESC telemetry (bridge/esc_telemetry.py; derivations in the module docstring). Off unless
    # telemetry_hz is set: no ESC record exists otherwise.
    "esc": {
        "telemetry_hz": F("float", None, above=0, unit="Hz",
                          text="each ESC's report rate (one record per motor per report); "
                          "unset: no ESC telemetry"),
        "kv_rpm_v": F("float", 920.0, above=0, unit="rpm/V", text="motor velocity constant"),
        "winding_ohm": F("float", 0.134, min=0, unit="ohm", text="motor winding resistance"),
        "temp_k_per_w": F("float", 0.1, min=0, unit="K/W",
                          text="ESC steady temperature rise per W it passes to its motor"),
        "temp_tau_s": F("float", 14.0, above=0, unit="s",
                        text="time constant of the ESC temperature rise"),
    },
    # The physics-side battery pack (bridge/battery/; derivations in the module docstring).
    # Always on: every autopilot reads this pack.
    "battery": {
        "cells": F("int", 4, min=1, max=14, text="cells in series"),
        "capacity_mah": F("float", 3300.0, above=0, unit="mAh", text="nominal capacity"),
        "internal_mohm": F("float", 25.0, min=0, unit="mOhm",
                           text="pack internal resistance, full charge, 25 degC"),
        "avionics_a": F("float", 0.6, min=0, unit="A", text="pack current besides the ESCs"),
        "initial_soc": F("float", 1.0, min=0, max=1, drawable=True,
                         text="state of charge at the start (1 = full)"),
        "temperature_c": F("float", None, unit="degC",
                           text="pack temperature at the start; default: the air's"),
        "activation_kj_mol": F("float", 35.0, min=0, unit="kJ/mol",
                               text="Arrhenius activation energy of the internal resistance"),
        "heat_capacity_j_k": F("float", 320.0, above=0, unit="J/K", text="pack heat capacity"),
        "thermal_k_per_w": F("float", 1.8, above=0, unit="K/W",
                             text="pack to air thermal resistance"),
        "rate_hz": F("float", 10.0, above=0, unit="Hz",
                     text="pack update and BATTERY record rate"),
    },
}

# Keys that moved: old dotted name -> new dotted name (a file with the old key is refused
# with a message naming the new one).
MOVED = {
    "esc.battery_cells": "battery.cells",
    "esc.battery_mah": "battery.capacity_mah",
    "esc.battery_mohm": "battery.internal_mohm",
    "esc.avionics_a": "battery.avionics_a",
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

# [[failure]] entries (issue 28): a fault of the catalog (shm/fault_catalog.py) on at at_s for
# duration_s. The common keys are declared here; each type's parameters are the catalog's,
# turned into fields below, so a parameter is declared once, there.
FAILURE_COMMON = {
    "unit": F("str", choices=tuple(u.name for u in fault_catalog.UNITS),
              text="what fails (the catalog's unit)"),
    "type": F("str", text="how it fails (one of the unit's types)"),
    "instance": F("int", 1, text="which one: 1, or 0 = all where the unit allows it"),
    "at_s": F("float", min=0, drawable=True, unit="s", text="sim time it switches on"),
    "duration_s": F("float", None, above=0, drawable=True, unit="s",
                    text="how long it stays on; default: to the end of the run"),
}


def _failure_field(p: fault_catalog.FaultParam) -> Field:
    kind = "vec3" if p.kind == "vec3" else p.kind
    return F(kind, p.default, min=p.min, max=p.max, drawable=True, unit=p.unit, text=p.text)


# {unit: {type: {parameter: Field}}}
FAILURE_TYPES = {u.name: {t.name: {p.name: _failure_field(p) for p in t.params} for t in u.types}
                 for u in fault_catalog.UNITS}
