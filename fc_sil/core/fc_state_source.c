/*
 * fc_state_source.c - the estimate and ground truth into the vehicle state
 * (see fc_state_source.h for when each part is published).
 */
#include "fc_state_source.h"

#include "fc_math.h"

static bool truth_fresh(int64_t now_ns, int64_t truth_ns, bool have)
{
    return have && now_ns - truth_ns <= FC_TRUTH_STALE_NS && truth_ns - now_ns <= FC_TRUTH_STALE_NS;
}

void fc_state_source_reset(fc_state_source_t *src)
{
    fc_quat_identity(src->truth_q_wxyz);
    src->truth_att_ns = 0;
    src->have_truth_att = false;
    src->truth_alt_m = 0.0f;
    src->truth_climb_m_s = 0.0f;
    src->truth_nav_ns = 0;
    src->have_truth_nav = false;
    fc_blend_reset(&src->blend, 0.0f);
}

fc_status_t fc_state_source_truth_att(fc_state_source_t *src, int64_t sim_ns,
                                      const float q_wxyz[4])
{
    if (!fc_finitef(q_wxyz[0]) || !fc_finite3(&q_wxyz[1])) {
        return FC_ERR_NONFINITE;
    }
    for (int i = 0; i < 4; i++) {
        src->truth_q_wxyz[i] = q_wxyz[i];
    }
    fc_quat_normalize(src->truth_q_wxyz);
    src->truth_att_ns = sim_ns;
    src->have_truth_att = true;
    return FC_OK;
}

fc_status_t fc_state_source_truth_nav(fc_state_source_t *src, int64_t sim_ns,
                                      const float pos_ned_m[3], const float vel_ned_m_s[3])
{
    const float pos_d = pos_ned_m[2];
    if (!fc_finitef(pos_d) || !fc_finitef(vel_ned_m_s[2])) {
        return FC_ERR_NONFINITE;
    }
    src->truth_alt_m = -pos_d; /* NED down -> altitude up */
    src->truth_climb_m_s = -vel_ned_m_s[2];
    src->truth_nav_ns = sim_ns;
    src->have_truth_nav = true;
    return FC_OK;
}

void fc_state_source_attitude(fc_state_source_t *src, const fc_source_config_t *cfg,
                              const fc_mahony_t *ahrs, const fc_ins_t *ins, int64_t now_ns,
                              float dt_s, fc_vehicle_state_t *vs)
{
    const bool fresh = truth_fresh(now_ns, src->truth_att_ns, src->have_truth_att);
    const float want = (cfg->use_truth && fresh) ? 1.0f : 0.0f;
    vs->truth_w = fc_blend_update(&src->blend, want, cfg->blend_tc_s, cfg->blend_continuous, dt_s);
    for (int i = 0; i < 4; i++) {
        vs->q_wxyz[i] = ahrs->q_wxyz[i];
        vs->q_truth_wxyz[i] = src->truth_q_wxyz[i];
    }
    fc_quat_to_euler(vs->q_wxyz, vs->euler_rad);
    for (int i = 0; i < 3; i++) {
        /* The estimator's whole bias estimate is bias - integrator (fc_mahony.h);
         * without removing it the rate loop would hold the vehicle bias/ATC_ANG_P
         * off its attitude target. */
        vs->rate_frd_rad_s[i] =
            ins->gyro_frd_rad_s[i] - (ahrs->bias_rad_s[i] - ahrs->integ_rad_s[i]);
    }
}

void fc_state_source_vertical(const fc_state_source_t *src, const fc_mahony_t *ahrs,
                              const fc_alt_est_t *alt, int64_t now_ns, fc_vehicle_state_t *vs)
{
    /* The vertical channel follows the attitude's weight, so one switch
     * (SB_ATT_SRC) moves both, as the paper's blend does. */
    const float w = src->blend.w;
    if (w > 0.0f && truth_fresh(now_ns, src->truth_nav_ns, src->have_truth_nav)) {
        const float est[2] = {alt->alt_m, alt->climb_m_s};
        const float truth[2] = {src->truth_alt_m, src->truth_climb_m_s};
        float mixed[2];
        fc_blend_mix(w, est, truth, mixed, 2);
        vs->alt_m = mixed[0];
        vs->climb_m_s = mixed[1];
    } else {
        vs->alt_m = alt->alt_m;
        vs->climb_m_s = alt->climb_m_s;
    }
    vs->accel_up_m_s2 = alt->accel_up_m_s2;
    const float *q = ahrs->q_wxyz;
    vs->cos_tilt = 1.0f - 2.0f * (q[1] * q[1] + q[2] * q[2]);
}
