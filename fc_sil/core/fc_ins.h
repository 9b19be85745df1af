/*
 * fc_ins.h - IMU front end: the gyro's harmonic notches (INS_HNTCH_* and
 * INS_HNTC2_*, fc_notch.h), then the gyro and accelerometer low-pass filters
 * (INS_GYRO_FILTER, INS_ACCEL_FILTER; 2nd-order Butterworth biquads as
 * ArduPilot's LowPassFilter2p). The notches come first, as in ArduPilot's
 * AP_InertialSensor_Backend::apply_gyro_filters, so the low-pass also smooths
 * what a moving notch leaves; everything downstream (estimator, rate loop and
 * its D term) sees the filtered gyro.
 *
 * A non-finite sample is refused whole (FC_ERR_NONFINITE) and the outputs
 * keep their previous values, so a NaN can never enter a filter state. The
 * first accepted sample primes every filter to its value: no start-up
 * transient (an accelerometer LPF starting from 0 g would zero the
 * estimator's accelerometer trust for a while).
 */
#ifndef FC_INS_H
#define FC_INS_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_filter.h"
#include "fc_notch.h"
#include "fc_status.h"

#define FC_INS_NOTCHES 2 /* INS_HNTCH_*, INS_HNTC2_*, applied in that order */

typedef struct fc_ins_config {
    float gyro_cutoff_hz;  /* 0 = off */
    float accel_cutoff_hz; /* 0 = off */
    fc_notch_config_t notch[FC_INS_NOTCHES];
} fc_ins_config_t;

typedef struct fc_ins {
    fc_ins_config_t cfg;
    float dt_s;                 /* sample period the coefficients were computed for [s] */
    fc_biquad_t gyro_lpf[3];
    fc_biquad_t accel_lpf[3];
    fc_notch_t notch[FC_INS_NOTCHES];
    float gyro_frd_rad_s[3];    /* filtered body rate, FRD [rad/s] */
    float accel_frd_m_s2[3];    /* filtered specific force, FRD [m/s^2] */
    uint32_t rejected;          /* non-finite samples refused */
    bool primed;                /* false until the first accepted sample */
} fc_ins_t;

/* Initialise (state cleared, not primed). Returns the first filter error, if any
 * (that filter then passes through). */
fc_status_t fc_ins_init(fc_ins_t *ins, const fc_ins_config_t *cfg, float dt_s);
/* New configuration or sample period, filter states kept. */
fc_status_t fc_ins_configure(fc_ins_t *ins, const fc_ins_config_t *cfg, float dt_s);
fc_status_t fc_ins_update(fc_ins_t *ins, const float accel_frd_m_s2[3],
                          const float gyro_frd_rad_s[3]);

/* Is any notch enabled? (Nothing to track otherwise.) */
bool fc_ins_notch_enabled(const fc_ins_t *ins);
/* Once per loop tick of tick_s: the notches' centres from what the FC knows
 * of the rotors (fc_notch_track). */
void fc_ins_notch_track(fc_ins_t *ins, const fc_notch_inputs_t *in, float tick_s);

#endif /* FC_INS_H */
