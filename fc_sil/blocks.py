"""Thin Python wrappers, one per block of the C core, for tests and experiments.

Each object owns its block's C state in an 8-byte aligned numpy buffer and
calls the block's C functions through the test-only extension `_blocks`
(fc_sil/ext/blocks/), a whole input array per call (so a 100,000-sample filter
test is one C loop). Configurations are plain keyword arguments with the units
in their names; defaults are the declared parameter defaults where one exists.
They cross to C by name: a configuration struct as a dict keyed by its C field
names, every other setting as a keyword.
"""

from __future__ import annotations

import numpy as np

from . import _blocks
from .params import BY_NAME

_SIZES = _blocks.block_sizes()

FILTER_NONE, FILTER_PT1, FILTER_PT2, FILTER_PT2X2, FILTER_BIQUAD_LPF, FILTER_NOTCH = range(6)


def _state(block: str) -> np.ndarray:
    return np.zeros((_SIZES[block] + 7) // 8, dtype=np.uint64)


def _default(name: str) -> float:
    return BY_NAME[name].default


def _f32(x) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.float32)


def _vec(v) -> tuple[float, ...]:
    return tuple(float(x) for x in v)


def _attitude_config(ang_p, rate_max_rad_s) -> dict:
    """fc_attitude_config_t by field name."""
    return dict(ang_p=tuple(ang_p), rate_max_rad_s=tuple(rate_max_rad_s))


class Filter:
    """One filter of fc_filter.h, chosen once: kind in FILTER_*."""

    def __init__(self, kind: int, cutoff_hz: float, sample_hz: float, bandwidth_hz: float = 0.0):
        self._s = _state("filter")
        self.kind = kind
        self.sample_hz = sample_hz
        self.init_status = _blocks.filter_init(self._s, kind=kind, cutoff_hz=cutoff_hz,
                                               bandwidth_hz=bandwidth_hz, dt_s=1.0 / sample_hz)

    def apply(self, x) -> np.ndarray:
        return _blocks.filter_apply(self._s, _f32(np.atleast_1d(x)))

    def reset(self, value: float = 0.0) -> None:
        _blocks.filter_reset(self._s, value=value)

    def update_cutoff(self, cutoff_hz: float, bandwidth_hz: float = 0.0) -> int:
        return _blocks.filter_update(self._s, cutoff_hz=cutoff_hz, bandwidth_hz=bandwidth_hz,
                                     dt_s=1.0 / self.sample_hz)


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
        config = dict(gyro_cutoff_hz=gyro_cutoff_hz, accel_cutoff_hz=accel_cutoff_hz,
                      notch_enable=notch, notch_center_hz=notch_hz,
                      notch_bandwidth_hz=notch_bw_hz)
        self.init_status = _blocks.ins_init(self._s, config=config, dt_s=1.0 / sample_hz)

    def run(self, accel_frd_m_s2, gyro_frd_rad_s):
        """(filtered gyro (n,3), filtered accel (n,3), status per sample)."""
        return _blocks.ins_run(self._s, _f32(accel_frd_m_s2), _f32(gyro_frd_rad_s))


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
                 ki_gnss: float = _default("SB_AHRS_GPS_KI"),
                 gnss_boost: float = _default("SB_AHRS_GPS_BST"),
                 gnss_innov_sigma: float = _default("SB_AHRS_GPS_INN")):
        self._s = _state("mahony")
        config = dict(kp=kp, ki=ki, kmag=kmag, trust_tc_s=trust_tc_s, trust_span_g=trust_span_g,
                      bias_rate_hz=bias_rate_hz, still_gyro_rad_s=still_gyro_rad_s,
                      still_acc_g=still_acc_g, trust_ema_enable=trust_ema, bias_enable=bias,
                      kp_gnss=kp_gnss, ki_gnss=ki_gnss, gnss_boost=gnss_boost,
                      gnss_innov_sigma=gnss_innov_sigma)
        _blocks.mahony_init(self._s, config=config)

    def set_attitude(self, q_wxyz) -> None:
        _blocks.mahony_set_attitude(self._s, q_wxyz=_vec(q_wxyz))

    def run(self, gyro_frd_rad_s, accel_frd_m_s2, dt_s: float):
        """(q (n,4), bias (n,3), trust (n,)) after each sample."""
        return _blocks.mahony_run(self._s, _f32(gyro_frd_rad_s), _f32(accel_frd_m_s2), dt_s=dt_s)

    def mag(self, field_frd, declination_rad: float = 0.0) -> int:
        return _blocks.mahony_mag(self._s, field_frd=_vec(field_frd),
                                  declination_rad=declination_rad)

    def set_accel_ref(self, accel_ned_m_s2) -> int:
        """Kinematic acceleration reference, NED [m/s^2]; expires after 0.5 s."""
        return _blocks.mahony_accel_ref(self._s, accel_ned_m_s2=_vec(accel_ned_m_s2))

    def gnss(self, f_imu_ned_m_s2, f_gnss_ned_m_s2) -> int:
        """GNSS-aided tilt: mean specific force over a past interval, measured (IMU rotated
        by the estimate) and from GNSS velocity, NED; held 0.5 s (fc_mahony_gnss)."""
        return _blocks.mahony_gnss(self._s, f_imu_ned_m_s2=_vec(f_imu_ned_m_s2),
                                   f_gnss_ned_m_s2=_vec(f_gnss_ned_m_s2))

    def state(self) -> dict:
        return _blocks.mahony_state(self._s)


def attitude_error(q_wxyz, roll_rad: float, pitch_rad: float, yaw_rad: float = 0.0,
                   hold_yaw: bool = False) -> tuple[float, float, float]:
    """Small-angle error (ex, ey, ez) [rad], body FRD (fc_attitude)."""
    return _blocks.attitude_error(q_wxyz=_vec(q_wxyz), roll_rad=roll_rad, pitch_rad=pitch_rad,
                                  yaw_rad=yaw_rad, hold_yaw=hold_yaw)


def rate_targets(err_frd_rad, ang_p=(4.5, 4.5, 0.0), rate_max_rad_s=(0.0, 0.0, 0.0),
                 yaw_rate_ff_rad_s: float = 0.0) -> tuple[float, float, float]:
    return _blocks.attitude_rate_targets(config=_attitude_config(ang_p, rate_max_rad_s),
                                         err_frd_rad=tuple(err_frd_rad),
                                         yaw_rate_ff_rad_s=yaw_rate_ff_rad_s)


def rate_targets_ff(err_frd_rad, q_err_wxyz, ang_vel_target_rad_s, gyro_z_rad_s: float = 0.0,
                    ang_p=(4.5, 4.5, 0.0), rate_max_rad_s=(0.0, 0.0, 0.0)):
    """((roll, pitch, yaw) rate targets, feed-forward fade) with the target's
    angular velocity fed forward (fc_attitude_rate_targets_ff)."""
    return _blocks.attitude_rate_targets_ff(config=_attitude_config(ang_p, rate_max_rad_s),
                                            err_frd_rad=tuple(err_frd_rad),
                                            q_err_wxyz=tuple(q_err_wxyz),
                                            ang_vel_target_rad_s=tuple(ang_vel_target_rad_s),
                                            gyro_z_rad_s=gyro_z_rad_s)


def sqrt_controller(error: float, p: float, second_ord_lim: float, dt_s: float) -> float:
    return _blocks.sqrt_controller(error=error, p=p, second_ord_lim=second_ord_lim, dt_s=dt_s)


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
        self.cfg = dict(enable=enable, input_tc_s=input_tc_s,
                        accel_max_rad_s2=tuple(float(np.radians(a * 0.01))
                                               for a in accel_max_cdeg_s2),
                        rate_max_rad_s=tuple(float(np.radians(r)) for r in rate_max_deg_s))
        self.reset(euler0_rad)

    def reset(self, euler_rad=(0.0, 0.0, 0.0)) -> None:
        _blocks.shaper_reset(self._s, euler_rad=_vec(euler_rad))

    def run(self, roll_rad, pitch_rad=0.0, yaw_rad=0.0, yaw_rate_rad_s=0.0,
            hold_yaw=False, n: int | None = None) -> np.ndarray:
        """Rows of COLUMNS, one per loop step; inputs broadcast to n steps."""
        n = n if n is not None else len(np.atleast_1d(roll_rad))
        cmd = np.empty((n, 4), np.float32)
        for k, v in enumerate((roll_rad, pitch_rad, yaw_rad, yaw_rate_rad_s)):
            cmd[:, k] = np.broadcast_to(v, n)
        hold = np.ascontiguousarray(np.broadcast_to(hold_yaw, n), dtype=np.uint8)
        return _blocks.shaper_run(self._s, cmd, hold, config=self.cfg, dt_s=self.dt_s)


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
        self._cfg = dict(kp=kp, ki=ki, kd=kd, kff=kff, imax=imax, fltt_hz=fltt_hz,
                         flte_hz=flte_hz, fltd_hz=fltd_hz, out_us_per_unit=out_us_per_unit,
                         d_clamp_us=d_clamp_us, d_clamp_enable=d_clamp, d_pt2x2=d_pt2x2,
                         antiwindup=antiwindup)
        _blocks.pid_init(self._s, config=self._cfg, dt_s=self.dt_s)

    def run(self, target_rad_s, meas_rad_s, limit=None, integrate: bool = True) -> np.ndarray:
        """Rows of COLUMNS, one per sample."""
        t = _f32(target_rad_s)
        lim = np.zeros(len(t), np.uint8) if limit is None else \
            np.ascontiguousarray(np.broadcast_to(limit, len(t)), dtype=np.uint8)
        return _blocks.pid_run(self._s, t, _f32(meas_rad_s), lim, dt_s=self.dt_s,
                               integrate=integrate)


class HoverTrim:
    """Hover-trim learning and ramp-in (fc_trim)."""

    def __init__(self, window_s: float = _default("SB_TRIM_WIN_S"),
                 gain_us_per_rad: float = _default("SB_TRIM_GAIN"),
                 max_us: float = _default("SB_TRIM_MAX_US"),
                 ramp_s: float = _default("SB_TRIM_RAMP_S"),
                 enable: bool = bool(_default("SB_TRIM_EN")),
                 ramp: bool = bool(_default("SB_TRIM_RAMP_EN"))):
        self._s = _state("trim")
        _blocks.trim_reset(self._s)
        self.cfg = dict(enable=enable, ramp_enable=ramp, window_s=window_s,
                        gain_us_per_rad=gain_us_per_rad, max_us=max_us, ramp_s=ramp_s)

    def run(self, airborne, ex_rad, ey_rad, dt_s: float) -> np.ndarray:
        """Applied trim (n, 2) [us], roll and pitch."""
        air = np.ascontiguousarray(airborne, dtype=np.uint8)
        return _blocks.trim_run(self._s, air, _f32(ex_rad), _f32(ey_rad), config=self.cfg,
                                dt_s=dt_s)


class Blend:
    """EST/GT blend weight (fc_blend)."""

    def __init__(self, tau_s: float = _default("SB_BLEND_TC"),
                 continuous: bool = bool(_default("SB_BLEND_EN")), w0: float = 0.0):
        self._s = _state("blend")
        self.tau_s = tau_s
        self.continuous = continuous
        _blocks.blend_reset(self._s, w=w0)

    def run(self, target_w, dt_s: float) -> np.ndarray:
        return _blocks.blend_run(self._s, _f32(target_w), tau_s=self.tau_s,
                                 continuous=self.continuous, dt_s=dt_s)


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
        self.cfg = dict(pwm_min_us=pwm_min_us, pwm_max_us=pwm_max_us, spin_min=spin_min,
                        spin_max=spin_max, yaw_headroom_us=yaw_headroom_us,
                        slew_up_time_s=slew_up_time_s, slew_dn_time_s=slew_dn_time_s,
                        slew_enable=slew)
        _blocks.mixer_reset(self._s, config=self.cfg)

    def run(self, throttle_us, roll_us, pitch_us, yaw_us, dt_s: float = 0.0025,
            spool: int = 2):
        """(motor_us (n,4) before slew, pwm_us (n,4), sat_flags (n,), applied (n,4):
        throttle, roll, pitch, yaw as actually mixed)."""
        cols = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=np.float32))
                                     for v in (throttle_us, roll_us, pitch_us, yaw_us)))
        inputs = np.ascontiguousarray(np.stack(cols, axis=1), dtype=np.float32)
        return _blocks.mixer_run(self._s, inputs, config=self.cfg, spool=spool, dt_s=dt_s)

    @staticmethod
    def factors() -> list[tuple[float, float, float]]:
        """(roll, pitch, yaw) factor of motors 1..4 (ArduCopter QUAD X order)."""
        return _blocks.mixer_factors()
