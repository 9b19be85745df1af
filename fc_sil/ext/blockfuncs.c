/*
 * blockfuncs.c - entry points to the individual blocks of the core, for the
 * thin wrappers in silbridge.fc_sil.blocks (and so the tests exercise each
 * C file on its own, as Crazyflie's bindings do).
 *
 * Each block's state lives in a caller-owned, 8-byte aligned buffer (a numpy
 * uint64 array) of the size block_sizes() reports; the functions take that
 * buffer, the configuration as plain numbers, and numpy arrays of inputs,
 * and run the block over every row in C.
 */
#include "ext_common.h"

#include <string.h>

#include "fc_alt_ctrl.h"
#include "fc_alt_est.h"
#include "fc_attitude.h"
#include "fc_blend.h"
#include "fc_filter.h"
#include "fc_ins.h"
#include "fc_mahony.h"
#include "fc_mixer.h"
#include "fc_rate_pid.h"
#include "fc_shaper.h"
#include "fc_trim.h"

/* A C-contiguous float32 array of shape (n,) or (n, cols); NULL + error otherwise. */
static PyArrayObject *f32_in(PyObject *obj, int cols, const char *what)
{
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(obj, NPY_FLOAT32, 1, 2,
                                                        NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
    if (a == NULL) {
        return NULL;
    }
    const int ok = (cols == 0) ? PyArray_NDIM(a) == 1
                               : (PyArray_NDIM(a) == 2 && PyArray_DIM(a, 1) == cols);
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s must have shape (n,%s)", what, cols ? " 3/4" : "");
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

static PyArrayObject *u8_in(PyObject *obj, const char *what)
{
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(obj, NPY_UINT8, 1, 1,
                                                        NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
    if (a == NULL) {
        PyErr_Format(PyExc_ValueError, "%s must be a 1-D array of flags", what);
    }
    return a;
}

static PyObject *f32_out(npy_intp n, int cols)
{
    npy_intp dims[2] = {n, cols};
    return PyArray_SimpleNew(cols ? 2 : 1, dims, NPY_FLOAT32);
}

static int same_len(npy_intp n, PyArrayObject *a)
{
    if (PyArray_DIM(a, 0) != n) {
        PyErr_SetString(PyExc_ValueError, "input arrays must have the same length");
        return 0;
    }
    return 1;
}

/* ---- sizes ------------------------------------------------------------------ */

static PyObject *block_sizes(PyObject *m, PyObject *noargs)
{
    (void)m;
    (void)noargs;
    return Py_BuildValue("{s:n,s:n,s:n,s:n,s:n,s:n,s:n,s:n,s:n,s:n}", "shaper",
                         (Py_ssize_t)sizeof(fc_shaper_t), "filter",
                         (Py_ssize_t)sizeof(fc_filter_t), "ins", (Py_ssize_t)sizeof(fc_ins_t),
                         "mahony", (Py_ssize_t)sizeof(fc_mahony_t), "rate_pid",
                         (Py_ssize_t)sizeof(fc_rate_pid_t), "trim", (Py_ssize_t)sizeof(fc_trim_t),
                         "blend", (Py_ssize_t)sizeof(fc_blend_t), "mixer",
                         (Py_ssize_t)sizeof(fc_mixer_t), "alt_est",
                         (Py_ssize_t)sizeof(fc_alt_est_t), "alt_ctrl",
                         (Py_ssize_t)sizeof(fc_alt_ctrl_t));
}

/* ---- filters ------------------------------------------------------------------ */

static PyObject *filter_init(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    int kind;
    float cutoff, bw, dt;
    if (!PyArg_ParseTuple(args, "w*ifff", &b, &kind, &cutoff, &bw, &dt)) {
        return NULL;
    }
    fc_filter_t *f = fc_ext_state(&b, sizeof *f, "filter");
    PyObject *r = f ? PyLong_FromLong(fc_filter_init(f, kind, cutoff, bw, dt)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *filter_update(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float cutoff, bw, dt;
    if (!PyArg_ParseTuple(args, "w*fff", &b, &cutoff, &bw, &dt)) {
        return NULL;
    }
    fc_filter_t *f = fc_ext_state(&b, sizeof *f, "filter");
    PyObject *r = f ? PyLong_FromLong(fc_filter_update_cutoff(f, cutoff, bw, dt)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *filter_reset(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float v;
    if (!PyArg_ParseTuple(args, "w*f", &b, &v)) {
        return NULL;
    }
    fc_filter_t *f = fc_ext_state(&b, sizeof *f, "filter");
    if (f) {
        fc_filter_reset(f, v);
    }
    PyBuffer_Release(&b);
    if (!f) {
        return NULL;
    }
    Py_RETURN_NONE;
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
    fc_filter_t *f = fc_ext_state(&b, sizeof *f, "filter");
    if (f && (x = f32_in(xo, 0, "x")) != NULL) {
        const npy_intp n = PyArray_DIM(x, 0);
        out = f32_out(n, 0);
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

static PyObject *ins_init(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    fc_ins_config_t cfg;
    int notch;
    float dt;
    if (!PyArg_ParseTuple(args, "w*ffpfff", &b, &cfg.gyro_cutoff_hz, &cfg.accel_cutoff_hz, &notch,
                          &cfg.notch_center_hz, &cfg.notch_bandwidth_hz, &dt)) {
        return NULL;
    }
    cfg.notch_enable = notch != 0;
    fc_ins_t *ins = fc_ext_state(&b, sizeof *ins, "ins");
    PyObject *r = ins ? PyLong_FromLong(fc_ins_init(ins, &cfg, dt)) : NULL;
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
    fc_ins_t *ins = fc_ext_state(&b, sizeof *ins, "ins");
    if (ins && (acc = f32_in(ao, 3, "accel")) && (gyr = f32_in(go, 3, "gyro"))
        && same_len(PyArray_DIM(acc, 0), gyr)) {
        const npy_intp n = PyArray_DIM(acc, 0);
        ga = f32_out(n, 3);
        aa = f32_out(n, 3);
        npy_intp dims[1] = {n};
        st = PyArray_SimpleNew(1, dims, NPY_INT8);
        if (ga && aa && st) {
            const float *a = PyArray_DATA(acc), *g = PyArray_DATA(gyr);
            float *go_ = PyArray_DATA((PyArrayObject *)ga), *ao_ = PyArray_DATA((PyArrayObject *)aa);
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

/* ---- Mahony ----------------------------------------------------------------- */

static int parse_mahony_cfg(PyObject *t, fc_mahony_config_t *cfg)
{
    int ema, bias;
    cfg->kp_gnss = 0.0f; /* optional: the GNSS-aided gains */
    cfg->ki_gnss = 0.0f;
    if (!PyArg_ParseTuple(t, "ffffffffpp|ff", &cfg->kp, &cfg->ki, &cfg->kmag, &cfg->trust_tc_s,
                          &cfg->trust_span_g, &cfg->bias_rate_hz, &cfg->still_gyro_rad_s,
                          &cfg->still_acc_g, &ema, &bias, &cfg->kp_gnss, &cfg->ki_gnss)) {
        return 0;
    }
    cfg->trust_ema_enable = ema != 0;
    cfg->bias_enable = bias != 0;
    return 1;
}

static PyObject *mahony_init(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *cfgt;
    if (!PyArg_ParseTuple(args, "w*O!", &b, &PyTuple_Type, &cfgt)) {
        return NULL;
    }
    fc_mahony_config_t cfg;
    fc_mahony_t *mh = fc_ext_state(&b, sizeof *mh, "mahony");
    int ok = mh && parse_mahony_cfg(cfgt, &cfg);
    if (ok) {
        fc_mahony_init(mh, &cfg);
    }
    PyBuffer_Release(&b);
    if (!ok) {
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *mahony_set_attitude(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float q[4];
    if (!PyArg_ParseTuple(args, "w*(ffff)", &b, &q[0], &q[1], &q[2], &q[3])) {
        return NULL;
    }
    fc_mahony_t *mh = fc_ext_state(&b, sizeof *mh, "mahony");
    if (mh) {
        fc_mahony_set_attitude(mh, q);
    }
    PyBuffer_Release(&b);
    if (!mh) {
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *mahony_mag(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float f[3], dec;
    if (!PyArg_ParseTuple(args, "w*(fff)f", &b, &f[0], &f[1], &f[2], &dec)) {
        return NULL;
    }
    fc_mahony_t *mh = fc_ext_state(&b, sizeof *mh, "mahony");
    PyObject *r = mh ? PyLong_FromLong(fc_mahony_mag(mh, f, dec)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

/* Rows of gyro and accel at a fixed dt; returns (q (n,4), bias (n,3), trust (n,)). */
static PyObject *mahony_run(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *go, *ao;
    float dt;
    if (!PyArg_ParseTuple(args, "w*OOf", &b, &go, &ao, &dt)) {
        return NULL;
    }
    PyObject *res = NULL, *qo = NULL, *bo = NULL, *to = NULL;
    PyArrayObject *gyr = NULL, *acc = NULL;
    fc_mahony_t *mh = fc_ext_state(&b, sizeof *mh, "mahony");
    if (mh && (gyr = f32_in(go, 3, "gyro")) && (acc = f32_in(ao, 3, "accel"))
        && same_len(PyArray_DIM(gyr, 0), acc)) {
        const npy_intp n = PyArray_DIM(gyr, 0);
        qo = f32_out(n, 4);
        bo = f32_out(n, 3);
        to = f32_out(n, 0);
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

static PyObject *mahony_accel_ref(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float a[3];
    if (!PyArg_ParseTuple(args, "w*(fff)", &b, &a[0], &a[1], &a[2])) {
        return NULL;
    }
    fc_mahony_t *mh = fc_ext_state(&b, sizeof *mh, "mahony");
    PyObject *r = mh ? PyLong_FromLong(fc_mahony_set_accel_ref(mh, a)) : NULL;
    PyBuffer_Release(&b);
    return r;
}

static PyObject *mahony_gnss(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float fi[3], fg[3];
    if (!PyArg_ParseTuple(args, "w*(fff)(fff)", &b, &fi[0], &fi[1], &fi[2], &fg[0], &fg[1],
                          &fg[2])) {
        return NULL;
    }
    fc_mahony_t *mh = fc_ext_state(&b, sizeof *mh, "mahony");
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
    fc_mahony_t *mh = fc_ext_state(&b, sizeof *mh, "mahony");
    PyObject *r = NULL;
    if (mh) {
        r = Py_BuildValue("{s:(dddd),s:(ddd),s:(ddd),s:d,s:d,s:O,s:O,s:O}", "q_wxyz",
                          (double)mh->q_wxyz[0], (double)mh->q_wxyz[1], (double)mh->q_wxyz[2],
                          (double)mh->q_wxyz[3], "bias_rad_s", (double)mh->bias_rad_s[0],
                          (double)mh->bias_rad_s[1], (double)mh->bias_rad_s[2], "integ_rad_s",
                          (double)mh->integ_rad_s[0], (double)mh->integ_rad_s[1],
                          (double)mh->integ_rad_s[2], "trust", (double)mh->trust, "trust_raw",
                          (double)mh->trust_raw, "still", mh->still ? Py_True : Py_False,
                          "heading_valid", mh->heading_valid ? Py_True : Py_False,
                          "gnss_active", fc_mahony_gnss_active(mh) ? Py_True : Py_False);
    }
    PyBuffer_Release(&b);
    return r;
}

/* ---- attitude P ----------------------------------------------------------------- */

static PyObject *attitude_error(PyObject *m, PyObject *args)
{
    (void)m;
    float q[4], roll, pitch, yaw;
    int hold;
    if (!PyArg_ParseTuple(args, "(ffff)fffp", &q[0], &q[1], &q[2], &q[3], &roll, &pitch, &yaw,
                          &hold)) {
        return NULL;
    }
    float e[3];
    fc_attitude_error(q, roll, pitch, yaw, hold != 0, e);
    return Py_BuildValue("(ddd)", (double)e[0], (double)e[1], (double)e[2]);
}

static PyObject *attitude_rate_targets(PyObject *m, PyObject *args)
{
    (void)m;
    fc_attitude_config_t cfg;
    float e[3], ff;
    if (!PyArg_ParseTuple(args, "(fff)(fff)(fff)f", &cfg.ang_p[0], &cfg.ang_p[1], &cfg.ang_p[2],
                          &cfg.rate_max_rad_s[0], &cfg.rate_max_rad_s[1], &cfg.rate_max_rad_s[2],
                          &e[0], &e[1], &e[2], &ff)) {
        return NULL;
    }
    float r[3];
    fc_attitude_rate_targets(&cfg, e, ff, r);
    return Py_BuildValue("(ddd)", (double)r[0], (double)r[1], (double)r[2]);
}

/* ---- input shaping -------------------------------------------------------------- */

static int parse_shaper_cfg(PyObject *t, fc_shaper_config_t *cfg)
{
    int enable;
    if (!PyArg_ParseTuple(t, "pf(fff)(fff)", &enable, &cfg->input_tc_s, &cfg->accel_max_rad_s2[0],
                          &cfg->accel_max_rad_s2[1], &cfg->accel_max_rad_s2[2],
                          &cfg->rate_max_rad_s[0], &cfg->rate_max_rad_s[1],
                          &cfg->rate_max_rad_s[2])) {
        return 0;
    }
    cfg->enable = enable != 0;
    return 1;
}

static PyObject *shaper_reset(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float e[3];
    if (!PyArg_ParseTuple(args, "w*(fff)", &b, &e[0], &e[1], &e[2])) {
        return NULL;
    }
    fc_shaper_t *s = fc_ext_state(&b, sizeof *s, "shaper");
    if (s) {
        fc_shaper_reset(s, e);
    }
    PyBuffer_Release(&b);
    if (!s) {
        return NULL;
    }
    Py_RETURN_NONE;
}

/* cmd: (n, 4) roll, pitch, yaw, yaw rate; hold: (n,) flags. Returns (n, 9):
 * target roll, pitch, yaw, their Euler rates, body angular velocity. */
static PyObject *shaper_run(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *cfgt, *co, *ho;
    float dt;
    if (!PyArg_ParseTuple(args, "w*O!OOf", &b, &PyTuple_Type, &cfgt, &co, &ho, &dt)) {
        return NULL;
    }
    PyObject *out = NULL;
    PyArrayObject *cmd = NULL, *hold = NULL;
    fc_shaper_config_t cfg;
    fc_shaper_t *s = fc_ext_state(&b, sizeof *s, "shaper");
    if (s && parse_shaper_cfg(cfgt, &cfg) && (cmd = f32_in(co, 4, "cmd"))
        && (hold = u8_in(ho, "hold_yaw")) && same_len(PyArray_DIM(cmd, 0), hold)) {
        const npy_intp n = PyArray_DIM(cmd, 0);
        out = f32_out(n, 9);
        if (out) {
            const float *c = PyArray_DATA(cmd);
            const uint8_t *h = PyArray_DATA(hold);
            float *o = PyArray_DATA((PyArrayObject *)out);
            for (npy_intp i = 0; i < n; i++) {
                const float *ci = &c[4 * i];
                fc_shaper_update(s, &cfg, ci[0], ci[1], ci[2], ci[3], h[i] != 0, dt);
                float *row = &o[9 * i];
                for (int k = 0; k < 3; k++) {
                    row[k] = s->euler_rad[k];
                    row[3 + k] = s->euler_rate_rad_s[k];
                    row[6 + k] = s->ang_vel_frd_rad_s[k];
                }
            }
        }
    }
    Py_XDECREF(cmd);
    Py_XDECREF(hold);
    PyBuffer_Release(&b);
    return out;
}

static PyObject *sqrt_controller(PyObject *m, PyObject *args)
{
    (void)m;
    float err, p, lim, dt;
    if (!PyArg_ParseTuple(args, "ffff", &err, &p, &lim, &dt)) {
        return NULL;
    }
    return PyFloat_FromDouble((double)fc_sqrt_controller(err, p, lim, dt));
}

/* Rate targets with feed-forward: (ang_p3, rate_max3, err3, q_err4, ang_vel_target3, gyro_z)
 * -> ((r, p, y), fade). */
static PyObject *attitude_rate_targets_ff(PyObject *m, PyObject *args)
{
    (void)m;
    fc_attitude_config_t cfg;
    float e[3], q[4], w[3], gz;
    if (!PyArg_ParseTuple(args, "(fff)(fff)(fff)(ffff)(fff)f", &cfg.ang_p[0], &cfg.ang_p[1],
                          &cfg.ang_p[2], &cfg.rate_max_rad_s[0], &cfg.rate_max_rad_s[1],
                          &cfg.rate_max_rad_s[2], &e[0], &e[1], &e[2], &q[0], &q[1], &q[2], &q[3],
                          &w[0], &w[1], &w[2], &gz)) {
        return NULL;
    }
    float r[3];
    const float fade = fc_attitude_rate_targets_ff(&cfg, e, q, w, gz, r);
    return Py_BuildValue("((ddd)d)", (double)r[0], (double)r[1], (double)r[2], (double)fade);
}

/* ---- rate PID ------------------------------------------------------------------ */

static int parse_pid_cfg(PyObject *t, fc_rate_pid_config_t *cfg)
{
    int clamp, pt2x2, aw;
    if (!PyArg_ParseTuple(t, "ffffffffffppp", &cfg->kp, &cfg->ki, &cfg->kd, &cfg->kff, &cfg->imax,
                          &cfg->fltt_hz, &cfg->flte_hz, &cfg->fltd_hz, &cfg->out_us_per_unit,
                          &cfg->d_clamp_us, &clamp, &pt2x2, &aw)) {
        return 0;
    }
    cfg->d_clamp_enable = clamp != 0;
    cfg->d_pt2x2 = pt2x2 != 0;
    cfg->antiwindup = aw != 0;
    return 1;
}

static PyObject *pid_init(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *cfgt;
    float dt;
    int configure_only = 0;
    if (!PyArg_ParseTuple(args, "w*O!f|p", &b, &PyTuple_Type, &cfgt, &dt, &configure_only)) {
        return NULL;
    }
    fc_rate_pid_config_t cfg;
    fc_rate_pid_t *pid = fc_ext_state(&b, sizeof *pid, "rate_pid");
    int ok = pid && parse_pid_cfg(cfgt, &cfg);
    if (ok) {
        if (configure_only) {
            fc_rate_pid_configure(pid, &cfg, dt);
        } else {
            fc_rate_pid_init(pid, &cfg, dt);
        }
    }
    PyBuffer_Release(&b);
    if (!ok) {
        return NULL;
    }
    Py_RETURN_NONE;
}

/* Returns an (n, 7) float32 array: p_us, i_us, d_us, ff_us, out_us, limited, d_clamped. */
static PyObject *pid_run(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *to, *mo, *lo;
    float dt;
    int integrate;
    if (!PyArg_ParseTuple(args, "w*OOfOp", &b, &to, &mo, &dt, &lo, &integrate)) {
        return NULL;
    }
    PyObject *out = NULL;
    PyArrayObject *tgt = NULL, *meas = NULL, *lim = NULL;
    fc_rate_pid_t *pid = fc_ext_state(&b, sizeof *pid, "rate_pid");
    if (pid && (tgt = f32_in(to, 0, "target")) && (meas = f32_in(mo, 0, "measurement"))
        && (lim = u8_in(lo, "limit")) && same_len(PyArray_DIM(tgt, 0), meas)
        && same_len(PyArray_DIM(tgt, 0), lim)) {
        const npy_intp n = PyArray_DIM(tgt, 0);
        out = f32_out(n, 7);
        if (out) {
            const float *t = PyArray_DATA(tgt), *me = PyArray_DATA(meas);
            const uint8_t *l = PyArray_DATA(lim);
            float *o = PyArray_DATA((PyArrayObject *)out);
            for (npy_intp i = 0; i < n; i++) {
                (void)fc_rate_pid_update(pid, t[i], me[i], dt, l[i] != 0, integrate != 0);
                const fc_pid_info_t *info = &pid->info;
                float *row = &o[7 * i];
                row[0] = info->p_us;
                row[1] = info->i_us;
                row[2] = info->d_us;
                row[3] = info->ff_us;
                row[4] = info->out_us;
                row[5] = (float)info->limited;
                row[6] = (float)info->d_clamped;
            }
        }
    }
    Py_XDECREF(tgt);
    Py_XDECREF(meas);
    Py_XDECREF(lim);
    PyBuffer_Release(&b);
    return out;
}

/* ---- trim ---------------------------------------------------------------------- */

static PyObject *trim_reset(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    if (!PyArg_ParseTuple(args, "w*", &b)) {
        return NULL;
    }
    fc_trim_t *t = fc_ext_state(&b, sizeof *t, "trim");
    if (t) {
        fc_trim_reset(t);
    }
    PyBuffer_Release(&b);
    if (!t) {
        return NULL;
    }
    Py_RETURN_NONE;
}

/* cfg = (enable, ramp_enable, window_s, gain_us_per_rad, max_us, ramp_s); returns (n, 2). */
static PyObject *trim_run(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    fc_trim_config_t cfg;
    int en, ramp;
    PyObject *airo, *exo, *eyo;
    float dt;
    if (!PyArg_ParseTuple(args, "w*(ppffff)OOOf", &b, &en, &ramp, &cfg.window_s,
                          &cfg.gain_us_per_rad, &cfg.max_us, &cfg.ramp_s, &airo, &exo, &eyo, &dt)) {
        return NULL;
    }
    cfg.enable = en != 0;
    cfg.ramp_enable = ramp != 0;
    PyObject *out = NULL;
    PyArrayObject *air = NULL, *ex = NULL, *ey = NULL;
    fc_trim_t *t = fc_ext_state(&b, sizeof *t, "trim");
    if (t && (air = u8_in(airo, "airborne")) && (ex = f32_in(exo, 0, "ex"))
        && (ey = f32_in(eyo, 0, "ey")) && same_len(PyArray_DIM(air, 0), ex)
        && same_len(PyArray_DIM(air, 0), ey)) {
        const npy_intp n = PyArray_DIM(air, 0);
        out = f32_out(n, 2);
        if (out) {
            const uint8_t *a = PyArray_DATA(air);
            const float *x = PyArray_DATA(ex), *y = PyArray_DATA(ey);
            float *o = PyArray_DATA((PyArrayObject *)out);
            for (npy_intp i = 0; i < n; i++) {
                fc_trim_update(t, &cfg, a[i] != 0, x[i], y[i], dt, &o[2 * i]);
            }
        }
    }
    Py_XDECREF(air);
    Py_XDECREF(ex);
    Py_XDECREF(ey);
    PyBuffer_Release(&b);
    return out;
}

/* ---- blend --------------------------------------------------------------------- */

static PyObject *blend_reset(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    float w;
    if (!PyArg_ParseTuple(args, "w*f", &b, &w)) {
        return NULL;
    }
    fc_blend_t *bl = fc_ext_state(&b, sizeof *bl, "blend");
    if (bl) {
        fc_blend_reset(bl, w);
    }
    PyBuffer_Release(&b);
    if (!bl) {
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *blend_run(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *to;
    float tau, dt;
    int cont;
    if (!PyArg_ParseTuple(args, "w*Ofpf", &b, &to, &tau, &cont, &dt)) {
        return NULL;
    }
    PyObject *out = NULL;
    PyArrayObject *tgt = NULL;
    fc_blend_t *bl = fc_ext_state(&b, sizeof *bl, "blend");
    if (bl && (tgt = f32_in(to, 0, "target_w"))) {
        const npy_intp n = PyArray_DIM(tgt, 0);
        out = f32_out(n, 0);
        if (out) {
            const float *t = PyArray_DATA(tgt);
            float *o = PyArray_DATA((PyArrayObject *)out);
            for (npy_intp i = 0; i < n; i++) {
                o[i] = fc_blend_update(bl, t[i], tau, cont != 0, dt);
            }
        }
    }
    Py_XDECREF(tgt);
    PyBuffer_Release(&b);
    return out;
}

/* ---- mixer --------------------------------------------------------------------- */

static int parse_mixer_cfg(PyObject *t, fc_mixer_config_t *cfg)
{
    int slew;
    if (!PyArg_ParseTuple(t, "fffffffp", &cfg->pwm_min_us, &cfg->pwm_max_us, &cfg->spin_min,
                          &cfg->spin_max, &cfg->yaw_headroom_us, &cfg->slew_up_time_s,
                          &cfg->slew_dn_time_s, &slew)) {
        return 0;
    }
    cfg->slew_enable = slew != 0;
    return 1;
}

static PyObject *mixer_reset(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *cfgt;
    if (!PyArg_ParseTuple(args, "w*O!", &b, &PyTuple_Type, &cfgt)) {
        return NULL;
    }
    fc_mixer_config_t cfg;
    fc_mixer_t *mx = fc_ext_state(&b, sizeof *mx, "mixer");
    int ok = mx && parse_mixer_cfg(cfgt, &cfg);
    if (ok) {
        fc_mixer_reset(mx, &cfg);
    }
    PyBuffer_Release(&b);
    if (!ok) {
        return NULL;
    }
    Py_RETURN_NONE;
}

/* inputs (n, 4): throttle, roll, pitch, yaw [us]. Returns (motor (n,4) f4,
 * pwm (n,4) u2, flags (n,) u1, applied (n,4) f4 = throttle, roll, pitch, yaw). */
static PyObject *mixer_run(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    PyObject *cfgt, *io;
    int spool;
    float dt;
    if (!PyArg_ParseTuple(args, "w*O!iOf", &b, &PyTuple_Type, &cfgt, &spool, &io, &dt)) {
        return NULL;
    }
    PyObject *res = NULL, *mo = NULL, *po = NULL, *fo = NULL, *ao = NULL;
    PyArrayObject *in = NULL;
    fc_mixer_config_t cfg;
    fc_mixer_t *mx = fc_ext_state(&b, sizeof *mx, "mixer");
    if (mx && parse_mixer_cfg(cfgt, &cfg) && (in = f32_in(io, 4, "inputs"))) {
        const npy_intp n = PyArray_DIM(in, 0);
        npy_intp d2[2] = {n, 4}, d1[1] = {n};
        mo = f32_out(n, 4);
        ao = f32_out(n, 4);
        po = PyArray_SimpleNew(2, d2, NPY_UINT16);
        fo = PyArray_SimpleNew(1, d1, NPY_UINT8);
        if (mo && ao && po && fo) {
            const float *x = PyArray_DATA(in);
            float *mot = PyArray_DATA((PyArrayObject *)mo), *app = PyArray_DATA((PyArrayObject *)ao);
            uint16_t *pw = PyArray_DATA((PyArrayObject *)po);
            uint8_t *fl = PyArray_DATA((PyArrayObject *)fo);
            for (npy_intp i = 0; i < n; i++) {
                const float *r = &x[4 * i];
                (void)fc_mixer_update(mx, &cfg, spool, r[0], r[1], r[2], r[3], dt, &pw[4 * i]);
                memcpy(&mot[4 * i], mx->motor_us, sizeof(float) * 4);
                app[4 * i + 0] = mx->throttle_us;
                app[4 * i + 1] = mx->roll_us;
                app[4 * i + 2] = mx->pitch_us;
                app[4 * i + 3] = mx->yaw_us;
                fl[i] = mx->sat_flags;
            }
            res = Py_BuildValue("(OOOO)", mo, po, fo, ao);
        }
    }
    Py_XDECREF(mo);
    Py_XDECREF(po);
    Py_XDECREF(fo);
    Py_XDECREF(ao);
    Py_XDECREF(in);
    PyBuffer_Release(&b);
    return res;
}

static PyObject *mixer_factors(PyObject *m, PyObject *noargs)
{
    (void)m;
    (void)noargs;
    PyObject *out = PyList_New(FC_MIXER_MOTORS);
    if (out == NULL) {
        return NULL;
    }
    for (int i = 0; i < FC_MIXER_MOTORS; i++) {
        PyList_SET_ITEM(out, i,
                        Py_BuildValue("(ddd)", (double)fc_mixer_roll_factor[i],
                                      (double)fc_mixer_pitch_factor[i],
                                      (double)fc_mixer_yaw_factor[i]));
    }
    return out;
}

PyMethodDef fc_ext_block_methods[] = {
    {"block_sizes", block_sizes, METH_NOARGS, "sizeof of each block state."},
    {"filter_init", filter_init, METH_VARARGS, "filter_init(buf, kind, cutoff_hz, bw_hz, dt_s)"},
    {"filter_update", filter_update, METH_VARARGS, "filter_update(buf, cutoff_hz, bw_hz, dt_s)"},
    {"filter_reset", filter_reset, METH_VARARGS, "filter_reset(buf, value)"},
    {"filter_apply", filter_apply, METH_VARARGS, "filter_apply(buf, x) -> y"},
    {"ins_init", ins_init, METH_VARARGS, "ins_init(buf, gyro_hz, accel_hz, notch, f0, bw, dt)"},
    {"ins_run", ins_run, METH_VARARGS, "ins_run(buf, accel, gyro) -> (gyro_f, accel_f, status)"},
    {"mahony_init", mahony_init, METH_VARARGS, "mahony_init(buf, cfg_tuple)"},
    {"mahony_set_attitude", mahony_set_attitude, METH_VARARGS, "mahony_set_attitude(buf, q)"},
    {"mahony_run", mahony_run, METH_VARARGS, "mahony_run(buf, gyro, accel, dt) -> (q, bias, trust)"},
    {"mahony_mag", mahony_mag, METH_VARARGS, "mahony_mag(buf, field3, declination)"},
    {"mahony_accel_ref", mahony_accel_ref, METH_VARARGS, "mahony_accel_ref(buf, a_ned3)"},
    {"mahony_gnss", mahony_gnss, METH_VARARGS, "mahony_gnss(buf, f_imu_ned3, f_gnss_ned3)"},
    {"mahony_state", mahony_state, METH_VARARGS, "mahony_state(buf) -> dict"},
    {"attitude_error", attitude_error, METH_VARARGS, "attitude_error(q, roll, pitch, yaw, hold)"},
    {"attitude_rate_targets", attitude_rate_targets, METH_VARARGS,
     "attitude_rate_targets(ang_p3, rate_max3, err3, yaw_rate_ff)"},
    {"attitude_rate_targets_ff", attitude_rate_targets_ff, METH_VARARGS,
     "attitude_rate_targets_ff(ang_p3, rate_max3, err3, q_err4, ang_vel3, gyro_z)"},
    {"shaper_reset", shaper_reset, METH_VARARGS, "shaper_reset(buf, euler3)"},
    {"shaper_run", shaper_run, METH_VARARGS, "shaper_run(buf, cfg, cmd (n,4), hold, dt) -> (n,9)"},
    {"sqrt_controller", sqrt_controller, METH_VARARGS, "sqrt_controller(err, p, lim, dt)"},
    {"pid_init", pid_init, METH_VARARGS, "pid_init(buf, cfg_tuple, dt[, configure_only])"},
    {"pid_run", pid_run, METH_VARARGS, "pid_run(buf, target, meas, dt, limit, integrate)"},
    {"trim_reset", trim_reset, METH_VARARGS, "trim_reset(buf)"},
    {"trim_run", trim_run, METH_VARARGS, "trim_run(buf, cfg, airborne, ex, ey, dt) -> (n,2)"},
    {"blend_reset", blend_reset, METH_VARARGS, "blend_reset(buf, w)"},
    {"blend_run", blend_run, METH_VARARGS, "blend_run(buf, target_w, tau, continuous, dt) -> w"},
    {"mixer_reset", mixer_reset, METH_VARARGS, "mixer_reset(buf, cfg)"},
    {"mixer_run", mixer_run, METH_VARARGS, "mixer_run(buf, cfg, spool, inputs, dt)"},
    {"mixer_factors", mixer_factors, METH_NOARGS, "[(roll, pitch, yaw) factor per motor]"},
    {NULL, NULL, 0, NULL},
};
