/*
 * rate_funcs.c - bindings of the rate loop's blocks: the rate PID of one axis
 * (fc_rate_pid.h, its P/I/D/FF info per sample), the hover-trim learner that feeds the
 * mixer (fc_trim.h), and the estimate/ground-truth blend weight (fc_blend.h).
 */
#include "blocks_common.h"

#include "fc_blend.h"
#include "fc_rate_pid.h"
#include "fc_trim.h"

/* ---- rate PID ------------------------------------------------------------------ */

static const fc_blk_field_t pid_fields[] = {
    FC_BLK_FIELD(fc_rate_pid_config_t, kp, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, ki, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, kd, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, kff, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, imax, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, fltt_hz, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, flte_hz, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, fltd_hz, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, out_us_per_unit, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, d_clamp_us, FC_BLK_F32),
    FC_BLK_FIELD(fc_rate_pid_config_t, d_clamp_enable, FC_BLK_BOOL),
    FC_BLK_FIELD(fc_rate_pid_config_t, d_pt2x2, FC_BLK_BOOL),
    FC_BLK_FIELD(fc_rate_pid_config_t, antiwindup, FC_BLK_BOOL),
};

/* pid_init resets the state; pid_configure keeps it (gains changed in flight). */
static PyObject *pid_setup(PyObject *args, PyObject *kwds, int keep_state)
{
    static char *kwlist[] = {"state", "config", "dt_s", NULL};
    Py_buffer b;
    PyObject *cfgd;
    float dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$Of", kwlist, &b, &cfgd, &dt)) {
        return NULL;
    }
    fc_rate_pid_config_t cfg;
    fc_rate_pid_t *pid = fc_blk_state(&b, sizeof *pid, "rate_pid");
    int ok = pid && FC_BLK_CONFIG(cfgd, pid_fields, &cfg, "rate_pid");
    if (ok) {
        if (keep_state) {
            fc_rate_pid_configure(pid, &cfg, dt);
        } else {
            fc_rate_pid_init(pid, &cfg, dt);
        }
    }
    return fc_blk_release_none(&b, ok);
}

static PyObject *pid_init(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    return pid_setup(args, kwds, 0);
}

static PyObject *pid_configure(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    return pid_setup(args, kwds, 1);
}

/* Returns an (n, 7) float32 array: p_us, i_us, d_us, ff_us, out_us, limited, d_clamped. */
static PyObject *pid_run(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "target", "measurement", "limit", "dt_s", "integrate",
                             NULL};
    Py_buffer b;
    PyObject *to, *mo, *lo;
    float dt;
    int integrate;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*OOO$fp", kwlist, &b, &to, &mo, &lo, &dt,
                                     &integrate)) {
        return NULL;
    }
    PyObject *out = NULL;
    PyArrayObject *tgt = NULL, *meas = NULL, *lim = NULL;
    fc_rate_pid_t *pid = fc_blk_state(&b, sizeof *pid, "rate_pid");
    if (pid && (tgt = fc_blk_f32_in(to, 0, "target"))
        && (meas = fc_blk_f32_in(mo, 0, "measurement")) && (lim = fc_blk_u8_in(lo, "limit"))
        && fc_blk_same_len(PyArray_DIM(tgt, 0), meas)
        && fc_blk_same_len(PyArray_DIM(tgt, 0), lim)) {
        const npy_intp n = PyArray_DIM(tgt, 0);
        out = fc_blk_f32_out(n, 7);
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

static const fc_blk_field_t trim_fields[] = {
    FC_BLK_FIELD(fc_trim_config_t, enable, FC_BLK_BOOL),
    FC_BLK_FIELD(fc_trim_config_t, ramp_enable, FC_BLK_BOOL),
    FC_BLK_FIELD(fc_trim_config_t, window_s, FC_BLK_F32),
    FC_BLK_FIELD(fc_trim_config_t, gain_us_per_rad, FC_BLK_F32),
    FC_BLK_FIELD(fc_trim_config_t, max_us, FC_BLK_F32),
    FC_BLK_FIELD(fc_trim_config_t, ramp_s, FC_BLK_F32),
};

static PyObject *trim_reset(PyObject *m, PyObject *args)
{
    (void)m;
    Py_buffer b;
    if (!PyArg_ParseTuple(args, "w*", &b)) {
        return NULL;
    }
    fc_trim_t *t = fc_blk_state(&b, sizeof *t, "trim");
    if (t) {
        fc_trim_reset(t);
    }
    return fc_blk_release_none(&b, t != NULL);
}

/* Returns the applied trim (n, 2) [us], roll and pitch. */
static PyObject *trim_run(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "airborne", "ex", "ey", "config", "dt_s", NULL};
    Py_buffer b;
    PyObject *cfgd, *airo, *exo, *eyo;
    float dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*OOO$Of", kwlist, &b, &airo, &exo, &eyo,
                                     &cfgd, &dt)) {
        return NULL;
    }
    fc_trim_config_t cfg;
    PyObject *out = NULL;
    PyArrayObject *air = NULL, *ex = NULL, *ey = NULL;
    fc_trim_t *t = fc_blk_state(&b, sizeof *t, "trim");
    if (t && FC_BLK_CONFIG(cfgd, trim_fields, &cfg, "trim")
        && (air = fc_blk_u8_in(airo, "airborne")) && (ex = fc_blk_f32_in(exo, 0, "ex"))
        && (ey = fc_blk_f32_in(eyo, 0, "ey")) && fc_blk_same_len(PyArray_DIM(air, 0), ex)
        && fc_blk_same_len(PyArray_DIM(air, 0), ey)) {
        const npy_intp n = PyArray_DIM(air, 0);
        out = fc_blk_f32_out(n, 2);
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

static PyObject *blend_reset(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "w", NULL};
    Py_buffer b;
    float w;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$f", kwlist, &b, &w)) {
        return NULL;
    }
    fc_blend_t *bl = fc_blk_state(&b, sizeof *bl, "blend");
    if (bl) {
        fc_blend_reset(bl, w);
    }
    return fc_blk_release_none(&b, bl != NULL);
}

static PyObject *blend_run(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "target_w", "tau_s", "continuous", "dt_s", NULL};
    Py_buffer b;
    PyObject *to;
    float tau, dt;
    int cont;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*O$fpf", kwlist, &b, &to, &tau, &cont, &dt)) {
        return NULL;
    }
    PyObject *out = NULL;
    PyArrayObject *tgt = NULL;
    fc_blend_t *bl = fc_blk_state(&b, sizeof *bl, "blend");
    if (bl && (tgt = fc_blk_f32_in(to, 0, "target_w"))) {
        const npy_intp n = PyArray_DIM(tgt, 0);
        out = fc_blk_f32_out(n, 0);
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

PyMethodDef fc_blk_rate_methods[] = {
    {"pid_init", FC_BLK_KW(pid_init), "pid_init(state, config={fc_rate_pid_config_t}, dt_s=)"},
    {"pid_configure", FC_BLK_KW(pid_configure),
     "pid_configure(state, config=, dt_s=): new gains, state kept"},
    {"pid_run", FC_BLK_KW(pid_run),
     "pid_run(state, target, measurement, limit, dt_s=, integrate=) -> (n,7)"},
    {"trim_reset", trim_reset, METH_VARARGS, "trim_reset(state)"},
    {"trim_run", FC_BLK_KW(trim_run),
     "trim_run(state, airborne, ex, ey, config={fc_trim_config_t}, dt_s=) -> (n,2)"},
    {"blend_reset", FC_BLK_KW(blend_reset), "blend_reset(state, w=)"},
    {"blend_run", FC_BLK_KW(blend_run),
     "blend_run(state, target_w, tau_s=, continuous=, dt_s=) -> w"},
    {NULL, NULL, 0, NULL},
};
