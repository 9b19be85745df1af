/*
 * fc_control.h - the control law: what runs between the vehicle state
 * (fc_vehicle_state.h) and the mixer, as a block of its own.
 *
 *   rate-loop step : SYSTEMID sample -> attitude target (input shaping, or the
 *                    command as it is) -> attitude error on the state -> rate
 *                    targets -> rate PI+D (x3) -> hover trim -> mixer inputs
 *                    cr, cp, cy.
 *   PWM tick       : altitude loop (or ground idle, or shut down) -> mixer
 *                    throttle input.
 *
 * As PX4's RateControl, it knows no parameter table, no scheduler and no
 * sensor: a configuration (fc_control_config_t, SI units), its state, the
 * inputs of a step (targets, flight phase, the mixer's saturation) and the
 * vehicle state go in; fc_control_out_t comes out. The host (fc_core.c) owns
 * one of each, refreshes the inputs before every step and runs the mixer on
 * the outputs; a test builds these files without it. Attitude, rates and
 * altitude come from the vehicle state only; whether it holds the estimate or
 * a blend with ground truth is not this file's concern.
 */
#ifndef FC_CONTROL_H
#define FC_CONTROL_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_alt_ctrl.h"
#include "fc_attitude.h"
#include "fc_inputs.h"
#include "fc_rate_pid.h"
#include "fc_shaper.h"
#include "fc_spool.h"
#include "fc_sysid.h"
#include "fc_trim.h"
#include "fc_vehicle_state.h"

typedef struct fc_control_config {
    fc_attitude_config_t att;
    fc_shaper_config_t shaper;
    fc_rate_pid_config_t pid[3];  /* roll, pitch, yaw */
    fc_trim_config_t trim;
    fc_alt_ctrl_config_t alt;
    fc_sysid_config_t sysid;
    fc_spool_config_t spool;      /* the spool logic's: ground idle, landing descent,
                                   * "flight wanted" */
    float angle_max_rad;          /* roll and pitch target limit (ANGLE_MAX) [rad] */
    float pwm_min_us, pwm_max_us; /* the mixer's output range: throttle 0..1 -> [us] */
} fc_control_config_t;

typedef struct fc_control_state {
    fc_shaper_t shaper;           /* shaped attitude target (input shaping) */
    fc_rate_pid_t pid[3];
    fc_trim_t trim;
    fc_alt_ctrl_t alt_ctrl;
    fc_sysid_t sysid;             /* SYSTEMID sweep (SID_*), injected on its axis */
} fc_control_state_t;

/* What a step reads besides the vehicle state; the host refreshes it before
 * each step, as the spool logic and the mixer move it in between. */
typedef struct fc_control_in {
    fc_core_inputs_t cmd;         /* the host's targets (fc_inputs.h) */
    int64_t now_ns;               /* latest IMU sample: the sweep's clock [ns] */
    uint8_t spool;                /* fc_spool_t */
    uint8_t airborne;             /* lift-off detected and not landed */
    uint8_t sat_flags;            /* the mixer's FC_SAT_* of its last tick: no integrator
                                   * grows into a saturation */
} fc_control_in_t;

/* att_target_rad .. pid_ff_us lie as the core's status snapshot holds the
 * same signals, so the host copies them in one piece (checked in fc_core.c). */
typedef struct fc_control_out {
    float att_target_rad[3];        /* target roll, pitch, yaw: the shaped target [rad] */
    float att_error_frd_rad[3];     /* small-angle error ex, ey, ez on the state [rad] */
    float rate_target_frd_rad_s[3]; /* rate-loop targets, the sweep included [rad/s] */
    float rate_frd_rad_s[3];        /* the body rates the step used [rad/s] */
    float pid_p_us[3];              /* rate-loop terms per axis (fc_pid_info_t) [us] */
    float pid_i_us[3];
    float pid_d_us[3];
    float pid_ff_us[3];
    float pid_out_us[3];            /* rate-loop outputs before a mixer-input sweep [us] */
    float trim_us[2];               /* applied hover trim, roll and pitch [us] */
    float cr_us, cp_us, cy_us;      /* mixer inputs about 0, trim included [us] */
    float throttle_us;              /* mixer throttle input [us] */
    uint8_t limited[3];             /* rate-loop integrator limited, per axis */
} fc_control_out_t;

/* Every controller built and at rest, the sweep idle, the outputs zero (the
 * throttle at pwm_min_us). rate_dt_s: the period the rate PIDs start with
 * until they step; throttle_dt_s: the PWM period of the altitude loop [s]. */
void fc_control_init(fc_control_state_t *s, const fc_control_config_t *cfg, float rate_dt_s,
                     float throttle_dt_s, fc_control_out_t *out);

/* A new configuration, states kept: each rate PID keeps the period it last
 * stepped at (fc_rate_pid_update); throttle_dt_s as in fc_control_init. */
void fc_control_configure(fc_control_state_t *s, const fc_control_config_t *cfg,
                          float throttle_dt_s);

/* Controllers back to rest and the sweep stopped (arming, disarming,
 * landing); the shaped target and the latest attitude target and rates stay. */
void fc_control_reset(fc_control_state_t *s, const fc_control_config_t *cfg,
                      fc_control_out_t *out);

/* One rate-loop step of dt_s, the measured rate-loop period [s]: the only
 * place the rate PIDs get their period from. */
void fc_control_rate_step(fc_control_state_t *s, const fc_control_config_t *cfg,
                          const fc_control_in_t *in, const fc_vehicle_state_t *vs, float dt_s,
                          fc_control_out_t *out);

/* The mixer's throttle input for this PWM tick of dt_s [s], into out->throttle_us. */
void fc_control_throttle_step(fc_control_state_t *s, const fc_control_config_t *cfg,
                              const fc_control_in_t *in, const fc_vehicle_state_t *vs,
                              float dt_s, fc_control_out_t *out);

#endif /* FC_CONTROL_H */
