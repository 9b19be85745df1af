"""STATUS_DTYPE: one row per PWM tick, the numpy view of fc_core_status_t.

The layout mirrors the C struct in fc_sil/core/fc_core.h field for field
(tests/fc_sil/test_status_layout.py compares every offset with the compiled
extension). Units are in the names; cp/cr/cy are mixer offsets about 0 us,
throttle_us and motor_us absolute PWM (about 1000..2000 us), altitude and
climb positive up. This module imports nothing compiled, so the log writer
and the analysis can use the dtype without the C core.
"""

from __future__ import annotations

import numpy as np

STATUS_DTYPE = np.dtype([
    ("sim_ns", "<i8"),                     # PWM tick time [ns]
    ("imu_sim_ns", "<i8"),                 # latest IMU sample used [ns]
    ("q_est_wxyz", "<f4", (4,)),           # estimated attitude, FRD -> NED
    ("euler_est_rad", "<f4", (3,)),        # roll, pitch, yaw
    ("att_target_rad", "<f4", (3,)),       # target roll, pitch, yaw (shaped, fc_shaper.h)
    ("att_error_frd_rad", "<f4", (3,)),    # blended small-angle error ex, ey, ez
    ("rate_target_frd_rad_s", "<f4", (3,)),
    ("rate_frd_rad_s", "<f4", (3,)),       # filtered, bias-corrected gyro of the rate loop
    ("pid_p", "<f4", (3,)),                # rate-loop terms [us]
    ("pid_i", "<f4", (3,)),
    ("pid_d", "<f4", (3,)),
    ("pid_ff", "<f4", (3,)),
    ("cp_us", "<f4"),                      # mixer inputs about 0 [us] (trim included)
    ("cr_us", "<f4"),
    ("cy_us", "<f4"),
    ("throttle_us", "<f4"),                # mixer throttle [us]
    ("motor_us", "<f4", (4,)),             # before the slew limit [us]
    ("trust", "<f4"),                      # accelerometer trust 0..1
    ("gyro_bias_rad_s", "<f4", (3,)),
    ("blend_w", "<f4"),                    # ground-truth weight 0..1
    ("alt_est_m", "<f4"),                  # above home, up
    ("climb_est_m_s", "<f4"),              # up
    ("alt_target_m", "<f4"),               # NaN unless in altitude mode
    ("climb_target_m_s", "<f4"),
    ("throttle", "<f4"),                   # altitude-loop output 0..1
    ("trim_us", "<f4", (2,)),              # applied hover trim, roll and pitch
    ("loop_count", "<u4"),                 # rate-loop runs so far
    ("rejected_count", "<u4"),             # refused input samples so far
    ("pwm_us", "<u2", (4,)),               # outputs after slew [us]
    ("limited", "u1", (3,)),               # rate integrator limited per axis
    ("sat_flags", "u1"),                   # SAT_* bits below
    ("armed", "u1"),
    ("airborne", "u1"),
    ("spool", "u1"),                       # SPOOL_* below
    ("reserved", "u1", (5,)),
])
assert STATUS_DTYPE.itemsize == 248

# Mixer saturation bits (fc_mixer.h).
SAT_ROLL, SAT_PITCH, SAT_YAW, SAT_THR_HIGH, SAT_THR_LOW = 0x01, 0x02, 0x04, 0x08, 0x10
# Spool states (fc_mixer.h).
SPOOL_SHUT_DOWN, SPOOL_GROUND_IDLE, SPOOL_FLIGHT = 0, 1, 2
