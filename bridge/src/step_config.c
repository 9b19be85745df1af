/*
 * step_config.c - the Kernel methods used between steps (step_run.c has the step
 * itself, step_forces.c the disturbance forces): the IMU noise block and injected gyro
 * bias, the baro and magnetometer configuration and noise, counters and the attributes
 * Python reads or sets (next_slow_ns, pos). The sensor stage reads the noise through
 * pointers into the Py_buffer views held here.
 */
#include "step_kernel.h"

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
    sb_sensor_stage_set_imu_noise(&self->stage, (const double *)bv.buf,
                                  (const double *)tv.buf, (size_t)bv.shape[0]);
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
        self->stage.injected_rad_s[i] = v;
    }
    Py_RETURN_NONE;
}

PyObject *Kernel_seqs(Kernel *self, PyObject *Py_UNUSED(ignored))
{
    const sb_sensor_stage *s = &self->stage;
    return Py_BuildValue("(kkkkk)", (unsigned long)s->seq_imu, (unsigned long)s->seq_att,
                         (unsigned long)s->seq_nav, (unsigned long)s->baro.seq,
                         (unsigned long)s->mag.seq);
}

int sb_step_set_noise(sb_lowrate *lr, Py_buffer *held, PyObject *arr, Py_ssize_t width,
                      Py_ssize_t pos, const char *what)
{
    Py_buffer v;
    if (sb_step_get_f64(arr, &v, width, 0, what) < 0)
        return -1;
    if (v.ndim != 2 || v.shape[1] != width) {
        PyErr_Format(PyExc_ValueError, "%s must be (rows, %zd) float64", what, width);
        PyBuffer_Release(&v);
        return -1;
    }
    if (pos < 0 || pos > v.shape[0]) {
        PyErr_Format(PyExc_ValueError, "%s: the first row to read must be 0..%zd, not %zd",
                     what, v.shape[0], pos);
        PyBuffer_Release(&v);
        return -1;
    }
    sb_step_release(held);
    *held = v;
    sb_lowrate_set_noise(lr, (const double *)v.buf, (size_t)v.shape[0], (size_t)pos);
    return 0;
}

static int start_schedule(sb_lowrate *lr, double rate_hz)
{
    if (sb_lowrate_start(lr, rate_hz) < 0) {
        PyErr_SetString(PyExc_ValueError, "rate_hz must be > 0");
        return -1;
    }
    return 0;
}

/* configure_baro(rate_hz, offset_pa, noise_pa) */
PyObject *Kernel_configure_baro(Kernel *self, PyObject *args)
{
    double rate, off, noise;
    if (!PyArg_ParseTuple(args, "ddd", &rate, &off, &noise))
        return NULL;
    if (start_schedule(&self->stage.baro, rate) < 0)
        return NULL;
    self->stage.baro_offset_pa = off;
    self->stage.baro_noise_pa = noise;
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
    if (start_schedule(&self->stage.mag, rate) < 0)
        return NULL;
    memcpy(self->stage.mag_field_ned_gauss, f, sizeof f);
    memcpy(self->stage.mag_offset_gauss, o, sizeof o);
    self->stage.mag_noise_gauss = noise;
    Py_RETURN_NONE;
}

PyObject *Kernel_set_baro_block(Kernel *self, PyObject *arr)
{
    return sb_step_set_noise(&self->stage.baro, &self->baro_noise, arr, 1, 0, "baro noise") < 0
               ? NULL : Py_NewRef(Py_None);
}

PyObject *Kernel_set_mag_block(Kernel *self, PyObject *arr)
{
    return sb_step_set_noise(&self->stage.mag, &self->mag_noise, arr, 3, 0, "mag noise") < 0
               ? NULL : Py_NewRef(Py_None);
}

static PyObject *Kernel_get_next_slow(Kernel *self, void *closure)
{
    (void)closure;
    return PyLong_FromLongLong(self->stage.next_slow_ns);
}

static int Kernel_set_next_slow(Kernel *self, PyObject *v, void *closure)
{
    (void)closure;
    long long x = v ? PyLong_AsLongLong(v) : -1;
    if (x == -1 && PyErr_Occurred())
        return -1;
    self->stage.next_slow_ns = x;
    return 0;
}

static PyObject *Kernel_get_pos(Kernel *self, void *closure)
{
    (void)closure;
    return PyLong_FromSize_t(self->stage.imu_pos);
}

/* hold(due_ns, record): a 64-byte record the stage writes at the first step at or after
 * due_ns (sensor_stage.h sb_held), so that its release needs no Python. */
PyObject *Kernel_hold(Kernel *self, PyObject *args)
{
    long long due_ns;
    Py_buffer rec;
    if (!PyArg_ParseTuple(args, "Ly*", &due_ns, &rec))
        return NULL;
    sb_record r;
    const int ok = rec.len == (Py_ssize_t)sizeof r;
    if (ok)
        memcpy(&r, rec.buf, sizeof r);
    PyBuffer_Release(&rec);
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "hold: a record is %zu bytes", sizeof r);
        return NULL;
    }
    if (sb_sensor_stage_hold(&self->stage, &r, due_ns) < 0) {
        PyErr_Format(PyExc_RuntimeError, "hold: %d records are held already", SB_HELD_MAX);
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *Kernel_get_held(Kernel *self, void *closure)
{
    (void)closure;
    return PyLong_FromLong(self->stage.held.n);
}

PyGetSetDef sb_step_getset[] = {
    {"next_slow_ns", (getter)Kernel_get_next_slow, (setter)Kernel_set_next_slow,
     "sim time [ns] from which step flags F_SLOW_DUE", NULL},
    {"pos", (getter)Kernel_get_pos, NULL, "next row of the noise block", NULL},
    {"held", (getter)Kernel_get_held, NULL, "records held for a later step (hold())", NULL},
    {"gnss_on", (getter)Kernel_get_gnss_on, NULL, "the stage makes the GNSS epochs", NULL},
    {"gnss_seq", (getter)Kernel_get_gnss_seq, NULL,
     "the next GNSS record's sequence number, while gnss_on", NULL},
    {NULL, NULL, NULL, NULL, NULL}};
