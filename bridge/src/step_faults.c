/*
 * step_faults.c - the Kernel methods through which bridge/faults/sensors.py and motors.py
 * set issue 28's faults between steps: the sensor faults the stage applies
 * (sensor_faults.h) and a damaged prop's vibration. Arguments by keyword, as the structs
 * name them; each call replaces the sensor's whole fault set (Python folds the active
 * faults of a unit into one).
 */
#include "step_kernel.h"

static int any3(const int v[3])
{
    return v[0] || v[1] || v[2];
}

/* set_imu_fault(sensor="gyro"|"accel", stuck=(3 bools), bias=(3), sigma=(3), clip): clip < 0
 * for none */
PyObject *Kernel_set_imu_fault(Kernel *self, PyObject *args, PyObject *kwds)
{
    const char *sensor;
    int st[3];
    double b[3], sg[3], clip;
    static char *kwlist[] = {"sensor", "stuck", "bias", "sigma", "clip", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "s(ppp)(ddd)(ddd)d", kwlist, &sensor, &st[0],
                                     &st[1], &st[2], &b[0], &b[1], &b[2], &sg[0], &sg[1], &sg[2],
                                     &clip))
        return NULL;
    sb_sensor_faults *f = &self->stage.faults;
    sb_inertial_fault *x = strcmp(sensor, "gyro") == 0    ? &f->gyro
                           : strcmp(sensor, "accel") == 0 ? &f->accel
                                                          : NULL;
    if (x == NULL) {
        PyErr_Format(PyExc_ValueError, "set_imu_fault: sensor is gyro or accel, not %s", sensor);
        return NULL;
    }
    /* A stuck axis keeps the value it froze at while any axis stays stuck. */
    x->primed = x->primed && any3(x->stuck) && any3(st);
    for (int i = 0; i < 3; i++) {
        x->stuck[i] = st[i];
        x->bias[i] = b[i];
        x->sigma[i] = sg[i];
    }
    x->clip = clip;
    x->on = any3(st) || b[0] != 0.0 || b[1] != 0.0 || b[2] != 0.0 || sg[0] > 0.0 ||
            sg[1] > 0.0 || sg[2] > 0.0 || clip >= 0.0;
    f->imu_on = f->gyro.on || f->accel.on;
    Py_RETURN_NONE;
}

/* set_baro_fault(stuck=0, offset_m=0.0, drift_m_s=0.0): the altitude error at sim time t
 * is offset_m + drift_m_s t. */
PyObject *Kernel_set_baro_fault(Kernel *self, PyObject *args, PyObject *kwds)
{
    int stuck;
    double off, drift;
    static char *kwlist[] = {"stuck", "offset_m", "drift_m_s", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "pdd", kwlist, &stuck, &off, &drift))
        return NULL;
    sb_baro_fault *x = &self->stage.faults.baro;
    x->primed = x->primed && x->stuck && stuck;
    x->stuck = stuck;
    x->offset_m = off;
    x->drift_m_s = drift;
    x->on = stuck || off != 0.0 || drift != 0.0;
    Py_RETURN_NONE;
}

/* set_mag_fault(off=0, offset_gauss=(3)): silent or not, and the FRD offset the reading
 * carries (the hard-iron offset plus any motor interference). */
PyObject *Kernel_set_mag_fault(Kernel *self, PyObject *args, PyObject *kwds)
{
    int off;
    double o[3];
    static char *kwlist[] = {"off", "offset_gauss", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "p(ddd)", kwlist, &off, &o[0], &o[1], &o[2]))
        return NULL;
    self->stage.faults.mag_off = off;
    memcpy(self->stage.mag_offset_gauss, o, sizeof o);
    Py_RETURN_NONE;
}

/* set_fault_seed(seed): the noisy-axis faults' generator (a run's named stream). */
PyObject *Kernel_set_fault_seed(Kernel *self, PyObject *arg)
{
    unsigned long long seed = PyLong_AsUnsignedLongLongMask(arg);
    if (seed == (unsigned long long)-1 && PyErr_Occurred())
        return NULL;
    self->stage.faults.rng = seed;
    Py_RETURN_NONE;
}

/* set_imbalance_scale(motor, scale): motor 0..3's imbalance is scale x the scenario's
 * (a damaged prop); needs the vibration model on. */
PyObject *Kernel_set_imbalance_scale(Kernel *self, PyObject *args)
{
    int m;
    double scale;
    if (!PyArg_ParseTuple(args, "id", &m, &scale))
        return NULL;
    if (m < 0 || m > 3 || !(scale >= 0.0)) {
        PyErr_SetString(PyExc_ValueError, "set_imbalance_scale(motor 0..3, scale >= 0)");
        return NULL;
    }
    sb_sensor_stage *s = &self->stage;
    if (s->c.vib.on == 0.0) {
        PyErr_SetString(PyExc_RuntimeError, "set_imbalance_scale: the vibration model is off");
        return NULL;
    }
    s->vib.c.imbalance_kg_m[m] = s->c.vib.imbalance_kg_m[m] * scale;
    Py_RETURN_NONE;
}
