/*
 * fc_control.c - attitude stage, rate loop and throttle path of the control
 * law (see fc_control.h for the order of the blocks).
 */
#include "fc_control.h"

#include "fc_math.h"
#include "fc_mixer.h"

/* The PID terms as logs and PID_TUNING read them. A step and a reset are the
 * only places the PID info moves, so both end here. */
static void report_pids(const fc_control_state_t *s, fc_control_out_t *out)
{
    for (int i = 0; i < 3; i++) {
        const fc_pid_info_t *info = &s->pid[i].info;
        out->pid_p_us[i] = info->p_us;
        out->pid_i_us[i] = info->i_us;
        out->pid_d_us[i] = info->d_us;
        out->pid_ff_us[i] = info->ff_us;
        out->limited[i] = info->limited;
    }
}

void fc_control_reset(fc_control_state_t *s, const fc_control_config_t *cfg,
                      fc_control_out_t *out)
{
    for (int i = 0; i < 3; i++) {
        fc_rate_pid_reset(&s->pid[i]);
    }
    fc_trim_reset(&s->trim);
    fc_alt_ctrl_reset(&s->alt_ctrl);
    fc_sysid_stop(&s->sysid); /* arming, disarming, landing: no sweep carries over */
    for (int i = 0; i < 3; i++) {
        out->att_error_frd_rad[i] = 0.0f;
        out->rate_target_frd_rad_s[i] = 0.0f;
        out->pid_out_us[i] = 0.0f;
    }
    out->trim_us[0] = 0.0f;
    out->trim_us[1] = 0.0f;
    out->cr_us = 0.0f;
    out->cp_us = 0.0f;
    out->cy_us = 0.0f;
    out->throttle_us = cfg->pwm_min_us;
    report_pids(s, out);
}

void fc_control_init(fc_control_state_t *s, const fc_control_config_t *cfg, float rate_dt_s,
                     float throttle_dt_s, fc_control_out_t *out)
{
    const fc_control_out_t zero_out = {0};
    *out = zero_out;
    for (int i = 0; i < 3; i++) {
        fc_rate_pid_init(&s->pid[i], &cfg->pid[i], rate_dt_s);
    }
    fc_alt_ctrl_init(&s->alt_ctrl, &cfg->alt, throttle_dt_s);
    const fc_sysid_t idle = {0};
    s->sysid = idle;
    fc_shaper_reset(&s->shaper, out->att_target_rad);
    fc_control_reset(s, cfg, out);
}

void fc_control_configure(fc_control_state_t *s, const fc_control_config_t *cfg,
                          float throttle_dt_s)
{
    for (int i = 0; i < 3; i++) {
        /* Each PID keeps the period it last stepped at (fc_rate_pid_update). */
        fc_rate_pid_configure(&s->pid[i], &cfg->pid[i], s->pid[i].dt_s);
    }
    fc_alt_ctrl_configure(&s->alt_ctrl, &cfg->alt, throttle_dt_s);
}

/* A SYSTEMID sample on the attitude inputs (SID_AXIS 1-6): [rad] or [rad/s]. */
static float sysid_on(const fc_sysid_t *sysid, uint8_t axis_a, uint8_t axis_b, float sid)
{
    const uint8_t a = sysid->axis;
    return (sysid->active && (a == axis_a || a == axis_b)) ? sid * FC_DEG_TO_RAD_F : 0.0f;
}

/* The attitude command of this step, the sweep on it, within ANGLE_MAX. */
typedef struct attitude_cmd {
    float roll_rad, pitch_rad;
    float yaw_rad;         /* heading target, used when hold_yaw */
    float yaw_rate_rad_s;  /* yaw rate feed-forward (the rate target when not holding) */
    bool hold_yaw;
    bool recover;          /* a "recovery" sweep axis: the raw command path */
} attitude_cmd_t;

static attitude_cmd_t attitude_command(const fc_control_state_t *s,
                                       const fc_control_config_t *cfg,
                                       const fc_core_inputs_t *cmd, float sid)
{
    const float angle_max = cfg->angle_max_rad;
    attitude_cmd_t a;
    a.roll_rad = fc_constrainf(
        cmd->roll_target_rad + sysid_on(&s->sysid, FC_SID_INPUT_ROLL, FC_SID_RECOVER_ROLL, sid),
        -angle_max, angle_max);
    a.pitch_rad = fc_constrainf(
        cmd->pitch_target_rad
            + sysid_on(&s->sysid, FC_SID_INPUT_PITCH, FC_SID_RECOVER_PITCH, sid),
        -angle_max, angle_max);
    a.yaw_rad = cmd->yaw_target_rad;
    a.hold_yaw = cmd->yaw_hold != 0 && cfg->att.ang_p[2] > 0.0f;
    a.yaw_rate_rad_s = ((cmd->yaw_hold != 0) ? 0.0f : cmd->yaw_rate_target_rad_s)
                       + sysid_on(&s->sysid, FC_SID_INPUT_YAW, FC_SID_RECOVER_YAW, sid);
    /* The "recovery" axes excite the raw command path (ArduCopter turns its
     * body-frame feed-forward off for them). */
    a.recover = s->sysid.active && s->sysid.axis >= FC_SID_RECOVER_ROLL
                && s->sysid.axis <= FC_SID_RECOVER_YAW;
    return a;
}

/* Attitude stage with input shaping: the shaped target, its error e on the
 * state and the rate targets with the shaper's angular-velocity feed-forward. */
static void run_shaped(fc_control_state_t *s, const fc_control_config_t *cfg, uint8_t spool,
                       const attitude_cmd_t *a, const fc_vehicle_state_t *vs, float dt_s,
                       float e[3], fc_control_out_t *out)
{
    const float yaw_now = vs->euler_rad[2];
    if (spool != FC_SPOOL_FLIGHT) {
        /* On the ground, as ArduCopter's make_safe_ground_handling: the
         * heading target rests on the vehicle's heading, while roll and
         * pitch keep shaping toward their commands. */
        fc_shaper_reset_yaw(&s->shaper, yaw_now);
    }
    fc_shaper_update(&s->shaper, &cfg->shaper, a->roll_rad, a->pitch_rad, a->yaw_rad,
                     a->yaw_rate_rad_s, a->hold_yaw, dt_s);
    if (!a->hold_yaw) {
        fc_shaper_set_yaw(&s->shaper, yaw_now); /* rate damping: no heading error */
    }
    const float *t = s->shaper.euler_rad;
    float q_t[4], q_err[4];
    fc_quat_from_euler(t[0], t[1], t[2], q_t);
    fc_vehicle_att_error_q(vs, q_t, q_err, e);
    (void)fc_attitude_rate_targets_ff(&cfg->att, e, q_err, s->shaper.ang_vel_frd_rad_s,
                                      vs->rate_frd_rad_s[2], out->rate_target_frd_rad_s);
    for (int i = 0; i < 3; i++) {
        out->att_target_rad[i] = t[i];
    }
}

/* Attitude stage: (shaped) target -> error e on the state -> rate targets.
 * sid: the SYSTEMID sample of this step (0 when no sweep runs). */
static void run_attitude(fc_control_state_t *s, const fc_control_config_t *cfg,
                         const fc_control_in_t *in, const fc_vehicle_state_t *vs, float dt_s,
                         float e[3], float sid, fc_control_out_t *out)
{
    const attitude_cmd_t a = attitude_command(s, cfg, &in->cmd, sid);
    if (cfg->shaper.enable && !a.recover) {
        run_shaped(s, cfg, in->spool, &a, vs, dt_s, e, out);
        return;
    }
    fc_vehicle_att_error(vs, a.roll_rad, a.pitch_rad, a.yaw_rad, a.hold_yaw, e);
    fc_attitude_rate_targets(&cfg->att, e, a.yaw_rate_rad_s, out->rate_target_frd_rad_s);
    out->att_target_rad[0] = a.roll_rad;
    out->att_target_rad[1] = a.pitch_rad;
    out->att_target_rad[2] = a.hold_yaw ? a.yaw_rad : vs->euler_rad[2];
    /* Kept on the command, so switching shaping on continues from here. */
    fc_shaper_reset(&s->shaper, out->att_target_rad);
}

/* The rate PIDs on the rate targets; out_us receives their outputs. */
static void run_rate_pids(fc_control_state_t *s, const fc_control_in_t *in,
                          const fc_vehicle_state_t *vs, float dt_s, float out_us[3],
                          fc_control_out_t *out)
{
    const bool integrate = in->spool == FC_SPOOL_FLIGHT && in->airborne != 0;
    const uint8_t sat = in->sat_flags;
    const bool limit[3] = {(sat & FC_SAT_ROLL) != 0, (sat & FC_SAT_PITCH) != 0,
                           (sat & FC_SAT_YAW) != 0};
    for (int i = 0; i < 3; i++) {
        out_us[i] = fc_rate_pid_update(&s->pid[i], out->rate_target_frd_rad_s[i],
                                       vs->rate_frd_rad_s[i], dt_s, limit[i], integrate);
        if (!integrate) {
            fc_rate_pid_reset_integrator(&s->pid[i]); /* no ground wind-up */
        }
        out->pid_out_us[i] = out_us[i];
    }
    report_pids(s, out);
}

void fc_control_rate_step(fc_control_state_t *s, const fc_control_config_t *cfg,
                          const fc_control_in_t *in, const fc_vehicle_state_t *vs, float dt_s,
                          fc_control_out_t *out)
{
    for (int i = 0; i < 3; i++) {
        out->rate_frd_rad_s[i] = vs->rate_frd_rad_s[i]; /* as this step used it, for the host */
    }
    /* SYSTEMID: ends by itself, and (as ArduCopter) when the tilt passes ANGLE_MAX. */
    const float sid = fc_sysid_update(&s->sysid, &cfg->sysid, in->now_ns);
    if (s->sysid.active) {
        if (fabsf(vs->euler_rad[0]) > cfg->angle_max_rad
            || fabsf(vs->euler_rad[1]) > cfg->angle_max_rad) {
            fc_sysid_stop(&s->sysid);
        }
    }
    float e[3];
    run_attitude(s, cfg, in, vs, dt_s, e, sid, out);
    if (s->sysid.active && s->sysid.axis >= FC_SID_RATE_ROLL
        && s->sysid.axis <= FC_SID_RATE_YAW) {
        out->rate_target_frd_rad_s[s->sysid.axis - FC_SID_RATE_ROLL] += sid * FC_DEG_TO_RAD_F;
    }

    float out_us[3];
    run_rate_pids(s, in, vs, dt_s, out_us, out);
    if (s->sysid.active && s->sysid.axis >= FC_SID_MIX_ROLL
        && s->sysid.axis <= FC_SID_MIX_YAW) {
        const int i = s->sysid.axis - FC_SID_MIX_ROLL;
        out_us[i] += sid * cfg->pid[i].out_us_per_unit;
    }
    fc_trim_update(&s->trim, &cfg->trim, in->airborne != 0, e[0], e[1], dt_s, out->trim_us);

    for (int i = 0; i < 3; i++) {
        out->att_error_frd_rad[i] = e[i];
    }
    out->cr_us = out_us[0] + out->trim_us[0];
    out->cp_us = out_us[1] + out->trim_us[1];
    out->cy_us = out_us[2];
}

/* The altitude loop's mode and target: the host's, except while landing. */
static int vertical_target(const fc_control_config_t *cfg, const fc_core_inputs_t *cmd,
                           const fc_vehicle_state_t *vs, float *target)
{
    if (cmd->alt_mode == FC_ALT_MODE_CLIMB) {
        *target = cmd->climb_target_m_s;
        return FC_ALT_MODE_CLIMB;
    }
    if (cmd->alt_mode == FC_ALT_MODE_THROTTLE) {
        *target = cmd->throttle;
        return FC_ALT_MODE_THROTTLE;
    }
    if (!fc_spool_wants_flight(&cfg->spool, cmd)) {
        /* Landing (target below the lift-off height): descend at least at
         * LAND_SPEED so touchdown is a definite event for the land detector,
         * rather than the asymptotic approach of a position loop. */
        *target = fc_constrainf(cfg->alt.pos_p * (cmd->alt_target_m - vs->alt_m),
                                -cfg->alt.speed_dn_m_s, -cfg->spool.land_speed_m_s);
        return FC_ALT_MODE_CLIMB;
    }
    *target = cmd->alt_target_m;
    return cmd->alt_mode;
}

void fc_control_throttle_step(fc_control_state_t *s, const fc_control_config_t *cfg,
                              const fc_control_in_t *in, const fc_vehicle_state_t *vs,
                              float dt_s, fc_control_out_t *out)
{
    const float range_us = cfg->pwm_max_us - cfg->pwm_min_us;
    if (in->spool == FC_SPOOL_FLIGHT) {
        float target;
        const int mode = vertical_target(cfg, &in->cmd, vs, &target);
        const uint8_t sat = in->sat_flags;
        const float thr = fc_alt_ctrl_update(&s->alt_ctrl, &cfg->alt, mode, target, vs->alt_m,
                                             vs->climb_m_s, vs->accel_up_m_s2, vs->cos_tilt,
                                             (sat & FC_SAT_THR_HIGH) != 0,
                                             (sat & FC_SAT_THR_LOW) != 0,
                                             in->cmd.vibe_comp != 0, dt_s);
        out->throttle_us = cfg->pwm_min_us + thr * range_us;
        if (s->sysid.active && s->sysid.axis == FC_SID_MIX_THROTTLE) {
            out->throttle_us += s->sysid.sample * range_us;
        }
    } else if (in->spool == FC_SPOOL_GROUND_IDLE) {
        out->throttle_us = cfg->pwm_min_us + cfg->spool.spin_arm * range_us;
    } else {
        out->throttle_us = cfg->pwm_min_us;
    }
}
