/*
 * sysidmethods.c - the Core methods of system identification (fc_sysid.h):
 * sysid_start, sysid_stop, and sysid_sample, which the tuning tools call after
 * every lockstep step to record the sweep and the rate-loop signals it moves.
 * Kept apart from coremodule.c so the identification surface is one small file.
 */
#include "ext_common.h"

#include "core_object.h"

PyObject *fc_ext_sysid_start(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    return PyLong_FromLong((long)fc_core_sysid_start(&self->core));
}

PyObject *fc_ext_sysid_stop(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    fc_core_sysid_stop(&self->core);
    Py_RETURN_NONE;
}

/* One flat tuple (cheap to build at every step):
 *   sim_ns, active, axis, t_s, sample, freq_hz, runs,
 *   rate_target[3] (rad/s, the sweep included), rate[3] (the rate loop's gyro, rad/s),
 *   pid_out[3] (rate-loop outputs before a mixer sweep, us),
 *   mixer_in[3] (roll, pitch, yaw mixer inputs after the sweep and trim, us). */
PyObject *fc_ext_sysid_sample(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_core_t *c = &self->core;
    const fc_sysid_t *s = &c->sysid;
    return Py_BuildValue("(LiidddI" "ddd" "ddd" "ddd" "ddd)", (long long)c->last_imu_ns,
                         (int)s->active, (int)s->axis, (double)s->t_s, (double)s->sample,
                         (double)s->freq_hz, (unsigned int)s->runs,
                         (double)c->rate_target_frd_rad_s[0], (double)c->rate_target_frd_rad_s[1],
                         (double)c->rate_target_frd_rad_s[2], (double)c->rate_frd_rad_s[0],
                         (double)c->rate_frd_rad_s[1], (double)c->rate_frd_rad_s[2],
                         (double)c->pid_out_us[0], (double)c->pid_out_us[1],
                         (double)c->pid_out_us[2], (double)c->cr_us, (double)c->cp_us,
                         (double)c->cy_us);
}
