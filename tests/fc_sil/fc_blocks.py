"""Thin Python wrappers, one per block of the C core, for the tests.

Each object owns its block's C state (a struct allocated by cffi) and calls the block's
C functions through the bindings generated from the headers (core_cffi.py): names,
struct layouts and enum values all come from C. Configurations are plain keyword
arguments with the units in their names; defaults are the declared parameter defaults
where one exists. They cross to C by name: a configuration struct is filled from a dict
keyed by its C field names (cffi refuses an unknown one). A run over an input array
steps the block once per row and returns the rows as numpy arrays. `ffi` and `lib` (the
bindings themselves: enums such as lib.FC_FILTER_NONE, macros, every declared function)
serve what no wrapper covers.
"""

from __future__ import annotations

import numpy as np
from core_cffi import ffi, lib

from silbridge.fc_sil.params import BY_NAME


def _default(name: str) -> float:
    return BY_NAME[name].default


def _rows(x, cols: int) -> np.ndarray:
    """float32 rows of `cols` values (cols 0: a flat array), C-contiguous."""
    a = np.ascontiguousarray(x, dtype=np.float32)
    if a.ndim != (1 if cols == 0 else 2) or (cols and a.shape[1] != cols):
        raise ValueError(f"expected shape (n,{' ' + str(cols) if cols else ''})")
    return a


def _floats(a: np.ndarray):
    """A float[] over a float32 array's own memory (no copy): C writes land in the array."""
    return ffi.from_buffer("float[]", a)


def _view(field) -> np.ndarray:
    """A numpy view of a float array field of a C struct: reads what C wrote last."""
    return np.frombuffer(ffi.buffer(field), np.float32)


def _vec(v) -> list[float]:
    return [float(x) for x in v]


def _same_len(*arrays) -> int:
    if len({len(a) for a in arrays}) != 1:
        raise ValueError("input arrays must have the same length")
    return len(arrays[0])


def _attitude_config(ang_p, rate_max_rad_s):
    return ffi.new("fc_attitude_config_t *", dict(ang_p=_vec(ang_p),
                                                  rate_max_rad_s=_vec(rate_max_rad_s)))


class Filter:
    """One filter of fc_filter.h, chosen once: kind is a lib.FC_FILTER_* (fc_filter_kind_t)."""

    def __init__(self, kind: int, cutoff_hz: float, sample_hz: float, bandwidth_hz: float = 0.0):
        self._s = ffi.new("fc_filter_t *")
        self.kind = kind
        self.sample_hz = sample_hz
        self.init_status = lib.fc_filter_init(self._s, kind, cutoff_hz, bandwidth_hz,
                                              1.0 / sample_hz)

    def apply(self, x) -> np.ndarray:
        f, apply = self._s, lib.fc_filter_apply
        return np.array([apply(f, v) for v in _rows(np.atleast_1d(x), 0).tolist()],
                        dtype=np.float32)

    def reset(self, value: float = 0.0) -> None:
        lib.fc_filter_reset(self._s, value)

    def update_cutoff(self, cutoff_hz: float, bandwidth_hz: float = 0.0) -> int:
        return lib.fc_filter_update_cutoff(self._s, cutoff_hz, bandwidth_hz, 1.0 / self.sample_hz)


def PT1(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(lib.FC_FILTER_PT1, cutoff_hz, sample_hz)


def PT2(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(lib.FC_FILTER_PT2, cutoff_hz, sample_hz)


def PT2x2(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(lib.FC_FILTER_PT2X2, cutoff_hz, sample_hz)


def BiquadLowPass(cutoff_hz: float, sample_hz: float) -> Filter:
    return Filter(lib.FC_FILTER_BIQUAD_LPF, cutoff_hz, sample_hz)


def Notch(center_hz: float, bandwidth_hz: float, sample_hz: float) -> Filter:
    return Filter(lib.FC_FILTER_NOTCH, center_hz, sample_hz, bandwidth_hz)


class InsFrontEnd:
    """Gyro/accel low-pass filters and an optional fixed gyro notch, one harmonic (fc_ins)."""

    def __init__(self, sample_hz: float, gyro_cutoff_hz: float = _default("INS_GYRO_FILTER"),
                 accel_cutoff_hz: float = _default("INS_ACCEL_FILTER"), notch: bool = False,
                 notch_hz: float = _default("INS_HNTCH_FREQ"),
                 notch_bw_hz: float = _default("INS_HNTCH_BW")):
        self._s = ffi.new("fc_ins_t *")
        fixed_notch = dict(enable=bool(notch), mode=lib.FC_NOTCH_MODE_FIXED, harmonics=1,
                           freq_hz=notch_hz, bw_hz=notch_bw_hz,
                           att_db=_default("INS_HNTCH_ATT"), fm_ratio=1.0)
        config = ffi.new("fc_ins_config_t *", dict(
            gyro_cutoff_hz=gyro_cutoff_hz, accel_cutoff_hz=accel_cutoff_hz,
            notch=[fixed_notch, dict(enable=False)]))
        self.init_status = lib.fc_ins_init(self._s, config, 1.0 / sample_hz)

    def run(self, accel_frd_m_s2, gyro_frd_rad_s):
        """(filtered gyro (n,3), filtered accel (n,3), status per sample)."""
        acc, gyr = _rows(accel_frd_m_s2, 3), _rows(gyro_frd_rad_s, 3)
        n = _same_len(acc, gyr)
        gyro_f, accel_f = np.empty((n, 3), np.float32), np.empty((n, 3), np.float32)
        status = np.empty(n, np.int8)
        a, g = _floats(acc), _floats(gyr)
        gyro_now, accel_now = _view(self._s.gyro_frd_rad_s), _view(self._s.accel_frd_m_s2)
        for i in range(n):
            status[i] = lib.fc_ins_update(self._s, a + 3 * i, g + 3 * i)
            gyro_f[i], accel_f[i] = gyro_now, accel_now
        return gyro_f, accel_f, status


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
        self._s = ffi.new("fc_mahony_t *")
        config = ffi.new("fc_mahony_config_t *", dict(
            kp=kp, ki=ki, kmag=kmag, trust_tc_s=trust_tc_s, trust_span_g=trust_span_g,
            bias_rate_hz=bias_rate_hz, still_gyro_rad_s=still_gyro_rad_s,
            still_acc_g=still_acc_g, trust_ema_enable=bool(trust_ema), bias_enable=bool(bias),
            kp_gnss=kp_gnss, ki_gnss=ki_gnss, gnss_boost=gnss_boost,
            gnss_innov_sigma=gnss_innov_sigma))
        lib.fc_mahony_init(self._s, config)

    def set_attitude(self, q_wxyz) -> None:
        lib.fc_mahony_set_attitude(self._s, _vec(q_wxyz))

    def run(self, gyro_frd_rad_s, accel_frd_m_s2, dt_s: float):
        """(q (n,4), bias (n,3), trust (n,)) after each sample."""
        gyr, acc = _rows(gyro_frd_rad_s, 3), _rows(accel_frd_m_s2, 3)
        n = _same_len(gyr, acc)
        q, bias, trust = np.empty((n, 4), np.float32), np.empty((n, 3), np.float32), \
            np.empty(n, np.float32)
        g, a, m = _floats(gyr), _floats(acc), self._s
        q_now, bias_now = _view(m.q_wxyz), _view(m.bias_rad_s)
        for i in range(n):
            lib.fc_mahony_update(m, g + 3 * i, a + 3 * i, dt_s)
            q[i], bias[i], trust[i] = q_now, bias_now, m.trust
        return q, bias, trust

    def mag(self, field_frd, declination_rad: float = 0.0) -> int:
        return lib.fc_mahony_mag(self._s, _vec(field_frd), declination_rad)

    def set_accel_ref(self, accel_ned_m_s2) -> int:
        """Kinematic acceleration reference, NED [m/s^2]; expires after 0.5 s."""
        return lib.fc_mahony_set_accel_ref(self._s, _vec(accel_ned_m_s2))

    def gnss(self, f_imu_ned_m_s2, f_gnss_ned_m_s2) -> int:
        """GNSS-aided tilt: mean specific force over a past interval, measured (IMU rotated
        by the estimate) and from GNSS velocity, NED; held 0.5 s (fc_mahony_gnss)."""
        return lib.fc_mahony_gnss(self._s, _vec(f_imu_ned_m_s2), _vec(f_gnss_ned_m_s2))

    def state(self) -> dict:
        m = self._s
        return dict(q_wxyz=tuple(m.q_wxyz), bias_rad_s=tuple(m.bias_rad_s),
                    integ_rad_s=tuple(m.integ_rad_s), trust=m.trust, trust_raw=m.trust_raw,
                    still=m.still, heading_valid=m.heading_valid,
                    gnss_active=lib.fc_mahony_gnss_active(m), gnss_scale=m.gnss_sched.scale)


def attitude_error(q_wxyz, roll_rad: float, pitch_rad: float, yaw_rad: float = 0.0,
                   hold_yaw: bool = False) -> tuple[float, float, float]:
    """Small-angle error (ex, ey, ez) [rad], body FRD (fc_attitude)."""
    err = ffi.new("float[3]")
    lib.fc_attitude_error(_vec(q_wxyz), roll_rad, pitch_rad, yaw_rad, bool(hold_yaw), err)
    return tuple(err)


def rate_targets(err_frd_rad, ang_p=(4.5, 4.5, 0.0), rate_max_rad_s=(0.0, 0.0, 0.0),
                 yaw_rate_ff_rad_s: float = 0.0) -> tuple[float, float, float]:
    rate = ffi.new("float[3]")
    lib.fc_attitude_rate_targets(_attitude_config(ang_p, rate_max_rad_s), _vec(err_frd_rad),
                                 yaw_rate_ff_rad_s, rate)
    return tuple(rate)


def rate_targets_ff(err_frd_rad, q_err_wxyz, ang_vel_target_rad_s, gyro_z_rad_s: float = 0.0,
                    ang_p=(4.5, 4.5, 0.0), rate_max_rad_s=(0.0, 0.0, 0.0)):
    """((roll, pitch, yaw) rate targets, feed-forward fade) with the target's
    angular velocity fed forward (fc_attitude_rate_targets_ff)."""
    rate = ffi.new("float[3]")
    fade = lib.fc_attitude_rate_targets_ff(_attitude_config(ang_p, rate_max_rad_s),
                                           _vec(err_frd_rad), _vec(q_err_wxyz),
                                           _vec(ang_vel_target_rad_s), gyro_z_rad_s, rate)
    return tuple(rate), fade


def sqrt_controller(error: float, p: float, second_ord_lim: float, dt_s: float) -> float:
    return lib.fc_sqrt_controller(error, p, second_ord_lim, dt_s)


class Shaper:
    """Attitude input shaping (fc_shaper): the target moving toward the command."""

    COLUMNS = ("roll_rad", "pitch_rad", "yaw_rad", "roll_rate_rad_s", "pitch_rate_rad_s",
               "yaw_rate_rad_s", "p_frd_rad_s", "q_frd_rad_s", "r_frd_rad_s")

    def __init__(self, loop_hz: float, input_tc_s: float = _default("ATC_INPUT_TC"),
                 accel_max_cdeg_s2=(_default("ATC_ACCEL_R_MAX"), _default("ATC_ACCEL_P_MAX"),
                                    _default("ATC_ACCEL_Y_MAX")),
                 rate_max_deg_s=(0.0, 0.0, 0.0), enable: bool = True, euler0_rad=(0, 0, 0)):
        self._s = ffi.new("fc_shaper_t *")
        self.dt_s = 1.0 / loop_hz
        self.cfg = ffi.new("fc_shaper_config_t *", dict(
            enable=bool(enable), input_tc_s=input_tc_s,
            accel_max_rad_s2=[float(np.radians(a * 0.01)) for a in accel_max_cdeg_s2],
            rate_max_rad_s=[float(np.radians(r)) for r in rate_max_deg_s]))
        self.reset(euler0_rad)

    def reset(self, euler_rad=(0.0, 0.0, 0.0)) -> None:
        lib.fc_shaper_reset(self._s, _vec(euler_rad))

    def run(self, roll_rad, pitch_rad=0.0, yaw_rad=0.0, yaw_rate_rad_s=0.0,
            hold_yaw=False, n: int | None = None) -> np.ndarray:
        """Rows of COLUMNS, one per loop step; inputs broadcast to n steps."""
        n = n if n is not None else len(np.atleast_1d(roll_rad))
        cmd = np.empty((n, 4), np.float32)
        for k, v in enumerate((roll_rad, pitch_rad, yaw_rad, yaw_rate_rad_s)):
            cmd[:, k] = np.broadcast_to(v, n)
        hold = np.broadcast_to(np.asarray(hold_yaw, dtype=bool), n).tolist()
        out = np.empty((n, 9), np.float32)
        s = self._s
        target = [_view(s.euler_rad), _view(s.euler_rate_rad_s), _view(s.ang_vel_frd_rad_s)]
        for i, (row, h) in enumerate(zip(cmd.tolist(), hold)):
            lib.fc_shaper_update(s, self.cfg, *row, h, self.dt_s)
            out[i] = np.concatenate(target)
        return out


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
        self._s = ffi.new("fc_rate_pid_t *")
        self.dt_s = 1.0 / loop_hz
        self._cfg = ffi.new("fc_rate_pid_config_t *", dict(
            kp=kp, ki=ki, kd=kd, kff=kff, imax=imax, fltt_hz=fltt_hz, flte_hz=flte_hz,
            fltd_hz=fltd_hz, out_us_per_unit=out_us_per_unit, d_clamp_us=d_clamp_us,
            d_clamp_enable=bool(d_clamp), d_pt2x2=bool(d_pt2x2), antiwindup=bool(antiwindup)))
        lib.fc_rate_pid_init(self._s, self._cfg, self.dt_s)

    def run(self, target_rad_s, meas_rad_s, limit=None, integrate: bool = True) -> np.ndarray:
        """Rows of COLUMNS, one per sample."""
        t, m = _rows(target_rad_s, 0), _rows(meas_rad_s, 0)
        n = _same_len(t, m)
        lim = np.broadcast_to(False if limit is None else limit, n).astype(bool).tolist()
        out = np.empty((n, 7), np.float32)
        pid, info, integrate = self._s, self._s.info, bool(integrate)
        for i, (ti, mi, li) in enumerate(zip(t.tolist(), m.tolist(), lim)):
            lib.fc_rate_pid_update(pid, ti, mi, self.dt_s, li, integrate)
            out[i] = (info.p_us, info.i_us, info.d_us, info.ff_us, info.out_us, info.limited,
                      info.d_clamped)
        return out


class HoverTrim:
    """Hover-trim learning and ramp-in (fc_trim)."""

    def __init__(self, window_s: float = _default("SB_TRIM_WIN_S"),
                 gain_us_per_rad: float = _default("SB_TRIM_GAIN"),
                 max_us: float = _default("SB_TRIM_MAX_US"),
                 ramp_s: float = _default("SB_TRIM_RAMP_S"),
                 enable: bool = bool(_default("SB_TRIM_EN")),
                 ramp: bool = bool(_default("SB_TRIM_RAMP_EN"))):
        self._s = ffi.new("fc_trim_t *")
        lib.fc_trim_reset(self._s)
        self.cfg = ffi.new("fc_trim_config_t *", dict(
            enable=bool(enable), ramp_enable=bool(ramp), window_s=window_s,
            gain_us_per_rad=gain_us_per_rad, max_us=max_us, ramp_s=ramp_s))

    def run(self, airborne, ex_rad, ey_rad, dt_s: float) -> np.ndarray:
        """Applied trim (n, 2) [us], roll and pitch."""
        air = np.asarray(airborne).astype(bool)
        ex, ey = _rows(ex_rad, 0), _rows(ey_rad, 0)
        n = _same_len(air, ex, ey)
        out = np.empty((n, 2), np.float32)
        o = _floats(out)
        for i, (a, x, y) in enumerate(zip(air.tolist(), ex.tolist(), ey.tolist())):
            lib.fc_trim_update(self._s, self.cfg, a, x, y, dt_s, o + 2 * i)
        return out


class Blend:
    """EST/GT blend weight (fc_blend)."""

    def __init__(self, tau_s: float = _default("SB_BLEND_TC"),
                 continuous: bool = bool(_default("SB_BLEND_EN")), w0: float = 0.0):
        self._s = ffi.new("fc_blend_t *")
        self.tau_s = tau_s
        self.continuous = continuous
        lib.fc_blend_reset(self._s, w0)

    def run(self, target_w, dt_s: float) -> np.ndarray:
        b, tau, cont = self._s, self.tau_s, bool(self.continuous)
        return np.array([lib.fc_blend_update(b, w, tau, cont, dt_s)
                         for w in _rows(target_w, 0).tolist()], dtype=np.float32)


class Mixer:
    """Quad-X mixer with saturation flags and slew limit (fc_mixer)."""

    SPOOL_SHUT_DOWN, SPOOL_GROUND_IDLE = lib.FC_SPOOL_SHUT_DOWN, lib.FC_SPOOL_GROUND_IDLE
    SPOOL_FLIGHT = lib.FC_SPOOL_FLIGHT

    def __init__(self, pwm_min_us: float = _default("MOT_PWM_MIN"),
                 pwm_max_us: float = _default("MOT_PWM_MAX"),
                 spin_min: float = _default("MOT_SPIN_MIN"),
                 spin_max: float = _default("MOT_SPIN_MAX"),
                 yaw_headroom_us: float = _default("MOT_YAW_HEADROOM"),
                 slew_up_time_s: float = _default("MOT_SLEW_UP_TIME"),
                 slew_dn_time_s: float = _default("MOT_SLEW_DN_TIME"),
                 slew: bool = bool(_default("SB_SLEW_EN"))):
        self._s = ffi.new("fc_mixer_t *")
        self.cfg = ffi.new("fc_mixer_config_t *", dict(
            pwm_min_us=pwm_min_us, pwm_max_us=pwm_max_us, spin_min=spin_min,
            spin_max=spin_max, yaw_headroom_us=yaw_headroom_us, slew_up_time_s=slew_up_time_s,
            slew_dn_time_s=slew_dn_time_s, slew_enable=bool(slew)))
        lib.fc_mixer_reset(self._s, self.cfg)

    def run(self, throttle_us, roll_us, pitch_us, yaw_us, dt_s: float = 0.0025,
            spool: int = lib.FC_SPOOL_FLIGHT):
        """(motor_us (n,4) before slew, pwm_us (n,4), sat_flags (n,), applied (n,4):
        throttle, roll, pitch, yaw as actually mixed)."""
        cols = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=np.float32))
                                     for v in (throttle_us, roll_us, pitch_us, yaw_us)))
        inputs = np.stack(cols, axis=1).astype(np.float32)
        n = len(inputs)
        motor, applied = np.empty((n, 4), np.float32), np.empty((n, 4), np.float32)
        pwm, flags = np.empty((n, 4), np.uint16), np.empty(n, np.uint8)
        p, m = ffi.from_buffer("uint16_t[]", pwm), self._s
        motor_now = _view(m.motor_us)
        for i, row in enumerate(inputs.tolist()):
            lib.fc_mixer_update(m, self.cfg, spool, *row, dt_s, p + 4 * i)
            motor[i] = motor_now
            applied[i] = (m.throttle_us, m.roll_us, m.pitch_us, m.yaw_us)
            flags[i] = m.sat_flags
        return motor, pwm, flags, applied

    @staticmethod
    def factors() -> list[tuple[float, float, float]]:
        """(roll, pitch, yaw) factor of motors 1..4 (ArduCopter QUAD X order)."""
        return list(zip(lib.fc_mixer_roll_factor, lib.fc_mixer_pitch_factor,
                        lib.fc_mixer_yaw_factor))
