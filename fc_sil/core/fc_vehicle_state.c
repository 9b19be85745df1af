/*
 * fc_vehicle_state.c - the controllers' view of the vehicle and the attitude
 * error on it (see fc_vehicle_state.h for the blend of the two attitudes).
 */
#include "fc_vehicle_state.h"

#include "fc_attitude.h"
#include "fc_blend.h"
#include "fc_math.h"

void fc_vehicle_state_reset(fc_vehicle_state_t *vs)
{
    fc_vehicle_state_t zero = {0};
    *vs = zero;
    fc_quat_identity(vs->q_wxyz);
    fc_quat_identity(vs->q_truth_wxyz);
    vs->cos_tilt = 1.0f;
}

void fc_vehicle_att_error(const fc_vehicle_state_t *vs, float roll_target_rad,
                          float pitch_target_rad, float yaw_target_rad, bool hold_yaw,
                          float err_frd_rad[3])
{
    fc_attitude_error(vs->q_wxyz, roll_target_rad, pitch_target_rad, yaw_target_rad, hold_yaw,
                      err_frd_rad);
    /* Skipped at w = 0 rather than mixed with weight 0: the estimate's error
     * then passes bit for bit (no -0 + 0 rounding, no NaN from a stale truth). */
    if (vs->truth_w > 0.0f) {
        float e_truth[3];
        fc_attitude_error(vs->q_truth_wxyz, roll_target_rad, pitch_target_rad, yaw_target_rad,
                          hold_yaw, e_truth);
        fc_blend_mix(vs->truth_w, err_frd_rad, e_truth, err_frd_rad, 3);
    }
}

void fc_vehicle_att_error_q(const fc_vehicle_state_t *vs, const float q_target_wxyz[4],
                            float q_err_wxyz[4], float err_frd_rad[3])
{
    fc_attitude_error_q(vs->q_wxyz, q_target_wxyz, q_err_wxyz, err_frd_rad);
    if (vs->truth_w > 0.0f) {
        float e_truth[3], q_err_truth[4];
        fc_attitude_error_q(vs->q_truth_wxyz, q_target_wxyz, q_err_truth, e_truth);
        fc_blend_mix(vs->truth_w, err_frd_rad, e_truth, err_frd_rad, 3);
    }
}
