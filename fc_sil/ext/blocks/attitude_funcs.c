/*
 * attitude_funcs.c - bindings of the attitude controller (fc_attitude.h: the error
 * between estimate and target, the P stage to rate targets, with and without the
 * target's angular velocity fed forward) and of the input shaper that moves the target
 * toward the command (fc_shaper.h, with its square-root controller).
 */
#include "blocks_common.h"

#include "fc_attitude.h"
#include "fc_shaper.h"

static const fc_blk_field_t attitude_fields[] = {
    FC_BLK_FIELD(fc_attitude_config_t, ang_p, FC_BLK_F32X3),
    FC_BLK_FIELD(fc_attitude_config_t, rate_max_rad_s, FC_BLK_F32X3),
};

static PyObject *attitude_error(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"q_wxyz", "roll_rad", "pitch_rad", "yaw_rad", "hold_yaw", NULL};
    float q[4], roll, pitch, yaw;
    int hold;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "$(ffff)fffp", kwlist, &q[0], &q[1], &q[2],
                                     &q[3], &roll, &pitch, &yaw, &hold)) {
        return NULL;
    }
    float e[3];
    fc_attitude_error(q, roll, pitch, yaw, hold != 0, e);
    return Py_BuildValue("(ddd)", (double)e[0], (double)e[1], (double)e[2]);
}

static PyObject *attitude_rate_targets(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"config", "err_frd_rad", "yaw_rate_ff_rad_s", NULL};
    PyObject *cfgd;
    float e[3], ff;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "$O(fff)f", kwlist, &cfgd, &e[0], &e[1], &e[2],
                                     &ff)) {
        return NULL;
    }
    fc_attitude_config_t cfg;
    if (!FC_BLK_CONFIG(cfgd, attitude_fields, &cfg, "attitude")) {
        return NULL;
    }
    float r[3];
    fc_attitude_rate_targets(&cfg, e, ff, r);
    return Py_BuildValue("(ddd)", (double)r[0], (double)r[1], (double)r[2]);
}

/* Rate targets with feed-forward -> ((roll, pitch, yaw), fade). */
static PyObject *attitude_rate_targets_ff(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"config", "err_frd_rad", "q_err_wxyz", "ang_vel_target_rad_s",
                             "gyro_z_rad_s", NULL};
    PyObject *cfgd;
    float e[3], q[4], w[3], gz;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "$O(fff)(ffff)(fff)f", kwlist, &cfgd, &e[0],
                                     &e[1], &e[2], &q[0], &q[1], &q[2], &q[3], &w[0], &w[1],
                                     &w[2], &gz)) {
        return NULL;
    }
    fc_attitude_config_t cfg;
    if (!FC_BLK_CONFIG(cfgd, attitude_fields, &cfg, "attitude")) {
        return NULL;
    }
    float r[3];
    const float fade = fc_attitude_rate_targets_ff(&cfg, e, q, w, gz, r);
    return Py_BuildValue("((ddd)d)", (double)r[0], (double)r[1], (double)r[2], (double)fade);
}

/* ---- input shaping -------------------------------------------------------------- */

static const fc_blk_field_t shaper_fields[] = {
    FC_BLK_FIELD(fc_shaper_config_t, enable, FC_BLK_BOOL),
    FC_BLK_FIELD(fc_shaper_config_t, input_tc_s, FC_BLK_F32),
    FC_BLK_FIELD(fc_shaper_config_t, accel_max_rad_s2, FC_BLK_F32X3),
    FC_BLK_FIELD(fc_shaper_config_t, rate_max_rad_s, FC_BLK_F32X3),
};

static PyObject *shaper_reset(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "euler_rad", NULL};
    Py_buffer b;
    float e[3];
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*$(fff)", kwlist, &b, &e[0], &e[1], &e[2])) {
        return NULL;
    }
    fc_shaper_t *s = fc_blk_state(&b, sizeof *s, "shaper");
    if (s) {
        fc_shaper_reset(s, e);
    }
    return fc_blk_release_none(&b, s != NULL);
}

/* cmd: (n, 4) roll, pitch, yaw, yaw rate; hold_yaw: (n,) flags. Returns (n, 9):
 * target roll, pitch, yaw, their Euler rates, body angular velocity. */
static PyObject *shaper_run(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"state", "cmd", "hold_yaw", "config", "dt_s", NULL};
    Py_buffer b;
    PyObject *cfgd, *co, *ho;
    float dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*OO$Of", kwlist, &b, &co, &ho, &cfgd, &dt)) {
        return NULL;
    }
    PyObject *out = NULL;
    PyArrayObject *cmd = NULL, *hold = NULL;
    fc_shaper_config_t cfg;
    fc_shaper_t *s = fc_blk_state(&b, sizeof *s, "shaper");
    if (s && FC_BLK_CONFIG(cfgd, shaper_fields, &cfg, "shaper")
        && (cmd = fc_blk_f32_in(co, 4, "cmd")) && (hold = fc_blk_u8_in(ho, "hold_yaw"))
        && fc_blk_same_len(PyArray_DIM(cmd, 0), hold)) {
        const npy_intp n = PyArray_DIM(cmd, 0);
        out = fc_blk_f32_out(n, 9);
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

static PyObject *sqrt_controller(PyObject *m, PyObject *args, PyObject *kwds)
{
    (void)m;
    static char *kwlist[] = {"error", "p", "second_ord_lim", "dt_s", NULL};
    float err, p, lim, dt;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "$ffff", kwlist, &err, &p, &lim, &dt)) {
        return NULL;
    }
    return PyFloat_FromDouble((double)fc_sqrt_controller(err, p, lim, dt));
}

PyMethodDef fc_blk_attitude_methods[] = {
    {"attitude_error", FC_BLK_KW(attitude_error),
     "attitude_error(q_wxyz=, roll_rad=, pitch_rad=, yaw_rad=, hold_yaw=) -> (ex, ey, ez)"},
    {"attitude_rate_targets", FC_BLK_KW(attitude_rate_targets),
     "attitude_rate_targets(config={ang_p, rate_max_rad_s}, err_frd_rad=, yaw_rate_ff_rad_s=)"},
    {"attitude_rate_targets_ff", FC_BLK_KW(attitude_rate_targets_ff),
     "attitude_rate_targets_ff(config=, err_frd_rad=, q_err_wxyz=, ang_vel_target_rad_s=, "
     "gyro_z_rad_s=) -> ((r, p, y), fade)"},
    {"shaper_reset", FC_BLK_KW(shaper_reset), "shaper_reset(state, euler_rad=)"},
    {"shaper_run", FC_BLK_KW(shaper_run),
     "shaper_run(state, cmd (n,4), hold_yaw (n,), config={fc_shaper_config_t}, dt_s=) -> (n,9)"},
    {"sqrt_controller", FC_BLK_KW(sqrt_controller),
     "sqrt_controller(error=, p=, second_ord_lim=, dt_s=)"},
    {NULL, NULL, 0, NULL},
};
