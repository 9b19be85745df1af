/*
 * step_run.c - one physics step of the bridge kernel, the CPython side (stepmodule.c has
 * the Python object around it): write the pulse widths and the disturbance forces into
 * JSBSim, run it, read the FDM sample back through its property nodes (their C++ getters
 * once bind_native proved them, jsbsim_native.h; else their bound Python methods), and hand
 * it to the pure-C sensor stage (sensor_stage.c), which writes the step's records into the
 * step buffer. The only place that knows both JSBSim and the stage. The returned flags tell
 * Python what it handles itself (bridge/simulator.py).
 */
#include "step_kernel.h"

/* The four pulse widths [us] into JSBSim; NaN is refused (a bug upstream, never fly it).
 * A width equal to the one last written is not written again: the properties are inputs
 * of the model's motor system that nothing else sets, so JSBSim holds the value, and the
 * held command (PWM at 400 Hz, physics at 1 kHz) skips most of the setter calls. */
static int write_pwm(Kernel *self, PyObject *const *pwm, int64_t k)
{
    double d[4];
    for (int i = 0; i < 4; i++) {
        d[i] = PyFloat_AsDouble(pwm[i]);
        if (d[i] == -1.0 && PyErr_Occurred())
            return -1;
        if (d[i] != d[i]) {
            PyErr_Format(PyExc_ValueError, "PWM command contains NaN at step %lld: [%R, %R, "
                         "%R, %R]", (long long)k, pwm[0], pwm[1], pwm[2], pwm[3]);
            return -1;
        }
    }
    for (int i = 0; i < 4; i++) {
        if (self->pwm_written_ok && d[i] == self->pwm_written[i])
            continue;
        if (self->jsb.set != NULL) {       /* bind_native(): no Python on the way */
            self->jsb.set(self->set_node[i], d[i]);
            self->pwm_written[i] = d[i];
            continue;
        }
        PyObject *r = sb_call1(&self->setters[i], pwm[i]);
        if (r == NULL) {
            self->pwm_written_ok = 0;   /* unknown what JSBSim holds now: write all next time */
            return -1;
        }
        Py_DECREF(r);
        self->pwm_written[i] = d[i];
    }
    self->pwm_written_ok = 1;
    return 0;
}

/* Fill the FDM sample by name: getter i feeds field SB_FDM_SAMPLE_FIELDS[i]. A field the
 * stage reads only on some steps (sb_sensor_stage_optional) is read on those steps only. */
static int read_sample(Kernel *self, sb_fdm_sample *in, int64_t sim_ns)
{
    const size_t skip = sb_sensor_stage_optional(&self->stage, sim_ns);
    for (int i = 0; i < SB_FDM_SAMPLE_FIELD_COUNT; i++) {
        const size_t off = SB_FDM_SAMPLE_FIELDS[i].offset;
        if (off == skip)
            continue;
        if (self->jsb.get != NULL) {       /* bind_native(): no Python on the way */
            const double v = self->jsb.get(self->get_node[i]);
            memcpy((char *)in + off, &v, sizeof v);
            continue;
        }
        PyObject *r = sb_call0(&self->getters[i]);
        if (r == NULL)
            return -1;
        const double v = sb_call_double(r);
        Py_DECREF(r);
        if (v == -1.0 && PyErr_Occurred())
            return -1;
        memcpy((char *)in + off, &v, sizeof v);
    }
    return 0;
}

/* Inputs into JSBSim, run it, and the sample after the step. */
static int advance_fdm(Kernel *self, PyObject *const *pwm, sb_fdm_sample *in)
{
    const int64_t k = self->step_index + 1;
    if (write_pwm(self, pwm, k) < 0)
        return -1;
    if (self->n_force_frames && sb_step_apply_forces(self, k) < 0)
        return -1;
    PyObject *r = sb_call0(&self->run);
    if (r == NULL)
        return -1;
    Py_DECREF(r);
    self->step_index = k;
    return read_sample(self, in, k * self->dt_ns);
}

/* Run one step; write the records from slot `first`; return flags. */
long sb_step_run_items(Kernel *self, PyObject *const *pwm, Py_ssize_t first)
{
    if (self->stage.state == NULL) {   /* __init__ failed or never ran */
        PyErr_SetString(PyExc_RuntimeError, "Kernel is not initialised");
        return -1;
    }
    sb_fdm_sample in;
    if (advance_fdm(self, pwm, &in) < 0)
        return -1;
    /* The battery's load, on its report steps only (4 torque getters, 1 step in 100). */
    if (sb_sensor_stage_pack_due(&self->stage, self->step_index * self->dt_ns) &&
        sb_step_pack_load(self, in.omega_rad_s) < 0)
        return -1;
    const long flags = sb_sensor_stage_step(&self->stage, &in, self->step_index * self->dt_ns,
                                            self->slots, (size_t)self->n_slots, (size_t)first);
    if (flags < 0)
        PyErr_SetString(flags == SB_STAGE_BUFFER_FULL ? PyExc_ValueError : PyExc_RuntimeError,
                        sb_sensor_stage_error(flags));
    return flags < 0 ? -1 : flags;
}

long sb_step_run(Kernel *self, PyObject *pwm, Py_ssize_t first)
{
    /* A tuple passes through PySequence_Fast untouched; lists work too. */
    PyObject *seq = PySequence_Fast(pwm, "pwm must be a sequence of 4 pulse widths [us]");
    if (seq == NULL)
        return -1;
    long flags = -1;
    if (PySequence_Fast_GET_SIZE(seq) != 4)
        PyErr_SetString(PyExc_TypeError, "pwm must hold 4 pulse widths [us]");
    else
        flags = sb_step_run_items(self, PySequence_Fast_ITEMS(seq), first);
    Py_DECREF(seq);
    return flags;
}
