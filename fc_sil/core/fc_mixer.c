/*
 * fc_mixer.c - quad-X mixer (see fc_mixer.h for order, signs and priorities).
 */
#include "fc_mixer.h"

#include "fc_math.h"

const float fc_mixer_roll_factor[FC_MIXER_MOTORS] = {-1.0f, 1.0f, 1.0f, -1.0f};
const float fc_mixer_pitch_factor[FC_MIXER_MOTORS] = {1.0f, -1.0f, 1.0f, -1.0f};
const float fc_mixer_yaw_factor[FC_MIXER_MOTORS] = {1.0f, 1.0f, -1.0f, -1.0f};

void fc_mixer_reset(fc_mixer_t *m, const fc_mixer_config_t *cfg)
{
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        m->motor_us[i] = cfg->pwm_min_us;
        m->out_us[i] = cfg->pwm_min_us;
    }
    m->roll_us = 0.0f;
    m->pitch_us = 0.0f;
    m->yaw_us = 0.0f;
    m->throttle_us = cfg->pwm_min_us;
    m->sat_flags = 0;
}

static float finite_or_zero(float x, bool *bad)
{
    if (!fc_finitef(x)) {
        *bad = true;
        return 0.0f;
    }
    return x;
}

/* Mix in the flight band [lo, hi]; fills m->motor_us and the flags. */
static void mix_flight(fc_mixer_t *m, const fc_mixer_config_t *cfg, float thr, float cr,
                       float cp, float cy)
{
    const float range = cfg->pwm_max_us - cfg->pwm_min_us;
    const float lo = cfg->pwm_min_us + cfg->spin_min * range;
    const float hi = cfg->pwm_min_us + cfg->spin_max * range;
    const float span = hi - lo;
    uint8_t flags = 0;

    float t = thr;
    if (t > hi) {
        t = hi;
        flags |= FC_SAT_THR_HIGH;
    } else if (t < lo) {
        t = lo;
        flags |= FC_SAT_THR_LOW;
    }

    /* Roll and pitch first: scale both down together if they need more than the span. */
    float rp[FC_MIXER_MOTORS];
    float rp_max = -1e30f, rp_min = 1e30f;
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        rp[i] = fc_mixer_roll_factor[i] * cr + fc_mixer_pitch_factor[i] * cp;
        rp_max = fmaxf(rp_max, rp[i]);
        rp_min = fminf(rp_min, rp[i]);
    }
    if (rp_max - rp_min > span) {
        const float scale = span / (rp_max - rp_min);
        cr *= scale;
        cp *= scale;
        for (int i = 0; i < FC_MIXER_MOTORS; i++) {
            rp[i] *= scale;
        }
        rp_max *= scale;
        rp_min *= scale;
        flags |= FC_SAT_ROLL | FC_SAT_PITCH;
    }
    /* Throttle gives way so that roll and pitch fit. */
    const float t_rp = fc_constrainf(t, lo - rp_min, hi - rp_max);
    if (t_rp < t) {
        flags |= FC_SAT_THR_HIGH;
    } else if (t_rp > t) {
        flags |= FC_SAT_THR_LOW;
    }
    t = t_rp;

    /* Yaw: the room left in the direction each motor is pushed, at least the headroom. */
    float room = 1e30f;
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        const float base = t + rp[i];
        const float r = (fc_mixer_yaw_factor[i] * cy >= 0.0f) ? hi - base : base - lo;
        room = fminf(room, r);
    }
    const float yaw_allowed = fmaxf(room, cfg->yaw_headroom_us);
    if (fabsf(cy) > yaw_allowed) {
        cy = (cy > 0.0f) ? yaw_allowed : -yaw_allowed;
        flags |= FC_SAT_YAW;
    }

    /* Throttle gives way again for the yaw it had to make room for. */
    float m_max = -1e30f, m_min = 1e30f;
    float mot[FC_MIXER_MOTORS];
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        mot[i] = t + rp[i] + fc_mixer_yaw_factor[i] * cy;
        m_max = fmaxf(m_max, mot[i]);
        m_min = fminf(m_min, mot[i]);
    }
    float shift = 0.0f;
    if (m_max > hi && m_min - (m_max - hi) >= lo) {
        shift = hi - m_max;
        flags |= FC_SAT_THR_HIGH;
    } else if (m_min < lo && m_max + (lo - m_min) <= hi) {
        shift = lo - m_min;
        flags |= FC_SAT_THR_LOW;
    }
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        float v = mot[i] + shift;
        if (v > hi || v < lo) {
            v = fc_constrainf(v, lo, hi); /* only the yaw headroom can force this */
            flags |= FC_SAT_YAW;
        }
        m->motor_us[i] = v;
    }
    m->throttle_us = t + shift;
    m->roll_us = cr;
    m->pitch_us = cp;
    m->yaw_us = cy;
    m->sat_flags = flags;
}

/* Largest step of one output in dt for a full-range transition time; 0 = none. */
static float slew_step(float range_us, float time_s, float dt_s)
{
    return (time_s > 0.0f) ? range_us * dt_s / time_s : 1e30f;
}

fc_status_t fc_mixer_update(fc_mixer_t *m, const fc_mixer_config_t *cfg, int spool,
                            float throttle_us, float roll_us, float pitch_us, float yaw_us,
                            float dt_s, uint16_t pwm_out_us[FC_MIXER_MOTORS])
{
    bool bad = false;
    const float thr = finite_or_zero(throttle_us, &bad);
    const float cr = finite_or_zero(roll_us, &bad);
    const float cp = finite_or_zero(pitch_us, &bad);
    const float cy = finite_or_zero(yaw_us, &bad);
    const float dt = (dt_s > 0.0f && fc_finitef(dt_s)) ? dt_s : 0.0f;

    if (spool == FC_SPOOL_FLIGHT) {
        mix_flight(m, cfg, bad ? cfg->pwm_min_us : thr, cr, cp, cy);
    } else {
        /* Shut down: everything at the minimum. Ground idle: throttle only. */
        const float v = (spool == FC_SPOOL_GROUND_IDLE)
                            ? fc_constrainf(thr, cfg->pwm_min_us, cfg->pwm_max_us)
                            : cfg->pwm_min_us;
        for (int i = 0; i < FC_MIXER_MOTORS; i++) {
            m->motor_us[i] = v;
        }
        m->throttle_us = v;
        m->roll_us = 0.0f;
        m->pitch_us = 0.0f;
        m->yaw_us = 0.0f;
        m->sat_flags = 0;
    }

    const float range = cfg->pwm_max_us - cfg->pwm_min_us;
    const bool slew = cfg->slew_enable && spool != FC_SPOOL_SHUT_DOWN;
    const float up = slew ? slew_step(range, cfg->slew_up_time_s, dt) : 1e30f;
    const float dn = slew ? slew_step(range, cfg->slew_dn_time_s, dt) : 1e30f;
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        const float prev = m->out_us[i];
        float v = fc_constrainf(m->motor_us[i], prev - dn, prev + up);
        v = fc_constrainf(v, cfg->pwm_min_us, cfg->pwm_max_us);
        if (!fc_finitef(v)) {
            v = cfg->pwm_min_us;
        }
        m->out_us[i] = v;
        pwm_out_us[i] = (uint16_t)(v + 0.5f);
    }
    return bad ? FC_ERR_NONFINITE : FC_OK;
}
