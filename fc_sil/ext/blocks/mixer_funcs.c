/*
 * mixer_funcs.c - bindings of the quad-X mixer (fc_mixer.h): its reset, a run over rows
 * of (throttle, roll, pitch, yaw) inputs returning the motors before and after the slew
 * limit, the saturation flags and the inputs as actually applied, and the motor factors.
 */
#include "blocks_common.h"

#include <string.h>

#include "fc_mixer.h"

static const fc_blk_field_t mixer_fields[] = {
    FC_BLK_FIELD(fc_mixer_config_t, pwm_min_us, FC_BLK_F32),
    FC_BLK_FIELD(fc_mixer_config_t, pwm_max_us, FC_BLK_F32),
    FC_BLK_FIELD(fc_mixer_config_t, spin_min, FC_BLK_F32),
    FC_BLK_FIELD(fc_mixer_config_t, spin_max, FC_BLK_F32),
    FC_BLK_FIELD(fc_mixer_config_t, yaw_headroom_us, FC_BLK_F32),
    FC_BLK_FIELD(fc_mixer_config_t, slew_up_time_s, FC_BLK_F32),
    FC_BLK_FIELD(fc_mixer_config_t, slew_dn_time_s, FC_BLK_F32),
    FC_BLK_FIELD(fc_mixer_config_t, slew_enable, FC_BLK_BOOL),
};

static PyObject *mixer_reset(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "config", NULL};
    Py_buffer b;
    PyObject *cfgd;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$O", kwlist, &b, &cfgd)) {
        return NULL;
    }
    fc_mixer_config_t cfg;
    fc_mixer_t *mx = fc_blk_state(&b, sizeof *mx, "mixer");
    int ok = mx && FC_BLK_CONFIG(cfgd, mixer_fields, &cfg, "mixer");
    if (ok) {
        fc_mixer_reset(mx, &cfg);
    }
    return fc_blk_release_none(&b, ok);
}

/* inputs (n, 4): throttle, roll, pitch, yaw [us]. Returns (motor (n,4) f4,
 * pwm (n,4) u2, flags (n,) u1, applied (n,4) f4 = throttle, roll, pitch, yaw). */
static PyObject *mixer_run(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "inputs", "config", "spool", "dt_s", NULL};
    Py_buffer b;
    PyObject *cfgd, *io;
    int spool;
    float dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*O$Oif", kwlist, &b, &io, &cfgd, &spool,
                                     &dt)) {
        return NULL;
    }
    PyObject *res = NULL, *mo = NULL, *po = NULL, *fo = NULL, *ao = NULL;
    PyArrayObject *in = NULL;
    fc_mixer_config_t cfg;
    fc_mixer_t *mx = fc_blk_state(&b, sizeof *mx, "mixer");
    if (mx && FC_BLK_CONFIG(cfgd, mixer_fields, &cfg, "mixer")
        && (in = fc_blk_f32_in(io, 4, "inputs"))) {
        const npy_intp n = PyArray_DIM(in, 0);
        npy_intp d2[2] = {n, 4}, d1[1] = {n};
        mo = fc_blk_f32_out(n, 4);
        ao = fc_blk_f32_out(n, 4);
        po = PyArray_SimpleNew(2, d2, NPY_UINT16);
        fo = PyArray_SimpleNew(1, d1, NPY_UINT8);
        if (mo && ao && po && fo) {
            const float *x = PyArray_DATA(in);
            float *mot = PyArray_DATA((PyArrayObject *)mo);
            float *app = PyArray_DATA((PyArrayObject *)ao);
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

PyMethodDef fc_blk_mixer_methods[] = {
    {"mixer_reset", FC_BLK_KW(mixer_reset), "mixer_reset(state, config={fc_mixer_config_t})"},
    {"mixer_run", FC_BLK_KW(mixer_run),
     "mixer_run(state, inputs (n,4), config=, spool=, dt_s=) -> (motor, pwm, flags, applied)"},
    {"mixer_factors", mixer_factors, METH_NOARGS, "[(roll, pitch, yaw) factor per motor]"},
    {NULL, NULL, 0, NULL},
};
