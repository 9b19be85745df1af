/*
 * core_steps.c - the core one call at a time, and what the host reads back.
 *
 * Single steps (imu, baro, mag, gt_att, gt_nav, pwm_due, pwm_step) serve tests and hosts
 * that have no records; the flight loop uses record batches (record_batch.c). The reads
 * (status_bytes, counters, inputs, gnss, last_seen, take_accel_mean) are what the
 * host's supervisor, telemetry and pre-arm checks look at between polls.
 */
#include "core_object.h"

/* ---- single steps ------------------------------------------------------------ */

static PyObject *Core_imu(CoreObject *self, PyObject *args)
{
    long long t;
    float a[3], g[3];
    if (!PyArg_ParseTuple(args, "L(fff)(fff)", &t, &a[0], &a[1], &a[2], &g[0], &g[1], &g[2])) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_imu_step(&self->core, (int64_t)t, a, g));
}

static PyObject *Core_baro(CoreObject *self, PyObject *args)
{
    long long t;
    float p;
    if (!PyArg_ParseTuple(args, "Lf", &t, &p)) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_baro_step(&self->core, (int64_t)t, p));
}

static PyObject *Core_mag(CoreObject *self, PyObject *args)
{
    long long t;
    float m[3];
    if (!PyArg_ParseTuple(args, "L(fff)", &t, &m[0], &m[1], &m[2])) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_mag_step(&self->core, (int64_t)t, m));
}

static PyObject *Core_gt_att(CoreObject *self, PyObject *args)
{
    long long t;
    float q[4];
    if (!PyArg_ParseTuple(args, "L(ffff)", &t, &q[0], &q[1], &q[2], &q[3])) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_gt_att_step(&self->core, (int64_t)t, q));
}

static PyObject *Core_gt_nav(CoreObject *self, PyObject *args)
{
    long long t;
    float p[3], v[3];
    if (!PyArg_ParseTuple(args, "L(fff)(fff)", &t, &p[0], &p[1], &p[2], &v[0], &v[1], &v[2])) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_gt_nav_step(&self->core, (int64_t)t, p, v));
}

static PyObject *Core_pwm_due(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    int64_t tick;
    if (!fc_core_pwm_due(&self->core, &tick)) {
        Py_RETURN_NONE;
    }
    return PyLong_FromLongLong((long long)tick);
}

static PyObject *Core_pwm_step(CoreObject *self, PyObject *args)
{
    long long tick;
    if (!PyArg_ParseTuple(args, "L", &tick)) {
        return NULL;
    }
    uint16_t pwm[FC_MIXER_MOTORS];
    (void)fc_core_pwm_step(&self->core, (int64_t)tick, pwm);
    return Py_BuildValue("(iiii)", pwm[0], pwm[1], pwm[2], pwm[3]);
}

/* ---- reads -------------------------------------------------------------------- */

static PyObject *Core_status_bytes(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    return PyBytes_FromStringAndSize((const char *)&self->core.status,
                                     (Py_ssize_t)sizeof(fc_core_status_t));
}

static PyObject *Core_inputs(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_core_inputs_t *in = &self->core.in;
    return Py_BuildValue("{s:O,s:O,s:i,s:d,s:d,s:d,s:d,s:d,s:d,s:d,s:O}", "armed",
                         in->armed ? Py_True : Py_False, "yaw_hold",
                         in->yaw_hold ? Py_True : Py_False, "alt_mode", (int)in->alt_mode,
                         "roll_target_rad", (double)in->roll_target_rad, "pitch_target_rad",
                         (double)in->pitch_target_rad, "yaw_target_rad",
                         (double)in->yaw_target_rad, "yaw_rate_target_rad_s",
                         (double)in->yaw_rate_target_rad_s, "alt_target_m",
                         (double)in->alt_target_m, "climb_target_m_s",
                         (double)in->climb_target_m_s, "throttle", (double)in->throttle,
                         "vibe_comp", in->vibe_comp ? Py_True : Py_False);
}

static PyObject *Core_counters(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_core_t *c = &self->core;
    return Py_BuildValue("{s:K,s:K,s:K,s:K,s:K,s:K,s:K,s:L,s:K,s:O,s:d,s:d,s:d}", "imu",
                         (unsigned long long)c->imu_count,
                         "rate_loop", (unsigned long long)c->loop_count, "pwm",
                         (unsigned long long)c->pwm_count, "rejected",
                         (unsigned long long)c->rejected_count, "records",
                         (unsigned long long)self->records_in, "unknown_kind",
                         (unsigned long long)self->unknown_kind, "ins_rejected",
                         (unsigned long long)c->ins.rejected, "last_imu_ns",
                         (long long)c->last_imu_ns, "gnss_aid",
                         (unsigned long long)c->gnss_aid_count, "gnss_aid_active",
                         fc_mahony_gnss_active(&c->ahrs) ? Py_True : Py_False,
                         "heading_offset_rad", (double)c->ahrs.heading_offset_rad,
                         "gnss_aid_scale", (double)c->ahrs.gnss_sched.scale,
                         "alt_tc_s", (double)c->alt_sched.tc_s);
}

static PyObject *Core_gnss(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_gnss_store_t *g = &self->core.gnss;
    if (!g->valid) {
        Py_RETURN_NONE;
    }
    return Py_BuildValue("{s:L,s:i,s:i,s:i,s:(ddd),s:i,s:i,s:i,s:i}", "sim_ns",
                         (long long)g->sim_ns, "lat_e7", g->lat_e7, "lon_e7", g->lon_e7,
                         "alt_mm", g->alt_mm, "vel_ned_m_s", (double)g->vel_ned_m_s[0],
                         (double)g->vel_ned_m_s[1], (double)g->vel_ned_m_s[2], "fix_type",
                         (int)g->fix_type, "satellites", (int)g->satellites, "eph_cm",
                         (int)g->eph_cm, "epv_cm", (int)g->epv_cm);
}

/* The estimators' latest measurement innovations, read-only, for the failsafes' test ratios
 * (fc_sil/innovations.py): baro against the vertical filter, magnetometer heading against the
 * attitude estimate. */
static PyObject *Core_innovations(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_core_t *c = &self->core;
    return Py_BuildValue("{s:d,s:d,s:O,s:d,s:d,s:O,s:L}", "heading_err_rad",
                         (double)c->ahrs.heading_err_rad, "heading_age_s",
                         (double)c->ahrs.heading_age_s, "heading_valid",
                         c->ahrs.heading_valid ? Py_True : Py_False, "baro_innov_m",
                         (double)c->alt_est.innov_m, "baro_alt_m", (double)c->alt_est.baro_alt_m,
                         "have_baro", c->alt_est.have_baro ? Py_True : Py_False, "last_baro_ns",
                         (long long)c->alt_est.last_baro_ns);
}

/* Sensor-stream health for the host (pre-arm checks, failsafes). */
static PyObject *Core_last_seen(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    PyObject *t = PyTuple_New(16);
    if (t == NULL) {
        return NULL;
    }
    for (int k = 0; k < 16; k++) {
        PyTuple_SET_ITEM(t, k, PyLong_FromLongLong((long long)self->last_kind_ns[k]));
    }
    return t;
}

static PyObject *Core_take_accel_mean(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    if (self->accel_n == 0) {
        Py_RETURN_NONE;
    }
    const double n = (double)self->accel_n;
    PyObject *r = Py_BuildValue("(ddd)", self->accel_sum[0] / n, self->accel_sum[1] / n,
                                self->accel_sum[2] / n);
    self->accel_sum[0] = self->accel_sum[1] = self->accel_sum[2] = 0.0;
    self->accel_n = 0;
    return r;
}

PyMethodDef fc_ext_step_methods[] = {
    {"imu", (PyCFunction)Core_imu, METH_VARARGS, "imu(sim_ns, accel3, gyro3) -> status."},
    {"baro", (PyCFunction)Core_baro, METH_VARARGS, "baro(sim_ns, pressure_pa) -> status."},
    {"mag", (PyCFunction)Core_mag, METH_VARARGS, "mag(sim_ns, field3) -> status."},
    {"gt_att", (PyCFunction)Core_gt_att, METH_VARARGS, "gt_att(sim_ns, q_wxyz) -> status."},
    {"gt_nav", (PyCFunction)Core_gt_nav, METH_VARARGS,
     "gt_nav(sim_ns, pos_ned3, vel_ned3) -> status."},
    {"pwm_due", (PyCFunction)Core_pwm_due, METH_NOARGS, "Next due PWM tick [ns] or None."},
    {"pwm_step", (PyCFunction)Core_pwm_step, METH_VARARGS, "pwm_step(tick_ns) -> 4 PWM [us]."},
    {"status_bytes", (PyCFunction)Core_status_bytes, METH_NOARGS, "Last status snapshot."},
    {"inputs", (PyCFunction)Core_inputs, METH_NOARGS, "Current inputs as a dict."},
    {"counters", (PyCFunction)Core_counters, METH_NOARGS, "Step counters."},
    {"gnss", (PyCFunction)Core_gnss, METH_NOARGS, "Last GNSS fix or None."},
    {"innovations", (PyCFunction)Core_innovations, METH_NOARGS,
     "Latest baro and magnetometer-heading innovations (read-only)."},
    {"last_seen", (PyCFunction)Core_last_seen, METH_NOARGS,
     "Sim time [ns] of the last record of each kind 0..15 (-1: never)."},
    {"take_accel_mean", (PyCFunction)Core_take_accel_mean, METH_NOARGS,
     "Mean raw IMU accel (FRD, m/s^2) since the last call, or None."},
    {NULL, NULL, 0, NULL},
};
