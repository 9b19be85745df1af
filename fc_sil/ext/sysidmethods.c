/*
 * sysidmethods.c - the Core methods of system identification (fc_sysid.h):
 * sysid_start, sysid_stop, and sysid_sample, which the tuning tools call after
 * every lockstep step to record the sweep and the rate-loop signals it moves.
 * Kept apart from the other Core methods so the identification surface is one small file.
 */
#include "core_object.h"

static PyObject *Core_sysid_start(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    return PyLong_FromLong((long)fc_core_sysid_start(&self->core));
}

static PyObject *Core_sysid_stop(CoreObject *self, PyObject *noargs)
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
static PyObject *Core_sysid_sample(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_core_t *c = &self->core;
    const fc_sysid_t *s = &c->ctl.sysid;
    const fc_control_out_t *o = &c->ctl_out; /* the control law's latest step */
    return Py_BuildValue("(LiidddI" "ddd" "ddd" "ddd" "ddd)", (long long)c->last_imu_ns,
                         (int)s->active, (int)s->axis, (double)s->t_s, (double)s->sample,
                         (double)s->freq_hz, (unsigned int)s->runs,
                         (double)o->rate_target_frd_rad_s[0], (double)o->rate_target_frd_rad_s[1],
                         (double)o->rate_target_frd_rad_s[2], (double)o->rate_frd_rad_s[0],
                         (double)o->rate_frd_rad_s[1], (double)o->rate_frd_rad_s[2],
                         (double)o->pid_out_us[0], (double)o->pid_out_us[1],
                         (double)o->pid_out_us[2], (double)o->cr_us, (double)o->cp_us,
                         (double)o->cy_us);
}

PyMethodDef fc_ext_sysid_methods[] = {
    {"sysid_start", (PyCFunction)Core_sysid_start, METH_NOARGS,
     "Start the SID_* sweep -> status code (FC_ERR_ARG: SID_AXIS 0 or bad sweep)."},
    {"sysid_stop", (PyCFunction)Core_sysid_stop, METH_NOARGS, "Stop the sweep."},
    {"sysid_sample", (PyCFunction)Core_sysid_sample, METH_NOARGS,
     "Sweep state and rate-loop signals of the latest step (sysidmethods.c)."},
    {NULL, NULL, 0, NULL},
};
