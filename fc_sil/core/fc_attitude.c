/*
 * fc_attitude.c - attitude P (see fc_attitude.h).
 */
#include "fc_attitude.h"

#include "fc_math.h"
#include "fc_shaper.h"

void fc_attitude_error_q(const float q_est_wxyz[4], const float q_target_wxyz[4],
                         float q_err_wxyz[4], float err_frd_rad[3])
{
    const float q_conj[4] = {q_est_wxyz[0], -q_est_wxyz[1], -q_est_wxyz[2], -q_est_wxyz[3]};
    fc_quat_mul(q_conj, q_target_wxyz, q_err_wxyz);
    const float *q_err = q_err_wxyz;
    /* Rotation vector (axis times angle) of q_err; q and -q are the same
     * rotation, so take the short way round. For small angles this is the
     * paper's (ex, ey, ez); unlike 2 * vec(q_err) it stays exact for large ones. */
    const float sgn = (q_err[0] < 0.0f) ? -1.0f : 1.0f;
    const float vn = sqrtf(q_err[1] * q_err[1] + q_err[2] * q_err[2] + q_err[3] * q_err[3]);
    const float scale = (vn > 1e-6f) ? sgn * 2.0f * atan2f(vn, fabsf(q_err[0])) / vn : 2.0f * sgn;
    err_frd_rad[0] = scale * q_err[1];
    err_frd_rad[1] = scale * q_err[2];
    err_frd_rad[2] = scale * q_err[3];
}

void fc_attitude_error(const float q_est_wxyz[4], float roll_target_rad, float pitch_target_rad,
                       float yaw_target_rad, bool hold_yaw, float err_frd_rad[3])
{
    float yaw = yaw_target_rad;
    if (!hold_yaw) {
        float euler[3];
        fc_quat_to_euler(q_est_wxyz, euler);
        yaw = euler[2];
    }
    float q_t[4], q_err[4];
    fc_quat_from_euler(roll_target_rad, pitch_target_rad, yaw, q_t);
    fc_attitude_error_q(q_est_wxyz, q_t, q_err, err_frd_rad);
}

void fc_attitude_rate_targets(const fc_attitude_config_t *cfg, const float err_frd_rad[3],
                              float yaw_rate_ff_rad_s, float rate_target_frd_rad_s[3])
{
    for (int i = 0; i < 3; i++) {
        float r = cfg->ang_p[i] * err_frd_rad[i];
        if (i == 2) {
            r += yaw_rate_ff_rad_s;
        }
        if (cfg->rate_max_rad_s[i] > 0.0f) {
            r = fc_constrainf(r, -cfg->rate_max_rad_s[i], cfg->rate_max_rad_s[i]);
        }
        rate_target_frd_rad_s[i] = r;
    }
}

float fc_attitude_rate_targets_ff(const fc_attitude_config_t *cfg, const float err_frd_rad[3],
                                  const float q_err_wxyz[4], const float ang_vel_target_rad_s[3],
                                  float gyro_z_rad_s, float rate_target_frd_rad_s[3])
{
    float r[3];
    for (int i = 0; i < 3; i++) {
        r[i] = cfg->ang_p[i] * err_frd_rad[i];
    }
    fc_ang_vel_limit(r, cfg->rate_max_rad_s);
    /* The target's angular velocity is defined in the target frame; q_err
     * rotates it into the body frame the rate loop works in. */
    float ff[3];
    fc_quat_rotate(q_err_wxyz, ang_vel_target_rad_s, ff);
    /* Angle between the thrust axes: the target's z axis seen in the body
     * frame has z component 1 - 2 (x^2 + y^2) of q_err. */
    const float qx = q_err_wxyz[1], qy = q_err_wxyz[2];
    const float thrust_err_rad =
        acosf(fc_constrainf(1.0f - 2.0f * (qx * qx + qy * qy), -1.0f, 1.0f));
    float fade = 1.0f;
    if (thrust_err_rad > 2.0f * FC_ATT_THRUST_ERR_RAD) {
        fade = 0.0f;
        r[2] = gyro_z_rad_s;
    } else if (thrust_err_rad > FC_ATT_THRUST_ERR_RAD) {
        fade = 1.0f - (thrust_err_rad - FC_ATT_THRUST_ERR_RAD) / FC_ATT_THRUST_ERR_RAD;
        r[0] += ff[0] * fade;
        r[1] += ff[1] * fade;
        r[2] = gyro_z_rad_s * (1.0f - fade) + (r[2] + ff[2]) * fade;
    } else {
        r[0] += ff[0];
        r[1] += ff[1];
        r[2] += ff[2];
    }
    for (int i = 0; i < 3; i++) {
        rate_target_frd_rad_s[i] = r[i];
    }
    return fade;
}
