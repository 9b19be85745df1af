/*
 * fc_sysid.h - frequency-sweep excitation for system identification, as
 * ArduCopter's SYSTEMID mode makes it (SID_* parameters, same meaning).
 *
 * A logarithmic chirp: after a 1 s delay from the start, two full cycles at
 * SID_F_START_HZ, then a frequency rising exponentially to SID_F_STOP_HZ at
 * SID_T_REC; a raised-cosine window fades the amplitude in over
 * SID_T_FADE_IN and out over the last SID_T_FADE_OUT of SID_T_REC. The sample
 * is added where SID_AXIS says (fc_sysid_axis_t): the angle target (deg), the
 * rate-loop input (deg/s), or the mixer input (normalised, 1 = the motor
 * authority of one rate-loop unit). Why the same shape as ArduCopter: logs and
 * analysis scripts written for SYSTEMID flights then read ours unchanged, and
 * a sweep tuned on one transfers to the other.
 *
 * Time is the int64 sim time of the rate loop minus the start time, so a run
 * of any length keeps the phase exact (a float accumulator would drift).
 */
#ifndef FC_SYSID_H
#define FC_SYSID_H

#include <stdbool.h>
#include <stdint.h>

/* SID_AXIS values (ArduCopter 4.6). */
typedef enum fc_sysid_axis {
    FC_SID_NONE = 0,
    FC_SID_INPUT_ROLL = 1,   /* roll angle target [deg] */
    FC_SID_INPUT_PITCH = 2,  /* pitch angle target [deg] */
    FC_SID_INPUT_YAW = 3,    /* yaw rate target [deg/s] */
    FC_SID_RECOVER_ROLL = 4, /* as 1-3 without the body-frame feed-forward (shaping off) */
    FC_SID_RECOVER_PITCH = 5,
    FC_SID_RECOVER_YAW = 6,
    FC_SID_RATE_ROLL = 7,    /* rate-loop target [deg/s] */
    FC_SID_RATE_PITCH = 8,
    FC_SID_RATE_YAW = 9,
    FC_SID_MIX_ROLL = 10,    /* mixer input [normalised] */
    FC_SID_MIX_PITCH = 11,
    FC_SID_MIX_YAW = 12,
    FC_SID_MIX_THROTTLE = 13 /* throttle [0..1 of the PWM range] */
} fc_sysid_axis_t;

/* Delay between the start and the first non-zero sample [s] (ArduCopter's). */
#define FC_SYSID_DELAY_S 1.0f

typedef struct fc_sysid_config {
    uint8_t axis;          /* fc_sysid_axis_t */
    float magnitude;       /* deg, deg/s or normalised, by axis */
    float f_start_hz, f_stop_hz;
    float t_fade_in_s, t_rec_s, t_fade_out_s;
} fc_sysid_config_t;

typedef struct fc_sysid {
    bool active;
    uint8_t axis;          /* axis of the running test */
    int64_t start_ns;      /* sim time of the start */
    float t_s;             /* time since the start [s] */
    float sample;          /* latest waveform sample (axis units) */
    float freq_hz;         /* its instantaneous frequency [Hz] */
    uint32_t runs;         /* tests started so far */
} fc_sysid_t;

void fc_sysid_reset(fc_sysid_t *s);
/* Whether cfg describes a sweep ArduCopter would run (frequencies > 0, times
 * >= 0, SID_T_REC longer than the two start cycles, axis set). */
bool fc_sysid_config_valid(const fc_sysid_config_t *cfg);
/* The waveform at t seconds after the 1 s delay (t <= 0: nothing); freq_hz
 * (may be NULL) receives the instantaneous frequency. */
float fc_sysid_waveform(const fc_sysid_config_t *cfg, float t_s, float *freq_hz);
/* Start a test at sim_ns; false (and nothing started) when cfg is not valid. */
bool fc_sysid_start(fc_sysid_t *s, const fc_sysid_config_t *cfg, int64_t sim_ns);
void fc_sysid_stop(fc_sysid_t *s);
/* One rate-loop step at sim_ns: updates sample (0 when idle) and ends the
 * test after the delay + SID_T_REC. Returns the sample. */
float fc_sysid_update(fc_sysid_t *s, const fc_sysid_config_t *cfg, int64_t sim_ns);

#endif /* FC_SYSID_H */
