/*
 * fc_spool.h - the spool state machine and the land detector, stepped once
 * per PWM tick.
 *
 *   SHUT_DOWN --arm--> GROUND_IDLE --flight wanted--> FLIGHT
 *       ^                   ^                            |
 *       +------disarm-------+-----landing detected-------+
 *
 * "Flight wanted": an altitude target above SB_LIFTOFF_ALT, a climb target
 * above 0, or a direct throttle above MOT_SPIN_ARM. In FLIGHT, lift-off is the
 * altitude passing SB_LIFTOFF_ALT; landing (as ArduCopter's land detector) is
 * flight no longer wanted, the throttle at its floor and no vertical motion
 * for FC_LAND_DETECT_S: the ground then carries the vehicle (altitude alone is
 * not trusted: the baro drifts).
 *
 * The phase itself (fc_spool_t, fc_mixer.h) is held by the caller, since the
 * mixer and the host read it; this block moves it and reports the events the
 * caller acts on (FC_SPOOL_EV_*), so it never touches a controller itself.
 */
#ifndef FC_SPOOL_H
#define FC_SPOOL_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_inputs.h"
#include "fc_vehicle_state.h"

/* Landing: throttle at its floor and not climbing or descending faster than
 * FC_LAND_CLIMB_M_S for FC_LAND_DETECT_S. */
#define FC_LAND_DETECT_S 1.0f
#define FC_LAND_CLIMB_M_S 0.3f

/* Events of one tick (bit flags). */
#define FC_SPOOL_EV_ARMING 1u  /* armed or disarmed: controllers and mixer to rest */
#define FC_SPOOL_EV_TAKEOFF 2u /* ground idle -> flight: altitude loop from rest */
#define FC_SPOOL_EV_LANDED 4u  /* flight -> ground idle: controllers to rest, outputs
                                * slew down from where they are */

typedef struct fc_spool_config {
    float liftoff_alt_m;  /* SB_LIFTOFF_ALT: climb that counts as lift-off [m] */
    float spin_arm;       /* MOT_SPIN_ARM: ground-idle throttle, fraction of the range */
    float spin_min;       /* MOT_SPIN_MIN: in-flight throttle floor, fraction of the range */
    float land_speed_m_s; /* LAND_SPEED: least descent rate while landing [m/s] */
} fc_spool_config_t;

typedef struct fc_spool_logic {
    uint8_t armed_prev;   /* armed at the previous tick */
    uint8_t airborne;     /* lift-off detected and not landed */
    float landed_s;       /* how long the landing criteria have held [s] */
} fc_spool_logic_t;

/* Disarmed, on the ground; *spool = FC_SPOOL_SHUT_DOWN. */
void fc_spool_reset(fc_spool_logic_t *sl, uint8_t *spool);

/* Do the inputs ask the vehicle to fly (or to stay in the air)? */
bool fc_spool_wants_flight(const fc_spool_config_t *cfg, const fc_core_inputs_t *in);

/* Arming edges and take-off, from the inputs; returns FC_SPOOL_EV_ARMING and
 * FC_SPOOL_EV_TAKEOFF (both on a tick that arms with flight wanted). */
unsigned fc_spool_update(fc_spool_logic_t *sl, const fc_spool_config_t *cfg,
                         const fc_core_inputs_t *in, uint8_t *spool);

/* Lift-off and landing, from the vehicle state and the throttle path (the
 * mixer's FC_SAT_* flags and the altitude loop's throttle 0..1); returns
 * FC_SPOOL_EV_LANDED on the tick the landing is detected. */
unsigned fc_spool_detect(fc_spool_logic_t *sl, const fc_spool_config_t *cfg,
                         const fc_core_inputs_t *in, const fc_vehicle_state_t *vs,
                         uint8_t sat_flags, float throttle, float dt_s, uint8_t *spool);

#endif /* FC_SPOOL_H */
