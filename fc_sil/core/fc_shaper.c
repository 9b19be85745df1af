/*
 * fc_shaper.c - attitude input shaping (see fc_shaper.h).
 */
#include "fc_shaper.h"

#include "fc_math.h"

/* ArduCopter floors the input time constant at 10 ms (1 / MAX(tc, 0.01)). */
#define FC_SHAPER_TC_MIN_S 0.01f
/* euler_accel_limit keeps its sines and cosines off zero so no limit becomes infinite. */
#define FC_SHAPER_TRIG_FLOOR 0.1f

float fc_sqrt_controller(float error, float p, float second_ord_lim, float dt_s)
{
    float rate;
    if (!(second_ord_lim > 0.0f)) {
        /* No acceleration limit: linear; p = 0 here means an infinite gain,
         * i.e. the whole error in one step (the clamp below). */
        rate = (p > 0.0f) ? error * p : ((dt_s > 0.0f) ? error / dt_s : 0.0f);
    } else if (!(p > 0.0f)) {
        rate = (error >= 0.0f) ? sqrtf(2.0f * second_ord_lim * error)
                               : -sqrtf(-2.0f * second_ord_lim * error);
    } else {
        /* Linear inside a / p^2, where the sqrt curve's slope equals p; the
         * half-distance offset makes the two pieces meet with equal rates. */
        const float linear_dist = second_ord_lim / (p * p);
        if (error > linear_dist) {
            rate = sqrtf(2.0f * second_ord_lim * (error - 0.5f * linear_dist));
        } else if (error < -linear_dist) {
            rate = -sqrtf(2.0f * second_ord_lim * (-error - 0.5f * linear_dist));
        } else {
            rate = error * p;
        }
    }
    if (dt_s > 0.0f) {
        /* Never step past zero error within one step. */
        const float lim = fabsf(error) / dt_s;
        rate = fc_constrainf(rate, -lim, lim);
    }
    return rate;
}

float fc_shape_ang_vel(float target_ang_vel, float desired_ang_vel, float accel_max, float dt_s)
{
    if (!(accel_max > 0.0f)) {
        return desired_ang_vel;
    }
    const float step = accel_max * dt_s;
    return fc_constrainf(desired_ang_vel, target_ang_vel - step, target_ang_vel + step);
}

float fc_shape_angle(float error_rad, float input_tc_s, float accel_max, float target_ang_vel,
                     float dt_s)
{
    const float p = 1.0f / fmaxf(input_tc_s, FC_SHAPER_TC_MIN_S);
    const float desired = fc_sqrt_controller(error_rad, p, accel_max, dt_s);
    return fc_shape_ang_vel(target_ang_vel, desired, accel_max, dt_s);
}

void fc_ang_vel_limit(float ang_vel_rad_s[3], const float rate_max_rad_s[3])
{
    const float rmax = rate_max_rad_s[0], pmax = rate_max_rad_s[1], ymax = rate_max_rad_s[2];
    if (rmax > 0.0f && pmax > 0.0f) {
        /* Roll and pitch tilt the thrust vector together: scale both so the
         * pair stays on the ellipse of the two limits, keeping its direction. */
        const float x = ang_vel_rad_s[0] / rmax, y = ang_vel_rad_s[1] / pmax;
        const float len = sqrtf(x * x + y * y);
        if (len > 1.0f) {
            ang_vel_rad_s[0] = x * rmax / len;
            ang_vel_rad_s[1] = y * pmax / len;
        }
    } else {
        if (rmax > 0.0f) {
            ang_vel_rad_s[0] = fc_constrainf(ang_vel_rad_s[0], -rmax, rmax);
        }
        if (pmax > 0.0f) {
            ang_vel_rad_s[1] = fc_constrainf(ang_vel_rad_s[1], -pmax, pmax);
        }
    }
    if (ymax > 0.0f) {
        ang_vel_rad_s[2] = fc_constrainf(ang_vel_rad_s[2], -ymax, ymax);
    }
}

void fc_euler_accel_limit(const float euler_rad[3], const float body_accel[3],
                          float euler_accel[3])
{
    if (!(body_accel[0] > 0.0f) || !(body_accel[1] > 0.0f) || !(body_accel[2] > 0.0f)) {
        for (int i = 0; i < 3; i++) {
            euler_accel[i] = body_accel[i];
        }
        return;
    }
    const float sp = fc_constrainf(fabsf(sinf(euler_rad[0])), FC_SHAPER_TRIG_FLOOR, 1.0f);
    const float cp = fc_constrainf(fabsf(cosf(euler_rad[0])), FC_SHAPER_TRIG_FLOOR, 1.0f);
    const float st = fc_constrainf(fabsf(sinf(euler_rad[1])), FC_SHAPER_TRIG_FLOOR, 1.0f);
    const float ct = fc_constrainf(fabsf(cosf(euler_rad[1])), FC_SHAPER_TRIG_FLOOR, 1.0f);
    /* An Euler-axis acceleration loads the body axes through the rate
     * transform below; each Euler limit is the smallest any body axis allows. */
    euler_accel[0] = body_accel[0];
    euler_accel[1] = fminf(body_accel[1] / cp, body_accel[2] / sp);
    euler_accel[2] = fminf(fminf(body_accel[0] / st, body_accel[1] / (sp * ct)),
                           body_accel[2] / (cp * ct));
}

void fc_euler_rate_to_ang_vel(const float euler_rad[3], const float euler_rate[3],
                              float ang_vel[3])
{
    const float sr = sinf(euler_rad[0]), cr = cosf(euler_rad[0]);
    const float sp = sinf(euler_rad[1]), cp = cosf(euler_rad[1]);
    ang_vel[0] = euler_rate[0] - sp * euler_rate[2];
    ang_vel[1] = cr * euler_rate[1] + sr * cp * euler_rate[2];
    ang_vel[2] = -sr * euler_rate[1] + cp * cr * euler_rate[2];
}

void fc_ang_vel_to_euler_rate(const float euler_rad[3], const float ang_vel[3],
                              float euler_rate[3])
{
    const float sr = sinf(euler_rad[0]), cr = cosf(euler_rad[0]);
    const float sp = sinf(euler_rad[1]), cp = cosf(euler_rad[1]);
    if (fabsf(cp) < 1e-6f) {
        return; /* pitched straight up or down: Euler rates undefined, keep the last */
    }
    const float tp = sp / cp;
    euler_rate[0] = ang_vel[0] + sr * tp * ang_vel[1] + cr * tp * ang_vel[2];
    euler_rate[1] = cr * ang_vel[1] - sr * ang_vel[2];
    euler_rate[2] = (sr * ang_vel[1] + cr * ang_vel[2]) / cp;
}

void fc_shaper_reset(fc_shaper_t *s, const float euler_rad[3])
{
    for (int i = 0; i < 3; i++) {
        s->euler_rad[i] = euler_rad[i];
        s->euler_rate_rad_s[i] = 0.0f;
        s->ang_vel_frd_rad_s[i] = 0.0f;
    }
}

void fc_shaper_set_yaw(fc_shaper_t *s, float yaw_rad)
{
    s->euler_rad[2] = fc_wrap_pi(yaw_rad);
}

void fc_shaper_reset_yaw(fc_shaper_t *s, float yaw_rad)
{
    fc_shaper_set_yaw(s, yaw_rad);
    s->euler_rate_rad_s[2] = 0.0f;
    /* the body rates follow from the Euler rates at the same attitude */
    fc_euler_rate_to_ang_vel(s->euler_rad, s->euler_rate_rad_s, s->ang_vel_frd_rad_s);
}

/* One angle axis: shaped, or (no time constant and no acceleration limit)
 * straight through with no rate. */
static void shape_axis(fc_shaper_t *s, const fc_shaper_config_t *cfg, int axis, float cmd_rad,
                       float accel_max, float dt_s)
{
    if (!(cfg->input_tc_s > 0.0f) && !(accel_max > 0.0f)) {
        s->euler_rad[axis] = cmd_rad;
        s->euler_rate_rad_s[axis] = 0.0f;
        return;
    }
    const float err = fc_wrap_pi(cmd_rad - s->euler_rad[axis]);
    s->euler_rate_rad_s[axis] =
        fc_shape_angle(err, cfg->input_tc_s, accel_max, s->euler_rate_rad_s[axis], dt_s);
}

void fc_shaper_update(fc_shaper_t *s, const fc_shaper_config_t *cfg, float roll_cmd_rad,
                      float pitch_cmd_rad, float yaw_cmd_rad, float yaw_rate_cmd_rad_s,
                      bool hold_yaw, float dt_s)
{
    if (!cfg->enable) {
        s->euler_rad[0] = roll_cmd_rad;
        s->euler_rad[1] = pitch_cmd_rad;
        s->euler_rad[2] = hold_yaw ? fc_wrap_pi(yaw_cmd_rad)
                                   : fc_wrap_pi(s->euler_rad[2] + yaw_rate_cmd_rad_s * dt_s);
        for (int i = 0; i < 3; i++) {
            s->euler_rate_rad_s[i] = 0.0f;
            s->ang_vel_frd_rad_s[i] = 0.0f;
        }
        return;
    }
    /* Advance the target by the rate it was given last step (ArduCopter
     * update_attitude_target), then choose the next rate. */
    s->euler_rad[0] = fc_wrap_pi(s->euler_rad[0] + s->euler_rate_rad_s[0] * dt_s);
    s->euler_rad[1] = s->euler_rad[1] + s->euler_rate_rad_s[1] * dt_s;
    s->euler_rad[2] = fc_wrap_pi(s->euler_rad[2] + s->euler_rate_rad_s[2] * dt_s);

    float accel[3];
    fc_euler_accel_limit(s->euler_rad, cfg->accel_max_rad_s2, accel);
    shape_axis(s, cfg, 0, roll_cmd_rad, accel[0], dt_s);
    shape_axis(s, cfg, 1, pitch_cmd_rad, accel[1], dt_s);
    if (hold_yaw) {
        shape_axis(s, cfg, 2, fc_wrap_pi(yaw_cmd_rad), accel[2], dt_s);
    } else {
        s->euler_rate_rad_s[2] =
            fc_shape_ang_vel(s->euler_rate_rad_s[2], yaw_rate_cmd_rad_s, accel[2], dt_s);
    }
    /* Limit in the body frame, where ATC_RATE_*_MAX are defined, and bring the
     * limited rates back to the Euler axes the target integrates on. */
    fc_euler_rate_to_ang_vel(s->euler_rad, s->euler_rate_rad_s, s->ang_vel_frd_rad_s);
    fc_ang_vel_limit(s->ang_vel_frd_rad_s, cfg->rate_max_rad_s);
    fc_ang_vel_to_euler_rate(s->euler_rad, s->ang_vel_frd_rad_s, s->euler_rate_rad_s);
}
