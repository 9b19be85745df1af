/*
 * fc_control.c - attitude stage, rate loop and throttle path of the core
 * (see fc_control.h for the order of the blocks).
 */
#include "fc_control.h"

#include "fc_math.h"

void fc_control_reset(fc_core_t *c, bool reset_mixer)
{
    for (int i = 0; i < 3; i++) {
        fc_rate_pid_reset(&c->pid[i]);
    }
    fc_trim_reset(&c->trim);
    fc_alt_ctrl_reset(&c->alt_ctrl);
    if (reset_mixer) {
        fc_mixer_reset(&c->mixer, &c->cfg.mix);
    }
    fc_sysid_stop(&c->sysid); /* arming, disarming, landing: no sweep carries over */
    for (int i = 0; i < 3; i++) {
        c->att_err_frd_rad[i] = 0.0f;
        c->rate_target_frd_rad_s[i] = 0.0f;
        c->pid_out_us[i] = 0.0f;
    }
    c->trim_us[0] = 0.0f;
    c->trim_us[1] = 0.0f;
    c->cr_us = 0.0f;
    c->cp_us = 0.0f;
    c->cy_us = 0.0f;
    c->throttle_us = c->cfg.mix.pwm_min_us;
}

/* A SYSTEMID sample on the attitude inputs (SID_AXIS 1-6): [rad] or [rad/s]. */
static float sysid_on(const fc_core_t *c, uint8_t axis_a, uint8_t axis_b, float sid)
{
    const uint8_t a = c->sysid.axis;
    return (c->sysid.active && (a == axis_a || a == axis_b)) ? sid * FC_DEG_TO_RAD_F : 0.0f;
}

/* Attitude stage: (shaped) target -> error e on the state -> rate targets.
 * sid: the SYSTEMID sample of this step (0 when no sweep runs). */
static void run_attitude(fc_core_t *c, const fc_vehicle_state_t *vs, float dt_s, float e[3],
                         float sid)
{
    const float angle_max = c->cfg.angle_max_rad;
    const float roll_t = fc_constrainf(
        c->in.roll_target_rad + sysid_on(c, FC_SID_INPUT_ROLL, FC_SID_RECOVER_ROLL, sid),
        -angle_max, angle_max);
    const float pitch_t = fc_constrainf(
        c->in.pitch_target_rad + sysid_on(c, FC_SID_INPUT_PITCH, FC_SID_RECOVER_PITCH, sid),
        -angle_max, angle_max);
    const bool hold_yaw = c->in.yaw_hold != 0 && c->cfg.att.ang_p[2] > 0.0f;
    const float yaw_rate_ff = ((c->in.yaw_hold != 0) ? 0.0f : c->in.yaw_rate_target_rad_s)
                              + sysid_on(c, FC_SID_INPUT_YAW, FC_SID_RECOVER_YAW, sid);
    /* The "recovery" axes excite the raw command path (ArduCopter turns its
     * body-frame feed-forward off for them). */
    const bool recover = c->sysid.active && c->sysid.axis >= FC_SID_RECOVER_ROLL
                         && c->sysid.axis <= FC_SID_RECOVER_YAW;
    const float yaw_now = vs->euler_rad[2];
    if (c->cfg.shaper.enable && !recover) {
        if (c->spool != FC_SPOOL_FLIGHT) {
            /* On the ground, as ArduCopter's make_safe_ground_handling: the
             * heading target rests on the vehicle's heading, while roll and
             * pitch keep shaping toward their commands. */
            fc_shaper_reset_yaw(&c->shaper, yaw_now);
        }
        fc_shaper_update(&c->shaper, &c->cfg.shaper, roll_t, pitch_t, c->in.yaw_target_rad,
                         yaw_rate_ff, hold_yaw, dt_s);
        if (!hold_yaw) {
            fc_shaper_set_yaw(&c->shaper, yaw_now); /* rate damping: no heading error */
        }
        const float *t = c->shaper.euler_rad;
        float q_t[4], q_err[4];
        fc_quat_from_euler(t[0], t[1], t[2], q_t);
        fc_vehicle_att_error_q(vs, q_t, q_err, e);
        (void)fc_attitude_rate_targets_ff(&c->cfg.att, e, q_err, c->shaper.ang_vel_frd_rad_s,
                                          vs->rate_frd_rad_s[2], c->rate_target_frd_rad_s);
        for (int i = 0; i < 3; i++) {
            c->att_target_rad[i] = t[i];
        }
    } else {
        fc_vehicle_att_error(vs, roll_t, pitch_t, c->in.yaw_target_rad, hold_yaw, e);
        fc_attitude_rate_targets(&c->cfg.att, e, yaw_rate_ff, c->rate_target_frd_rad_s);
        c->att_target_rad[0] = roll_t;
        c->att_target_rad[1] = pitch_t;
        c->att_target_rad[2] = hold_yaw ? c->in.yaw_target_rad : yaw_now;
        /* Kept on the command, so switching shaping on continues from here. */
        fc_shaper_reset(&c->shaper, c->att_target_rad);
    }
}

void fc_control_rate_step(fc_core_t *c, const fc_vehicle_state_t *vs, float dt_s)
{
    for (int i = 0; i < 3; i++) {
        c->rate_frd_rad_s[i] = vs->rate_frd_rad_s[i]; /* as this step used it, for the host */
    }
    /* SYSTEMID: ends by itself, and (as ArduCopter) when the tilt passes ANGLE_MAX. */
    const float sid = fc_sysid_update(&c->sysid, &c->cfg.sysid, c->last_imu_ns);
    if (c->sysid.active) {
        if (fabsf(vs->euler_rad[0]) > c->cfg.angle_max_rad
            || fabsf(vs->euler_rad[1]) > c->cfg.angle_max_rad) {
            fc_sysid_stop(&c->sysid);
        }
    }
    float e[3];
    run_attitude(c, vs, dt_s, e, sid);
    if (c->sysid.active && c->sysid.axis >= FC_SID_RATE_ROLL
        && c->sysid.axis <= FC_SID_RATE_YAW) {
        c->rate_target_frd_rad_s[c->sysid.axis - FC_SID_RATE_ROLL] += sid * FC_DEG_TO_RAD_F;
    }

    const bool airborne = c->spool_logic.airborne != 0;
    const bool integrate = c->spool == FC_SPOOL_FLIGHT && airborne;
    const uint8_t sat = c->mixer.sat_flags;
    const bool limit[3] = {(sat & FC_SAT_ROLL) != 0, (sat & FC_SAT_PITCH) != 0,
                           (sat & FC_SAT_YAW) != 0};
    float out_us[3];
    for (int i = 0; i < 3; i++) {
        out_us[i] = fc_rate_pid_update(&c->pid[i], c->rate_target_frd_rad_s[i],
                                       vs->rate_frd_rad_s[i], dt_s, limit[i], integrate);
        if (!integrate) {
            fc_rate_pid_reset_integrator(&c->pid[i]); /* no ground wind-up */
        }
        c->pid_out_us[i] = out_us[i];
    }
    if (c->sysid.active && c->sysid.axis >= FC_SID_MIX_ROLL && c->sysid.axis <= FC_SID_MIX_YAW) {
        const int i = c->sysid.axis - FC_SID_MIX_ROLL;
        out_us[i] += sid * c->cfg.pid[i].out_us_per_unit;
    }
    fc_trim_update(&c->trim, &c->cfg.trim, airborne, e[0], e[1], dt_s, c->trim_us);

    for (int i = 0; i < 3; i++) {
        c->att_err_frd_rad[i] = e[i];
    }
    c->cr_us = out_us[0] + c->trim_us[0];
    c->cp_us = out_us[1] + c->trim_us[1];
    c->cy_us = out_us[2];
    c->loop_count++;
}

void fc_control_throttle_step(fc_core_t *c, const fc_vehicle_state_t *vs, float dt_s)
{
    const fc_mixer_config_t *mix = &c->cfg.mix;
    const float range_us = mix->pwm_max_us - mix->pwm_min_us;
    if (c->spool == FC_SPOOL_FLIGHT) {
        int mode = c->in.alt_mode;
        float target = c->in.alt_target_m;
        if (mode == FC_ALT_MODE_CLIMB) {
            target = c->in.climb_target_m_s;
        } else if (mode == FC_ALT_MODE_THROTTLE) {
            target = c->in.throttle;
        } else if (!fc_spool_wants_flight(&c->cfg.spool, &c->in)) {
            /* Landing (target below the lift-off height): descend at least at
             * LAND_SPEED so touchdown is a definite event for the land detector,
             * rather than the asymptotic approach of a position loop. */
            mode = FC_ALT_MODE_CLIMB;
            target = fc_constrainf(c->cfg.alt.pos_p * (c->in.alt_target_m - vs->alt_m),
                                   -c->cfg.alt.speed_dn_m_s, -c->cfg.spool.land_speed_m_s);
        }
        const uint8_t sat = c->mixer.sat_flags;
        const float thr = fc_alt_ctrl_update(&c->alt_ctrl, &c->cfg.alt, mode, target, vs->alt_m,
                                             vs->climb_m_s, vs->accel_up_m_s2, vs->cos_tilt,
                                             (sat & FC_SAT_THR_HIGH) != 0,
                                             (sat & FC_SAT_THR_LOW) != 0, dt_s);
        c->throttle_us = mix->pwm_min_us + thr * range_us;
        if (c->sysid.active && c->sysid.axis == FC_SID_MIX_THROTTLE) {
            c->throttle_us += c->sysid.sample * range_us;
        }
    } else if (c->spool == FC_SPOOL_GROUND_IDLE) {
        c->throttle_us = mix->pwm_min_us + c->cfg.spool.spin_arm * range_us;
    } else {
        c->throttle_us = mix->pwm_min_us;
    }
}
