/*
 * fc_gnss_aid.h - GNSS-aided acceleration compensation for the attitude
 * estimator: what the accelerometer should have measured, from GNSS velocity.
 *
 * On a multirotor the accelerometer sees thrust (body z) plus drag, never the
 * vehicle's own acceleration apart from gravity: through a held tilt or a
 * steady push it "looks level", and a tilt correction from the accelerometer
 * alone pulls the estimate towards the thrust axis. GNSS velocity tells the
 * vehicle's kinematic acceleration; the two are compared here the way
 * ArduPilot's DCM does it, over the same stretch of time:
 *
 *   measured  f_imu  = (1/T) integral of R_est(t) f_frd(t) dt   (specific force, NED)
 *   kinematic f_gnss = (v(t1) - v(t0)) / T - g_ned             (same thing from GNSS)
 *
 * over [t0, t1] = the epochs of two successive fixes, T = t1 - t0. A fix
 * arrives GPS_DELAY_MS after its epoch, so the IMU side must be integrated
 * over that delayed interval: every IMU sample's R_est f dt is summed into a
 * history of fixed 10 ms slots (sim-time aligned), and the interval is read
 * back from the history with partial slots weighted by their overlap. If the
 * estimate is right the two mean specific forces are parallel; the rotation
 * between them is the estimate's tilt error at that time (fc_mahony_gnss).
 * Comparing means over 100 ms instead of the current accelerometer with a
 * 160 ms old acceleration keeps the latency out of the error.
 *
 * Velocity noise: each fix's noise enters two successive differences with
 * opposite signs, so its effect on the tilt telescopes instead of summing.
 *
 * No heap: the history is 128 slots x 3 floats (1.5 kB), 1.28 s, enough for a
 * 500 ms receiver delay plus a 5 Hz fix interval.
 */
#ifndef FC_GNSS_AID_H
#define FC_GNSS_AID_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_status.h"

#define FC_GNSS_AID_SLOTS 128              /* a power of two (index mask) */
#define FC_GNSS_AID_SLOT_NS 10000000LL     /* 10 ms */

typedef struct fc_gnss_aid {
    float dv_ned_m_s[FC_GNSS_AID_SLOTS][3]; /* sum of R_est f dt per slot, NED [m/s] */
    int64_t newest_slot;       /* absolute slot index (sim_ns / slot) of the newest slot */
    int64_t start_ns;          /* history begins here (no data before) [ns] */
    int64_t end_ns;            /* history ends here (end of the latest IMU sample) [ns] */
    bool have_history;
    float vel_prev_ned_m_s[3]; /* velocity of the previous fix [m/s] */
    int64_t epoch_prev_ns;     /* epoch of the previous fix [ns] */
    bool have_prev;
} fc_gnss_aid_t;

void fc_gnss_aid_reset(fc_gnss_aid_t *g);

/* One IMU sample covering (t0_ns, t1_ns]: its specific force, rotated to NED
 * with the estimate q_wxyz (body FRD -> NED), is added to the history. A t0_ns
 * other than the previous sample's t1_ns (a gap) restarts the history. */
void fc_gnss_aid_add_imu(fc_gnss_aid_t *g, int64_t t0_ns, int64_t t1_ns, const float q_wxyz[4],
                         const float accel_frd_m_s2[3]);

/* One GNSS fix (epoch = arrival - receiver delay). With the previous fix it
 * gives the mean specific force over the interval between their epochs, as
 * the IMU measured it (f_imu_ned) and as GNSS velocity implies it
 * (f_gnss_ned), both [m/s^2]: FC_OK. FC_ERR_ARG when they cannot be compared
 * (first fix, interval outside 20 ms..1 s, history not covering the interval);
 * the fix is remembered for the next call either way. */
fc_status_t fc_gnss_aid_fix(fc_gnss_aid_t *g, int64_t epoch_ns, const float vel_ned_m_s[3],
                            float f_imu_ned_m_s2[3], float f_gnss_ned_m_s2[3]);

/* Forget the previous fix (fix lost, aiding switched off). */
void fc_gnss_aid_forget_fix(fc_gnss_aid_t *g);

#endif /* FC_GNSS_AID_H */
