/*
 * filter_funcs.c - bindings of the filters (fc_filter.h) and the INS front end that
 * filters the raw IMU (fc_ins.h). Each call runs its block over a whole input array in
 * C, so a 100,000-sample attenuation test is one loop, not 100,000 calls.
 */
#include "blocks_common.h"

#include <string.h>

#include "fc_filter.h"
#include "fc_ins.h"

/* ---- filters ------------------------------------------------------------------ */

static PyObject *filter_init(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "kind", "cutoff_hz", "bandwidth_hz", "dt_s", NULL};
    Py_buffer b;
    int kind;
    float cutoff, bw, dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$ifff", kwlist, &b, &kind, &cutoff, &bw,
                                     &dt)) {
        return NULL;
    }
    fc_filter_t *f = fc_blk_state(&b, sizeof *f, "filter");
    PyObject *r = f ? PyLong_FromLong(fc_filter_init(f, kind, cutoff, bw, dt)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *filter_update(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "cutoff_hz", "bandwidth_hz", "dt_s", NULL};
    Py_buffer b;
    float cutoff, bw, dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$fff", kwlist, &b, &cutoff, &bw, &dt)) {
        return NULL;
    }
    fc_filter_t *f = fc_blk_state(&b, sizeof *f, "filter");
    PyObject *r = f ? PyLong_FromLong(fc_filter_update_cutoff(f, cutoff, bw, dt)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *filter_reset(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "value", NULL};
    Py_buffer b;
    float v;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$f", kwlist, &b, &v)) {
        return NULL;
    }
    fc_filter_t *f = fc_blk_state(&b, sizeof *f, "filter");
    if (f) {
        fc_filter_reset(f, v);
    }
    return fc_blk_release_none(&b, f != NULL);
}

static PyObject *filter_apply(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *xo;
    if (!PyArg_ParseTuple(args, "w*O", &b, &xo)) {
        return NULL;
    }
    PyObject *out = NULL;
    PyArrayObject *x = NULL;
    fc_filter_t *f = fc_blk_state(&b, sizeof *f, "filter");
    if (f && (x = fc_blk_f32_in(xo, 0, "x")) != NULL) {
        const npy_intp n = PyArray_DIM(x, 0);
        out = fc_blk_f32_out(n, 0);
        if (out) {
            const float *in = PyArray_DATA(x);
            float *y = PyArray_DATA((PyArrayObject *)out);
            for (npy_intp i = 0; i < n; i++) {
                y[i] = fc_filter_apply(f, in[i]);
            }
        }
    }
    Py_XDECREF(x);
    PyBuffer_Release(&b);
    return out;
}

/* ---- INS front end ------------------------------------------------------------ */

static const fc_blk_field_t ins_fields[] = {
    FC_BLK_FIELD(fc_ins_config_t, gyro_cutoff_hz, FC_BLK_F32),
    FC_BLK_FIELD(fc_ins_config_t, accel_cutoff_hz, FC_BLK_F32),
    FC_BLK_FIELD(fc_ins_config_t, notch_enable, FC_BLK_BOOL),
    FC_BLK_FIELD(fc_ins_config_t, notch_center_hz, FC_BLK_F32),
    FC_BLK_FIELD(fc_ins_config_t, notch_bandwidth_hz, FC_BLK_F32),
};

static PyObject *ins_init(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "config", "dt_s", NULL};
    Py_buffer b;
    PyObject *cfgd;
    float dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$Of", kwlist, &b, &cfgd, &dt)) {
        return NULL;
    }
    fc_ins_config_t cfg;
    fc_ins_t *ins = fc_blk_state(&b, sizeof *ins, "ins");
    PyObject *r = ins && FC_BLK_CONFIG(cfgd, ins_fields, &cfg, "ins")
                      ? PyLong_FromLong(fc_ins_init(ins, &cfg, dt))
                      : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *ins_run(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *ao, *go;
    if (!PyArg_ParseTuple(args, "w*OO", &b, &ao, &go)) {
        return NULL;
    }
    PyObject *res = NULL, *ga = NULL, *aa = NULL, *st = NULL;
    PyArrayObject *acc = NULL, *gyr = NULL;
    fc_ins_t *ins = fc_blk_state(&b, sizeof *ins, "ins");
    if (ins && (acc = fc_blk_f32_in(ao, 3, "accel")) && (gyr = fc_blk_f32_in(go, 3, "gyro"))
        && fc_blk_same_len(PyArray_DIM(acc, 0), gyr)) {
        const npy_intp n = PyArray_DIM(acc, 0);
        ga = fc_blk_f32_out(n, 3);
        aa = fc_blk_f32_out(n, 3);
        npy_intp dims[1] = {n};
        st = PyArray_SimpleNew(1, dims, NPY_INT8);
        if (ga && aa && st) {
            const float *a = PyArray_DATA(acc), *g = PyArray_DATA(gyr);
            float *go_ = PyArray_DATA((PyArrayObject *)ga);
            float *ao_ = PyArray_DATA((PyArrayObject *)aa);
            int8_t *s = PyArray_DATA((PyArrayObject *)st);
            for (npy_intp i = 0; i < n; i++) {
                s[i] = (int8_t)fc_ins_update(ins, &a[3 * i], &g[3 * i]);
                memcpy(&go_[3 * i], ins->gyro_frd_rad_s, sizeof(float) * 3);
                memcpy(&ao_[3 * i], ins->accel_frd_m_s2, sizeof(float) * 3);
            }
            res = Py_BuildValue("(OOO)", ga, aa, st);
        }
    }
    Py_XDECREF(ga);
    Py_XDECREF(aa);
    Py_XDECREF(st);
    Py_XDECREF(acc);
    Py_XDECREF(gyr);
    PyBuffer_Release(&b);
    return res;
}

PyMethodDef fc_blk_filter_methods[] = {
    {"filter_init", FC_BLK_KW(filter_init),
     "filter_init(state, kind=, cutoff_hz=, bandwidth_hz=, dt_s=) -> status"},
    {"filter_update", FC_BLK_KW(filter_update),
     "filter_update(state, cutoff_hz=, bandwidth_hz=, dt_s=) -> status"},
    {"filter_reset", FC_BLK_KW(filter_reset), "filter_reset(state, value=)"},
    {"filter_apply", filter_apply, METH_VARARGS, "filter_apply(state, x) -> y"},
    {"ins_init", FC_BLK_KW(ins_init),
     "ins_init(state, config={fc_ins_config_t fields}, dt_s=) -> status"},
    {"ins_run", ins_run, METH_VARARGS, "ins_run(state, accel, gyro) -> (gyro_f, accel_f, status)"},
    {NULL, NULL, 0, NULL},
};
