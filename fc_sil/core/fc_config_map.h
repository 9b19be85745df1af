/*
 * fc_config_map.h - parameters to block configurations: the one place that
 * knows both the parameter table (fc_params.def, ArduCopter's names and units)
 * and the blocks' own configuration structs (SI units, radians, microseconds).
 * The blocks never see a parameter; the core re-maps after every accepted
 * parameter change and pushes the result into the blocks (fc_core_apply_params).
 */
#ifndef FC_CONFIG_MAP_H
#define FC_CONFIG_MAP_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_control.h"
#include "fc_ins.h"
#include "fc_mahony.h"
#include "fc_sched.h"
#include "fc_mixer.h"
#include "fc_params.h"
#include "fc_spool.h"
#include "fc_state_source.h"

typedef struct fc_core_config {
    fc_ins_config_t ins;
    fc_mahony_config_t ahrs;        /* in flight (armed) */
    fc_mahony_config_t ahrs_ground; /* disarmed: fast alignment and bias learning */
    fc_source_config_t source;
    fc_control_config_t ctl;        /* the control law (fc_control.h) */
    fc_mixer_config_t mix;
    fc_alt_sched_config_t alt_sched; /* the vertical filter's time constants (fc_sched.h) */
    fc_spool_config_t spool;
    float loop_period_s;            /* shortest rate-loop period (SB_LOOP_HZ) [s] */
} fc_core_config_t;

/* Every block configuration from the parameters. */
void fc_config_map(const fc_params_t *p, fc_core_config_t *cfg);

/* The PWM tick period (SB_PWM_HZ) [ns]. */
int64_t fc_config_pwm_period_ns(const fc_params_t *p);

/* Combinations a single range check cannot see (MOT_PWM_MIN + 100 <=
 * MOT_PWM_MAX, MOT_SPIN_ARM <= MOT_SPIN_MIN < MOT_SPIN_MAX, each harmonic
 * notch's bandwidth below twice its centre). */
bool fc_config_consistent(const fc_params_t *p);

#endif /* FC_CONFIG_MAP_H */
