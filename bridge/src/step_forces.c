/*
 * step_forces.c - the disturbance forces of the bridge kernel (bridge/disturbances.py
 * plans them): set_forces() takes the plan, and before each JSBSim run() the summed
 * force of each frame is written into that frame's external force direction. They are
 * inputs to the FDM, not sensors: they live beside the shim, not in the sensor stage.
 */
#include "step_kernel.h"

void sb_step_clear_forces(Kernel *self)
{
    for (int f = 0; f < self->n_force_frames; f++) {
        for (int i = 0; i < 3; i++)
            Py_CLEAR(self->forces[f].set[i]);
        PyMem_Free(self->forces[f].items);
        self->forces[f].items = NULL;
        self->forces[f].n = 0;
    }
    self->n_force_frames = 0;
}

/* Disturbance forces at the start time of step k into their frames' directions. */
int sb_step_apply_forces(Kernel *self, int64_t k)
{
    const double t_s = (double)((k - 1) * self->dt_ns) * 1e-9;
    for (int f = 0; f < self->n_force_frames; f++) {
        const force_frame_t *fr = &self->forces[f];
        double v[3] = {0.0, 0.0, 0.0};
        for (Py_ssize_t i = 0; i < fr->n; i++) {
            const force_item_t *it = &fr->items[i];
            const double f_n =
                it->c_n * (it->periodic ? sin(it->w_rad_s * (t_s - it->t_on_s) + it->phase_rad)
                                        : 1.0);
            v[0] += f_n * it->axis[0];
            v[1] += f_n * it->axis[1];
            v[2] += f_n * it->axis[2];
        }
        for (int j = 0; j < 3; j++) {
            PyObject *x = PyFloat_FromDouble(v[j]);
            if (x == NULL)
                return -1;
            PyObject *r = PyObject_CallOneArg(fr->set[j], x);
            Py_DECREF(x);
            if (r == NULL)
                return -1;
            Py_DECREF(r);
        }
    }
    return 0;
}

/* One frame: (setters (3 callables), [(c_n, w_rad_s, t_on_s, phase_rad, periodic,
 * (ax, ay, az)), ...]) into fr. */
static int take_frame(force_frame_t *fr, PyObject *frame)
{
    PyObject *setters, *items;
    if (!PyArg_ParseTuple(frame, "OO", &setters, &items))
        return -1;
    if (sb_step_take_callables(setters, fr->set, 3, "force direction setters") < 0)
        return -1;
    PyObject *its = PySequence_Fast(items, "set_forces: items must be a sequence");
    if (its == NULL)
        return -1;
    fr->n = PySequence_Fast_GET_SIZE(its);
    fr->items = PyMem_Calloc((size_t)(fr->n ? fr->n : 1), sizeof *fr->items);
    int rc = 0;
    if (fr->items == NULL) {
        PyErr_NoMemory();
        rc = -1;
    }
    for (Py_ssize_t i = 0; rc == 0 && i < fr->n; i++) {
        force_item_t *it = &fr->items[i];
        if (!PyArg_ParseTuple(PySequence_Fast_GET_ITEM(its, i), "ddddp(ddd)", &it->c_n,
                              &it->w_rad_s, &it->t_on_s, &it->phase_rad, &it->periodic,
                              &it->axis[0], &it->axis[1], &it->axis[2]))
            rc = -1;
    }
    Py_DECREF(its);
    return rc;
}

/* set_forces([(setters, items), ...]): at most 2 frames (ned, frd); [] clears. */
PyObject *Kernel_set_forces(Kernel *self, PyObject *plan)
{
    PyObject *frames = PySequence_Fast(plan, "set_forces: a list of (setters, items)");
    if (frames == NULL)
        return NULL;
    sb_step_clear_forces(self);
    const Py_ssize_t nf = PySequence_Fast_GET_SIZE(frames);
    if (nf > 2) {
        PyErr_SetString(PyExc_ValueError, "set_forces: at most 2 frames (ned, frd)");
        Py_DECREF(frames);
        return NULL;
    }
    for (Py_ssize_t f = 0; f < nf; f++) {
        self->n_force_frames = (int)f + 1;   /* counted first: a failure clears it too */
        if (take_frame(&self->forces[f], PySequence_Fast_GET_ITEM(frames, f)) < 0) {
            sb_step_clear_forces(self);
            Py_DECREF(frames);
            return NULL;
        }
    }
    Py_DECREF(frames);
    Py_RETURN_NONE;
}
