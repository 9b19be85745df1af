"""Thin Python wrappers, one per block of the C core, for tests and experiments.

Each object owns its block's C state in an 8-byte aligned numpy buffer and
calls the block's C functions through the extension, a whole input array per
call (so a 100,000-sample filter test is one C loop). Configurations are
plain keyword arguments with the units in their names; defaults are the
declared parameter defaults where one exists.
"""

from __future__ import annotations

import numpy as np

from . import _core
from .params import BY_NAME

_SIZES = _core.block_sizes()

FILTER_NONE, FILTER_PT1, FILTER_PT2, FILTER_PT2X2, FILTER_BIQUAD_LPF, FILTER_NOTCH = range(6)


def _state(block: str) -> np.ndarray:
    return np.zeros((_SIZES[block] + 7) // 8, dtype=np.uint64)


def _default(name: str) -> float:
    return BY_NAME[name].default


def _f32(x) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.float32)


class Filter:
    """One filter of fc_filter.h, chosen once: kind in FILTER_*."""

    def __init__(self, kind: int, cutoff_hz: float, sample_hz: float, bandwidth_hz: float = 0.0):
        self._s = _state("filter")
        self.kind = kind
        self.sample_hz = sample_hz
        self.init_status = _core.filter_init(self._s, kind, cutoff_hz, bandwidth_hz,
                                             1.0 / sample_hz)

    def apply(self, x) -> np.ndarray:
        return _core.filter_apply(self._s, _f32(np.atleast_1d(x)))

    def reset(self, value: float = 0.0) -> None:
        _core.filter_reset(self._s, value)

    def update_cutoff(self, cutoff_hz: float, bandwidth_hz: float = 0.0) -> int:
        return _core.filter_update(self._s, cutoff_hz, bandwidth_hz, 1.0 / self.sample_hz)


def PT1(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(FILTER_PT1, cutoff_hz, sample_hz)


def PT2(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(FILTER_PT2, cutoff_hz, sample_hz)


def PT2x2(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(FILTER_PT2X2, cutoff_hz, sample_hz)


def BiquadLowPass(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(FILTER_BIQUAD_LPF, cutoff_hz, sample_hz)


def Notch(center_hz: float, bandwidth_hz: float, sample_hz: float) -> Filter:
    return Filter(FILTER_NOTCH, center_hz, sample_hz, bandwidth_hz)


class InsFrontEnd:
    """Gyro/accel low-pass filters and the optional gyro notch (fc_ins)."""

    def __init__(self, sample_hz: float, gyro_cutoff_hz: float = _default("INS_GYRO_FILTER"),
                 accel_cutoff_hz: float = _default("INS_ACCEL_FILTER"), notch: bool = False,
                 notch_hz: float = _default("INS_HNTCH_FREQ"),
                 notch_bw_hz: float = _default("INS_HNTCH_BW")):
        self._s = _state("ins")
        self.init_status = _core.ins_init(self._s, gyro_cutoff_hz, accel_cutoff_hz, notch,
                                          notch_hz, notch_bw_hz, 1.0 / sample_hz)

    def run(self, accel_frd_m_s2, gyro_frd_rad_s):
        """(filtered gyro (n,3), filtered accel (n,3), status per sample)."""
        return _core.ins_run(self._s, _f32(accel_frd_m_s2), _f32(gyro_frd_rad_s))


class Mahony:
    """The attitude estimator (fc_mahony)."""

    def __init__(self, kp: float = _default("SB_AHRS_KP"), ki: float = _default("SB_AHRS_KI"),
                 kmag: float = _default("SB_AHRS_KMAG"),
                 trust_tc_s: float = _default("SB_TRUST_TC"),
                 trust_span_g: float = _default("SB_TRUST_SPAN"),
                 bias_rate_hz: float = _default("SB_BIAS_RATE"),
                 still_gyro_rad_s: float = _default("SB_STILL_GYRO"),
                 still_acc_g: float = _default("SB_STILL_ACC"),
                 trust_ema: bool = True, bias: bool = True,
                 kp_gnss: float = _default("SB_AHRS_GPS_KP"),
                 ki_gnss: float = _default("SB_AHRS_GPS_KI")):
        self._s = _state("mahony")
        _core.mahony_init(self._s, (kp, ki, kmag, trust_tc_s, trust_span_g, bias_rate_hz,
                                    still_gyro_rad_s, still_acc_g, trust_ema, bias, kp_gnss,
                                    ki_gnss))

    def set_attitude(self, q_wxyz) -> None:
        _core.mahony_set_attitude(self._s, tuple(float(v) for v in q_wxyz))

    def run(self, gyro_frd_rad_s, accel_frd_m_s2, dt_s: float):
        """(q (n,4), bias (n,3), trust (n,)) after each sample."""
        return _core.mahony_run(self._s, _f32(gyro_frd_rad_s), _f32(accel_frd_m_s2), dt_s)

    def mag(self, field_frd, declination_rad: float = 0.0) -> int:
        return _core.mahony_mag(self._s, tuple(float(v) for v in field_frd), declination_rad)

    def set_accel_ref(self, accel_ned_m_s2) -> int:
        """Kinematic acceleration reference, NED [m/s^2]; expires after 0.5 s."""
        return _core.mahony_accel_ref(self._s, tuple(float(v) for v in accel_ned_m_s2))

    def gnss(self, f_imu_ned_m_s2, f_gnss_ned_m_s2) -> int:
        """GNSS-aided tilt: mean specific force over a past interval, measured (IMU rotated
        by the estimate) and from GNSS velocity, NED; held 0.5 s (fc_mahony_gnss)."""
        return _core.mahony_gnss(self._s, tuple(float(v) for v in f_imu_ned_m_s2),
                                 tuple(float(v) for v in f_gnss_ned_m_s2))

    def state(self) -> dict:
        return _core.mahony_state(self._s)


def attitude_error(q_wxyz, roll_rad: float, pitch_rad: float, yaw_rad: float = 0.0,
                   hold_yaw: bool = False) -> tuple[float, float, float]:
    """Small-angle error (ex, ey, ez) [rad], body FRD (fc_attitude)."""
    return _core.attitude_error(tuple(float(v) for v in q_wxyz), roll_rad, pitch_rad, yaw_rad,
                                hold_yaw)


def rate_targets(err_frd_rad, ang_p=(4.5, 4.5, 0.0), rate_max_rad_s=(0.0, 0.0, 0.0),
                 yaw_rate_ff_rad_s: float = 0.0) -> tuple[float, float, float]:
    return _core.attitude_rate_targets(tuple(ang_p), tuple(rate_max_rad_s), tuple(err_frd_rad),
                                       yaw_rate_ff_rad_s)


def rate_targets_ff(err_frd_rad, q_err_wxyz, ang_vel_target_rad_s, gyro_z_rad_s: float = 0.0,
                    ang_p=(4.5, 4.5, 0.0), rate_max_rad_s=(0.0, 0.0, 0.0)):
    """((roll, pitch, yaw) rate targets, feed-forward fade) with the target's
    angular velocity fed forward (fc_attitude_rate_targets_ff)."""
    return _core.attitude_rate_targets_ff(tuple(ang_p), tuple(rate_max_rad_s), tuple(err_frd_rad),
                                          tuple(q_err_wxyz), tuple(ang_vel_target_rad_s),
                                          gyro_z_rad_s)


def sqrt_controller(error: float, p: float, second_ord_lim: float, dt_s: float) -> float:
    return _core.sqrt_controller(error, p, second_ord_lim, dt_s)


class Shaper:
    """Attitude input shaping (fc_shaper): the target moving toward the command."""

    COLUMNS = ("roll_rad", "pitch_rad", "yaw_rad", "roll_rate_rad_s", "pitch_rate_rad_s",
               "yaw_rate_rad_s", "p_frd_rad_s", "q_frd_rad_s", "r_frd_rad_s")

    def __init__(self, loop_hz: float, input_tc_s: float = _default("ATC_INPUT_TC"),
                 accel_max_cdeg_s2=(_default("ATC_ACCEL_R_MAX"), _default("ATC_ACCEL_P_MAX"),
                                    _default("ATC_ACCEL_Y_MAX")),
                 rate_max_deg_s=(0.0, 0.0, 0.0), enable: bool = True, euler0_rad=(0, 0, 0)):
        self._s = _state("shaper")
        self.dt_s = 1.0 / loop_hz
        self.cfg = (enable, input_tc_s,
                    tuple(float(np.radians(a * 0.01)) for a in accel_max_cdeg_s2),
                    tuple(float(np.radians(r)) for r in rate_max_deg_s))
        self.reset(euler0_rad)

    def reset(self, euler_rad=(0.0, 0.0, 0.0)) -> None:
        _core.shaper_reset(self._s, tuple(float(v) for v in euler_rad))

    def run(self, roll_rad, pitch_rad=0.0, yaw_rad=0.0, yaw_rate_rad_s=0.0,
            hold_yaw=False, n: int | None = None) -> np.ndarray:
        """Rows of COLUMNS, one per loop step; inputs broadcast to n steps."""
        n = n if n is not None else len(np.atleast_1d(roll_rad))
        cmd = np.empty((n, 4), np.float32)
        for k, v in enumerate((roll_rad, pitch_rad, yaw_rad, yaw_rate_rad_s)):
            cmd[:, k] = np.broadcast_to(v, n)
        hold = np.ascontiguousarray(np.broadcast_to(hold_yaw, n), dtype=np.uint8)
        return _core.shaper_run(self._s, self.cfg, cmd, hold, self.dt_s)


class RatePID:
    """One axis of the rate loop (fc_rate_pid); outputs in us."""

    COLUMNS = ("p_us", "i_us", "d_us", "ff_us", "out_us", "limited", "d_clamped")

    def __init__(self, loop_hz: float, kp: float = _default("ATC_RAT_RLL_P"),
                 ki: float = _default("ATC_RAT_RLL_I"), kd: float = _default("ATC_RAT_RLL_D"),
                 kff: float = _default("ATC_RAT_RLL_FF"), imax: float = _default("ATC_RAT_RLL_IMAX"),
                 fltt_hz: float = _default("ATC_RAT_RLL_FLTT"),
                 flte_hz: float = _default("ATC_RAT_RLL_FLTE"),
                 fltd_hz: float = _default("ATC_RAT_RLL_FLTD"), out_us_per_unit: float = 500.0,
                 d_clamp_us: float = _default("SB_DCLAMP_US"),
                 d_clamp: bool = bool(_default("SB_DCLAMP_EN")),
                 d_pt2x2: bool = bool(_default("SB_DFILT_EN")),
                 antiwindup: bool = True):
        self._s = _state("rate_pid")
        self.dt_s = 1.0 / loop_hz
        self._cfg = (kp, ki, kd, kff, imax, fltt_hz, flte_hz, fltd_hz, out_us_per_unit,
                     d_clamp_us, d_clamp, d_pt2x2, antiwindup)
        _core.pid_init(self._s, self._cfg, self.dt_s)

    def run(self, target_rad_s, meas_rad_s, limit=None, integrate: bool = True) -> np.ndarray:
        """Rows of COLUMNS, one per sample."""
        t = _f32(target_rad_s)
        lim = np.zeros(len(t), np.uint8) if limit is None else \
            np.ascontiguousarray(np.broadcast_to(limit, len(t)), dtype=np.uint8)
        return _core.pid_run(self._s, t, _f32(meas_rad_s), self.dt_s, lim, integrate)


class HoverTrim:
    """Hover-trim learning and ramp-in (fc_trim)."""

    def __init__(self, window_s: float = _default("SB_TRIM_WIN_S"),
                 gain_us_per_rad: float = _default("SB_TRIM_GAIN"),
                 max_us: float = _default("SB_TRIM_MAX_US"),
                 ramp_s: float = _default("SB_TRIM_RAMP_S"),
                 enable: bool = bool(_default("SB_TRIM_EN")),
                 ramp: bool = bool(_default("SB_TRIM_RAMP_EN"))):
        self._s = _state("trim")
        _core.trim_reset(self._s)
        self.cfg = (enable, ramp, window_s, gain_us_per_rad, max_us, ramp_s)

    def run(self, airborne, ex_rad, ey_rad, dt_s: float) -> np.ndarray:
        """Applied trim (n, 2) [us], roll and pitch."""
        air = np.ascontiguousarray(airborne, dtype=np.uint8)
        return _core.trim_run(self._s, self.cfg, air, _f32(ex_rad), _f32(ey_rad), dt_s)


class Blend:
    """EST/GT blend weight (fc_blend)."""

    def __init__(self, tau_s: float = _default("SB_BLEND_TC"),
                 continuous: bool = bool(_default("SB_BLEND_EN")), w0: float = 0.0):
        self._s = _state("blend")
        self.tau_s = tau_s
        self.continuous = continuous
        _core.blend_reset(self._s, w0)

    def run(self, target_w, dt_s: float) -> np.ndarray:
        return _core.blend_run(self._s, _f32(target_w), self.tau_s, self.continuous, dt_s)


class Mixer:
    """Quad-X mixer with saturation flags and slew limit (fc_mixer)."""

    SPOOL_SHUT_DOWN, SPOOL_GROUND_IDLE, SPOOL_FLIGHT = 0, 1, 2

    def __init__(self, pwm_min_us: float = _default("MOT_PWM_MIN"),
                 pwm_max_us: float = _default("MOT_PWM_MAX"),
                 spin_min: float = _default("MOT_SPIN_MIN"),
                 spin_max: float = _default("MOT_SPIN_MAX"),
                 yaw_headroom_us: float = _default("MOT_YAW_HEADROOM"),
                 slew_up_time_s: float = _default("MOT_SLEW_UP_TIME"),
                 slew_dn_time_s: float = _default("MOT_SLEW_DN_TIME"),
                 slew: bool = bool(_default("SB_SLEW_EN"))):
        self._s = _state("mixer")
        self.cfg = (pwm_min_us, pwm_max_us, spin_min, spin_max, yaw_headroom_us,
                    slew_up_time_s, slew_dn_time_s, slew)
        _core.mixer_reset(self._s, self.cfg)

    def run(self, throttle_us, roll_us, pitch_us, yaw_us, dt_s: float = 0.0025,
            spool: int = 2):
        """(motor_us (n,4) before slew, pwm_us (n,4), sat_flags (n,), applied (n,4):
        throttle, roll, pitch, yaw as actually mixed)."""
        cols = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=np.float32))
                                     for v in (throttle_us, roll_us, pitch_us, yaw_us)))
        inputs = np.ascontiguousarray(np.stack(cols, axis=1), dtype=np.float32)
        return _core.mixer_run(self._s, self.cfg, spool, inputs, dt_s)

    @staticmethod
    def factors() -> list[tuple[float, float, float]]:
        """(roll, pitch, yaw) factor of motors 1..4 (ArduCopter QUAD X order)."""
        return _core.mixer_factors()
