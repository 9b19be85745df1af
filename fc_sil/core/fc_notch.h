/*
 * fc_notch.h - a harmonic notch on the gyro, with ArduCopter 4.6's parameters
 * and tracking semantics (INS_HNTCH_* / INS_HNTC2_*; ArduPilot's
 * HarmonicNotchFilter, NotchFilter and AP_Vehicle::update_dynamic_notch).
 *
 * What follows ArduCopter:
 * - Each notch has the transfer function of ArduPilot's NotchFilter: the
 *   bilinear transform, pre-warped at the centre, of
 *       H(s) = (s^2 + A^2 (w0/Q) s + w0^2) / (s^2 + (w0/Q) s + w0^2)
 *   with A = 10^(-ATT/40) (so the centre is ATT dB down) and Q from the
 *   bandwidth BW at FREQ as an octave width (r = f / (f - BW/2),
 *   Q = r / (r^2 - 1): ArduPilot's sqrt(2^N)/(2^N - 1) with 2^N = r^2).
 *   Q is fixed at configuration and shared by every harmonic and every
 *   tracked centre (constant-Q notches).
 * - A bank of notches: each set bit k of HMNCS puts one at (k+1) x every
 *   source centre; double, triple and quintuple notches (OPTS) split each
 *   into 2, 3 or 5 of bandwidth BW/n spaced by the fraction BW/(32 FREQ).
 *   At most FC_NOTCH_MAX_FILTERS, laid out harmonic-major as ArduPilot does,
 *   so the highest harmonics of the last sources are what a tight budget drops.
 * - Centres: MODE 0 FREQ; 1 FREQ max(FM_RAT, sqrt(throttle/REF)), bypassed
 *   while the motors are stopped; 3 ESC telemetry (mean x REF, at least FREQ,
 *   or one centre per motor with OPTS bit 1); 4 the in-flight FFT; 2 and 5
 *   (RPM sensor) have no sensor here and stay at FREQ, as ArduCopter does
 *   without a reading. REF = 0 fixes the centre at FREQ in every mode.
 *   Updated at 200 Hz, or every loop (PWM) tick with OPTS bit 2.
 * - A centre below FREQ x FM_RAT fades its attenuation out down to a quarter
 *   of it and switches off below; a harmonic at or above 0.48 x the sample
 *   rate is off. Each centre moves at most 5 % per update.
 *
 * Where we differ, and why: ArduPilot recomputes a biquad's coefficients at
 * each update and steps the filter to them (the 5 % slew keeps the steps
 * small). Here each notch is a trapezoidal state-variable filter (Zavalishin's
 * TPT SVF, in Simper's form), whose states are integrator outputs that stay
 * meaningful while the tuning moves, and its tuning (g = tan(pi f dt), 1/Q and
 * the depth) ramps linearly sample by sample from the old value to the new one
 * over the time until the next update: no coefficient step at all. The
 * frozen-time response is exactly the ArduPilot biquad's (tests check it
 * against scipy.signal); a retune leaves the output within the noise
 * (tests/fc_sil/test_notch.py, test_notch_flight.py).
 *
 * No heap, no globals, float32. With `enable` false the notch is never
 * called (fc_ins skips it), so the gyro path is bit for bit the plain one.
 */
#ifndef FC_NOTCH_H
#define FC_NOTCH_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_status.h"

#define FC_NOTCH_MAX_HARMONICS 16 /* HMNCS bits */
#define FC_NOTCH_MAX_SOURCES 8    /* centres: one per motor (ESC) or per FFT peak */
/* ArduPilot's HAL_HNF_MAX_FILTERS on boards without an H7 (F4: 24): a triple
 * notch per motor of a quad with two harmonics. */
#define FC_NOTCH_MAX_FILTERS 24

typedef enum fc_notch_mode {
    FC_NOTCH_MODE_FIXED = 0,
    FC_NOTCH_MODE_THROTTLE = 1,
    FC_NOTCH_MODE_RPM = 2, /* RPM sensor: none here, stays at FREQ */
    FC_NOTCH_MODE_ESC = 3,
    FC_NOTCH_MODE_FFT = 4,
    FC_NOTCH_MODE_RPM2 = 5 /* second RPM sensor: none here, stays at FREQ */
} fc_notch_mode_t;

/* INS_HNTCH_OPTS bits (ArduPilot HarmonicNotchFilterParams::Options). */
#define FC_NOTCH_OPT_DOUBLE 0x01u       /* two notches per harmonic */
#define FC_NOTCH_OPT_MULTI_SOURCE 0x02u /* one centre per motor / FFT peak */
#define FC_NOTCH_OPT_LOOP_RATE 0x04u    /* update the centres every loop tick, not 200 Hz */
#define FC_NOTCH_OPT_ALL_IMUS 0x08u     /* one IMU here: no effect */
#define FC_NOTCH_OPT_TRIPLE 0x10u       /* three notches per harmonic */
#define FC_NOTCH_OPT_LOW_AS_MIN 0x20u   /* a low centre sits at the minimum, never fades out */
#define FC_NOTCH_OPT_QUINTUPLE 0x40u    /* five notches per harmonic */

typedef struct fc_notch_config {
    bool enable;
    uint8_t mode;       /* fc_notch_mode_t */
    uint16_t options;   /* FC_NOTCH_OPT_* */
    uint32_t harmonics; /* HMNCS: bit k = the (k+1)-th harmonic */
    float freq_hz;      /* FREQ: the centre (fixed), at REF (throttle), the floor (ESC) [Hz] */
    float bw_hz;        /* BW: -3 dB bandwidth at FREQ [Hz] */
    float att_db;       /* ATT: attenuation at the centre [dB] */
    float ref;          /* REF: throttle at FREQ (MODE 1), ESC frequency scale (MODE 3) */
    float fm_ratio;     /* FM_RAT: lowest centre as a fraction of FREQ */
} fc_notch_config_t;

/* What the flight controller knows of the rotors now (fc_notch_feed.c fills it). */
typedef struct fc_notch_inputs {
    float throttle;                      /* motors' throttle out, 0..1 of the PWM range */
    bool motors_stopped;                 /* spool shut down */
    uint8_t esc_count;                   /* motors that ever sent telemetry */
    float esc_hz[FC_NOTCH_MAX_SOURCES];  /* rotor frequency per motor [Hz]; 0 = stale */
    float esc_mean_hz;                   /* mean over the fresh motors [Hz]; 0 = none */
    uint8_t fft_count;                   /* FFT centres; 0 = no FFT result */
    float fft_hz[FC_NOTCH_MAX_SOURCES];  /* [0]: the tracked fundamental, then other peaks [Hz] */
} fc_notch_inputs_t;

/* One notch of the bank: tuning shared by the three axes, states per axis. */
typedef struct fc_notch_filter {
    float center_hz;          /* centre the tuning is heading for [Hz] */
    float g, k, m;            /* tan(pi f dt), 1/Q, depth k (1 - A^2): now */
    float g_to, k_to, m_to;   /* ... and where the ramp ends */
    float dg, dk, dm;         /* ... per-sample steps while ramping */
    float c1, c2, c3;         /* SVF gains 1/(1 + g (g + k)), g c1, g c2 */
    float ic1[3], ic2[3];     /* SVF integrator states per axis [rad/s] */
    uint16_t ramp;            /* samples left in the ramp */
    uint8_t state;            /* FC_NOTCH_FILTER_OFF / _START / _ON (fc_notch.c) */
} fc_notch_filter_t;

typedef struct fc_notch {
    fc_notch_config_t cfg;
    float dt_s;            /* sample period the tuning is for [s] */
    float k;               /* 1/Q of each notch */
    float att;             /* A: the centre's gain is A^2 */
    float spread;          /* composite notch spacing, fraction of the centre */
    float min_hz;          /* FREQ x FM_RAT [Hz] */
    uint8_t composite;     /* notches per harmonic: 1, 2, 3 or 5 */
    uint8_t count;         /* filters laid out by the latest centres */
    uint8_t n_sources;     /* centres of the latest update */
    uint8_t countdown;     /* loop ticks to the next centre update */
    bool active;           /* false: bypassed (throttle notch with the motors stopped) */
    float source_hz[FC_NOTCH_MAX_SOURCES]; /* the latest centres, before harmonics [Hz] */
    fc_notch_filter_t f[FC_NOTCH_MAX_FILTERS];
} fc_notch_t;

/* States cleared, design from cfg, centres at FREQ. FC_ERR_ARG (notch then
 * passes through) for a dt or design it cannot use. */
fc_status_t fc_notch_init(fc_notch_t *n, const fc_notch_config_t *cfg, float dt_s);
/* New configuration or sample period, states kept; a moved centre ramps. */
fc_status_t fc_notch_configure(fc_notch_t *n, const fc_notch_config_t *cfg, float dt_s);
/* Centres (before harmonics) [Hz]; the tuning ramps over interval_s (0: at once). */
void fc_notch_set_centers(fc_notch_t *n, unsigned count, const float hz[], float interval_s);
/* Once per loop tick of tick_s: the centres from the inputs, at the update rate. */
void fc_notch_track(fc_notch_t *n, const fc_notch_inputs_t *in, float tick_s);
/* One gyro sample through the bank, in place. */
void fc_notch_apply(fc_notch_t *n, float v[3]);

#endif /* FC_NOTCH_H */
