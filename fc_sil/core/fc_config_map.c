/*
 * fc_config_map.c - parameters to block configurations (see fc_config_map.h).
 */
#include "fc_config_map.h"

#include "fc_math.h"

/* Estimator gains while disarmed (on the ground, still): a critically damped
 * PI at 1 rad/s (s^2 + 2 s + 1) aligns and learns the gyro bias in about 5 s,
 * as a real flight controller calibrates its gyros before take-off; at arming
 * the slower flight gains (SB_AHRS_KP/KI) take over, bias kept. */
#define FC_AHRS_GROUND_KP 2.0f
#define FC_AHRS_GROUND_KI 1.0f

/* One harmonic notch's parameters, INS_HNTCH_* or INS_HNTC2_* (same shape). */
static fc_notch_config_t notch_config(int8_t enable, int8_t mode, float freq, float bw, float att,
                                      int32_t hmncs, float ref, float fm_rat, int16_t opts)
{
    fc_notch_config_t n;
    n.enable = enable != 0;
    n.mode = (uint8_t)mode;       /* range 0..5 (fc_params.def) */
    n.options = (uint16_t)opts;   /* range 0..127 */
    n.harmonics = (uint32_t)hmncs; /* range 0..65535 */
    n.freq_hz = freq;
    n.bw_hz = bw;
    n.att_db = att;
    n.ref = ref;
    n.fm_ratio = fm_rat;
    return n;
}

static void map_estimation(const fc_params_t *p, fc_core_config_t *cfg)
{
    cfg->ins.gyro_cutoff_hz = p->ins_gyro_filter;
    cfg->ins.accel_cutoff_hz = p->ins_accel_filter;
    cfg->ins.notch[0] = notch_config(p->ins_hntch_enable, p->ins_hntch_mode, p->ins_hntch_freq,
                                     p->ins_hntch_bw, p->ins_hntch_att, p->ins_hntch_hmncs,
                                     p->ins_hntch_ref, p->ins_hntch_fm_rat, p->ins_hntch_opts);
    cfg->ins.notch[1] = notch_config(p->ins_hntc2_enable, p->ins_hntc2_mode, p->ins_hntc2_freq,
                                     p->ins_hntc2_bw, p->ins_hntc2_att, p->ins_hntc2_hmncs,
                                     p->ins_hntc2_ref, p->ins_hntc2_fm_rat, p->ins_hntc2_opts);

    fc_mahony_config_t *a = &cfg->ahrs;
    a->kp = p->sb_ahrs_kp;
    a->ki = p->sb_ahrs_ki;
    a->kmag = (p->compass_use != 0) ? p->sb_ahrs_kmag : 0.0f;
    a->trust_tc_s = p->sb_trust_tc;
    a->trust_span_g = p->sb_trust_span;
    a->bias_rate_hz = p->sb_bias_rate;
    a->still_gyro_rad_s = p->sb_still_gyro;
    a->still_acc_g = p->sb_still_acc;
    a->trust_ema_enable = p->sb_trust_ema_en != 0;
    a->bias_enable = p->sb_bias_en != 0;
    a->kp_gnss = p->sb_ahrs_gps_kp;
    a->ki_gnss = p->sb_ahrs_gps_ki;
    a->gnss_boost = p->sb_ahrs_gps_bst;
    a->gnss_innov_sigma = p->sb_ahrs_gps_inn;
    cfg->ahrs_ground = *a;
    cfg->ahrs_ground.kp = fmaxf(p->sb_ahrs_kp, FC_AHRS_GROUND_KP);
    cfg->ahrs_ground.ki = fmaxf(p->sb_ahrs_ki, FC_AHRS_GROUND_KI);

    cfg->source.use_truth = p->sb_att_src == 1;
    cfg->source.blend_continuous = p->sb_blend_en != 0;
    cfg->source.blend_tc_s = p->sb_blend_tc;
}

static void map_attitude(const fc_params_t *p, fc_core_config_t *cfg)
{
    cfg->ctl.att.ang_p[0] = p->atc_ang_rll_p;
    cfg->ctl.att.ang_p[1] = p->atc_ang_pit_p;
    cfg->ctl.att.ang_p[2] = p->atc_ang_yaw_p;
    cfg->ctl.att.rate_max_rad_s[0] = p->atc_rate_r_max * FC_DEG_TO_RAD_F;
    cfg->ctl.att.rate_max_rad_s[1] = p->atc_rate_p_max * FC_DEG_TO_RAD_F;
    cfg->ctl.att.rate_max_rad_s[2] = p->atc_rate_y_max * FC_DEG_TO_RAD_F;
    cfg->ctl.angle_max_rad = p->angle_max * 0.01f * FC_DEG_TO_RAD_F; /* centidegrees */

    cfg->ctl.shaper.enable = p->atc_rate_ff_enab != 0 && p->sb_shape_en != 0;
    cfg->ctl.shaper.input_tc_s = p->atc_input_tc;
    cfg->ctl.shaper.accel_max_rad_s2[0] = p->atc_accel_r_max * 0.01f * FC_DEG_TO_RAD_F;
    cfg->ctl.shaper.accel_max_rad_s2[1] = p->atc_accel_p_max * 0.01f * FC_DEG_TO_RAD_F;
    cfg->ctl.shaper.accel_max_rad_s2[2] = p->atc_accel_y_max * 0.01f * FC_DEG_TO_RAD_F;
    for (int i = 0; i < 3; i++) {
        cfg->ctl.shaper.rate_max_rad_s[i] = cfg->ctl.att.rate_max_rad_s[i];
    }
}

static void map_rate_loop(const fc_params_t *p, fc_core_config_t *cfg)
{
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
        fc_rate_pid_config_t *pc = &cfg->ctl.pid[i];
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

    cfg->ctl.trim.enable = p->sb_trim_en != 0;
    cfg->ctl.trim.ramp_enable = p->sb_trim_ramp_en != 0;
    cfg->ctl.trim.window_s = p->sb_trim_win_s;
    cfg->ctl.trim.gain_us_per_rad = p->sb_trim_gain;
    cfg->ctl.trim.max_us = p->sb_trim_max_us;
    cfg->ctl.trim.ramp_s = p->sb_trim_ramp_s;

    cfg->ctl.sysid.axis = (uint8_t)p->sid_axis; /* range 0..13 (fc_params.def) */
    cfg->ctl.sysid.magnitude = p->sid_magnitude;
    cfg->ctl.sysid.f_start_hz = p->sid_f_start_hz;
    cfg->ctl.sysid.f_stop_hz = p->sid_f_stop_hz;
    cfg->ctl.sysid.t_fade_in_s = p->sid_t_fade_in;
    cfg->ctl.sysid.t_rec_s = p->sid_t_rec;
    cfg->ctl.sysid.t_fade_out_s = p->sid_t_fade_out;

    cfg->loop_period_s = 1.0f / (float)p->sb_loop_hz;
}

static void map_vertical_and_motors(const fc_params_t *p, fc_core_config_t *cfg)
{
    cfg->mix.pwm_min_us = (float)p->mot_pwm_min;
    cfg->mix.pwm_max_us = (float)p->mot_pwm_max;
    cfg->mix.spin_min = p->mot_spin_min;
    cfg->mix.spin_max = p->mot_spin_max;
    cfg->mix.yaw_headroom_us = (float)p->mot_yaw_headroom;
    cfg->mix.slew_up_time_s = p->mot_slew_up_time;
    cfg->mix.slew_dn_time_s = p->mot_slew_dn_time;
    cfg->mix.slew_enable = p->sb_slew_en != 0;

    cfg->ctl.alt.pos_p = p->psc_posz_p;
    cfg->ctl.alt.vel_p = p->psc_velz_p;
    cfg->ctl.alt.acc_p = p->psc_accz_p;
    cfg->ctl.alt.acc_i = p->psc_accz_i;
    cfg->ctl.alt.acc_imax = p->psc_accz_imax;
    cfg->ctl.alt.acc_flte_hz = p->psc_accz_flte;
    cfg->ctl.alt.speed_up_m_s = p->pilot_speed_up * 0.01f; /* cm/s */
    cfg->ctl.alt.speed_dn_m_s =
        ((p->pilot_speed_dn > 0) ? p->pilot_speed_dn : p->pilot_speed_up) * 0.01f;
    cfg->ctl.alt.hover_throttle = p->mot_thst_hover;
    cfg->alt_sched.tc_s = p->sb_alt_tc;
    cfg->alt_sched.tc_hold_s = p->sb_alt_tc_hold;
    cfg->alt_sched.innov_m = p->sb_alt_innov;

    cfg->spool.liftoff_alt_m = p->sb_liftoff_alt;
    cfg->spool.spin_arm = p->mot_spin_arm;
    cfg->spool.spin_min = p->mot_spin_min;
    cfg->spool.land_speed_m_s = (float)p->land_speed * 0.01f; /* cm/s */

    /* What the control law needs of the mixer's and the spool logic's settings. */
    cfg->ctl.spool = cfg->spool;
    cfg->ctl.pwm_min_us = cfg->mix.pwm_min_us;
    cfg->ctl.pwm_max_us = cfg->mix.pwm_max_us;
}

void fc_config_map(const fc_params_t *p, fc_core_config_t *cfg)
{
    map_estimation(p, cfg);
    map_attitude(p, cfg);
    map_rate_loop(p, cfg);
    map_vertical_and_motors(p, cfg);
}

int64_t fc_config_pwm_period_ns(const fc_params_t *p)
{
    return 1000000000LL / (int64_t)p->sb_pwm_hz;
}

bool fc_config_consistent(const fc_params_t *p)
{
    return p->mot_pwm_min + 100 <= p->mot_pwm_max && p->mot_spin_arm <= p->mot_spin_min
           && p->mot_spin_min < p->mot_spin_max
           && p->ins_hntch_freq > 0.5f * p->ins_hntch_bw
           && p->ins_hntc2_freq > 0.5f * p->ins_hntc2_bw;
}
