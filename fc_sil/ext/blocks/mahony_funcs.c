/*
 * mahony_funcs.c - bindings of the attitude estimator (fc_mahony.h): its configuration by
 * field name, the gyro/accel update over whole arrays, the magnetometer, acceleration
 * reference and GNSS-aided corrections one call each, and its state as a dict.
 */
#include "blocks_common.h"

#include <string.h>

#include "fc_mahony.h"

/* kp_gnss and ki_gnss may be left out: 0, the estimator without GNSS aiding;
 * gnss_boost and gnss_innov_sigma too: fixed aided gains. */
static const fc_blk_field_t mahony_fields[] = {
    FC_BLK_FIELD(fc_mahony_config_t, kp, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, ki, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, kmag, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, trust_tc_s, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, trust_span_g, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, bias_rate_hz, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, still_gyro_rad_s, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, still_acc_g, FC_BLK_F32),
    FC_BLK_FIELD(fc_mahony_config_t, trust_ema_enable, FC_BLK_BOOL),
    FC_BLK_FIELD(fc_mahony_config_t, bias_enable, FC_BLK_BOOL),
    FC_BLK_OPTIONAL(fc_mahony_config_t, kp_gnss, FC_BLK_F32),
    FC_BLK_OPTIONAL(fc_mahony_config_t, ki_gnss, FC_BLK_F32),
    FC_BLK_OPTIONAL(fc_mahony_config_t, gnss_boost, FC_BLK_F32),
    FC_BLK_OPTIONAL(fc_mahony_config_t, gnss_innov_sigma, FC_BLK_F32),
};

static PyObject *mahony_init(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "config", NULL};
    Py_buffer b;
    PyObject *cfgd;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$O", kwlist, &b, &cfgd)) {
        return NULL;
    }
    fc_mahony_config_t cfg;
    fc_mahony_t *mh = fc_blk_state(&b, sizeof *mh, "mahony");
    int ok = mh && FC_BLK_CONFIG(cfgd, mahony_fields, &cfg, "mahony");
    if (ok) {
        fc_mahony_init(mh, &cfg);
    }
    return fc_blk_release_none(&b, ok);
}

static PyObject *mahony_set_attitude(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "q_wxyz", NULL};
    Py_buffer b;
    float q[4];
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$(ffff)", kwlist, &b, &q[0], &q[1], &q[2],
                                     &q[3])) {
        return NULL;
    }
    fc_mahony_t *mh = fc_blk_state(&b, sizeof *mh, "mahony");
    if (mh) {
        fc_mahony_set_attitude(mh, q);
    }
    return fc_blk_release_none(&b, mh != NULL);
}

static PyObject *mahony_mag(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "field_frd", "declination_rad", NULL};
    Py_buffer b;
    float f[3], dec;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$(fff)f", kwlist, &b, &f[0], &f[1], &f[2],
                                     &dec)) {
        return NULL;
    }
    fc_mahony_t *mh = fc_blk_state(&b, sizeof *mh, "mahony");
    PyObject *r = mh ? PyLong_FromLong(fc_mahony_mag(mh, f, dec)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

/* Rows of gyro and accel at a fixed dt; returns (q (n,4), bias (n,3), trust (n,)). */
static PyObject *mahony_run(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "gyro", "accel", "dt_s", NULL};
    Py_buffer b;
    PyObject *go, *ao;
    float dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*OO$f", kwlist, &b, &go, &ao, &dt)) {
        return NULL;
    }
    PyObject *res = NULL, *qo = NULL, *bo = NULL, *to = NULL;
    PyArrayObject *gyr = NULL, *acc = NULL;
    fc_mahony_t *mh = fc_blk_state(&b, sizeof *mh, "mahony");
    if (mh && (gyr = fc_blk_f32_in(go, 3, "gyro")) && (acc = fc_blk_f32_in(ao, 3, "accel"))
        && fc_blk_same_len(PyArray_DIM(gyr, 0), acc)) {
        const npy_intp n = PyArray_DIM(gyr, 0);
        qo = fc_blk_f32_out(n, 4);
        bo = fc_blk_f32_out(n, 3);
        to = fc_blk_f32_out(n, 0);
        if (qo && bo && to) {
            const float *g = PyArray_DATA(gyr), *a = PyArray_DATA(acc);
            float *q = PyArray_DATA((PyArrayObject *)qo), *bi = PyArray_DATA((PyArrayObject *)bo);
            float *tr = PyArray_DATA((PyArrayObject *)to);
            for (npy_intp i = 0; i < n; i++) {
                (void)fc_mahony_update(mh, &g[3 * i], &a[3 * i], dt);
                memcpy(&q[4 * i], mh->q_wxyz, sizeof(float) * 4);
                memcpy(&bi[3 * i], mh->bias_rad_s, sizeof(float) * 3);
                tr[i] = mh->trust;
            }
            res = Py_BuildValue("(OOO)", qo, bo, to);
        }
    }
    Py_XDECREF(qo);
    Py_XDECREF(bo);
    Py_XDECREF(to);
    Py_XDECREF(gyr);
    Py_XDECREF(acc);
    PyBuffer_Release(&b);
    return res;
}

static PyObject *mahony_accel_ref(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "accel_ned_m_s2", NULL};
    Py_buffer b;
    float a[3];
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$(fff)", kwlist, &b, &a[0], &a[1], &a[2])) {
        return NULL;
    }
    fc_mahony_t *mh = fc_blk_state(&b, sizeof *mh, "mahony");
    PyObject *r = mh ? PyLong_FromLong(fc_mahony_set_accel_ref(mh, a)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *mahony_gnss(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "f_imu_ned_m_s2", "f_gnss_ned_m_s2", NULL};
    Py_buffer b;
    float fi[3], fg[3];
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$(fff)(fff)", kwlist, &b, &fi[0], &fi[1],
                                     &fi[2], &fg[0], &fg[1], &fg[2])) {
        return NULL;
    }
    fc_mahony_t *mh = fc_blk_state(&b, sizeof *mh, "mahony");
    PyObject *r = mh ? PyLong_FromLong(fc_mahony_gnss(mh, fi, fg)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *mahony_state(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    if (!PyArg_ParseTuple(args, "w*", &b)) {
        return NULL;
    }
    fc_mahony_t *mh = fc_blk_state(&b, sizeof *mh, "mahony");
    PyObject *r = NULL;
    if (mh) {
        r = Py_BuildValue("{s:(dddd),s:(ddd),s:(ddd),s:d,s:d,s:O,s:O,s:O,s:d}", "q_wxyz",
                          (double)mh->q_wxyz[0], (double)mh->q_wxyz[1], (double)mh->q_wxyz[2],
                          (double)mh->q_wxyz[3], "bias_rad_s", (double)mh->bias_rad_s[0],
                          (double)mh->bias_rad_s[1], (double)mh->bias_rad_s[2], "integ_rad_s",
                          (double)mh->integ_rad_s[0], (double)mh->integ_rad_s[1],
                          (double)mh->integ_rad_s[2], "trust", (double)mh->trust, "trust_raw",
                          (double)mh->trust_raw, "still", mh->still ? Py_True : Py_False,
                          "heading_valid", mh->heading_valid ? Py_True : Py_False,
                          "gnss_active", fc_mahony_gnss_active(mh) ? Py_True : Py_False,
                          "gnss_scale", (double)mh->gnss_sched.scale);
    }
    PyBuffer_Release(&b);
    return r;
}

PyMethodDef fc_blk_mahony_methods[] = {
    {"mahony_init", FC_BLK_KW(mahony_init), "mahony_init(state, config={fc_mahony_config_t})"},
    {"mahony_set_attitude", FC_BLK_KW(mahony_set_attitude), "mahony_set_attitude(state, q_wxyz=)"},
    {"mahony_run", FC_BLK_KW(mahony_run),
     "mahony_run(state, gyro, accel, dt_s=) -> (q, bias, trust)"},
    {"mahony_mag", FC_BLK_KW(mahony_mag),
     "mahony_mag(state, field_frd=, declination_rad=) -> status"},
    {"mahony_accel_ref", FC_BLK_KW(mahony_accel_ref),
     "mahony_accel_ref(state, accel_ned_m_s2=) -> status"},
    {"mahony_gnss", FC_BLK_KW(mahony_gnss),
     "mahony_gnss(state, f_imu_ned_m_s2=, f_gnss_ned_m_s2=) -> status"},
    {"mahony_state", mahony_state, METH_VARARGS, "mahony_state(state) -> dict"},
    {NULL, NULL, 0, NULL},
};
