/*
 * fc_core_inputs.c - the host's side of the core between steps: targets and
 * commands (fc_core_set_*, the SYSTEMID start and stop, declared in
 * fc_core.h). Each validates what it is given and leaves the previous value
 * in place when it refuses; nothing runs until the next step.
 */
#include "fc_core.h"

#include "fc_math.h"

void fc_core_set_armed(fc_core_t *c, bool armed)
{
    c->in.armed = armed ? 1u : 0u;
}

fc_status_t fc_core_set_attitude_target(fc_core_t *c, float roll_rad, float pitch_rad)
{
    if (!fc_finitef(roll_rad) || !fc_finitef(pitch_rad)) {
        return FC_ERR_NONFINITE;
    }
    c->in.roll_target_rad = roll_rad;
    c->in.pitch_target_rad = pitch_rad;
    return FC_OK;
}

fc_status_t fc_core_set_yaw_target(fc_core_t *c, float yaw_rad)
{
    if (!fc_finitef(yaw_rad)) {
        return FC_ERR_NONFINITE;
    }
    c->in.yaw_target_rad = fc_wrap_pi(yaw_rad);
    c->in.yaw_hold = 1;
    c->in.yaw_rate_target_rad_s = 0.0f;
    return FC_OK;
}

fc_status_t fc_core_set_yaw_rate_target(fc_core_t *c, float yaw_rate_rad_s)
{
    if (!fc_finitef(yaw_rate_rad_s)) {
        return FC_ERR_NONFINITE;
    }
    c->in.yaw_rate_target_rad_s = yaw_rate_rad_s;
    c->in.yaw_hold = 0;
    return FC_OK;
}

fc_status_t fc_core_set_altitude_target(fc_core_t *c, float alt_m)
{
    if (!fc_finitef(alt_m)) {
        return FC_ERR_NONFINITE;
    }
    c->in.alt_target_m = alt_m;
    c->in.alt_mode = FC_ALT_MODE_ALTITUDE;
    return FC_OK;
}

fc_status_t fc_core_set_climb_target(fc_core_t *c, float climb_m_s)
{
    if (!fc_finitef(climb_m_s)) {
        return FC_ERR_NONFINITE;
    }
    c->in.climb_target_m_s = climb_m_s;
    c->in.alt_mode = FC_ALT_MODE_CLIMB;
    return FC_OK;
}

void fc_core_set_vibe_comp(fc_core_t *c, bool on)
{
    c->in.vibe_comp = on ? 1u : 0u;
}

fc_status_t fc_core_set_throttle(fc_core_t *c, float throttle)
{
    if (!fc_finitef(throttle)) {
        return FC_ERR_NONFINITE;
    }
    if (throttle < 0.0f || throttle > 1.0f) {
        return FC_ERR_RANGE;
    }
    c->in.throttle = throttle;
    c->in.alt_mode = FC_ALT_MODE_THROTTLE;
    return FC_OK;
}

fc_status_t fc_core_set_accel_ref(fc_core_t *c, const float accel_ned_m_s2[3])
{
    return fc_mahony_set_accel_ref(&c->ahrs, accel_ned_m_s2);
}

fc_status_t fc_core_sysid_start(fc_core_t *c)
{
    return fc_sysid_start(&c->ctl.sysid, &c->cfg.ctl.sysid, c->last_imu_ns) ? FC_OK : FC_ERR_ARG;
}

void fc_core_sysid_stop(fc_core_t *c)
{
    fc_sysid_stop(&c->ctl.sysid);
}
