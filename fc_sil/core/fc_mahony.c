/*
 * fc_mahony.c - Mahony attitude estimator (see fc_mahony.h for the design
 * and the two corrections to the paper's Listing 3).
 */
#include "fc_mahony.h"

#include "fc_math.h"

/* A MEMS gyro whose bias exceeds this is broken; bounding the integrator and
 * the bias keeps a bad accelerometer stretch from winding them up. */
#define FC_MAHONY_BIAS_MAX_RAD_S 0.5f
/* Magnetometer heading errors older than this are no longer applied (the
 * magnetometer normally reports at 100 Hz; 25 missed samples means it is gone). */
#define FC_MAHONY_HEADING_STALE_S 0.25f
/* An acceleration reference older than this is ignored (GNSS-derived ones
 * arrive at 5 to 10 Hz; two missed updates mean the source is gone). */
#define FC_MAHONY_ACCEL_REF_STALE_S 0.5f
/* A tilt error beyond this is an alignment error, not a bias (a 0.1 rad/s
 * bias holds the tilt only 0.2 rad off at kp = 0.5): the integrator waits, or
 * it would learn a fake bias during the initial convergence and overshoot. */
#define FC_MAHONY_I_GATE_RAD 0.2f
/* A GNSS-aided error older than this is dropped (fixes come at 5 to 10 Hz;
 * two missed fixes mean the aiding is gone and the accelerometer takes over). */
#define FC_MAHONY_GNSS_STALE_S 0.5f
/* Specific forces below this carry no usable direction (near free fall). */
#define FC_MAHONY_GNSS_MIN_F_M_S2 (0.3f * FC_GRAVITY_M_S2)
/* Heading-offset learning rate per rad of the GNSS error's down component
 * [1/s]. That component is about -2 sin^2(tilt) times the heading error just
 * after the acceleration reverses and decays as the tilt loop re-converges,
 * so doublets every few seconds learn a declination error in 30 to 60 s
 * (S4: 4.5 deg in about 40 s); slow on purpose, as GNSS noise and tilt errors
 * along a one-way acceleration must average out. */
#define FC_MAHONY_HEADING_LEARN_RATE 1.0f
/* Declinations beyond this are outside inhabited latitudes' range: a bound
 * against learning nonsense from a bad stretch. */
#define FC_MAHONY_HEADING_OFFSET_MAX_RAD 0.35f

void fc_mahony_configure(fc_mahony_t *m, const fc_mahony_config_t *cfg)
{
    m->cfg = *cfg;
}

void fc_mahony_set_attitude(fc_mahony_t *m, const float q_wxyz[4])
{
    for (int i = 0; i < 4; i++) {
        m->q_wxyz[i] = q_wxyz[i];
    }
    fc_quat_normalize(m->q_wxyz);
    for (int i = 0; i < 3; i++) {
        m->bias_rad_s[i] = 0.0f;
        m->integ_rad_s[i] = 0.0f;
    }
    fc_mahony_gnss_forget(m); /* a held GNSS error refers to the old attitude */
    m->aligned = true;
}

void fc_mahony_turn_heading(fc_mahony_t *m, float delta_rad)
{
    /* A yaw of +delta is a rotation about NED down applied on the left, as the first
     * heading in fc_mahony_mag is. The held magnetometer error stays right: the rotated
     * field and the declination move by the same delta. */
    const float half = 0.5f * delta_rad;
    const float qz[4] = {cosf(half), 0.0f, 0.0f, sinf(half)};
    float out[4];
    fc_quat_mul(qz, m->q_wxyz, out);
    for (int i = 0; i < 4; i++) {
        m->q_wxyz[i] = out[i];
    }
    fc_quat_normalize(m->q_wxyz);
    fc_mahony_gnss_forget(m); /* a held GNSS error refers to the old heading */
}

void fc_mahony_init(fc_mahony_t *m, const fc_mahony_config_t *cfg)
{
    fc_mahony_configure(m, cfg);
    float q[4];
    fc_quat_identity(q);
    fc_mahony_set_attitude(m, q);
    m->aligned = false;
    m->trust = 0.0f;
    m->trust_raw = 0.0f;
    m->heading_err_rad = 0.0f;
    m->heading_age_s = 0.0f;
    m->heading_valid = false;
    m->heading_offset_rad = 0.0f;
    m->still = false;
    for (int i = 0; i < 3; i++) {
        m->accel_ref_ned_m_s2[i] = 0.0f;
    }
    m->accel_ref_age_s = 0.0f;
    m->accel_ref_valid = false;
    fc_mahony_gnss_forget(m);
}

fc_status_t fc_mahony_align(fc_mahony_t *m, const float accel_frd_m_s2[3])
{
    if (!fc_finite3(accel_frd_m_s2)) {
        return FC_ERR_NONFINITE;
    }
    const float ax = accel_frd_m_s2[0], ay = accel_frd_m_s2[1], az = accel_frd_m_s2[2];
    if (fc_norm3(accel_frd_m_s2) < 0.1f * FC_GRAVITY_M_S2) {
        return FC_ERR_ARG; /* free fall: no gravity direction to align to */
    }
    /* At rest the specific force is -g along body "down" rotated: f = -R^T (0,0,g). */
    const float roll = atan2f(-ay, -az);
    const float pitch = atan2f(ax, sqrtf(ay * ay + az * az));
    float q[4];
    fc_quat_from_euler(roll, pitch, 0.0f, q);
    fc_mahony_set_attitude(m, q);
    m->heading_valid = false;
    return FC_OK;
}

/* q <- q * exp(omega dt / 2), then renormalise. */
static void integrate_quat(float q[4], const float omega_rad_s[3], float dt_s)
{
    const float half[3] = {0.5f * omega_rad_s[0] * dt_s, 0.5f * omega_rad_s[1] * dt_s,
                           0.5f * omega_rad_s[2] * dt_s};
    const float angle = fc_norm3(half);
    float dq[4];
    if (angle < 1e-4f) {
        /* sin(x)/x = 1 - x^2/6 to float precision here */
        dq[0] = 1.0f - 0.5f * angle * angle;
        dq[1] = half[0];
        dq[2] = half[1];
        dq[3] = half[2];
    } else {
        const float s = sinf(angle) / angle;
        dq[0] = cosf(angle);
        dq[1] = half[0] * s;
        dq[2] = half[1] * s;
        dq[3] = half[2] * s;
    }
    float out[4];
    fc_quat_mul(q, dq, out);
    for (int i = 0; i < 4; i++) {
        q[i] = out[i];
    }
    fc_quat_normalize(q);
}

/* Third row of R(q): body components of NED "down". */
static void down_in_body(const float q[4], float down_frd[3])
{
    down_frd[0] = 2.0f * (q[1] * q[3] - q[0] * q[2]);
    down_frd[1] = 2.0f * (q[2] * q[3] + q[0] * q[1]);
    down_frd[2] = 1.0f - 2.0f * (q[1] * q[1] + q[2] * q[2]);
}

/* (1) Tilt error e: the measured specific-force direction against the
 * predicted one, "up" (gravity alone) or a_ref - g while an acceleration
 * reference is fresh. Returns | |a| - |expected| | / g, the accelerometer's
 * disagreement that trust and the quasi-static test read (1 when |a| is ~0). */
static float tilt_error(fc_mahony_t *m, const float down_frd[3], const float accel_frd_m_s2[3],
                        float dt_s, float e[3])
{
    const float a_norm = fc_norm3(accel_frd_m_s2);
    float g_ratio_err = 1.0f;
    float expect_frd[3] = {-down_frd[0], -down_frd[1], -down_frd[2]};
    float expect_norm = FC_GRAVITY_M_S2;
    if (m->accel_ref_valid && m->accel_ref_age_s < FC_MAHONY_ACCEL_REF_STALE_S) {
        const float f_ned[3] = {m->accel_ref_ned_m_s2[0], m->accel_ref_ned_m_s2[1],
                                m->accel_ref_ned_m_s2[2] - FC_GRAVITY_M_S2};
        const float n = fc_norm3(f_ned);
        if (n > 0.1f * FC_GRAVITY_M_S2) {
            float f_frd[3];
            fc_quat_rotate_inv(m->q_wxyz, f_ned, f_frd);
            for (int i = 0; i < 3; i++) {
                expect_frd[i] = f_frd[i] / n;
            }
            expect_norm = n;
        }
    }
    m->accel_ref_age_s += dt_s;
    e[0] = 0.0f;
    e[1] = 0.0f;
    e[2] = 0.0f;
    if (a_norm > 1e-3f) {
        const float inv = 1.0f / a_norm;
        const float a_dir[3] = {accel_frd_m_s2[0] * inv, accel_frd_m_s2[1] * inv,
                                accel_frd_m_s2[2] * inv};
        fc_cross3(a_dir, expect_frd, e);
        g_ratio_err = fabsf(a_norm - expect_norm) / FC_GRAVITY_M_S2;
    }
    return g_ratio_err;
}

/* (2) Accelerometer trust from the raw |a| (the listing used the normalised one). */
static void update_trust(fc_mahony_t *m, float g_ratio_err, float dt_s)
{
    const fc_mahony_config_t *cfg = &m->cfg;
    const float span = (cfg->trust_span_g > 1e-3f) ? cfg->trust_span_g : 1e-3f;
    m->trust_raw = fc_constrainf(1.0f - g_ratio_err / span, 0.0f, 1.0f);
    if (cfg->trust_ema_enable) {
        m->trust += fc_ema_alpha(dt_s, cfg->trust_tc_s) * (m->trust_raw - m->trust);
    } else {
        m->trust = m->trust_raw;
    }
}

/* The gains of the tilt correction and the weight on its error. */
typedef struct tilt_gains {
    float kp, ki, w;
} tilt_gains_t;

/* (3a) While a GNSS-aided error is fresh it replaces the accelerometer's e,
 * with its own scheduled gains and full weight; its down component teaches
 * the magnetometer's heading offset. */
static tilt_gains_t gnss_aided_error(fc_mahony_t *m, float dt_s, float e[3])
{
    const fc_mahony_config_t *cfg = &m->cfg;
    tilt_gains_t g = {cfg->kp, cfg->ki, m->trust};
    if (fc_mahony_gnss_active(m)) {
        fc_quat_rotate_inv(m->q_wxyz, m->gnss_err_ned_rad, e);
        const fc_aid_sched_config_t sc = {cfg->gnss_boost, cfg->gnss_innov_sigma};
        const float bw = fc_aid_sched_step(&m->gnss_sched, &sc, m->gnss_err_ned_rad, dt_s);
        g.kp = cfg->kp_gnss * bw;
        g.ki = cfg->ki_gnss * bw * bw; /* KI = w^2: the same damping at s times w */
        g.w = 1.0f; /* already free of the vehicle's acceleration: no trust weighting */
        if (m->heading_valid && cfg->kmag > 0.0f) {
            /* A positive down component means the estimate's heading is east of
             * true: the magnetometer's reference must turn east too, as it is
             * subtracted from the measured direction (fc_mahony_mag). */
            m->heading_offset_rad = fc_constrainf(
                m->heading_offset_rad + FC_MAHONY_HEADING_LEARN_RATE * m->gnss_err_down_rad * dt_s,
                -FC_MAHONY_HEADING_OFFSET_MAX_RAD, FC_MAHONY_HEADING_OFFSET_MAX_RAD);
        }
    }
    m->gnss_age_s += dt_s;
    return g;
}

/* (3b) PI correction corr: the weighted tilt error, plus the magnetometer
 * heading while fresh; both feed the integrator, which stays within the bias
 * bound. Returns whether the tilt error was small enough to learn from. */
static bool pi_correction(fc_mahony_t *m, const tilt_gains_t *g, const float e[3],
                          const float down_frd[3], float dt_s, float corr[3])
{
    const fc_mahony_config_t *cfg = &m->cfg;
    const bool learn = fc_norm3(e) < FC_MAHONY_I_GATE_RAD;
    for (int i = 0; i < 3; i++) {
        const float ew = g->w * e[i];
        corr[i] = g->kp * ew;
        if (learn) {
            m->integ_rad_s[i] += g->ki * ew * dt_s;
        }
    }
    if (m->heading_valid && m->heading_age_s < FC_MAHONY_HEADING_STALE_S) {
        /* Rotate the estimate by -heading_err about NED down: body axis = R^T e_down. */
        for (int i = 0; i < 3; i++) {
            const float em = -m->heading_err_rad * down_frd[i];
            corr[i] += cfg->kmag * em;
            m->integ_rad_s[i] += cfg->ki * em * dt_s;
        }
    }
    m->heading_age_s += dt_s;
    for (int i = 0; i < 3; i++) {
        m->integ_rad_s[i] =
            fc_constrainf(m->integ_rad_s[i], -FC_MAHONY_BIAS_MAX_RAD_S, FC_MAHONY_BIAS_MAX_RAD_S);
    }
    return learn;
}

/* (5) Quasi-static: hand what the integrator learned to the bias estimate. */
static void hand_over_bias(fc_mahony_t *m, const float gyro_frd_rad_s[3], float g_ratio_err,
                           bool learn, float dt_s)
{
    const fc_mahony_config_t *cfg = &m->cfg;
    const float rate_unbiased[3] = {gyro_frd_rad_s[0] - m->bias_rad_s[0],
                                    gyro_frd_rad_s[1] - m->bias_rad_s[1],
                                    gyro_frd_rad_s[2] - m->bias_rad_s[2]};
    m->still = (fc_norm3(rate_unbiased) < cfg->still_gyro_rad_s)
               && (g_ratio_err < cfg->still_acc_g);
    if (cfg->bias_enable && m->still && learn) {
        const float alpha = 1.0f - expf(-dt_s * cfg->bias_rate_hz);
        for (int i = 0; i < 3; i++) {
            const float moved = alpha * m->integ_rad_s[i];
            m->bias_rad_s[i] = fc_constrainf(m->bias_rad_s[i] - moved, -FC_MAHONY_BIAS_MAX_RAD_S,
                                             FC_MAHONY_BIAS_MAX_RAD_S);
            m->integ_rad_s[i] -= moved;
        }
    }
}

fc_status_t fc_mahony_update(fc_mahony_t *m, const float gyro_frd_rad_s[3],
                             const float accel_frd_m_s2[3], float dt_s)
{
    if (!fc_finite3(gyro_frd_rad_s) || !fc_finite3(accel_frd_m_s2)) {
        return FC_ERR_NONFINITE;
    }
    if (!(dt_s > 0.0f) || !fc_finitef(dt_s)) {
        return FC_ERR_ARG;
    }
    float down_frd[3];
    down_in_body(m->q_wxyz, down_frd);
    float e[3];
    const float g_ratio_err = tilt_error(m, down_frd, accel_frd_m_s2, dt_s, e);
    update_trust(m, g_ratio_err, dt_s);
    const tilt_gains_t g = gnss_aided_error(m, dt_s, e);
    float corr[3];
    const bool learn = pi_correction(m, &g, e, down_frd, dt_s, corr);

    /* (4) integrate the corrected, bias-free rate and renormalise. */
    float omega[3];
    for (int i = 0; i < 3; i++) {
        omega[i] = gyro_frd_rad_s[i] - m->bias_rad_s[i] + corr[i] + m->integ_rad_s[i];
    }
    integrate_quat(m->q_wxyz, omega, dt_s);

    hand_over_bias(m, gyro_frd_rad_s, g_ratio_err, learn, dt_s);
    return FC_OK;
}

fc_status_t fc_mahony_mag(fc_mahony_t *m, const float field_frd[3], float declination_rad)
{
    if (!fc_finite3(field_frd) || !fc_finitef(declination_rad)) {
        return FC_ERR_NONFINITE;
    }
    float field_ned[3];
    fc_quat_rotate(m->q_wxyz, field_frd, field_ned);
    const float horiz = sqrtf(field_ned[0] * field_ned[0] + field_ned[1] * field_ned[1]);
    if (horiz < 1e-6f) {
        return FC_ERR_ARG; /* at a magnetic pole the field has no heading */
    }
    /* With only a heading error d = yaw_est - yaw_true, R_est R_true^T = Rz(d), so the
     * rotated field points d (plus the declination) east of north. */
    const float err =
        fc_wrap_pi(atan2f(field_ned[1], field_ned[0]) - declination_rad - m->heading_offset_rad);
    if (!m->heading_valid) {
        /* First heading: take it at once rather than converging from yaw 0. */
        const float half = -0.5f * err;
        const float qz[4] = {cosf(half), 0.0f, 0.0f, sinf(half)};
        float out[4];
        fc_quat_mul(qz, m->q_wxyz, out); /* rotation about NED down, applied on the left */
        for (int i = 0; i < 4; i++) {
            m->q_wxyz[i] = out[i];
        }
        fc_quat_normalize(m->q_wxyz);
        m->heading_err_rad = 0.0f;
    } else {
        m->heading_err_rad = err;
    }
    m->heading_age_s = 0.0f;
    m->heading_valid = true;
    return FC_OK;
}

fc_status_t fc_mahony_set_accel_ref(fc_mahony_t *m, const float accel_ned_m_s2[3])
{
    if (!fc_finite3(accel_ned_m_s2)) {
        return FC_ERR_NONFINITE;
    }
    for (int i = 0; i < 3; i++) {
        m->accel_ref_ned_m_s2[i] = accel_ned_m_s2[i];
    }
    m->accel_ref_age_s = 0.0f;
    m->accel_ref_valid = true;
    return FC_OK;
}

void fc_mahony_gnss_forget(fc_mahony_t *m)
{
    for (int i = 0; i < 3; i++) {
        m->gnss_err_ned_rad[i] = 0.0f;
    }
    m->gnss_err_down_rad = 0.0f;
    m->gnss_age_s = 0.0f;
    m->gnss_valid = false;
    fc_aid_sched_reset(&m->gnss_sched);
}

bool fc_mahony_gnss_active(const fc_mahony_t *m)
{
    return m->gnss_valid && m->gnss_age_s < FC_MAHONY_GNSS_STALE_S;
}

fc_status_t fc_mahony_gnss(fc_mahony_t *m, const float f_imu_ned_m_s2[3],
                           const float f_gnss_ned_m_s2[3])
{
    if (!fc_finite3(f_imu_ned_m_s2) || !fc_finite3(f_gnss_ned_m_s2)) {
        return FC_ERR_NONFINITE;
    }
    const float n_imu = fc_norm3(f_imu_ned_m_s2);
    const float n_gnss = fc_norm3(f_gnss_ned_m_s2);
    if (n_imu < FC_MAHONY_GNSS_MIN_F_M_S2 || n_gnss < FC_MAHONY_GNSS_MIN_F_M_S2) {
        return FC_ERR_ARG;
    }
    float a[3], b[3];
    for (int i = 0; i < 3; i++) {
        a[i] = f_imu_ned_m_s2[i] / n_imu;
        b[i] = f_gnss_ned_m_s2[i] / n_gnss;
    }
    if (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] <= 0.0f) {
        return FC_ERR_ARG; /* more than 90 degrees apart: a glitch, not a tilt */
    }
    /* Same convention as the accelerometer path (measured x expected, there in
     * body axes): R (a x b) = (R a) x (R b), so this is that error in NED. The
     * down component is a heading error; the magnetometer owns the heading. */
    const float since_prev_s = m->gnss_valid ? m->gnss_age_s : 0.0f;
    fc_cross3(a, b, m->gnss_err_ned_rad);
    fc_aid_sched_fix(&m->gnss_sched, m->gnss_err_ned_rad, since_prev_s);
    m->gnss_err_down_rad = m->gnss_err_ned_rad[2];
    m->gnss_err_ned_rad[2] = 0.0f;
    m->gnss_age_s = 0.0f;
    m->gnss_valid = true;
    return FC_OK;
}
