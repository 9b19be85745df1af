"""Synthetic run logs with known answers, for the log tests and the logging benchmark.

`synthetic_run(...)` builds every channel a closed-loop run logs (sensor and
ground-truth records in the shm record dtypes, one FC status row per PWM tick,
one timing row per physics step, events and start metadata) from closed-form
signals (their constants: the fields of `RunSignals`, one step per channel), so each
metric has an answer known on paper:

- true roll = commanded roll + roll_err_amp_deg * sin(2 pi roll_err_hz t): the
  attitude error RMS is amp/sqrt(2) and its 95th percentile amp*sin(0.95 pi/2)
  over whole periods; pitch and yaw follow their commands exactly;
- motor i PWM = pwm_center_us + pwm_amp_us * sin(2 pi pwm_sine_hz t + i pi/2):
  peak-to-peak 2 * pwm_amp_us when the ticks hit the peaks; or, with
  pwm_ramp=True, every motor ramps linearly from 1000 to 2000 us across the
  run: |u| >= 0.99 for 1 % of it;
- true body yaw rate = yaw_rate_rad_s; cp, cr, cy = the given constants;
- wall timing: latency constant (sensor_latency_us, end_to_end_us) and loop
  period = nominal + period_jitter_us * sin(2 pi k / 97).

`SYNTH_STATUS_DTYPE` mirrors the fields the FC promises (the FC package is not
imported: the log works from field names). `step_slices()` cuts the run into
the per-physics-step pieces a real loop would hand the writer.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from silbridge.shm.records import Kind, empty
from silbridge.tools.logs.mcap_log import TIMING_DTYPE
from silbridge.shm.records import NS_PER_S

SYNTH_STATUS_DTYPE = np.dtype([
    ("sim_ns", "<i8"), ("q_est_wxyz", "<f4", (4,)), ("euler_est_rad", "<f4", (3,)),
    ("att_target_rad", "<f4", (3,)), ("rate_target_frd_rad_s", "<f4", (3,)),
    ("rate_frd_rad_s", "<f4", (3,)), ("pid_p", "<f4", (3,)), ("pid_i", "<f4", (3,)),
    ("pid_d", "<f4", (3,)), ("pid_ff", "<f4", (3,)), ("limited", "u1", (3,)),
    ("cp_us", "<f4"), ("cr_us", "<f4"), ("cy_us", "<f4"), ("throttle_us", "<f4"),
    ("motor_us", "<f4", (4,)), ("sat_flags", "u1"), ("trust", "<f4"),
    ("gyro_bias_rad_s", "<f4", (3,)), ("blend_w", "<f4"), ("alt_est_m", "<f4"),
    ("climb_est_m_s", "<f4"), ("alt_target_m", "<f4"), ("trim_us", "<f4", (2,)),
], align=True)  # laid out as the C struct the FC fills


def quat_from_euler(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """ZYX (yaw, pitch, roll) Euler angles [rad] -> unit quaternions (w, x, y, z), body to NED."""
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return np.stack([cr * cp * cy + sr * sp * sy,
                     sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy,
                     cr * cp * sy - sr * sp * cy], axis=-1)


@dataclasses.dataclass
class SyntheticRun:
    channels: dict[str, np.ndarray]
    events: list[tuple]        # (sim_ns, kind, text, fields)
    metadata: dict
    physics_hz: float


@dataclasses.dataclass(frozen=True)
class RunSignals:
    """What a synthetic run is made of: rates, the closed-form signals' constants, timing."""

    duration_s: float = 12.0
    imu_hz: float = 1000.0
    physics_hz: float = 1000.0      # ground truth and /timing rows
    pwm_hz: float = 400.0           # PWM and FC status rows
    baro_hz: float = 100.0
    mag_hz: float = 100.0
    gnss_hz: float = 10.0
    seed: int = 0
    roll_cmd_deg: float = 0.0
    roll_err_amp_deg: float = 2.0   # true roll - commanded roll: this amplitude ...
    roll_err_hz: float = 0.5        # ... at this frequency
    pwm_center_us: float = 1500.0
    pwm_amp_us: float = 20.0
    pwm_sine_hz: float = 1.0
    pwm_ramp: bool = False          # motors ramp 1000 -> 2000 us instead of the sines
    yaw_rate_rad_s: float = 0.01
    cp_us: float = 0.77
    cr_us: float = -0.25
    cy_us: float = 1.5
    sensor_latency_us: float = 20.0
    end_to_end_us: float = 60.0
    period_jitter_us: float = 5.0
    wall_start_ns: int = 10**12

    # The loop runs at 100x real time: 1 s of sim takes 10 ms of wall.
    WALL_PER_SIM = 0.01

    def ticks(self, rate_hz: float) -> np.ndarray:
        """Sample times k / rate for k = 1 .. duration * rate, as int64 ns (no float sums)."""
        n = int(round(self.duration_s * rate_hz))
        return (np.arange(1, n + 1, dtype=np.int64) * NS_PER_S) // int(round(rate_hz))

    def wall(self, t_ns: np.ndarray) -> np.ndarray:
        return self.wall_start_ns + (t_ns * self.WALL_PER_SIM).astype(np.int64)

    def true_euler(self, t_ns: np.ndarray):
        t = t_ns * 1e-9
        roll = np.deg2rad(self.roll_cmd_deg) + np.deg2rad(self.roll_err_amp_deg) * np.sin(
            2 * np.pi * self.roll_err_hz * t)
        return roll, np.zeros_like(t), self.yaw_rate_rad_s * t

    def records(self, kind: Kind, t: np.ndarray) -> np.ndarray:
        """Records of one kind at times t, numbered from 0, published at wall(t)."""
        rec = empty(kind, len(t))
        rec["seq"], rec["sim_ns"], rec["wall_ns"] = np.arange(len(t)), t, self.wall(t)
        return rec


def synthetic_run(duration_s: float = 12.0, **signals) -> SyntheticRun:
    """Every channel of a run with known answers (module docstring); `signals` are the other
    fields of RunSignals, by name."""
    s = RunSignals(duration_s=duration_s, **signals)
    rng = np.random.default_rng(s.seed)
    ch = {"/imu": _imu(s, rng), **_slow_sensors(s, rng), **_ground_truth(s)}
    t = s.ticks(s.pwm_hz)
    motors = _motors_us(s, t)
    ch["/pwm"] = _pwm(s, t, motors)
    ch["/fc/status"] = _status(s, t, motors)
    ch["/timing"] = _timing(s, ch["/pwm"]["sim_ns"])
    return SyntheticRun(ch, _events(s.duration_s), _metadata(s), s.physics_hz)


def _imu(s: RunSignals, rng) -> np.ndarray:
    t = s.ticks(s.imu_hz)
    imu = s.records(Kind.IMU, t)
    imu["accel_frd_m_s2"] = rng.normal(0.0, 0.05, (len(t), 3)) + [0.0, 0.0, -9.81]
    imu["gyro_frd_rad_s"] = rng.normal(0.0, 0.002, (len(t), 3)) + [0.0, 0.0, s.yaw_rate_rad_s]
    imu["temperature_c"] = 25.0
    imu["samples_per_step"] = max(1, int(round(s.imu_hz / s.physics_hz)))
    imu["sample_index"] = np.arange(len(t)) % imu["samples_per_step"]
    return imu


def _slow_sensors(s: RunSignals, rng) -> dict[str, np.ndarray]:
    ch = {name: s.records(kind, s.ticks(rate))
          for name, kind, rate in (("/baro", Kind.BARO, s.baro_hz), ("/mag", Kind.MAG, s.mag_hz),
                                   ("/gnss", Kind.GNSS, s.gnss_hz))}
    ch["/baro"]["pressure_pa"] = 101325.0 - 120.0 + rng.normal(0, 2.0, len(ch["/baro"]))
    ch["/mag"]["field_frd_gauss"] = [0.2, 0.0, 0.45]
    ch["/gnss"]["fix_type"], ch["/gnss"]["satellites"] = 3, 12
    return ch


def _ground_truth(s: RunSignals) -> dict[str, np.ndarray]:
    t = s.ticks(s.physics_hz)
    gta = s.records(Kind.GT_ATT, t)
    gta["q_wxyz"] = quat_from_euler(*s.true_euler(t))
    gta["rates_frd_rad_s"][:, 0] = np.deg2rad(s.roll_err_amp_deg) * 2 * np.pi * s.roll_err_hz \
        * np.cos(2 * np.pi * s.roll_err_hz * t * 1e-9)
    gta["rates_frd_rad_s"][:, 2] = s.yaw_rate_rad_s
    gta["specific_force_frd_m_s2"] = [0.0, 0.0, -9.81]
    gtn = s.records(Kind.GT_NAV, t)
    gtn["pos_ned_m"][:, 2] = -10.0
    return {"/gt_att": gta, "/gt_nav": gtn}


def _motors_us(s: RunSignals, t: np.ndarray) -> np.ndarray:
    """(n, 4) motor commands at the PWM ticks t: phased sines, or the ramp."""
    if s.pwm_ramp:
        return np.repeat(np.linspace(1000.0, 2000.0, len(t))[:, None], 4, axis=1)
    phase = np.arange(4) * np.pi / 2
    return s.pwm_center_us + s.pwm_amp_us * np.sin(
        2 * np.pi * s.pwm_sine_hz * (t * 1e-9)[:, None] + phase)


def _pwm(s: RunSignals, t: np.ndarray, motors: np.ndarray) -> np.ndarray:
    pwm = empty(Kind.PWM, len(t))
    pwm["seq"], pwm["sim_ns"] = np.arange(len(t)), t
    pwm["wall_ns"] = s.wall(t) + int(s.end_to_end_us * 1e3)
    pwm["pwm_us"][:, :4] = np.round(motors)
    pwm["channel_count"], pwm["armed"] = 4, 1
    pwm["imu_sim_ns"] = t
    return pwm


def _status(s: RunSignals, t: np.ndarray, motors: np.ndarray) -> np.ndarray:
    st = np.zeros(len(t), dtype=SYNTH_STATUS_DTYPE)
    roll, pitch, yaw = s.true_euler(t)
    st["sim_ns"] = t
    st["q_est_wxyz"] = quat_from_euler(roll, pitch, yaw)
    st["euler_est_rad"] = np.stack([roll, pitch, yaw], axis=1)
    st["att_target_rad"][:, 0] = np.deg2rad(s.roll_cmd_deg)
    st["att_target_rad"][:, 2] = yaw
    st["rate_frd_rad_s"][:, 2] = s.yaw_rate_rad_s
    st["cp_us"], st["cr_us"], st["cy_us"] = s.cp_us, s.cr_us, s.cy_us
    st["throttle_us"] = s.pwm_center_us
    st["motor_us"] = motors
    st["trust"], st["blend_w"] = 1.0, 0.0
    st["alt_est_m"] = st["alt_target_m"] = 10.0
    st["trim_us"] = [s.pwm_center_us, 0.0]
    return st


def _timing(s: RunSignals, pwm_sim_ns: np.ndarray) -> np.ndarray:
    t = s.ticks(s.physics_hz)
    k = np.arange(len(t))
    period_ns = 1e9 / s.physics_hz * s.WALL_PER_SIM
    tim = np.zeros(len(t), dtype=TIMING_DTYPE)
    tim["sim_ns"] = t
    tim["imu_wall_ns"] = s.wall(t)
    tim["consume_wall_ns"] = tim["imu_wall_ns"] + int(s.sensor_latency_us * 1e3)
    # A PWM follows the steps whose time reaches a PWM tick.
    pwm_step = np.zeros(len(t), bool)
    pwm_step[np.searchsorted(t, pwm_sim_ns)] = True
    tim["pwm_wall_ns"] = np.where(pwm_step, tim["imu_wall_ns"] + int(s.end_to_end_us * 1e3), 0)
    tim["loop_period_ns"] = np.round(
        period_ns + s.period_jitter_us * 1e3 * np.sin(2 * np.pi * k / 97)).astype(np.int64)
    return tim


def _events(duration_s: float) -> list[tuple]:
    return [(0, "mode", "takeoff", {}),
            (int(2e9), "param", "ATC_RAT_RLL_D 0.004", {"name": "ATC_RAT_RLL_D", "value": 0.004}),
            (int(min(10.0, duration_s / 2) * 1e9), "disturbance", "force on", {}),
            (int(duration_s * 1e9), "check", "imu rate ok", {"ok": True})]


def _metadata(s: RunSignals) -> dict:
    return {
        "config": {"imu_hz": s.imu_hz, "physics_hz": s.physics_hz, "pwm_hz": s.pwm_hz,
                   "baro_hz": s.baro_hz, "mag_hz": s.mag_hz, "gnss_hz": s.gnss_hz,
                   "duration_s": s.duration_s, "seed": s.seed, "transport": "shm",
                   "processes": 1, "mode": "lockstep"},
        "scenario": {"name": "synthetic", "seed": s.seed},
        "params": {"ATC_RAT_RLL_P": 0.135, "ATC_RAT_RLL_D": 0.0036, "MOT_PWM_MIN": 1000},
        "software": {"silbridge": "synthetic"},
    }


def step_slices(run: SyntheticRun) -> list[dict[str, np.ndarray]]:
    """Per physics step, the rows of every channel whose time falls in that step."""
    t_step = run.channels["/gt_att"]["sim_ns"]
    edges = {name: np.searchsorted(arr["sim_ns"], t_step, side="right")
             for name, arr in run.channels.items()}
    steps = []
    prev = {name: 0 for name in run.channels}
    for k in range(len(t_step)):
        step = {}
        for name, arr in run.channels.items():
            e = int(edges[name][k])
            step[name] = arr[prev[name]:e]
            prev[name] = e
        steps.append(step)
    return steps


def write_run(run: SyntheticRun, writer) -> None:
    """Write a whole synthetic run to a LogWriter (all rows at once)."""
    for name, arr in run.channels.items():
        writer.write(name, arr)
    for sim_ns, kind, text, fields in run.events:
        writer.event(sim_ns, kind, text, **fields)
