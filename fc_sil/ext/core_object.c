/*
 * core_object.c - the life of a Core and what its host sets: construction, reset and
 * clean-up, the C parameter table by index, arming, and the targets the host's modes
 * command (attitude, yaw, altitude, climb, throttle, the estimator's acceleration
 * reference). Setters return the core's status code (fc_status.h) rather than raise:
 * the host decides whether a refused value is an error (a GCS gets PARAM_ERROR).
 */
#include "core_object.h"

#include <time.h>

int64_t fc_ext_monotonic_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + (int64_t)ts.tv_nsec;
}

/* ---- life cycle ------------------------------------------------------------- */

PyObject *fc_ext_core_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    (void)args;
    (void)kwds;
    CoreObject *self = (CoreObject *)type->tp_alloc(type, 0);
    if (self != NULL) {
        fc_core_init(&self->core);
        for (int k = 0; k < 16; k++) {
            self->last_kind_ns[k] = -1;
        }
    }
    return (PyObject *)self;
}

void fc_ext_core_dealloc(CoreObject *self)
{
    fc_ext_detach_io(self);
    fc_ext_unbind_batch(self);
    fc_ext_clear_log(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *Core_reset(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    fc_core_reset(&self->core);
    self->pwm_seq = 0;
    self->last_seq = 0;
    Py_RETURN_NONE;
}

/* ---- parameters ---------------------------------------------------------- */

static PyObject *Core_set_param(CoreObject *self, PyObject *args)
{
    int index;
    double value;
    if (!PyArg_ParseTuple(args, "id", &index, &value)) {
        return NULL;
    }
    if (index < 0 || index > 65535) {
        return PyLong_FromLong(FC_ERR_INDEX);
    }
    return PyLong_FromLong(fc_core_set_param(&self->core, (uint16_t)index, (float)value));
}

static PyObject *Core_get_param(CoreObject *self, PyObject *args)
{
    int index;
    if (!PyArg_ParseTuple(args, "i", &index)) {
        return NULL;
    }
    float value = 0.0f;
    if (index < 0 || index > 65535
        || fc_core_get_param(&self->core, (uint16_t)index, &value) != FC_OK) {
        PyErr_Format(PyExc_KeyError, "no C-core parameter with index %d", index);
        return NULL;
    }
    return PyFloat_FromDouble((double)value);
}

/* ---- the host's inputs ------------------------------------------------------ */

static PyObject *Core_set_setpoint_input(CoreObject *self, PyObject *args)
{
    int enabled;
    if (!PyArg_ParseTuple(args, "p", &enabled)) {
        return NULL;
    }
    self->ignore_setpoints = !enabled;
    Py_RETURN_NONE;
}

static PyObject *Core_set_armed(CoreObject *self, PyObject *args)
{
    int armed;
    if (!PyArg_ParseTuple(args, "p", &armed)) {
        return NULL;
    }
    fc_core_set_armed(&self->core, armed != 0);
    Py_RETURN_NONE;
}

static PyObject *Core_set_vibe_comp(CoreObject *self, PyObject *args)
{
    int on;
    if (!PyArg_ParseTuple(args, "p", &on)) {
        return NULL;
    }
    fc_core_set_vibe_comp(&self->core, on != 0);
    Py_RETURN_NONE;
}

static PyObject *Core_set_attitude_target(CoreObject *self, PyObject *args)
{
    double r, p;
    if (!PyArg_ParseTuple(args, "dd", &r, &p)) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_set_attitude_target(&self->core, (float)r, (float)p));
}

#define SCALAR_SETTER(pyname, cfunc)                                        \
    static PyObject *pyname(CoreObject *self, PyObject *args)               \
    {                                                                       \
        double v;                                                           \
        if (!PyArg_ParseTuple(args, "d", &v)) {                             \
            return NULL;                                                    \
        }                                                                   \
        return PyLong_FromLong(cfunc(&self->core, (float)v));               \
    }

SCALAR_SETTER(Core_set_yaw_target, fc_core_set_yaw_target)
SCALAR_SETTER(Core_set_yaw_rate_target, fc_core_set_yaw_rate_target)
SCALAR_SETTER(Core_set_altitude_target, fc_core_set_altitude_target)
SCALAR_SETTER(Core_set_climb_target, fc_core_set_climb_target)
SCALAR_SETTER(Core_set_throttle, fc_core_set_throttle)

static PyObject *Core_set_accel_ref(CoreObject *self, PyObject *args)
{
    float a[3];
    if (!PyArg_ParseTuple(args, "(fff)", &a[0], &a[1], &a[2])) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_set_accel_ref(&self->core, a));
}

PyMethodDef fc_ext_object_methods[] = {
    {"reset", (PyCFunction)Core_reset, METH_NOARGS, "Reset state and inputs; keep parameters."},
    {"set_param", (PyCFunction)Core_set_param, METH_VARARGS,
     "set_param(index, value) -> status code (0 ok)."},
    {"get_param", (PyCFunction)Core_get_param, METH_VARARGS, "get_param(index) -> float."},
    {"set_armed", (PyCFunction)Core_set_armed, METH_VARARGS, "set_armed(bool)."},
    {"set_setpoint_input", (PyCFunction)Core_set_setpoint_input, METH_VARARGS,
     "set_setpoint_input(bool): consume (True, default) or skip scenario SETPOINT records."},
    {"set_attitude_target", (PyCFunction)Core_set_attitude_target, METH_VARARGS,
     "set_attitude_target(roll_rad, pitch_rad) -> status."},
    {"set_yaw_target", (PyCFunction)Core_set_yaw_target, METH_VARARGS,
     "set_yaw_target(yaw_rad) -> status (yaw angle mode)."},
    {"set_yaw_rate_target", (PyCFunction)Core_set_yaw_rate_target, METH_VARARGS,
     "set_yaw_rate_target(rad_s) -> status (yaw rate mode)."},
    {"set_altitude_target", (PyCFunction)Core_set_altitude_target, METH_VARARGS,
     "set_altitude_target(m) -> status."},
    {"set_climb_target", (PyCFunction)Core_set_climb_target, METH_VARARGS,
     "set_climb_target(m_s) -> status."},
    {"set_throttle", (PyCFunction)Core_set_throttle, METH_VARARGS,
     "set_throttle(0..1) -> status (direct throttle)."},
    {"set_vibe_comp", (PyCFunction)Core_set_vibe_comp, METH_VARARGS,
     "set_vibe_comp(bool): the altitude loop's vibration-resistant law on/off."},
    {"set_accel_ref", (PyCFunction)Core_set_accel_ref, METH_VARARGS,
     "set_accel_ref((ax, ay, az) NED m/s^2) -> status (estimator acceleration reference)."},
    {NULL, NULL, 0, NULL},
};
