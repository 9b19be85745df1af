"""NavConfig: the parameters the outer loops read, in SI units, re-read after any change.

The outer loops run at 50 Hz; reading ~40 parameters by name each step would cost more than
the navigation itself, so the vehicle rebuilds this object only when the parameter store's
version counter moves (a PARAM_SET, a .parm load). ArduPilot's centimetre and centidegree
parameters become metres and radians here, once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .battery import BatteryConfig
from .nav_loiter import LoiterConfig
from .nav_pos import G_M_S2, PosGains
from .nav_wp import WpSpeeds


@dataclass
class NavConfig:
    pos: PosGains = field(default_factory=PosGains)
    wp: WpSpeeds = field(default_factory=WpSpeeds)
    loiter: LoiterConfig = field(default_factory=LoiterConfig)
    battery: BatteryConfig = field(default_factory=BatteryConfig)
    angle_max_rad: float = math.radians(30.0)
    pilot_speed_up_m_s: float = 2.5
    pilot_speed_dn_m_s: float = 2.5
    pilot_y_rate_rad_s: float = math.radians(202.5)
    hover_throttle: float = 0.35
    land_speed_m_s: float = 0.5
    land_alt_low_m: float = 10.0
    rtl_alt_m: float = 15.0
    rtl_alt_final_m: float = 0.0
    rtl_loit_time_s: float = 5.0
    rtl_speed_m_s: float = 0.0
    rtl_climb_min_m: float = 0.0
    loit_speed_m_s: float = 12.5
    disarm_delay_s: float = 10.0
    guid_timeout_s: float = 3.0
    fs_gcs_enable: int = 1
    fs_gcs_timeout_s: float = 5.0
    batt_low_volt: float = 14.0
    batt_crt_volt: float = 0.0
    batt_low_mah: float = 0.0
    batt_crt_mah: float = 0.0
    batt_fs_low_act: int = 2
    batt_fs_crt_act: int = 1
    batt_low_timer_s: float = 10.0
    gps_delay_s: float = 0.11
    gps_timeout_s: float = 1.0
    sens_timeout_s: float = 0.2
    pos_tc_s: float = 1.5
    vel_tc_s: float = 0.2
    arming_check: int = 1
    wp_yaw_behavior: int = 2
    compass_use: int = 1
    rc_fs_timeout_s: float = 1.0
    pid_mask: int = 0
    pwm_min_us: float = 1000.0
    pwm_max_us: float = 2000.0
    # take-off: the lowest take-off altitude accepted and how close counts as "there"
    # (ArduCopter: 1 m minimum take-off; its wpnav reports arrival within about 0.5 m)
    takeoff_min_m: float = 1.0
    takeoff_done_m: float = 0.5

    @classmethod
    def from_store(cls, get) -> "NavConfig":
        cm = 0.01
        angle_max = math.radians(get("ANGLE_MAX") * 0.01)
        up = get("PILOT_SPEED_UP") * cm
        dn = get("PILOT_SPEED_DN") * cm or up
        return cls(
            pos=_pos_gains(get, angle_max), wp=_wp_speeds(get),
            loiter=_loiter(get, angle_max),
            battery=BatteryConfig.from_params(get),
            angle_max_rad=angle_max, pilot_speed_up_m_s=up, pilot_speed_dn_m_s=dn,
            pilot_y_rate_rad_s=math.radians(get("PILOT_Y_RATE")),
            hover_throttle=get("MOT_THST_HOVER"), land_speed_m_s=get("LAND_SPEED") * cm,
            land_alt_low_m=get("LAND_ALT_LOW") * cm, rtl_alt_m=get("RTL_ALT") * cm,
            rtl_alt_final_m=get("RTL_ALT_FINAL") * cm,
            rtl_loit_time_s=get("RTL_LOIT_TIME") * 1e-3, rtl_speed_m_s=get("RTL_SPEED") * cm,
            rtl_climb_min_m=get("RTL_CLIMB_MIN") * cm, loit_speed_m_s=get("LOIT_SPEED") * cm,
            disarm_delay_s=get("DISARM_DELAY"), guid_timeout_s=get("GUID_TIMEOUT"),
            fs_gcs_enable=int(get("FS_GCS_ENABLE")), fs_gcs_timeout_s=get("FS_GCS_TIMEOUT"),
            batt_low_volt=get("BATT_LOW_VOLT"), batt_crt_volt=get("BATT_CRT_VOLT"),
            batt_low_mah=get("BATT_LOW_MAH"), batt_crt_mah=get("BATT_CRT_MAH"),
            batt_fs_low_act=int(get("BATT_FS_LOW_ACT")),
            batt_fs_crt_act=int(get("BATT_FS_CRT_ACT")),
            batt_low_timer_s=get("BATT_LOW_TIMER"), gps_delay_s=get("GPS_DELAY_MS") * 1e-3,
            gps_timeout_s=get("SB_GPS_TO"), sens_timeout_s=get("SB_FS_SENS_TO"),
            pos_tc_s=get("SB_POS_TC"), vel_tc_s=get("SB_VEL_TC"),
            arming_check=int(get("ARMING_CHECK")), wp_yaw_behavior=int(get("WP_YAW_BEHAVIOR")),
            compass_use=int(get("COMPASS_USE")), rc_fs_timeout_s=get("RC_FS_TIMEOUT"),
            pid_mask=int(get("GCS_PID_MASK")), pwm_min_us=get("MOT_PWM_MIN"),
            pwm_max_us=get("MOT_PWM_MAX"))


def _attitude_jerk_caps(get, accel_m_s2: float) -> float:
    """Largest horizontal jerk the attitude controller can follow (AC_PosControl): the lean
    rate limit x g, and half the geometric mean of the acceleration and the lean's angular
    acceleration limit x g (the attitude shaping must be on for either to bind)."""
    cap = float("inf")
    if get("ATC_RATE_FF_ENAB"):
        rate = min(get("ATC_RATE_R_MAX"), get("ATC_RATE_P_MAX"))
        if rate > 0.0:
            cap = math.radians(rate) * G_M_S2
        snap = math.radians(min(get("ATC_ACCEL_R_MAX"), get("ATC_ACCEL_P_MAX")) * 0.01) * G_M_S2
        if snap > 0.0:
            cap = min(cap, 0.5 * math.sqrt(accel_m_s2 * snap))
    return cap


def _pos_angle_max(get, angle_max: float) -> float:
    psc = get("PSC_ANGLE_MAX")
    return math.radians(psc) if psc > 0.0 else angle_max


def _pos_gains(get, angle_max: float) -> PosGains:
    accel = get("WPNAV_ACCEL") * 0.01
    return PosGains(pos_p=get("PSC_POSXY_P"), vel_p=get("PSC_VELXY_P"), vel_i=get("PSC_VELXY_I"),
                    vel_d=get("PSC_VELXY_D"), vel_imax_m_s2=get("PSC_VELXY_IMAX") * 0.01,
                    vel_ff=get("PSC_VELXY_FF"), vel_flte_hz=get("PSC_VELXY_FLTE"),
                    vel_fltd_hz=get("PSC_VELXY_FLTD"),
                    jerk_m_s3=min(get("PSC_JERK_XY"), _attitude_jerk_caps(get, accel)),
                    accel_m_s2=accel, speed_m_s=get("WPNAV_SPEED") * 0.01,
                    angle_max_rad=_pos_angle_max(get, angle_max))


def _wp_speeds(get) -> WpSpeeds:
    cm = 0.01
    rate = min(get("ATC_RATE_R_MAX"), get("ATC_RATE_P_MAX"))
    jerk = get("WPNAV_JERK")
    if rate > 0.0:      # AC_WPNav: the S-curve jerk within what the lean rate limit allows
        jerk = min(jerk, math.radians(rate) * G_M_S2)
    # AC_WPNav's snap: the acceleration follows the lean, which the attitude input shaping
    # moves with time constant ATC_INPUT_TC and angular acceleration ATC_ACCEL_R/P_MAX; half
    # of what the aircraft could do
    snap = jerk * math.pi / (2.0 * max(get("ATC_INPUT_TC"), 0.1))
    ang_acc = math.radians(min(get("ATC_ACCEL_R_MAX"), get("ATC_ACCEL_P_MAX")) * 0.01) * G_M_S2
    if ang_acc > 0.0:
        snap = min(snap, ang_acc)
    return WpSpeeds(speed_m_s=get("WPNAV_SPEED") * cm, up_m_s=get("WPNAV_SPEED_UP") * cm,
                    dn_m_s=get("WPNAV_SPEED_DN") * cm, accel_m_s2=get("WPNAV_ACCEL") * cm,
                    radius_m=get("WPNAV_RADIUS") * cm, jerk_m_s3=jerk,
                    accel_z_m_s2=get("WPNAV_ACCEL_Z") * cm, pos_p=get("PSC_POSXY_P"),
                    snap_m_s4=0.5 * snap)


def _loiter(get, angle_max: float) -> LoiterConfig:
    pos_angle = _pos_angle_max(get, angle_max)
    loit = get("LOIT_ANG_MAX")
    ang = min(math.radians(loit), pos_angle) if loit > 0.0 else min(angle_max, pos_angle) * 2 / 3
    return LoiterConfig(speed_m_s=get("LOIT_SPEED") * 0.01,
                        accel_max_m_s2=get("LOIT_ACC_MAX") * 0.01,
                        brake_accel_m_s2=get("LOIT_BRK_ACCEL") * 0.01,
                        brake_jerk_m_s3=get("LOIT_BRK_JERK") * 0.01,
                        brake_delay_s=get("LOIT_BRK_DELAY"), angle_max_rad=ang,
                        vel_p=get("PSC_VELXY_P"), input_tc_s=get("ATC_INPUT_TC"))
