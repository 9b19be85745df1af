/*
 * fc_control.h - the control law of the core: what runs between the vehicle
 * state (fc_vehicle_state.h) and the mixer.
 *
 *   rate-loop step : SYSTEMID sample -> attitude target (input shaping, or the
 *                    command as it is) -> attitude error on the state -> rate
 *                    targets -> rate PI+D (x3) -> hover trim -> mixer inputs
 *                    cr, cp, cy.
 *   PWM tick       : altitude loop (or ground idle, or shut down) -> mixer
 *                    throttle input.
 *
 * Attitude, rates and altitude come from the vehicle state only; whether it
 * holds the estimate or a blend with ground truth is not this file's concern.
 * The blocks, their configurations and the results live in fc_core_t, whose
 * fields the host reads (fc_core.h).
 */
#ifndef FC_CONTROL_H
#define FC_CONTROL_H

#include <stdbool.h>

#include "fc_core.h"
#include "fc_vehicle_state.h"

/* Controllers back to rest. The mixer's slew state is kept unless reset_mixer
 * (arming and disarming): on landing the outputs slew down to idle, no dip. */
void fc_control_reset(fc_core_t *c, bool reset_mixer);

/* One rate-loop step of dt_s, the measured rate-loop period [s]: the only
 * place the rate PIDs get their period from. */
void fc_control_rate_step(fc_core_t *c, const fc_vehicle_state_t *vs, float dt_s);

/* The mixer's throttle input for this PWM tick of dt_s [s], into c->throttle_us. */
void fc_control_throttle_step(fc_core_t *c, const fc_vehicle_state_t *vs, float dt_s);

#endif /* FC_CONTROL_H */
