/*
 * fc_notch_feed.h - what the harmonic notches hear of the rotors: the one
 * place that reads the core's throttle, spool and ESC telemetry (and the
 * in-flight FFT's peaks) for them, so fc_notch itself knows no core.
 */
#ifndef FC_NOTCH_FEED_H
#define FC_NOTCH_FEED_H

#include "fc_core.h"

/* Once per PWM tick (ArduCopter's main loop), after the mixer: the notches'
 * inputs, and their centres at the update rate. Returns at once, touching
 * nothing, when no notch is enabled. */
void fc_notch_feed(fc_core_t *c);

#endif /* FC_NOTCH_FEED_H */
