/*
 * fc_core.c - the flight-controller chain's life cycle and scheduling: the
 * parameters, reset, the IMU step with its rate-loop decimation, the routing
 * of the other sensors and of ground truth, and the PWM tick with its status
 * snapshot (see fc_core.h for the order of the blocks). The control law is a
 * block of its own (fc_control.c), the spool logic in fc_spool.c, the inputs in
 * fc_core_inputs.c.
 */
#include "fc_core.h"

#include <stddef.h>
#include <string.h>

#include "fc_fft_params.h"
#include "fc_math.h"
#include "fc_notch_feed.h"

_Static_assert(sizeof(fc_core_status_t) == 248, "fc_core_status_t layout is mirrored in Python");

/* fc_control_out_t opens with the status's rate-loop block (att_target_rad ..
 * pid_ff) field for field, so fill_status copies that block in one piece. */
#define FC_STATUS_CTL_OFFSET offsetof(fc_core_status_t, att_target_rad)
#define FC_CTL_REPORT_BYTES (offsetof(fc_control_out_t, pid_ff_us) + sizeof(float[3]))
#define FC_CTL_SAME_PLACE(out_field, status_field)                                          \
    _Static_assert(offsetof(fc_control_out_t, out_field)                                    \
                           == offsetof(fc_core_status_t, status_field) - FC_STATUS_CTL_OFFSET \
                       && sizeof(((fc_control_out_t *)0)->out_field)                        \
                              == sizeof(((fc_core_status_t *)0)->status_field),             \
                   #out_field " is not where the status holds " #status_field)
FC_CTL_SAME_PLACE(att_target_rad, att_target_rad);
FC_CTL_SAME_PLACE(att_error_frd_rad, att_error_frd_rad);
FC_CTL_SAME_PLACE(rate_target_frd_rad_s, rate_target_frd_rad_s);
FC_CTL_SAME_PLACE(rate_frd_rad_s, rate_frd_rad_s);
FC_CTL_SAME_PLACE(pid_p_us, pid_p);
FC_CTL_SAME_PLACE(pid_i_us, pid_i);
FC_CTL_SAME_PLACE(pid_d_us, pid_d);
FC_CTL_SAME_PLACE(pid_ff_us, pid_ff);

/* dt limits for one IMU step: a longer gap (a paused simulation) is integrated
 * as 50 ms so the filters and integrators see a bounded step. */
#define FC_MAX_IMU_DT_S 0.05f
#define FC_MAX_IMU_DT_NS 50000000LL
/* The IMU and rate-loop period the filters start with, until the first
 * measured one [s]. */
#define FC_NOMINAL_DT_S 0.001f
/* GNSS-aided tilt needs a 3D fix (MAVLink GPS_FIX_TYPE_3D_FIX and better). */
#define FC_GNSS_AID_MIN_FIX 3

/* ---- parameters ------------------------------------------------------------ */

static void map_params(fc_core_t *c)
{
    fc_config_map(&c->params, &c->cfg);
    fc_fft_config_from_params(&c->params, &c->fft_cfg);
    c->pwm_period_ns = fc_config_pwm_period_ns(&c->params);
}

static float pwm_period_s(const fc_core_t *c)
{
    return (float)c->pwm_period_ns * 1e-9f;
}

/* The FFT samples the gyro at the IMU rate, or at the rate loop's (FFT_SAMPLE_MODE). */
static void fft_configure(fc_core_t *c)
{
    fc_fft_configure(&c->fft, &c->fft_cfg, 1.0f / c->imu_dt_s, 1.0f / c->cfg.loop_period_s);
}

void fc_core_apply_params(fc_core_t *c)
{
    map_params(c);
    (void)fc_ins_configure(&c->ins, &c->cfg.ins, c->imu_dt_s);
    fc_mahony_configure(&c->ahrs, c->ahrs_ground ? &c->cfg.ahrs_ground : &c->cfg.ahrs);
    fc_control_configure(&c->ctl, &c->cfg.ctl, pwm_period_s(c));
    fft_configure(c);
}

fc_status_t fc_core_set_param(fc_core_t *c, uint16_t index, float value)
{
    fc_params_t candidate = c->params;
    fc_status_t st = fc_param_set(&candidate, index, value);
    if (st != FC_OK) {
        return st;
    }
    if (!fc_config_consistent(&candidate)) {
        return FC_ERR_RANGE;
    }
    /* A new declination (COMPASS_AUTODEC sets it at the first GNSS fix, after the first
     * heading) turns the heading at once, as ArduCopter's EKF resets its yaw; left to the
     * heading loop, the step winds the yaw gyro bias up and takes a minute to unlearn. */
    const float dec_step_rad = candidate.compass_dec - c->params.compass_dec;
    c->params = candidate;
    fc_core_apply_params(c);
    if (dec_step_rad != 0.0f && c->ahrs.heading_valid) {
        fc_mahony_turn_heading(&c->ahrs, dec_step_rad);
    }
    return FC_OK;
}

fc_status_t fc_core_get_param(const fc_core_t *c, uint16_t index, float *value)
{
    return fc_param_get(&c->params, index, value);
}

/* ---- the control law's surroundings ------------------------------------ */

/* Its inputs as they stand now: the spool logic and the mixer move them
 * between its steps. */
static const fc_control_in_t *control_inputs(fc_core_t *c)
{
    fc_control_in_t *in = &c->ctl_in;
    in->cmd = c->in;
    in->now_ns = c->last_imu_ns;
    in->spool = c->spool;
    in->airborne = c->spool_logic.airborne;
    in->sat_flags = c->mixer.sat_flags;
    return in;
}

/* Controllers to rest; the mixer's slew state too only when reset_mixer
 * (arming and disarming): on landing the outputs slew down to idle, no dip. */
static void control_reset(fc_core_t *c, bool reset_mixer)
{
    fc_control_reset(&c->ctl, &c->cfg.ctl, &c->ctl_out);
    if (reset_mixer) {
        fc_mixer_reset(&c->mixer, &c->cfg.mix);
    }
}

/* ---- life cycle --------------------------------------------------------- */

void fc_core_reset(fc_core_t *c)
{
    fc_core_inputs_t in = {0};
    in.alt_mode = FC_ALT_MODE_ALTITUDE;
    c->in = in;
    c->imu_dt_s = FC_NOMINAL_DT_S;
    map_params(c);
    (void)fc_ins_init(&c->ins, &c->cfg.ins, c->imu_dt_s);
    fc_mahony_init(&c->ahrs, &c->cfg.ahrs_ground);
    c->ahrs_ground = true;
    fc_state_source_reset(&c->source);
    fc_vehicle_state_reset(&c->state);
    fc_alt_est_reset(&c->alt_est);
    fc_alt_sched_reset(&c->alt_sched, &c->cfg.alt_sched);
    fc_gnss_aid_reset(&c->gnss_aid);
    c->gnss_aid_count = 0;
    fc_control_init(&c->ctl, &c->cfg.ctl, FC_NOMINAL_DT_S, pwm_period_s(c), &c->ctl_out);
    fc_mixer_reset(&c->mixer, &c->cfg.mix);
    fc_spool_reset(&c->spool_logic, &c->spool);

    c->have_imu = false;
    c->last_imu_ns = 0;
    c->loop_accum_s = 0.0f;
    c->next_pwm_ns = 0;
    fc_gnss_store_t g = {0};
    c->gnss = g;
    fc_vibe_init(&c->vibe, FC_VIBE_CLIP_16G_M_S2);
    fc_esc_init(&c->esc);
    fc_fft_init(&c->fft, &c->fft_cfg, 1.0f / c->imu_dt_s, 1.0f / c->cfg.loop_period_s);
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

/* ---- IMU: estimation, then the decimated rate loop ---------------------- */

fc_status_t fc_core_imu_step(fc_core_t *c, int64_t sim_ns, const float accel_frd_m_s2[3],
                             const float gyro_frd_rad_s[3])
{
    if (!fc_finite3(accel_frd_m_s2) || !fc_finite3(gyro_frd_rad_s)) {
        c->rejected_count++;
        return FC_ERR_NONFINITE;
    }
    if (!c->have_imu) {
        fc_vibe_apply(&c->vibe, accel_frd_m_s2, 0.0f);
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
    fc_vibe_apply(&c->vibe, accel_frd_m_s2, dt_s); /* reads the sample only */

    if (fc_retune_needed(c->imu_dt_s, dt_s)) {
        c->imu_dt_s = dt_s;
        (void)fc_ins_configure(&c->ins, &c->cfg.ins, dt_s);
        fft_configure(c);
    }
    (void)fc_ins_update(&c->ins, accel_frd_m_s2, gyro_frd_rad_s);
    /* the FFT hears the raw gyro, or the filtered one (FFT_OPTIONS bit 0), and does a
     * share of a frame's work per sample */
    fc_fft_push(&c->fft, (c->fft_cfg.options & FC_FFT_OPT_POST_FILTER) ? c->ins.gyro_frd_rad_s
                                                                       : gyro_frd_rad_s);
    fc_fft_step(&c->fft);
    const bool ground = c->in.armed == 0;
    if (ground != c->ahrs_ground) {
        c->ahrs_ground = ground;
        fc_mahony_configure(&c->ahrs, ground ? &c->cfg.ahrs_ground : &c->cfg.ahrs);
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

    /* Rate loop, decimated to at most SB_LOOP_HZ (a 0.1 % margin absorbs rounding).
     * Its period is measured here, once, and handed down. */
    c->loop_accum_s += dt_s;
    if (c->loop_accum_s >= c->cfg.loop_period_s * 0.999f) {
        const float loop_dt = c->loop_accum_s;
        c->loop_accum_s = 0.0f;
        fc_state_source_attitude(&c->source, &c->cfg.source, &c->ahrs, &c->ins, c->last_imu_ns,
                                 loop_dt, &c->state);
        fc_control_rate_step(&c->ctl, &c->cfg.ctl, control_inputs(c), &c->state, loop_dt,
                             &c->ctl_out);
        c->loop_count++;
    }
    return FC_OK;
}

/* ---- other sensors and ground truth ------------------------------------- */

/* How far the vehicle is from holding an altitude in steady flight, 0..1:
 * the phase evidence for the vertical filter's time constant (fc_sched.h).
 * 1 (fast) on the ground, in a climb-rate or throttle mode and while landing
 * (target at or below SB_LIFTOFF_ALT: a touchdown must show at once). While
 * seeking a target it rises smoothly, from 0 at FC_ALT_HOLD_ERR_M of altitude
 * error or FC_LAND_CLIMB_M_S of climb demand (the speed the land detector
 * calls "still") to 1 at twice either: the hold loop's own correction of a
 * drifted estimate reaches these sizes, and a hard switch there steps the
 * time constant and kicks the throttle (issue 14, seed 20 of S1). */
#define FC_ALT_HOLD_ERR_M 0.5f
static float alt_seek_demand(const fc_core_t *c)
{
    if (c->in.armed == 0 || c->spool_logic.airborne == 0
        || c->in.alt_mode != FC_ALT_MODE_ALTITUDE
        || !(c->in.alt_target_m > c->params.sb_liftoff_alt)) {
        return 1.0f;
    }
    const float err = fabsf(c->in.alt_target_m - c->alt_est.alt_m) / FC_ALT_HOLD_ERR_M;
    const float climb = fabsf(c->ctl.alt_ctrl.climb_target_m_s) / FC_LAND_CLIMB_M_S;
    return fmaxf(err, climb) - 1.0f; /* NaN or above 1: fc_alt_sched_step clamps to 1 */
}

fc_status_t fc_core_baro_step(fc_core_t *c, int64_t sim_ns, float pressure_pa)
{
    /* The innovation of the previous sample (10 ms old) picks this one's gain. */
    float dt_s = 0.0f;
    if (c->alt_est.have_baro && sim_ns > c->alt_est.last_baro_ns) {
        dt_s = fminf((float)(sim_ns - c->alt_est.last_baro_ns) * 1e-9f, FC_MAX_IMU_DT_S);
    }
    /* While a baro jump is corrected (fc_alt_est.h) the time constant stays: the jump would
     * otherwise ask for the fast one, through the innovation and the distance to the target. */
    const float tau_s =
        c->alt_est.height_only ? c->alt_sched.tc_s
                         : fc_alt_sched_step(&c->alt_sched, &c->cfg.alt_sched,
                                             alt_seek_demand(c), c->alt_est.innov_m, dt_s);
    fc_status_t st = fc_alt_est_baro(&c->alt_est, sim_ns, pressure_pa, tau_s,
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
    const fc_status_t st = fc_state_source_truth_att(&c->source, sim_ns, q_wxyz);
    if (st != FC_OK) {
        c->rejected_count++;
    }
    return st;
}

fc_status_t fc_core_gt_nav_step(fc_core_t *c, int64_t sim_ns, const float pos_ned_m[3],
                                const float vel_ned_m_s[3])
{
    const fc_status_t st = fc_state_source_truth_nav(&c->source, sim_ns, pos_ned_m, vel_ned_m_s);
    if (st != FC_OK) {
        c->rejected_count++;
    }
    return st;
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

fc_status_t fc_core_esc_step(fc_core_t *c, int64_t sim_ns, unsigned motor, unsigned motor_count,
                             const float values[5])
{
    return fc_esc_store(&c->esc, sim_ns, motor, motor_count, values);
}

/* ---- PWM period ---------------------------------------------------------- */

/* Hover learning of FFT_FREQ_HOVER / FFT_BW_HOVER / FFT_THR_REF where ArduCopter learns
 * MOT_THST_HOVER (Copter::update_throttle_hover): airborne, altitude held (no climb
 * demanded there; here: within FC_ALT_HOLD_ERR_M of the target), |climb| < 0.6 m/s, roll
 * and pitch within 5 deg. The learned values become the
 * parameters on disarm (AP_GyroFFT::save_params_on_disarm). */
#define FC_FFT_HOVER_CLIMB_M_S 0.6f
#define FC_FFT_HOVER_TILT_RAD (5.0f * FC_DEG_TO_RAD_F)
static void fft_supervise(fc_core_t *c, float dt_s)
{
    if (!c->fft.active) {
        return;
    }
    if (c->in.armed == 0) {
        if (c->fft.learned) {
            c->params.fft_freq_hover = c->fft.freq_hover_hz;
            c->params.fft_bw_hover = c->fft.bw_hover_hz;
            c->params.fft_thr_ref = c->fft.thr_ref;
            c->fft.learned = false;
        }
        return;
    }
    const fc_core_status_t *s = &c->status;
    const float throttle = fc_mixer_throttle_out(&c->mixer, &c->cfg.mix);
    if (c->spool_logic.airborne && c->in.alt_mode == FC_ALT_MODE_ALTITUDE
        && fabsf(c->in.alt_target_m - c->alt_est.alt_m) < FC_ALT_HOLD_ERR_M && throttle > 0.0f
        && fabsf(c->alt_est.climb_m_s) < FC_FFT_HOVER_CLIMB_M_S
        && fabsf(s->euler_est_rad[0]) < FC_FFT_HOVER_TILT_RAD
        && fabsf(s->euler_est_rad[1]) < FC_FFT_HOVER_TILT_RAD) {
        fc_fft_update_freq_hover(&c->fft, dt_s, throttle);
    }
}

bool fc_core_pwm_due(const fc_core_t *c, int64_t *tick_ns)
{
    if (!c->have_imu || c->next_pwm_ns > c->last_imu_ns) {
        return false;
    }
    *tick_ns = c->next_pwm_ns;
    return true;
}

/* The status reports the estimator itself (attitude, bias, trust, the
 * unblended altitude), beside what the controllers did with the state. */
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
    const fc_control_out_t *o = &c->ctl_out;
    memcpy((unsigned char *)s + FC_STATUS_CTL_OFFSET, o, FC_CTL_REPORT_BYTES);
    for (int i = 0; i < 3; i++) {
        s->limited[i] = o->limited[i];
        s->gyro_bias_rad_s[i] = c->ahrs.bias_rad_s[i];
    }
    s->cr_us = c->mixer.roll_us;
    s->cp_us = c->mixer.pitch_us;
    s->cy_us = c->mixer.yaw_us;
    s->throttle_us = c->mixer.throttle_us;
    s->trust = c->ahrs.trust;
    s->blend_w = c->source.blend.w;
    s->alt_est_m = c->alt_est.alt_m;
    s->climb_est_m_s = c->alt_est.climb_m_s;
    s->alt_target_m = (c->in.alt_mode == FC_ALT_MODE_ALTITUDE) ? c->in.alt_target_m : NAN;
    s->climb_target_m_s = c->ctl.alt_ctrl.climb_target_m_s;
    s->throttle = c->ctl.alt_ctrl.throttle;
    s->trim_us[0] = o->trim_us[0];
    s->trim_us[1] = o->trim_us[1];
    s->loop_count = c->loop_count;
    s->rejected_count = c->rejected_count;
    s->sat_flags = c->mixer.sat_flags;
    s->armed = c->in.armed;
    s->airborne = c->spool_logic.airborne;
    s->spool = c->spool;
}

fc_status_t fc_core_pwm_step(fc_core_t *c, int64_t tick_ns, uint16_t pwm_us[FC_MIXER_MOTORS])
{
    const float dt_s = pwm_period_s(c);
    const unsigned ev = fc_spool_update(&c->spool_logic, &c->cfg.spool, &c->in, &c->spool);
    if (ev & FC_SPOOL_EV_ARMING) {
        control_reset(c, true);
    }
    if (ev & FC_SPOOL_EV_TAKEOFF) {
        fc_alt_ctrl_reset(&c->ctl.alt_ctrl); /* the altitude loop from rest */
    }
    fc_state_source_vertical(&c->source, &c->ahrs, &c->alt_est, c->last_imu_ns, &c->state);
    if (fc_spool_detect(&c->spool_logic, &c->cfg.spool, &c->in, &c->state, c->mixer.sat_flags,
                        c->ctl.alt_ctrl.throttle, dt_s, &c->spool)
        & FC_SPOOL_EV_LANDED) {
        control_reset(c, false);
    }
    fc_control_throttle_step(&c->ctl, &c->cfg.ctl, control_inputs(c), &c->state, dt_s,
                             &c->ctl_out);

    const fc_control_out_t *o = &c->ctl_out;
    const fc_status_t st = fc_mixer_update(&c->mixer, &c->cfg.mix, c->spool, o->throttle_us,
                                           o->cr_us, o->cp_us, o->cy_us, dt_s, pwm_us);
    fill_status(c, tick_ns, pwm_us);
    fft_supervise(c, dt_s); /* FFT hover learning (before the notches read the FFT) */
    fc_notch_feed(c); /* the notches' centres from this tick's throttle and telemetry */
    c->next_pwm_ns = tick_ns + c->pwm_period_ns;
    c->pwm_count++;
    return st;
}
