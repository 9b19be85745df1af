/*
 * fc_core.c - the flight-controller chain (see fc_core.h for the order of
 * the blocks and when each runs).
 */
#include "fc_core.h"

#include <stddef.h>

#include "fc_math.h"

_Static_assert(sizeof(fc_core_status_t) == 248, "fc_core_status_t layout is mirrored in Python");

/* Ground truth older than this (relative to the latest IMU sample) no longer
 * counts as available: the blend weight then returns to the estimate. */
#define FC_GT_STALE_NS 100000000LL
/* dt limits for one IMU step: a longer gap (a paused simulation) is integrated
 * as 50 ms so the filters and integrators see a bounded step. */
#define FC_MAX_IMU_DT_S 0.05f
#define FC_MAX_IMU_DT_NS 50000000LL
/* GNSS-aided tilt needs a 3D fix (MAVLink GPS_FIX_TYPE_3D_FIX and better). */
#define FC_GNSS_AID_MIN_FIX 3
/* Filters are recomputed when the measured period moves by more than 1 %. */
#define FC_RETUNE_TOLERANCE 0.01f
/* Estimator gains while disarmed (on the ground, still): a critically damped
 * PI at 1 rad/s (s^2 + 2 s + 1) aligns and learns the gyro bias in about 5 s,
 * as a real flight controller calibrates its gyros before take-off; at arming
 * the slower flight gains (SB_AHRS_KP/KI) take over, bias kept. */
#define FC_AHRS_GROUND_KP 2.0f
#define FC_AHRS_GROUND_KI 1.0f
/* Landing: throttle at its floor and not descending this long. */
#define FC_LAND_DETECT_S 1.0f
#define FC_LAND_CLIMB_M_S 0.3f

/* ---- parameters -> block configurations -------------------------------- */

static void derive_configs(fc_core_t *c)
{
    const fc_params_t *p = &c->params;

    c->ins_cfg.gyro_cutoff_hz = p->ins_gyro_filter;
    c->ins_cfg.accel_cutoff_hz = p->ins_accel_filter;
    c->ins_cfg.notch_enable = p->ins_hntch_enable != 0;
    c->ins_cfg.notch_center_hz = p->ins_hntch_freq;
    c->ins_cfg.notch_bandwidth_hz = p->ins_hntch_bw;

    c->ahrs_cfg.kp = p->sb_ahrs_kp;
    c->ahrs_cfg.ki = p->sb_ahrs_ki;
    c->ahrs_cfg.kmag = (p->compass_use != 0) ? p->sb_ahrs_kmag : 0.0f;
    c->ahrs_cfg.trust_tc_s = p->sb_trust_tc;
    c->ahrs_cfg.trust_span_g = p->sb_trust_span;
    c->ahrs_cfg.bias_rate_hz = p->sb_bias_rate;
    c->ahrs_cfg.still_gyro_rad_s = p->sb_still_gyro;
    c->ahrs_cfg.still_acc_g = p->sb_still_acc;
    c->ahrs_cfg.trust_ema_enable = p->sb_trust_ema_en != 0;
    c->ahrs_cfg.bias_enable = p->sb_bias_en != 0;
    c->ahrs_cfg.kp_gnss = p->sb_ahrs_gps_kp;
    c->ahrs_cfg.ki_gnss = p->sb_ahrs_gps_ki;
    c->ahrs_ground_cfg = c->ahrs_cfg;
    c->ahrs_ground_cfg.kp = fmaxf(p->sb_ahrs_kp, FC_AHRS_GROUND_KP);
    c->ahrs_ground_cfg.ki = fmaxf(p->sb_ahrs_ki, FC_AHRS_GROUND_KI);

    c->att_cfg.ang_p[0] = p->atc_ang_rll_p;
    c->att_cfg.ang_p[1] = p->atc_ang_pit_p;
    c->att_cfg.ang_p[2] = p->atc_ang_yaw_p;
    c->att_cfg.rate_max_rad_s[0] = p->atc_rate_r_max * FC_DEG_TO_RAD_F;
    c->att_cfg.rate_max_rad_s[1] = p->atc_rate_p_max * FC_DEG_TO_RAD_F;
    c->att_cfg.rate_max_rad_s[2] = p->atc_rate_y_max * FC_DEG_TO_RAD_F;
    c->angle_max_rad = p->angle_max * 0.01f * FC_DEG_TO_RAD_F;

    c->shaper_cfg.enable = p->atc_rate_ff_enab != 0 && p->sb_shape_en != 0;
    c->shaper_cfg.input_tc_s = p->atc_input_tc;
    c->shaper_cfg.accel_max_rad_s2[0] = p->atc_accel_r_max * 0.01f * FC_DEG_TO_RAD_F;
    c->shaper_cfg.accel_max_rad_s2[1] = p->atc_accel_p_max * 0.01f * FC_DEG_TO_RAD_F;
    c->shaper_cfg.accel_max_rad_s2[2] = p->atc_accel_y_max * 0.01f * FC_DEG_TO_RAD_F;
    for (int i = 0; i < 3; i++) {
        c->shaper_cfg.rate_max_rad_s[i] = c->att_cfg.rate_max_rad_s[i];
    }

    /* ArduPilot's normalised mixer output 1.0 moves a motor by half the PWM range
     * (its quad-X roll/pitch factors are normalised to 0.5). */
    const float range_us = (float)(p->mot_pwm_max - p->mot_pwm_min);
    const float gains[3][8] = {
        {p->atc_rat_rll_p, p->atc_rat_rll_i, p->atc_rat_rll_d, p->atc_rat_rll_ff,
         p->atc_rat_rll_imax, p->atc_rat_rll_fltt, p->atc_rat_rll_flte, p->atc_rat_rll_fltd},
        {p->atc_rat_pit_p, p->atc_rat_pit_i, p->atc_rat_pit_d, p->atc_rat_pit_ff,
         p->atc_rat_pit_imax, p->atc_rat_pit_fltt, p->atc_rat_pit_flte, p->atc_rat_pit_fltd},
        {p->atc_rat_yaw_p, p->atc_rat_yaw_i, p->atc_rat_yaw_d, p->atc_rat_yaw_ff,
         p->atc_rat_yaw_imax, p->atc_rat_yaw_fltt, p->atc_rat_yaw_flte, p->atc_rat_yaw_fltd},
    };
    for (int i = 0; i < 3; i++) {
        fc_rate_pid_config_t *pc = &c->pid_cfg[i];
        pc->kp = gains[i][0];
        pc->ki = gains[i][1];
        pc->kd = gains[i][2];
        pc->kff = gains[i][3];
        pc->imax = gains[i][4];
        pc->fltt_hz = gains[i][5];
        pc->flte_hz = gains[i][6];
        pc->fltd_hz = gains[i][7];
        pc->out_us_per_unit = 0.5f * range_us;
        pc->d_clamp_us = p->sb_dclamp_us;
        pc->d_clamp_enable = p->sb_dclamp_en != 0;
        pc->d_pt2x2 = p->sb_dfilt_en != 0;
        pc->antiwindup = (i == 2) ? (p->sb_yaw_aw_en != 0) : true;
    }

    c->trim_cfg.enable = p->sb_trim_en != 0;
    c->trim_cfg.ramp_enable = p->sb_trim_ramp_en != 0;
    c->trim_cfg.window_s = p->sb_trim_win_s;
    c->trim_cfg.gain_us_per_rad = p->sb_trim_gain;
    c->trim_cfg.max_us = p->sb_trim_max_us;
    c->trim_cfg.ramp_s = p->sb_trim_ramp_s;

    c->mix_cfg.pwm_min_us = (float)p->mot_pwm_min;
    c->mix_cfg.pwm_max_us = (float)p->mot_pwm_max;
    c->mix_cfg.spin_min = p->mot_spin_min;
    c->mix_cfg.spin_max = p->mot_spin_max;
    c->mix_cfg.yaw_headroom_us = (float)p->mot_yaw_headroom;
    c->mix_cfg.slew_up_time_s = p->mot_slew_up_time;
    c->mix_cfg.slew_dn_time_s = p->mot_slew_dn_time;
    c->mix_cfg.slew_enable = p->sb_slew_en != 0;

    c->alt_cfg.pos_p = p->psc_posz_p;
    c->alt_cfg.vel_p = p->psc_velz_p;
    c->alt_cfg.acc_p = p->psc_accz_p;
    c->alt_cfg.acc_i = p->psc_accz_i;
    c->alt_cfg.acc_imax = p->psc_accz_imax;
    c->alt_cfg.acc_flte_hz = p->psc_accz_flte;
    c->alt_cfg.speed_up_m_s = p->pilot_speed_up * 0.01f;
    c->alt_cfg.speed_dn_m_s =
        ((p->pilot_speed_dn > 0.0f) ? p->pilot_speed_dn : p->pilot_speed_up) * 0.01f;
    c->alt_cfg.hover_throttle = p->mot_thst_hover;

    c->sysid_cfg.axis = (uint8_t)p->sid_axis; /* range 0..13 (fc_params.def) */
    c->sysid_cfg.magnitude = p->sid_magnitude;
    c->sysid_cfg.f_start_hz = p->sid_f_start_hz;
    c->sysid_cfg.f_stop_hz = p->sid_f_stop_hz;
    c->sysid_cfg.t_fade_in_s = p->sid_t_fade_in;
    c->sysid_cfg.t_rec_s = p->sid_t_rec;
    c->sysid_cfg.t_fade_out_s = p->sid_t_fade_out;

    c->loop_period_s = 1.0f / (float)p->sb_loop_hz;
    c->pwm_period_ns = 1000000000LL / (int64_t)p->sb_pwm_hz;
}

static float pwm_period_s(const fc_core_t *c)
{
    return (float)c->pwm_period_ns * 1e-9f;
}

void fc_core_apply_params(fc_core_t *c)
{
    derive_configs(c);
    (void)fc_ins_configure(&c->ins, &c->ins_cfg, c->imu_dt_s);
    fc_mahony_configure(&c->ahrs, c->ahrs_ground ? &c->ahrs_ground_cfg : &c->ahrs_cfg);
    for (int i = 0; i < 3; i++) {
        fc_rate_pid_configure(&c->pid[i], &c->pid_cfg[i], c->loop_dt_s);
    }
    fc_alt_ctrl_configure(&c->alt_ctrl, &c->alt_cfg, pwm_period_s(c));
}

/* Combinations a single range check cannot see. */
static bool params_consistent(const fc_params_t *p)
{
    return p->mot_pwm_min + 100 <= p->mot_pwm_max && p->mot_spin_arm <= p->mot_spin_min
           && p->mot_spin_min < p->mot_spin_max
           && p->ins_hntch_freq > 0.5f * p->ins_hntch_bw;
}

fc_status_t fc_core_set_param(fc_core_t *c, uint16_t index, float value)
{
    fc_params_t candidate = c->params;
    fc_status_t st = fc_param_set(&candidate, index, value);
    if (st != FC_OK) {
        return st;
    }
    if (!params_consistent(&candidate)) {
        return FC_ERR_RANGE;
    }
    c->params = candidate;
    fc_core_apply_params(c);
    return FC_OK;
}

fc_status_t fc_core_get_param(const fc_core_t *c, uint16_t index, float *value)
{
    return fc_param_get(&c->params, index, value);
}

/* ---- life cycle --------------------------------------------------------- */

/* Controllers back to rest. The mixer's slew state is kept unless reset_mixer
 * (arming and disarming): on landing the outputs slew down to idle, no dip. */
static void reset_controllers(fc_core_t *c, bool reset_mixer)
{
    for (int i = 0; i < 3; i++) {
        fc_rate_pid_reset(&c->pid[i]);
    }
    fc_trim_reset(&c->trim);
    fc_alt_ctrl_reset(&c->alt_ctrl);
    if (reset_mixer) {
        fc_mixer_reset(&c->mixer, &c->mix_cfg);
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
    c->throttle_us = c->mix_cfg.pwm_min_us;
    c->airborne = 0;
    c->landed_s = 0.0f;
}

void fc_core_reset(fc_core_t *c)
{
    fc_core_inputs_t in = {0};
    in.alt_mode = FC_ALT_MODE_ALTITUDE;
    c->in = in;
    c->imu_dt_s = 0.001f; /* until the first measured IMU period */
    c->loop_dt_s = 0.001f;
    derive_configs(c);
    (void)fc_ins_init(&c->ins, &c->ins_cfg, c->imu_dt_s);
    fc_mahony_init(&c->ahrs, &c->ahrs_ground_cfg);
    c->ahrs_ground = true;
    for (int i = 0; i < 3; i++) {
        fc_rate_pid_init(&c->pid[i], &c->pid_cfg[i], c->loop_dt_s);
    }
    fc_blend_reset(&c->blend, 0.0f);
    fc_alt_est_reset(&c->alt_est);
    fc_alt_ctrl_init(&c->alt_ctrl, &c->alt_cfg, pwm_period_s(c));
    fc_gnss_aid_reset(&c->gnss_aid);
    c->gnss_aid_count = 0;
    fc_sysid_t sid = {0};
    c->sysid = sid;
    reset_controllers(c, true);

    c->have_imu = false;
    c->last_imu_ns = 0;
    c->loop_accum_s = 0.0f;
    c->next_pwm_ns = 0;
    fc_quat_identity(c->gt_q_wxyz);
    c->gt_att_ns = 0;
    c->have_gt_att = false;
    c->gt_alt_m = 0.0f;
    c->gt_climb_m_s = 0.0f;
    c->gt_nav_ns = 0;
    c->have_gt_nav = false;
    fc_gnss_store_t g = {0};
    c->gnss = g;
    for (int i = 0; i < 3; i++) {
        c->att_target_rad[i] = 0.0f;
        c->rate_frd_rad_s[i] = 0.0f;
    }
    fc_shaper_reset(&c->shaper, c->att_target_rad);
    c->spool = FC_SPOOL_SHUT_DOWN;
    c->armed_prev = 0;
    c->imu_count = 0;
    c->loop_count = 0;
    c->pwm_count = 0;
    c->rejected_count = 0;
    fc_core_status_t s = {0};
    c->status = s;
}

void fc_core_init(fc_core_t *c)
{
    fc_params_set_defaults(&c->params);
    fc_core_reset(c);
}

/* ---- inputs -------------------------------------------------------------- */

void fc_core_set_armed(fc_core_t *c, bool armed)
{
    c->in.armed = armed ? 1u : 0u;
}

fc_status_t fc_core_set_attitude_target(fc_core_t *c, float roll_rad, float pitch_rad)
{
    if (!fc_finitef(roll_rad) || !fc_finitef(pitch_rad)) {
        return FC_ERR_NONFINITE;
    }
    c->in.roll_target_rad = roll_rad;
    c->in.pitch_target_rad = pitch_rad;
    return FC_OK;
}

fc_status_t fc_core_set_yaw_target(fc_core_t *c, float yaw_rad)
{
    if (!fc_finitef(yaw_rad)) {
        return FC_ERR_NONFINITE;
    }
    c->in.yaw_target_rad = fc_wrap_pi(yaw_rad);
    c->in.yaw_hold = 1;
    c->in.yaw_rate_target_rad_s = 0.0f;
    return FC_OK;
}

fc_status_t fc_core_set_yaw_rate_target(fc_core_t *c, float yaw_rate_rad_s)
{
    if (!fc_finitef(yaw_rate_rad_s)) {
        return FC_ERR_NONFINITE;
    }
    c->in.yaw_rate_target_rad_s = yaw_rate_rad_s;
    c->in.yaw_hold = 0;
    return FC_OK;
}

fc_status_t fc_core_set_altitude_target(fc_core_t *c, float alt_m)
{
    if (!fc_finitef(alt_m)) {
        return FC_ERR_NONFINITE;
    }
    c->in.alt_target_m = alt_m;
    c->in.alt_mode = FC_ALT_MODE_ALTITUDE;
    return FC_OK;
}

fc_status_t fc_core_set_climb_target(fc_core_t *c, float climb_m_s)
{
    if (!fc_finitef(climb_m_s)) {
        return FC_ERR_NONFINITE;
    }
    c->in.climb_target_m_s = climb_m_s;
    c->in.alt_mode = FC_ALT_MODE_CLIMB;
    return FC_OK;
}

fc_status_t fc_core_set_throttle(fc_core_t *c, float throttle)
{
    if (!fc_finitef(throttle)) {
        return FC_ERR_NONFINITE;
    }
    if (throttle < 0.0f || throttle > 1.0f) {
        return FC_ERR_RANGE;
    }
    c->in.throttle = throttle;
    c->in.alt_mode = FC_ALT_MODE_THROTTLE;
    return FC_OK;
}

fc_status_t fc_core_set_accel_ref(fc_core_t *c, const float accel_ned_m_s2[3])
{
    return fc_mahony_set_accel_ref(&c->ahrs, accel_ned_m_s2);
}

/* ---- system identification ---------------------------------------------- */

fc_status_t fc_core_sysid_start(fc_core_t *c)
{
    return fc_sysid_start(&c->sysid, &c->sysid_cfg, c->last_imu_ns) ? FC_OK : FC_ERR_ARG;
}

void fc_core_sysid_stop(fc_core_t *c)
{
    fc_sysid_stop(&c->sysid);
}

/* ---- the rate loop (decimated IMU rate) -------------------------------- */

static bool gt_fresh(int64_t now_ns, int64_t gt_ns, bool have)
{
    return have && now_ns - gt_ns <= FC_GT_STALE_NS && gt_ns - now_ns <= FC_GT_STALE_NS;
}

/* A SYSTEMID sample on the attitude inputs (SID_AXIS 1-6): [rad] or [rad/s]. */
static float sysid_on(const fc_core_t *c, uint8_t axis_a, uint8_t axis_b, float sid)
{
    const uint8_t a = c->sysid.axis;
    return (c->sysid.active && (a == axis_a || a == axis_b)) ? sid * FC_DEG_TO_RAD_F : 0.0f;
}

/* Attitude stage: (shaped) target -> blended error e -> rate targets. sid: the
 * SYSTEMID sample of this step (0 when no sweep runs). */
static void run_attitude(fc_core_t *c, float w, float dt_s, float e[3], float sid)
{
    const float roll_t = fc_constrainf(
        c->in.roll_target_rad + sysid_on(c, FC_SID_INPUT_ROLL, FC_SID_RECOVER_ROLL, sid),
        -c->angle_max_rad, c->angle_max_rad);
    const float pitch_t = fc_constrainf(
        c->in.pitch_target_rad + sysid_on(c, FC_SID_INPUT_PITCH, FC_SID_RECOVER_PITCH, sid),
        -c->angle_max_rad, c->angle_max_rad);
    const bool hold_yaw = c->in.yaw_hold != 0 && c->att_cfg.ang_p[2] > 0.0f;
    const float yaw_rate_ff = ((c->in.yaw_hold != 0) ? 0.0f : c->in.yaw_rate_target_rad_s)
                              + sysid_on(c, FC_SID_INPUT_YAW, FC_SID_RECOVER_YAW, sid);
    /* The "recovery" axes excite the raw command path (ArduCopter turns its
     * body-frame feed-forward off for them). */
    const bool recover = c->sysid.active && c->sysid.axis >= FC_SID_RECOVER_ROLL
                         && c->sysid.axis <= FC_SID_RECOVER_YAW;
    float euler[3];
    fc_quat_to_euler(c->ahrs.q_wxyz, euler);
    if (c->shaper_cfg.enable && !recover) {
        if (c->spool != FC_SPOOL_FLIGHT) {
            /* On the ground, as ArduCopter's make_safe_ground_handling: the
             * heading target rests on the vehicle's heading, while roll and
             * pitch keep shaping toward their commands. */
            fc_shaper_reset_yaw(&c->shaper, euler[2]);
        }
        fc_shaper_update(&c->shaper, &c->shaper_cfg, roll_t, pitch_t, c->in.yaw_target_rad,
                         yaw_rate_ff, hold_yaw, dt_s);
        if (!hold_yaw) {
            fc_shaper_set_yaw(&c->shaper, euler[2]); /* rate damping: no heading error */
        }
        const float *t = c->shaper.euler_rad;
        float q_t[4], q_err[4];
        fc_quat_from_euler(t[0], t[1], t[2], q_t);
        fc_attitude_error_q(c->ahrs.q_wxyz, q_t, q_err, e);
        if (w > 0.0f) {
            float e_gt[3], q_err_gt[4];
            fc_attitude_error_q(c->gt_q_wxyz, q_t, q_err_gt, e_gt);
            fc_blend_mix(w, e, e_gt, e, 3);
        }
        (void)fc_attitude_rate_targets_ff(&c->att_cfg, e, q_err, c->shaper.ang_vel_frd_rad_s,
                                          c->rate_frd_rad_s[2], c->rate_target_frd_rad_s);
        for (int i = 0; i < 3; i++) {
            c->att_target_rad[i] = t[i];
        }
    } else {
        fc_attitude_error(c->ahrs.q_wxyz, roll_t, pitch_t, c->in.yaw_target_rad, hold_yaw, e);
        if (w > 0.0f) {
            float e_gt[3];
            fc_attitude_error(c->gt_q_wxyz, roll_t, pitch_t, c->in.yaw_target_rad, hold_yaw,
                              e_gt);
            fc_blend_mix(w, e, e_gt, e, 3);
        }
        fc_attitude_rate_targets(&c->att_cfg, e, yaw_rate_ff, c->rate_target_frd_rad_s);
        c->att_target_rad[0] = roll_t;
        c->att_target_rad[1] = pitch_t;
        c->att_target_rad[2] = hold_yaw ? c->in.yaw_target_rad : euler[2];
        /* Kept on the command, so switching shaping on continues from here. */
        fc_shaper_reset(&c->shaper, c->att_target_rad);
    }
}

static void run_rate_loop(fc_core_t *c, float dt_s)
{
    const fc_params_t *p = &c->params;
    const bool gt_ok = gt_fresh(c->last_imu_ns, c->gt_att_ns, c->have_gt_att);
    const float want_gt = (p->sb_att_src == 1 && gt_ok) ? 1.0f : 0.0f;
    const float w = fc_blend_update(&c->blend, want_gt, p->sb_blend_tc, p->sb_blend_en != 0, dt_s);

    for (int i = 0; i < 3; i++) {
        /* The estimator's whole bias estimate is bias - integrator (fc_mahony.h);
         * without removing it the rate loop would hold the vehicle bias/ATC_ANG_P
         * off its attitude target. */
        c->rate_frd_rad_s[i] =
            c->ins.gyro_frd_rad_s[i] - (c->ahrs.bias_rad_s[i] - c->ahrs.integ_rad_s[i]);
    }
    /* SYSTEMID: ends by itself, and (as ArduCopter) when the tilt passes ANGLE_MAX. */
    const float sid = fc_sysid_update(&c->sysid, &c->sysid_cfg, c->last_imu_ns);
    if (c->sysid.active) {
        float eul[3];
        fc_quat_to_euler(c->ahrs.q_wxyz, eul);
        if (fabsf(eul[0]) > c->angle_max_rad || fabsf(eul[1]) > c->angle_max_rad) {
            fc_sysid_stop(&c->sysid);
        }
    }
    float e[3];
    run_attitude(c, w, dt_s, e, sid);
    if (c->sysid.active && c->sysid.axis >= FC_SID_RATE_ROLL
        && c->sysid.axis <= FC_SID_RATE_YAW) {
        c->rate_target_frd_rad_s[c->sysid.axis - FC_SID_RATE_ROLL] += sid * FC_DEG_TO_RAD_F;
    }

    const bool flying = c->spool == FC_SPOOL_FLIGHT;
    const bool integrate = flying && c->airborne;
    const uint8_t sat = c->mixer.sat_flags;
    const bool limit[3] = {(sat & FC_SAT_ROLL) != 0, (sat & FC_SAT_PITCH) != 0,
                           (sat & FC_SAT_YAW) != 0};
    float out_us[3];
    for (int i = 0; i < 3; i++) {
        out_us[i] = fc_rate_pid_update(&c->pid[i], c->rate_target_frd_rad_s[i],
                                       c->rate_frd_rad_s[i], dt_s, limit[i], integrate);
        if (!integrate) {
            fc_rate_pid_reset_integrator(&c->pid[i]); /* no ground wind-up */
        }
        c->pid_out_us[i] = out_us[i];
    }
    if (c->sysid.active && c->sysid.axis >= FC_SID_MIX_ROLL && c->sysid.axis <= FC_SID_MIX_YAW) {
        const int i = c->sysid.axis - FC_SID_MIX_ROLL;
        out_us[i] += sid * c->pid_cfg[i].out_us_per_unit;
    }
    fc_trim_update(&c->trim, &c->trim_cfg, c->airborne != 0, e[0], e[1], dt_s, c->trim_us);

    for (int i = 0; i < 3; i++) {
        c->att_err_frd_rad[i] = e[i];
    }
    c->cr_us = out_us[0] + c->trim_us[0];
    c->cp_us = out_us[1] + c->trim_us[1];
    c->cy_us = out_us[2];
    c->loop_count++;
}

static bool retune_needed(float current_s, float measured_s)
{
    return fabsf(measured_s - current_s) > FC_RETUNE_TOLERANCE * current_s;
}

fc_status_t fc_core_imu_step(fc_core_t *c, int64_t sim_ns, const float accel_frd_m_s2[3],
                             const float gyro_frd_rad_s[3])
{
    if (!fc_finite3(accel_frd_m_s2) || !fc_finite3(gyro_frd_rad_s)) {
        c->rejected_count++;
        return FC_ERR_NONFINITE;
    }
    if (!c->have_imu) {
        (void)fc_ins_update(&c->ins, accel_frd_m_s2, gyro_frd_rad_s);
        (void)fc_mahony_align(&c->ahrs, accel_frd_m_s2);
        c->have_imu = true;
        c->last_imu_ns = sim_ns;
        /* First PWM tick: the first grid point at or after this sample. */
        int64_t k = sim_ns / c->pwm_period_ns;
        if (k * c->pwm_period_ns < sim_ns) {
            k++;
        }
        c->next_pwm_ns = k * c->pwm_period_ns;
        c->imu_count++;
        return FC_OK;
    }
    if (sim_ns <= c->last_imu_ns) {
        c->rejected_count++; /* duplicate or out of order: time must advance */
        return FC_ERR_ARG;
    }
    const float dt_s = fminf((float)(sim_ns - c->last_imu_ns) * 1e-9f, FC_MAX_IMU_DT_S);
    /* The interval this sample stands for, as integrated (a longer gap is cut). */
    const int64_t t0_ns = (sim_ns - c->last_imu_ns > FC_MAX_IMU_DT_NS)
                              ? sim_ns - FC_MAX_IMU_DT_NS
                              : c->last_imu_ns;
    c->last_imu_ns = sim_ns;
    c->imu_count++;

    if (retune_needed(c->imu_dt_s, dt_s)) {
        c->imu_dt_s = dt_s;
        (void)fc_ins_configure(&c->ins, &c->ins_cfg, dt_s);
    }
    (void)fc_ins_update(&c->ins, accel_frd_m_s2, gyro_frd_rad_s);
    const bool ground = c->in.armed == 0;
    if (ground != c->ahrs_ground) {
        c->ahrs_ground = ground;
        fc_mahony_configure(&c->ahrs, ground ? &c->ahrs_ground_cfg : &c->ahrs_cfg);
    }
    if (ground) {
        fc_mahony_gnss_forget(&c->ahrs); /* on the ground the still accelerometer aligns */
    }
    /* The raw accelerometer: its vibration integrates out, while the front-end
     * filter's delay would skew the interval against the GNSS epochs. */
    fc_gnss_aid_add_imu(&c->gnss_aid, t0_ns, sim_ns, c->ahrs.q_wxyz, accel_frd_m_s2);
    (void)fc_mahony_update(&c->ahrs, gyro_frd_rad_s, c->ins.accel_frd_m_s2, dt_s);
    fc_alt_est_predict(&c->alt_est, c->ahrs.q_wxyz, c->ins.accel_frd_m_s2, dt_s,
                       c->in.armed == 0);

    /* Rate loop, decimated to at most SB_LOOP_HZ (a 0.1 % margin absorbs rounding). */
    c->loop_accum_s += dt_s;
    if (c->loop_accum_s >= c->loop_period_s * 0.999f) {
        const float loop_dt = c->loop_accum_s;
        c->loop_accum_s = 0.0f;
        if (retune_needed(c->loop_dt_s, loop_dt)) {
            c->loop_dt_s = loop_dt;
            for (int i = 0; i < 3; i++) {
                fc_rate_pid_configure(&c->pid[i], &c->pid_cfg[i], loop_dt);
            }
        }
        run_rate_loop(c, loop_dt);
    }
    return FC_OK;
}

fc_status_t fc_core_baro_step(fc_core_t *c, int64_t sim_ns, float pressure_pa)
{
    fc_status_t st = fc_alt_est_baro(&c->alt_est, sim_ns, pressure_pa, c->params.sb_alt_tc,
                                     c->in.armed == 0);
    if (st != FC_OK) {
        c->rejected_count++;
    }
    return st;
}

fc_status_t fc_core_mag_step(fc_core_t *c, int64_t sim_ns, const float field_frd[3])
{
    (void)sim_ns;
    if (!fc_finite3(field_frd)) {
        c->rejected_count++;
        return FC_ERR_NONFINITE;
    }
    if (c->params.compass_use == 0 || !c->ahrs.aligned) {
        return FC_OK;
    }
    return fc_mahony_mag(&c->ahrs, field_frd, c->params.compass_dec);
}

fc_status_t fc_core_gt_att_step(fc_core_t *c, int64_t sim_ns, const float q_wxyz[4])
{
    if (!fc_finitef(q_wxyz[0]) || !fc_finite3(&q_wxyz[1])) {
        c->rejected_count++;
        return FC_ERR_NONFINITE;
    }
    for (int i = 0; i < 4; i++) {
        c->gt_q_wxyz[i] = q_wxyz[i];
    }
    fc_quat_normalize(c->gt_q_wxyz);
    c->gt_att_ns = sim_ns;
    c->have_gt_att = true;
    return FC_OK;
}

fc_status_t fc_core_gt_nav_step(fc_core_t *c, int64_t sim_ns, const float pos_ned_m[3],
                                const float vel_ned_m_s[3])
{
    const float pos_d = pos_ned_m[2]; /* only the vertical is used (blended altitude) */
    if (!fc_finitef(pos_d) || !fc_finitef(vel_ned_m_s[2])) {
        c->rejected_count++;
        return FC_ERR_NONFINITE;
    }
    c->gt_alt_m = -pos_d;             /* NED down -> altitude up */
    c->gt_climb_m_s = -vel_ned_m_s[2];
    c->gt_nav_ns = sim_ns;
    c->have_gt_nav = true;
    return FC_OK;
}

/* Compare the fix with the IMU history over the interval since the previous
 * fix's epoch (both GPS_DELAY_MS before arrival) and hand the result to the
 * estimator, in flight configuration only: disarmed, the still accelerometer
 * aligns faster with the ground gains. */
static void gnss_aid_tilt(fc_core_t *c, const fc_gnss_store_t *fix)
{
    const fc_params_t *p = &c->params;
    if (p->sb_ahrs_gps == 0 || fix->fix_type < FC_GNSS_AID_MIN_FIX) {
        fc_gnss_aid_forget_fix(&c->gnss_aid);
        fc_mahony_gnss_forget(&c->ahrs);
        return;
    }
    const int64_t epoch_ns = fix->sim_ns - (int64_t)p->gps_delay_ms * 1000000LL;
    float f_imu_ned[3], f_gnss_ned[3];
    if (fc_gnss_aid_fix(&c->gnss_aid, epoch_ns, fix->vel_ned_m_s, f_imu_ned, f_gnss_ned) != FC_OK
        || c->in.armed == 0) {
        return;
    }
    if (fc_mahony_gnss(&c->ahrs, f_imu_ned, f_gnss_ned) == FC_OK) {
        c->gnss_aid_count++;
    }
}

fc_status_t fc_core_gnss_step(fc_core_t *c, const fc_gnss_store_t *fix)
{
    if (!fc_finite3(fix->vel_ned_m_s)) {
        c->rejected_count++;
        return FC_ERR_NONFINITE;
    }
    c->gnss = *fix;
    c->gnss.valid = true;
    gnss_aid_tilt(c, fix);
    return FC_OK;
}

/* ---- PWM period ---------------------------------------------------------- */

bool fc_core_pwm_due(const fc_core_t *c, int64_t *tick_ns)
{
    if (!c->have_imu || c->next_pwm_ns > c->last_imu_ns) {
        return false;
    }
    *tick_ns = c->next_pwm_ns;
    return true;
}

static bool wants_flight(const fc_core_t *c)
{
    switch (c->in.alt_mode) {
    case FC_ALT_MODE_ALTITUDE:
        return c->in.alt_target_m > c->params.sb_liftoff_alt;
    case FC_ALT_MODE_CLIMB:
        return c->in.climb_target_m_s > 0.0f;
    default:
        return c->in.throttle > c->params.mot_spin_arm;
    }
}

static void update_spool(fc_core_t *c)
{
    const uint8_t armed = c->in.armed;
    if (armed && !c->armed_prev) {
        reset_controllers(c, true);
        c->spool = FC_SPOOL_GROUND_IDLE;
    } else if (!armed) {
        if (c->armed_prev) {
            reset_controllers(c, true);
        }
        c->spool = FC_SPOOL_SHUT_DOWN;
        c->airborne = 0;
    }
    c->armed_prev = armed;
    if (c->spool == FC_SPOOL_GROUND_IDLE && wants_flight(c)) {
        c->spool = FC_SPOOL_FLIGHT;
        fc_alt_ctrl_reset(&c->alt_ctrl);
    }
}

static void detect_liftoff_and_landing(fc_core_t *c, float alt_m, float climb_m_s, float dt_s)
{
    const float liftoff = c->params.sb_liftoff_alt;
    if (c->spool != FC_SPOOL_FLIGHT) {
        c->airborne = 0;
        return;
    }
    if (!c->airborne) {
        if (alt_m > liftoff) {
            c->airborne = 1;
            c->landed_s = 0.0f;
        }
        return;
    }
    const bool at_floor = (c->mixer.sat_flags & FC_SAT_THR_LOW) != 0
                          || c->alt_ctrl.throttle <= c->params.mot_spin_min;
    /* As ArduCopter's land detector: throttle at its floor without descending for
     * a second means the ground carries the vehicle (altitude is not trusted:
     * the baro drifts). */
    if (!wants_flight(c) && at_floor && fabsf(climb_m_s) < FC_LAND_CLIMB_M_S) {
        c->landed_s += dt_s;
        if (c->landed_s >= FC_LAND_DETECT_S) {
            c->airborne = 0;
            c->spool = FC_SPOOL_GROUND_IDLE;
            reset_controllers(c, false);
        }
    } else {
        c->landed_s = 0.0f;
    }
}

static void fill_status(fc_core_t *c, int64_t tick_ns, const uint16_t pwm_us[4])
{
    fc_core_status_t *s = &c->status;
    s->sim_ns = tick_ns;
    s->imu_sim_ns = c->last_imu_ns;
    for (int i = 0; i < 4; i++) {
        s->q_est_wxyz[i] = c->ahrs.q_wxyz[i];
        s->motor_us[i] = c->mixer.motor_us[i];
        s->pwm_us[i] = pwm_us[i];
    }
    fc_quat_to_euler(c->ahrs.q_wxyz, s->euler_est_rad);
    for (int i = 0; i < 3; i++) {
        const fc_pid_info_t *info = &c->pid[i].info;
        s->att_target_rad[i] = c->att_target_rad[i];
        s->att_error_frd_rad[i] = c->att_err_frd_rad[i];
        s->rate_target_frd_rad_s[i] = c->rate_target_frd_rad_s[i];
        s->rate_frd_rad_s[i] = c->rate_frd_rad_s[i];
        s->pid_p[i] = info->p_us;
        s->pid_i[i] = info->i_us;
        s->pid_d[i] = info->d_us;
        s->pid_ff[i] = info->ff_us;
        s->limited[i] = info->limited;
        s->gyro_bias_rad_s[i] = c->ahrs.bias_rad_s[i];
    }
    s->cr_us = c->mixer.roll_us;
    s->cp_us = c->mixer.pitch_us;
    s->cy_us = c->mixer.yaw_us;
    s->throttle_us = c->mixer.throttle_us;
    s->trust = c->ahrs.trust;
    s->blend_w = c->blend.w;
    s->alt_est_m = c->alt_est.alt_m;
    s->climb_est_m_s = c->alt_est.climb_m_s;
    s->alt_target_m = (c->in.alt_mode == FC_ALT_MODE_ALTITUDE) ? c->in.alt_target_m : NAN;
    s->climb_target_m_s = c->alt_ctrl.climb_target_m_s;
    s->throttle = c->alt_ctrl.throttle;
    s->trim_us[0] = c->trim_us[0];
    s->trim_us[1] = c->trim_us[1];
    s->loop_count = c->loop_count;
    s->rejected_count = c->rejected_count;
    s->sat_flags = c->mixer.sat_flags;
    s->armed = c->in.armed;
    s->airborne = c->airborne;
    s->spool = c->spool;
}

fc_status_t fc_core_pwm_step(fc_core_t *c, int64_t tick_ns, uint16_t pwm_us[FC_MIXER_MOTORS])
{
    const float dt_s = pwm_period_s(c);
    const fc_params_t *p = &c->params;
    update_spool(c);

    /* Altitude and climb: the estimate, blended with truth as the attitude is. */
    float alt_m = c->alt_est.alt_m;
    float climb_m_s = c->alt_est.climb_m_s;
    if (c->blend.w > 0.0f && gt_fresh(c->last_imu_ns, c->gt_nav_ns, c->have_gt_nav)) {
        const float w = c->blend.w;
        alt_m = (1.0f - w) * alt_m + w * c->gt_alt_m;
        climb_m_s = (1.0f - w) * climb_m_s + w * c->gt_climb_m_s;
    }
    detect_liftoff_and_landing(c, alt_m, climb_m_s, dt_s);

    const float range_us = c->mix_cfg.pwm_max_us - c->mix_cfg.pwm_min_us;
    if (c->spool == FC_SPOOL_FLIGHT) {
        const float *q = c->ahrs.q_wxyz;
        const float cos_tilt = 1.0f - 2.0f * (q[1] * q[1] + q[2] * q[2]);
        int mode = c->in.alt_mode;
        float target = c->in.alt_target_m;
        if (mode == FC_ALT_MODE_CLIMB) {
            target = c->in.climb_target_m_s;
        } else if (mode == FC_ALT_MODE_THROTTLE) {
            target = c->in.throttle;
        } else if (!wants_flight(c)) {
            /* Landing (target below the lift-off height): descend at least at
             * LAND_SPEED so touchdown is a definite event for the land detector,
             * rather than the asymptotic approach of a position loop. */
            const float land_m_s = (float)p->land_speed * 0.01f;
            mode = FC_ALT_MODE_CLIMB;
            target = fc_constrainf(c->alt_cfg.pos_p * (c->in.alt_target_m - alt_m),
                                   -c->alt_cfg.speed_dn_m_s, -land_m_s);
        }
        const uint8_t sat = c->mixer.sat_flags;
        const float thr = fc_alt_ctrl_update(&c->alt_ctrl, &c->alt_cfg, mode, target,
                                             alt_m, climb_m_s, c->alt_est.accel_up_m_s2,
                                             cos_tilt, (sat & FC_SAT_THR_HIGH) != 0,
                                             (sat & FC_SAT_THR_LOW) != 0, dt_s);
        c->throttle_us = c->mix_cfg.pwm_min_us + thr * range_us;
        if (c->sysid.active && c->sysid.axis == FC_SID_MIX_THROTTLE) {
            c->throttle_us += c->sysid.sample * range_us;
        }
    } else if (c->spool == FC_SPOOL_GROUND_IDLE) {
        c->throttle_us = c->mix_cfg.pwm_min_us + p->mot_spin_arm * range_us;
    } else {
        c->throttle_us = c->mix_cfg.pwm_min_us;
    }

    const fc_status_t st = fc_mixer_update(&c->mixer, &c->mix_cfg, c->spool, c->throttle_us,
                                           c->cr_us, c->cp_us, c->cy_us, dt_s, pwm_us);
    fill_status(c, tick_ns, pwm_us);
    c->next_pwm_ns = tick_ns + c->pwm_period_ns;
    c->pwm_count++;
    return st;
}
