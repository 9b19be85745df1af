/*
 * step_run.c - one physics step of the bridge kernel, the CPython side (stepmodule.c has
 * the Python object around it): write the pulse widths and the disturbance forces into
 * JSBSim, run it, read the FDM sample back through the bound getters, and hand it to the
 * pure-C sensor stage (sensor_stage.c), which writes the step's records into the step
 * buffer. The only place that knows both JSBSim and the stage: issue 25 replaces
 * read_sample with property nodes read from C. The returned flags tell Python what it
 * handles itself (bridge/simulator.py).
 */
#include "step_kernel.h"

/* The four pulse widths [us] into JSBSim; NaN is refused (a bug upstream, never fly it). */
static int write_pwm(Kernel *self, PyObject *pwm, int64_t k)
{
    if (PySequence_Fast_GET_SIZE(pwm) != 4) {
        PyErr_SetString(PyExc_TypeError, "pwm must hold 4 pulse widths [us]");
        return -1;
    }
    for (int i = 0; i < 4; i++) {
        double d = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(pwm, i));
        if (d == -1.0 && PyErr_Occurred())
            return -1;
        if (d != d) {
            PyObject *lst = PySequence_List(pwm);
            PyErr_Format(PyExc_ValueError, "PWM command contains NaN at step %lld: %R",
                         (long long)k, lst);
            Py_XDECREF(lst);
            return -1;
        }
    }
    for (int i = 0; i < 4; i++) {
        PyObject *r = PyObject_CallOneArg(self->setters[i], PySequence_Fast_GET_ITEM(pwm, i));
        if (r == NULL)
            return -1;
        Py_DECREF(r);
    }
    return 0;
}

/* Fill the FDM sample by name: getter i feeds field SB_FDM_SAMPLE_FIELDS[i]. */
static int read_sample(Kernel *self, sb_fdm_sample *in)
{
    for (int i = 0; i < SB_FDM_SAMPLE_FIELD_COUNT; i++) {
        PyObject *r = PyObject_CallNoArgs(self->getters[i]);
        if (r == NULL)
            return -1;
        const double v = PyFloat_AsDouble(r);
        Py_DECREF(r);
        if (v == -1.0 && PyErr_Occurred())
            return -1;
        memcpy((char *)in + SB_FDM_SAMPLE_FIELDS[i].offset, &v, sizeof v);
    }
    return 0;
}

/* Inputs into JSBSim, run it, and the sample after the step. */
static int advance_fdm(Kernel *self, PyObject *pwm, sb_fdm_sample *in)
{
    const int64_t k = self->step_index + 1;
    if (write_pwm(self, pwm, k) < 0)
        return -1;
    if (self->n_force_frames && sb_step_apply_forces(self, k) < 0)
        return -1;
    PyObject *r = PyObject_CallNoArgs(self->run);
    if (r == NULL)
        return -1;
    Py_DECREF(r);
    self->step_index = k;
    return read_sample(self, in);
}

/* Run one step; write the records from slot `first`; return flags. */
long sb_step_run(Kernel *self, PyObject *pwm, Py_ssize_t first)
{
    if (self->stage.state == NULL) {   /* __init__ failed or never ran */
        PyErr_SetString(PyExc_RuntimeError, "Kernel is not initialised");
        return -1;
    }
    /* A tuple passes through PySequence_Fast untouched; lists work too. */
    PyObject *seq = PySequence_Fast(pwm, "pwm must be a sequence of 4 pulse widths [us]");
    if (seq == NULL)
        return -1;
    sb_fdm_sample in;
    const int rc = advance_fdm(self, seq, &in);
    Py_DECREF(seq);
    if (rc < 0)
        return -1;
    const long flags = sb_sensor_stage_step(&self->stage, &in, self->step_index * self->dt_ns,
                                            self->slots, (size_t)self->n_slots, (size_t)first);
    if (flags < 0)
        PyErr_SetString(flags == SB_STAGE_BUFFER_FULL ? PyExc_ValueError : PyExc_RuntimeError,
                        sb_sensor_stage_error(flags));
    return flags < 0 ? -1 : flags;
}
