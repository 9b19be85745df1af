/*
 * fc_mixer.c - quad-X mixer (see fc_mixer.h for order, signs and priorities).
 */
#include "fc_mixer.h"

#include "fc_math.h"
#include "fc_mixer_sat.h"

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

/* One flight-band mix in progress: what each priority leaves to the next. */
typedef struct mix_work {
    float lo, hi;                /* the flight band (MOT_SPIN_MIN..MAX) [us] */
    float t;                     /* throttle [us] */
    float cr, cp, cy;            /* roll, pitch, yaw inputs as they will be applied [us] */
    float rp[FC_MIXER_MOTORS];   /* roll + pitch part of each motor [us] */
    float rp_max, rp_min;        /* its extremes [us] */
    uint8_t flags;               /* FC_SAT_* so far */
} mix_work_t;

/* Throttle into the band. */
static void band_throttle(mix_work_t *w, float thr)
{
    w->t = thr;
    if (w->t > w->hi) {
        w->t = w->hi;
        w->flags |= FC_SAT_THR_HIGH;
    } else if (w->t < w->lo) {
        w->t = w->lo;
        w->flags |= FC_SAT_THR_LOW;
    }
}

/* Roll and pitch first: scale both down together if they need more than the
 * span (around the collective fc_mixer_sat.h chooses); then the throttle gives
 * way so that they fit. */
static void fit_roll_pitch(mix_work_t *w)
{
    const float span = w->hi - w->lo;
    w->rp_max = -1e30f;
    w->rp_min = 1e30f;
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        w->rp[i] = fc_mixer_roll_factor[i] * w->cr + fc_mixer_pitch_factor[i] * w->cp;
        w->rp_max = fmaxf(w->rp_max, w->rp[i]);
        w->rp_min = fminf(w->rp_min, w->rp[i]);
    }
    if (w->rp_max - w->rp_min > span) {
        /* fc_mixer_sat.h: the collective follows the demand, as ArduCopter's rpy_scale */
        const float c = fc_mixer_sat_collective(w->t, w->lo, w->hi);
        const float scale = fc_mixer_sat_scale(c, w->lo, w->hi, w->rp_min, w->rp_max);
        w->cr *= scale;
        w->cp *= scale;
        for (int i = 0; i < FC_MIXER_MOTORS; i++) {
            w->rp[i] *= scale;
        }
        w->rp_max *= scale;
        w->rp_min *= scale;
        w->flags |= FC_SAT_ROLL | FC_SAT_PITCH;
    }
    const float t_rp = fc_constrainf(w->t, w->lo - w->rp_min, w->hi - w->rp_max);
    if (t_rp < w->t) {
        w->flags |= FC_SAT_THR_HIGH;
    } else if (t_rp > w->t) {
        w->flags |= FC_SAT_THR_LOW;
    }
    w->t = t_rp;
}

/* Yaw: the room left in the direction each motor is pushed, at least the headroom. */
static void fit_yaw(mix_work_t *w, float yaw_headroom_us)
{
    float room = 1e30f;
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        const float base = w->t + w->rp[i];
        const float r = (fc_mixer_yaw_factor[i] * w->cy >= 0.0f) ? w->hi - base : base - w->lo;
        room = fminf(room, r);
    }
    const float yaw_allowed = fmaxf(room, yaw_headroom_us);
    if (fabsf(w->cy) > yaw_allowed) {
        w->cy = (w->cy > 0.0f) ? yaw_allowed : -yaw_allowed;
        w->flags |= FC_SAT_YAW;
    }
}

/* The motors: the throttle gives way again for the yaw it had to make room
 * for, then each output within the band. */
static void place_motors(fc_mixer_t *m, mix_work_t *w)
{
    float m_max = -1e30f, m_min = 1e30f;
    float mot[FC_MIXER_MOTORS];
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        mot[i] = w->t + w->rp[i] + fc_mixer_yaw_factor[i] * w->cy;
        m_max = fmaxf(m_max, mot[i]);
        m_min = fminf(m_min, mot[i]);
    }
    float shift = 0.0f;
    if (m_max > w->hi && m_min - (m_max - w->hi) >= w->lo) {
        shift = w->hi - m_max;
        w->flags |= FC_SAT_THR_HIGH;
    } else if (m_min < w->lo && m_max + (w->lo - m_min) <= w->hi) {
        shift = w->lo - m_min;
        w->flags |= FC_SAT_THR_LOW;
    }
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        float v = mot[i] + shift;
        if (v > w->hi || v < w->lo) {
            v = fc_constrainf(v, w->lo, w->hi); /* only the yaw headroom can force this */
            w->flags |= FC_SAT_YAW;
        }
        m->motor_us[i] = v;
    }
    w->t += shift;
}

/* Mix in the flight band [lo, hi]; fills m->motor_us and the flags. */
static void mix_flight(fc_mixer_t *m, const fc_mixer_config_t *cfg, float thr, float cr,
                       float cp, float cy)
{
    const float range = cfg->pwm_max_us - cfg->pwm_min_us;
    mix_work_t w = {0};
    w.lo = cfg->pwm_min_us + cfg->spin_min * range;
    w.hi = cfg->pwm_min_us + cfg->spin_max * range;
    w.cr = cr;
    w.cp = cp;
    w.cy = cy;
    band_throttle(&w, thr);
    fit_roll_pitch(&w);
    fit_yaw(&w, cfg->yaw_headroom_us);
    place_motors(m, &w);
    m->throttle_us = w.t;
    m->roll_us = w.cr;
    m->pitch_us = w.cp;
    m->yaw_us = w.cy;
    m->sat_flags = w.flags;
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
