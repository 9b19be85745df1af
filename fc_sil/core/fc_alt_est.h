/*
 * fc_alt_est.h - vertical estimator: barometer + accelerometer complementary
 * filter (paper 3.4: BARO goes to the altitude estimator).
 *
 * Sign conventions: altitude and climb rate are positive UP (alt_m above the
 * home reference, climb_m_s > 0 climbing), although the world frame is NED:
 *     accel_up = -(R(q) f_frd + g e_down)_down,  alt_m = -pos_down.
 * The filter is ArduPilot's old third-order complementary filter (AP_InertialNav,
 * INAV_TC_Z): prediction with the bias-corrected vertical acceleration at the
 * IMU rate, correction by the baro altitude error at the baro rate with gains
 * k1 = 3/tau, k2 = 3/tau^2, k3 = 1/tau^3 (a triple pole at -1/tau), the third
 * state being the accelerometer's vertical bias.
 *
 * While disarmed the vehicle sits on the ground: the vertical accelerometer
 * bias is learned there (an EMA of tau 1 s), so the filter starts right at
 * take-off instead of learning it from the baro in flight.
 *
 * A baro jump (an innovation beyond FC_ALT_GATE_M, which fault-free flight stays well
 * below: at most 0.68 m in S1..S4) corrects the height only, not the climb rate or the
 * bias: the third-order filter would otherwise read the jump as a climb and overshoot it by
 * its design's 21 % (failure bench F3: a 5 m baro glitch took ours 7.6 m down where
 * ArduCopter's EKF3, which keeps its climb rate on the GNSS, went 5 m). The gate gives up
 * after FC_ALT_GATE_MAX_S, so an accelerometer that really drifts is still corrected.
 *
 * Baro altitude: the ISA relation h = 44330.77 (1 - (p/p0)^0.190263) m with p0
 * the ground pressure, learned while disarmed (an EMA of tau 1 s) and frozen
 * at arming, so altitude is relative to where the vehicle was armed.
 */
#ifndef FC_ALT_EST_H
#define FC_ALT_EST_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_status.h"

typedef struct fc_alt_est {
    float alt_m;              /* altitude above the reference, up [m] */
    float climb_m_s;          /* vertical speed, up [m/s] */
    float accel_bias_m_s2;    /* vertical accelerometer bias, up [m/s^2] */
    float accel_up_m_s2;      /* last bias-corrected vertical acceleration, up [m/s^2] */
    float ground_pressure_pa; /* p0 [Pa] */
    float baro_alt_m;         /* last baro altitude over p0 [m] */
    float innov_m;            /* last in-flight baro innovation, baro - estimate [m] */
    int64_t last_baro_ns;     /* sim time of the last baro sample [ns] */
    int64_t gated_since_ns;   /* sim time the innovation went beyond the gate (if gated) */
    bool gated;               /* the innovation is beyond the gate */
    bool height_only;         /* the last sample corrected the height only (a jump) */
    bool have_baro;
    uint32_t rejected;        /* baro samples refused (non-finite, <= 0 Pa) */
} fc_alt_est_t;

void fc_alt_est_reset(fc_alt_est_t *e);
/* IMU-rate prediction with the attitude and the (filtered) specific force.
 * calibrate (disarmed, on the ground, so the true vertical acceleration is 0):
 * learn the accelerometer's vertical bias instead of integrating it. */
void fc_alt_est_predict(fc_alt_est_t *e, const float q_wxyz[4], const float accel_frd_m_s2[3],
                        float dt_s, bool calibrate);
/* One baro sample. calibrate: still learning p0 (disarmed). */
fc_status_t fc_alt_est_baro(fc_alt_est_t *e, int64_t sim_ns, float pressure_pa, float tau_s,
                            bool calibrate);

#endif /* FC_ALT_EST_H */
