/*
 * fc_state_source.h - what fills the vehicle state (fc_vehicle_state.h): the
 * onboard estimate (Mahony attitude, front-end gyro, vertical filter), with
 * the simulator's ground truth blended in when SB_ATT_SRC asks for it.
 *
 * Ground truth is a second estimator here, not a case in the control law: its
 * samples are stored as they arrive, and at each publish the blend weight
 * moves toward 1 while truth is wanted and fresh, toward 0 otherwise, with the
 * EMA of fc_blend.h (paper 3.7: a source change is never a step). Truth
 * older than FC_TRUTH_STALE_NS against the latest IMU sample counts as absent.
 *
 * Two publishes, one per consumer rate: the attitude part at each rate-loop
 * step (which also advances the blend weight), the vertical part at each PWM
 * tick (the altitude loop's rate; baro and truth may have arrived since).
 */
#ifndef FC_STATE_SOURCE_H
#define FC_STATE_SOURCE_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_alt_est.h"
#include "fc_blend.h"
#include "fc_ins.h"
#include "fc_mahony.h"
#include "fc_status.h"
#include "fc_vehicle_state.h"

/* Ground truth older than this (relative to the latest IMU sample) no longer
 * counts as available: the blend weight then returns to the estimate. */
#define FC_TRUTH_STALE_NS 100000000LL

typedef struct fc_source_config {
    bool use_truth;         /* SB_ATT_SRC = 1: blend ground truth in while fresh */
    bool blend_continuous;  /* SB_BLEND_EN: EMA of the weight; off = discrete switch */
    float blend_tc_s;       /* SB_BLEND_TC: time constant of the weight [s] */
} fc_source_config_t;

typedef struct fc_state_source {
    float truth_q_wxyz[4];    /* latest ground-truth attitude, body FRD -> NED */
    int64_t truth_att_ns;     /* its sim time [ns] */
    bool have_truth_att;
    float truth_alt_m;        /* latest ground-truth altitude above home, up [m] */
    float truth_climb_m_s;    /* latest ground-truth climb rate, up [m/s] */
    int64_t truth_nav_ns;     /* their sim time [ns] */
    bool have_truth_nav;
    fc_blend_t blend;         /* weight of ground truth, 0..1 */
} fc_state_source_t;

/* No truth, weight 0 (the estimate). */
void fc_state_source_reset(fc_state_source_t *src);

/* Ground-truth samples (non-finite refused, store kept). */
fc_status_t fc_state_source_truth_att(fc_state_source_t *src, int64_t sim_ns,
                                      const float q_wxyz[4]);
/* Position relative to home and velocity, NED; only the vertical is used. */
fc_status_t fc_state_source_truth_nav(fc_state_source_t *src, int64_t sim_ns,
                                      const float pos_ned_m[3], const float vel_ned_m_s[3]);

/* Rate-loop publish: advance the weight by dt_s, then fill attitude, Euler
 * angles and the bias-corrected rates. now_ns: the latest IMU sample. */
void fc_state_source_attitude(fc_state_source_t *src, const fc_source_config_t *cfg,
                              const fc_mahony_t *ahrs, const fc_ins_t *ins, int64_t now_ns,
                              float dt_s, fc_vehicle_state_t *vs);

/* PWM-tick publish: altitude and climb (blended with the weight of the last
 * rate-loop step), vertical acceleration and tilt of the latest estimate. */
void fc_state_source_vertical(const fc_state_source_t *src, const fc_mahony_t *ahrs,
                              const fc_alt_est_t *alt, int64_t now_ns, fc_vehicle_state_t *vs);

#endif /* FC_STATE_SOURCE_H */
