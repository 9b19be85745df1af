/*
 * fc_alt_est.c - baro + accel vertical complementary filter (see fc_alt_est.h).
 */
#include "fc_alt_est.h"

#include "fc_math.h"

#define FC_ALT_P0_TAU_S 1.0f   /* ground-pressure and accel-bias EMAs while disarmed */
#define FC_ALT_MAX_BARO_DT_S 0.2f /* a longer baro gap is corrected as if 0.2 s */
#define FC_ALT_GATE_M 1.5f        /* a larger innovation is a jump: height only (.h) */
#define FC_ALT_GATE_OUT_M 0.5f    /* until the height has caught up to within this */
#define FC_ALT_GATE_MAX_S 10.0f   /* then the full correction again (.h) */

void fc_alt_est_reset(fc_alt_est_t *e)
{
    e->alt_m = 0.0f;
    e->climb_m_s = 0.0f;
    e->accel_bias_m_s2 = 0.0f;
    e->accel_up_m_s2 = 0.0f;
    e->ground_pressure_pa = 0.0f;
    e->baro_alt_m = 0.0f;
    e->innov_m = 0.0f;
    e->last_baro_ns = 0;
    e->gated_since_ns = 0;
    e->gated = false;
    e->height_only = false;
    e->have_baro = false;
    e->rejected = 0;
}

void fc_alt_est_predict(fc_alt_est_t *e, const float q_wxyz[4], const float accel_frd_m_s2[3],
                        float dt_s, bool calibrate)
{
    if (!fc_finite3(accel_frd_m_s2) || !(dt_s > 0.0f)) {
        return;
    }
    float f_ned[3];
    fc_quat_rotate(q_wxyz, accel_frd_m_s2, f_ned);
    /* Kinematic acceleration = specific force + gravity; NED down -> up flips the sign. */
    const float a_up_raw = -(f_ned[2] + FC_GRAVITY_M_S2);
    if (calibrate) {
        e->accel_bias_m_s2 += fc_ema_alpha(dt_s, FC_ALT_P0_TAU_S) * (a_up_raw - e->accel_bias_m_s2);
        e->accel_up_m_s2 = 0.0f;
        return; /* altitude and climb follow the baro while calibrating */
    }
    const float a_up = a_up_raw - e->accel_bias_m_s2;
    e->accel_up_m_s2 = a_up;
    e->alt_m += (e->climb_m_s + 0.5f * a_up * dt_s) * dt_s;
    e->climb_m_s += a_up * dt_s;
}

/* True while this innovation is a jump to correct the height only (see the header). */
static bool baro_jump(fc_alt_est_t *e, int64_t sim_ns, float err)
{
    if (!(fabsf(err) > (e->gated ? FC_ALT_GATE_OUT_M : FC_ALT_GATE_M))) {
        e->gated = false;
        return false;
    }
    if (!e->gated) {
        e->gated = true;
        e->gated_since_ns = sim_ns;
    }
    return (float)(sim_ns - e->gated_since_ns) * 1e-9f < FC_ALT_GATE_MAX_S;
}

fc_status_t fc_alt_est_baro(fc_alt_est_t *e, int64_t sim_ns, float pressure_pa, float tau_s,
                            bool calibrate)
{
    if (!fc_finitef(pressure_pa) || !(pressure_pa > 0.0f)) {
        e->rejected++;
        return FC_ERR_NONFINITE;
    }
    float dt_s = FC_ALT_MAX_BARO_DT_S;
    if (e->have_baro && sim_ns > e->last_baro_ns) {
        dt_s = fminf((float)(sim_ns - e->last_baro_ns) * 1e-9f, FC_ALT_MAX_BARO_DT_S);
    }
    if (!e->have_baro || !(e->ground_pressure_pa > 0.0f)) {
        e->ground_pressure_pa = pressure_pa;
    } else if (calibrate) {
        e->ground_pressure_pa += fc_ema_alpha(dt_s, FC_ALT_P0_TAU_S)
                                 * (pressure_pa - e->ground_pressure_pa);
    }
    e->baro_alt_m = 44330.77f * (1.0f - powf(pressure_pa / e->ground_pressure_pa, 0.190263f));
    if (!e->have_baro || calibrate) {
        /* On the ground before arming: follow the baro, no dynamics to estimate. */
        e->alt_m = e->baro_alt_m;
        e->climb_m_s = 0.0f;
        e->innov_m = 0.0f;
        e->gated = false;
        e->height_only = false;
    } else {
        const float tau = fmaxf(tau_s, 0.05f);
        const float err = e->baro_alt_m - e->alt_m;
        e->innov_m = err;
        /* Keep each correction step below one (stable) even at a slow baro. */
        const float k1 = fminf(3.0f / tau * dt_s, 1.0f);
        const float k2 = fminf(3.0f / (tau * tau) * dt_s, 1.0f);
        const float k3 = fminf(1.0f / (tau * tau * tau) * dt_s, 1.0f);
        e->alt_m += k1 * err;
        e->height_only = baro_jump(e, sim_ns, err);
        if (!e->height_only) {
            e->climb_m_s += k2 * err;
            e->accel_bias_m_s2 -= k3 * err; /* alt lagging the baro: the accel under-reads */
        }
    }
    e->last_baro_ns = sim_ns;
    e->have_baro = true;
    return FC_OK;
}
