/*
 * fc_ins.h - IMU front end: gyro and accelerometer low-pass filters
 * (INS_GYRO_FILTER, INS_ACCEL_FILTER; 2nd-order Butterworth biquads as
 * ArduPilot's LowPassFilter2p) and an optional static gyro notch
 * (INS_HNTCH_*; the centre does not track motor RPM).
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
#include "fc_status.h"

typedef struct fc_ins_config {
    float gyro_cutoff_hz;  /* 0 = off */
    float accel_cutoff_hz; /* 0 = off */
    bool notch_enable;
    float notch_center_hz;
    float notch_bandwidth_hz; /* -3 dB width */
} fc_ins_config_t;

typedef struct fc_ins {
    fc_ins_config_t cfg;
    float dt_s;                 /* sample period the coefficients were computed for [s] */
    fc_biquad_t gyro_lpf[3];
    fc_biquad_t accel_lpf[3];
    fc_biquad_t gyro_notch[3];
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

#endif /* FC_INS_H */
