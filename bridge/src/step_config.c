/*
 * step_config.c - the Kernel methods used between steps (step_run.c has the
 * step itself): the IMU noise block and injected gyro bias, the baro and
 * magnetometer configuration and noise, the disturbance forces, counters and
 * the attributes Python reads or sets (next_slow_ns, pos).
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

PyObject *Kernel_set_block(Kernel *self, PyObject *args)
{
    PyObject *block, *temps;
    if (!PyArg_ParseTuple(args, "OO", &block, &temps))
        return NULL;
    Py_buffer bv, tv;
    if (sb_step_get_f64(block, &bv, 6, 0, "block") < 0)
        return NULL;
    if (bv.ndim != 2 || bv.shape[1] != 6 || sb_step_get_f64(temps, &tv, bv.shape[0], 0, "temps") < 0) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "block must be (rows, 6) float64");
        PyBuffer_Release(&bv);
        return NULL;
    }
    sb_step_release(&self->block_view);
    sb_step_release(&self->temps_view);
    self->block_view = bv;
    self->temps_view = tv;
    self->rows = bv.shape[0];
    self->pos = 0;
    self->have_block = 1;
    Py_RETURN_NONE;
}

PyObject *Kernel_set_injected(Kernel *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "set_injected(x, y, z) [rad/s]");
        return NULL;
    }
    for (int i = 0; i < 3; i++) {
        double v = PyFloat_AsDouble(args[i]);
        if (v == -1.0 && PyErr_Occurred())
            return NULL;
        self->injected[i] = v;
    }
    Py_RETURN_NONE;
}

PyObject *Kernel_seqs(Kernel *self, PyObject *Py_UNUSED(ignored))
{
    return Py_BuildValue("(kkkkk)", (unsigned long)self->seq_imu, (unsigned long)self->seq_att,
                         (unsigned long)self->seq_nav, (unsigned long)self->baro.seq,
                         (unsigned long)self->mag.seq);
}

static int set_noise(lowrate_t *lr, PyObject *arr, Py_ssize_t width, const char *what)
{
    Py_buffer v;
    if (sb_step_get_f64(arr, &v, width, 0, what) < 0)
        return -1;
    if (v.ndim != 2 || v.shape[1] != width) {
        PyErr_Format(PyExc_ValueError, "%s must be (rows, %zd) float64", what, width);
        PyBuffer_Release(&v);
        return -1;
    }
    sb_step_release(&lr->noise);
    lr->noise = v;
    lr->rows = v.shape[0];
    lr->pos = 0;
    return 0;
}

static int start_schedule(lowrate_t *lr, double rate_hz)
{
    if (!(rate_hz > 0.0)) {
        PyErr_SetString(PyExc_ValueError, "rate_hz must be > 0");
        return -1;
    }
    lr->rate_hz = rate_hz;
    lr->m = 1;
    lr->next_ns = sb_due_ns(1, rate_hz);
    lr->on = 1;
    return 0;
}

/* configure_baro(rate_hz, offset_pa, noise_pa, get_temp) */
PyObject *Kernel_configure_baro(Kernel *self, PyObject *args)
{
    double rate, off, noise;
    PyObject *get_temp;
    if (!PyArg_ParseTuple(args, "dddO", &rate, &off, &noise, &get_temp))
        return NULL;
    if (!PyCallable_Check(get_temp)) {
        PyErr_SetString(PyExc_TypeError, "get_temp must be callable");
        return NULL;
    }
    if (start_schedule(&self->baro, rate) < 0)
        return NULL;
    self->baro_offset_pa = off;
    self->baro_noise_pa = noise;
    Py_INCREF(get_temp);
    Py_XSETREF(self->get_temp, get_temp);
    Py_RETURN_NONE;
}

/* configure_mag(rate_hz, field_ned (3), offset (3), noise_gauss) */
PyObject *Kernel_configure_mag(Kernel *self, PyObject *args)
{
    double rate, noise;
    double f[3], o[3];
    if (!PyArg_ParseTuple(args, "d(ddd)(ddd)d", &rate, &f[0], &f[1], &f[2], &o[0], &o[1], &o[2],
                          &noise))
        return NULL;
    if (start_schedule(&self->mag, rate) < 0)
        return NULL;
    memcpy(self->mag_field_ned, f, sizeof f);
    memcpy(self->mag_offset, o, sizeof o);
    self->mag_noise_gauss = noise;
    Py_RETURN_NONE;
}

PyObject *Kernel_set_baro_block(Kernel *self, PyObject *arr)
{
    return set_noise(&self->baro, arr, 1, "baro noise") < 0 ? NULL : Py_NewRef(Py_None);
}

PyObject *Kernel_set_mag_block(Kernel *self, PyObject *arr)
{
    return set_noise(&self->mag, arr, 3, "mag noise") < 0 ? NULL : Py_NewRef(Py_None);
}

/* set_forces([(setters (3 callables), [(c_n, w_rad_s, t_on_s, phase_rad, periodic,
 *   (ax, ay, az)), ...]), ...]): at most 2 frames; [] clears. */
PyObject *Kernel_set_forces(Kernel *self, PyObject *plan)
{
    PyObject *frames = PySequence_Fast(plan, "set_forces: a list of (setters, items)");
    if (frames == NULL)
        return NULL;
    sb_step_clear_forces(self);
    const Py_ssize_t nf = PySequence_Fast_GET_SIZE(frames);
    if (nf > 2) {
        PyErr_SetString(PyExc_ValueError, "set_forces: at most 2 frames (ned, frd)");
        goto fail;
    }
    for (Py_ssize_t f = 0; f < nf; f++) {
        PyObject *setters, *items;
        if (!PyArg_ParseTuple(PySequence_Fast_GET_ITEM(frames, f), "OO", &setters, &items))
            goto fail;
        force_frame_t *fr = &self->forces[f];
        self->n_force_frames = (int)f + 1;
        if (sb_step_take_callables(setters, fr->set, 3, "force direction setters") < 0)
            goto fail;
        PyObject *its = PySequence_Fast(items, "set_forces: items must be a sequence");
        if (its == NULL)
            goto fail;
        fr->n = PySequence_Fast_GET_SIZE(its);
        fr->items = PyMem_Calloc((size_t)(fr->n ? fr->n : 1), sizeof *fr->items);
        if (fr->items == NULL) {
            Py_DECREF(its);
            PyErr_NoMemory();
            goto fail;
        }
        for (Py_ssize_t i = 0; i < fr->n; i++) {
            force_item_t *it = &fr->items[i];
            if (!PyArg_ParseTuple(PySequence_Fast_GET_ITEM(its, i), "ddddp(ddd)", &it->c_n,
                                  &it->w_rad_s, &it->t_on_s, &it->phase_rad, &it->periodic,
                                  &it->axis[0], &it->axis[1], &it->axis[2])) {
                Py_DECREF(its);
                goto fail;
            }
        }
        Py_DECREF(its);
    }
    Py_DECREF(frames);
    Py_RETURN_NONE;
fail:
    sb_step_clear_forces(self);
    Py_DECREF(frames);
    return NULL;
}

static PyObject *Kernel_get_next_slow(Kernel *self, void *closure)
{
    (void)closure;
    return PyLong_FromLongLong(self->next_slow_ns);
}

static int Kernel_set_next_slow(Kernel *self, PyObject *v, void *closure)
{
    (void)closure;
    long long x = v ? PyLong_AsLongLong(v) : -1;
    if (x == -1 && PyErr_Occurred())
        return -1;
    self->next_slow_ns = x;
    return 0;
}

static PyObject *Kernel_get_pos(Kernel *self, void *closure)
{
    (void)closure;
    return PyLong_FromSsize_t(self->pos);
}

PyGetSetDef sb_step_getset[] = {
    {"next_slow_ns", (getter)Kernel_get_next_slow, (setter)Kernel_set_next_slow,
     "sim time [ns] from which step flags F_SLOW_DUE", NULL},
    {"pos", (getter)Kernel_get_pos, NULL, "next row of the noise block", NULL},
    {NULL, NULL, NULL, NULL, NULL}};
