/*
 * step_maths.h - the per-step sensor and truth maths of the bridge, in C.
 *
 * Same formulas, in the same operation order, as the readable Python reference
 * (tests/bridge/step_kernel_oracle.py): compiled without floating-point contraction, both
 * give the same doubles, so the C step and the reference produce byte-identical
 * records (tests/bridge/test_step_kernel.py holds them to that).
 */
#ifndef SB_STEP_MATHS_H
#define SB_STEP_MATHS_H

#include <stdint.h>

/* IMU constants of one run (imu.py documents the model and the figures). */
typedef struct {
    double dt_s;            /* physics step [s] */
    double inv_omega_max2;  /* 1 / omega_max^2 [s^2/rad^2] */
    double vib_accel;       /* vibration amplitude at full rotor speed [m/s^2] */
    double vib_gyro;        /* [rad/s] */
    double range_accel;     /* full scale [m/s^2] */
    double range_gyro;      /* full scale [rad/s] */
} sb_imu_consts;

/* One IMU sample at the end of a physics step (imu_hz == physics_hz).
 * true_af: specific force FRD [m/s^2]; true_w: body rates FRD [rad/s];
 * omega: rotor speeds [rad/s]; phase: rotor phases [rad], advanced in place;
 * stoch: slow bias + white noise of this step, gyro xyz then accel xyz;
 * injected: injected gyro bias FRD [rad/s]. out: accel xyz, gyro xyz. */
void sb_imu_scalar(const sb_imu_consts *c, const double true_af[3], const double true_w[3],
                   const double omega[4], double phase[4], const double stoch[6],
                   const double injected[3], double out[6]);

/* ZYX Euler [rad] -> unit quaternion (w, x, y, z), body FRD -> NED, w >= 0. */
void sb_quat_from_euler(double phi, double theta, double psi, double q[4]);

/* The grids HIL messages carry (mavlink/hil_quant.py): whole mm, whole cm/s (int16). */
double sb_quant_down_m(double d);
double sb_quant_velocity_m_s(double v);

/* Pa on the grid HIL_SENSOR.abs_pressure (float32 hPa) carries exactly: 17 significant
 * bits in hPa (mavlink/hil_quant.py pressure_pa). */
double sb_quant_pressure_pa(double pa);

/* Due time [ns] of sample m of a periodic sensor: round(m * 1e9 / rate_hz) (lowrate.py). */
int64_t sb_due_ns(int64_t m, double rate_hz);

/* Rotate a NED vector into body FRD for ZYX Euler angles (frames.py ned_to_frd). */
void sb_ned_to_frd(double phi, double theta, double psi, const double ned[3], double frd[3]);

/* 1 when a rotor hub of the quad is at or below flat ground at height hagl_m. */
int sb_rotor_strike(double phi, double theta, double hagl_m);

#endif
