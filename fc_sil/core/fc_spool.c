/*
 * fc_spool.c - spool state machine and land detector (see fc_spool.h).
 */
#include "fc_spool.h"

#include "fc_alt_ctrl.h"
#include "fc_math.h"
#include "fc_mixer.h"

static void rest(fc_spool_logic_t *sl)
{
    sl->airborne = 0;
    sl->landed_s = 0.0f;
}

void fc_spool_reset(fc_spool_logic_t *sl, uint8_t *spool)
{
    rest(sl);
    sl->armed_prev = 0;
    *spool = FC_SPOOL_SHUT_DOWN;
}

bool fc_spool_wants_flight(const fc_spool_config_t *cfg, const fc_core_inputs_t *in)
{
    switch (in->alt_mode) {
    case FC_ALT_MODE_ALTITUDE:
        return in->alt_target_m > cfg->liftoff_alt_m;
    case FC_ALT_MODE_CLIMB:
        return in->climb_target_m_s > 0.0f;
    default:
        return in->throttle > cfg->spin_arm;
    }
}

unsigned fc_spool_update(fc_spool_logic_t *sl, const fc_spool_config_t *cfg,
                         const fc_core_inputs_t *in, uint8_t *spool)
{
    unsigned ev = 0;
    const uint8_t armed = in->armed;
    if (armed && !sl->armed_prev) {
        rest(sl);
        ev |= FC_SPOOL_EV_ARMING;
        *spool = FC_SPOOL_GROUND_IDLE;
    } else if (!armed) {
        if (sl->armed_prev) {
            ev |= FC_SPOOL_EV_ARMING;
        }
        rest(sl);
        *spool = FC_SPOOL_SHUT_DOWN;
    }
    sl->armed_prev = armed;
    if (*spool == FC_SPOOL_GROUND_IDLE && fc_spool_wants_flight(cfg, in)) {
        *spool = FC_SPOOL_FLIGHT;
        ev |= FC_SPOOL_EV_TAKEOFF;
    }
    return ev;
}

unsigned fc_spool_detect(fc_spool_logic_t *sl, const fc_spool_config_t *cfg,
                         const fc_core_inputs_t *in, const fc_vehicle_state_t *vs,
                         uint8_t sat_flags, float throttle, float dt_s, uint8_t *spool)
{
    if (*spool != FC_SPOOL_FLIGHT) {
        sl->airborne = 0;
        return 0;
    }
    if (!sl->airborne) {
        if (vs->alt_m > cfg->liftoff_alt_m) {
            sl->airborne = 1;
            sl->landed_s = 0.0f;
        }
        return 0;
    }
    const bool at_floor = (sat_flags & FC_SAT_THR_LOW) != 0 || throttle <= cfg->spin_min;
    if (!fc_spool_wants_flight(cfg, in) && at_floor && fabsf(vs->climb_m_s) < FC_LAND_CLIMB_M_S) {
        sl->landed_s += dt_s;
        if (sl->landed_s >= FC_LAND_DETECT_S) {
            rest(sl);
            *spool = FC_SPOOL_GROUND_IDLE;
            return FC_SPOOL_EV_LANDED;
        }
    } else {
        sl->landed_s = 0.0f;
    }
    return 0;
}
