/*
 * record_batch.c - the record router's batches: the only place where records meet the
 * core (the core itself knows no records).
 *
 * step_batch consumes a whole array of 64-byte shared-memory records
 * (shm/include/sb_records.h) in one call, so the hot loop stays in C: IMU ->
 * fc_core_imu_step, BARO/MAG/GNSS/GT/SETPOINT to their inputs, and after each IMU
 * sample every PWM tick now due is stepped and written as one PWM record plus one
 * status row (the layout of fc_core_status_t, mirrored by fc_sil.STATUS_DTYPE).
 * bind_batch + step_bound(n) are the same with the arrays bound once, for the poll loop.
 */
#include "core_object.h"

#include <math.h>
#include <string.h>

/* Upper bound of the PWM ticks a batch can produce (exact for monotonic IMU time). */
static int64_t pwm_tick_bound(const fc_core_t *c, const unsigned char *base, Py_ssize_t n)
{
    const int64_t period = c->pwm_period_ns;
    int64_t next = c->have_imu ? c->next_pwm_ns : INT64_MIN;
    int64_t max_t = c->have_imu ? c->last_imu_ns : INT64_MIN;
    for (Py_ssize_t i = 0; i < n; i++) {
        sb_header h;
        memcpy(&h, base + (size_t)i * SB_RECORD_SIZE, sizeof h);
        if (h.kind != SB_KIND_IMU) {
            continue;
        }
        if (next == INT64_MIN) {
            int64_t k = h.sim_ns / period;
            if (k * period < h.sim_ns) {
                k++;
            }
            next = k * period;
        }
        if (h.sim_ns > max_t) {
            max_t = h.sim_ns;
        }
    }
    if (next == INT64_MIN || max_t < next) {
        return 0;
    }
    return (max_t - next) / period + 1;
}

static PyObject *Core_pwm_bound(CoreObject *self, PyObject *args)
{
    Py_buffer rec;
    if (!PyArg_ParseTuple(args, "y*", &rec)) {
        return NULL;
    }
    if (rec.len % SB_RECORD_SIZE != 0) {
        PyBuffer_Release(&rec);
        PyErr_SetString(PyExc_ValueError, "records must be whole 64-byte slots");
        return NULL;
    }
    int64_t bound = pwm_tick_bound(&self->core, rec.buf, rec.len / SB_RECORD_SIZE);
    PyBuffer_Release(&rec);
    return PyLong_FromLongLong((long long)bound);
}

static void consume_setpoint(fc_core_t *c, const sb_setpoint *sp)
{
    if (sp->mask & 0x1u) {
        (void)fc_core_set_attitude_target(c, sp->roll_rad, sp->pitch_rad);
    }
    if ((sp->mask & 0x2u) && isfinite(sp->altitude_m)) { /* NaN altitude = keep */
        (void)fc_core_set_altitude_target(c, sp->altitude_m);
    }
    if (sp->mask & 0x4u) {
        (void)fc_core_set_yaw_target(c, sp->yaw_rad);
    }
}

static void emit_pwm(CoreObject *self, int64_t tick, sb_record *out, fc_core_status_t *st_out)
{
    fc_core_t *c = &self->core;
    uint16_t pwm[FC_MIXER_MOTORS];
    (void)fc_core_pwm_step(c, tick, pwm);
    sb_record r;
    memset(&r, 0, sizeof r);
    r.h.kind = SB_KIND_PWM;
    r.h.seq = self->pwm_seq++;
    r.h.sim_ns = tick;
    r.h.wall_ns = fc_ext_monotonic_ns();
    for (int m = 0; m < FC_MIXER_MOTORS; m++) {
        r.u.pwm.pwm_us[m] = pwm[m];
    }
    r.u.pwm.channel_count = FC_MIXER_MOTORS;
    r.u.pwm.armed = c->in.armed;
    r.u.pwm.fc_step_seq = self->last_seq;
    r.u.pwm.imu_sim_ns = c->last_imu_ns;
    memcpy(out, &r, sizeof r);
    memcpy(st_out, &c->status, sizeof *st_out);
}

/* PWM ticks the outputs can hold: the smaller of the two arrays. */
static Py_ssize_t out_capacity(const Py_buffer *pwm_buf, const Py_buffer *st_buf)
{
    const Py_ssize_t a = pwm_buf->len / SB_RECORD_SIZE;
    const Py_ssize_t b = st_buf->len / (Py_ssize_t)sizeof(fc_core_status_t);
    return a < b ? a : b;
}

Py_ssize_t fc_ext_bound_capacity(const CoreObject *self)
{
    return out_capacity(&self->bound[1], &self->bound[2]);
}

static void consume_gnss(fc_core_t *c, const sb_record *r)
{
    fc_gnss_store_t g;
    memset(&g, 0, sizeof g);
    g.sim_ns = r->h.sim_ns;
    g.lat_e7 = r->u.gnss.lat_e7;
    g.lon_e7 = r->u.gnss.lon_e7;
    g.alt_mm = r->u.gnss.alt_mm;
    memcpy(g.vel_ned_m_s, r->u.gnss.vel_ned_m_s, sizeof g.vel_ned_m_s);
    g.eph_cm = r->u.gnss.eph_cm;
    g.epv_cm = r->u.gnss.epv_cm;
    g.fix_type = r->u.gnss.fix_type;
    g.satellites = r->u.gnss.satellites;
    (void)fc_core_gnss_step(c, &g);
}

Py_ssize_t fc_ext_run_records(CoreObject *self, const unsigned char *base, Py_ssize_t n,
                              sb_record *pwm_out, fc_core_status_t *st_out, Py_ssize_t cap)
{
    const int64_t bound = pwm_tick_bound(&self->core, base, n);
    if (bound > (int64_t)cap) {
        PyErr_Format(PyExc_ValueError,
                     "output arrays hold %zd PWM ticks but this batch can produce %lld; "
                     "size them with Core.pwm_bound(records)",
                     cap, (long long)bound);
        return -1;
    }
    fc_core_t *c = &self->core;
    Py_ssize_t emitted = 0;
    for (Py_ssize_t i = 0; i < n; i++) {
        sb_record r;
        memcpy(&r, base + (size_t)i * SB_RECORD_SIZE, sizeof r);
        switch (r.h.kind) {
        case SB_KIND_IMU:
            (void)fc_core_imu_step(c, r.h.sim_ns, r.u.imu.accel_frd_m_s2, r.u.imu.gyro_frd_rad_s);
            /* for the host's position estimator (outer loops at 50 Hz read the mean) */
            self->accel_sum[0] += r.u.imu.accel_frd_m_s2[0];
            self->accel_sum[1] += r.u.imu.accel_frd_m_s2[1];
            self->accel_sum[2] += r.u.imu.accel_frd_m_s2[2];
            self->accel_n++;
            break;
        case SB_KIND_BARO:
            (void)fc_core_baro_step(c, r.h.sim_ns, r.u.baro.pressure_pa);
            break;
        case SB_KIND_MAG:
            (void)fc_core_mag_step(c, r.h.sim_ns, r.u.mag.field_frd_gauss);
            break;
        case SB_KIND_GNSS:
            consume_gnss(c, &r);
            break;
        case SB_KIND_GT_ATT:
            (void)fc_core_gt_att_step(c, r.h.sim_ns, r.u.gt_att.q_wxyz);
            break;
        case SB_KIND_GT_NAV: {
            const float pos[3] = {(float)r.u.gt_nav.pos_ned_m[0], (float)r.u.gt_nav.pos_ned_m[1],
                                  (float)r.u.gt_nav.pos_ned_m[2]};
            (void)fc_core_gt_nav_step(c, r.h.sim_ns, pos, r.u.gt_nav.vel_ned_m_s);
            break;
        }
        case SB_KIND_ESC: {
            const float v[5] = {r.u.esc.rpm, r.u.esc.voltage_v, r.u.esc.current_a,
                                r.u.esc.temperature_c, r.u.esc.consumption_mah};
            (void)fc_core_esc_step(c, r.h.sim_ns, r.u.esc.motor, r.u.esc.motor_count, v);
            break;
        }
        case SB_KIND_BATTERY:
            /* The physics-side pack: kept for the supervisor's battery reader and failsafes
             * (fc_sil/battery.py, Core.battery()); nothing in the C core reads it. */
            self->battery = r.u.battery;
            self->battery_count++;
            break;
        case SB_KIND_SETPOINT:
            /* Under MAVLink control the GCS alone commands the vehicle (fc_sil/vehicle.py). */
            if (self->ignore_setpoints) {
                self->setpoints_ignored++;
            } else {
                consume_setpoint(c, &r.u.setpoint);
            }
            break;
        default:
            self->unknown_kind++;
            continue; /* not a sensor record: fc_step_seq unchanged */
        }
        self->last_seq = r.h.seq;
        self->records_in++;
        self->last_kind_ns[r.h.kind & 15u] = r.h.sim_ns;
        if (r.h.kind == SB_KIND_IMU) {
            int64_t tick;
            while (emitted < cap && fc_core_pwm_due(c, &tick)) {
                emit_pwm(self, tick, &pwm_out[emitted], &st_out[emitted]);
                emitted++;
            }
        }
    }
    return emitted;
}

static PyObject *Core_step_batch(CoreObject *self, PyObject *args)
{
    Py_buffer rec, pwm_buf, st_buf;
    if (!PyArg_ParseTuple(args, "y*w*w*", &rec, &pwm_buf, &st_buf)) {
        return NULL;
    }
    PyObject *result = NULL;
    if (rec.len % SB_RECORD_SIZE != 0) {
        PyErr_SetString(PyExc_ValueError, "records must be whole 64-byte slots");
    } else {
        Py_ssize_t k = fc_ext_run_records(self, rec.buf, rec.len / SB_RECORD_SIZE, pwm_buf.buf,
                                          st_buf.buf, out_capacity(&pwm_buf, &st_buf));
        result = k < 0 ? NULL : PyLong_FromSsize_t(k);
    }
    PyBuffer_Release(&rec);
    PyBuffer_Release(&pwm_buf);
    PyBuffer_Release(&st_buf);
    return result;
}

/* ---- bound arrays (the poll loop's path) ---------------------------------------- */

void fc_ext_unbind_batch(CoreObject *self)
{
    fc_ext_detach_io(self);   /* poll_io uses the bound arrays */
    if (self->have_bound) {
        for (int i = 0; i < 3; i++)
            PyBuffer_Release(&self->bound[i]);
        self->have_bound = 0;
    }
}

static PyObject *Core_bind_batch(CoreObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"records", "pwm_out", "status_out", NULL};
    Py_buffer v[3];
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "w*w*w*", kwlist, &v[0], &v[1], &v[2])) {
        return NULL;
    }
    if (v[0].len % SB_RECORD_SIZE != 0) {
        PyErr_SetString(PyExc_ValueError, "records must be whole 64-byte slots");
        for (int i = 0; i < 3; i++)
            PyBuffer_Release(&v[i]);
        return NULL;
    }
    fc_ext_unbind_batch(self);
    memcpy(self->bound, v, sizeof v);
    self->have_bound = 1;
    Py_RETURN_NONE;
}

static PyObject *Core_step_bound(CoreObject *self, PyObject *arg)
{
    Py_ssize_t n = PyLong_AsSsize_t(arg);
    if (n == -1 && PyErr_Occurred()) {
        return NULL;
    }
    if (!self->have_bound) {
        PyErr_SetString(PyExc_RuntimeError, "step_bound needs bind_batch(records, pwm, status)");
        return NULL;
    }
    if (n < 0 || n > self->bound[0].len / SB_RECORD_SIZE) {
        PyErr_Format(PyExc_ValueError, "step_bound(%zd): the bound record array holds %zd", n,
                     self->bound[0].len / SB_RECORD_SIZE);
        return NULL;
    }
    Py_ssize_t k = fc_ext_run_records(self, self->bound[0].buf, n, self->bound[1].buf,
                                      self->bound[2].buf, fc_ext_bound_capacity(self));
    if (k < 0 || fc_ext_log_batch(self, self->bound[0].buf, n, self->bound[1].buf,
                                  self->bound[2].buf, k) < 0) {
        return NULL;
    }
    return PyLong_FromSsize_t(k);
}

PyMethodDef fc_ext_batch_methods[] = {
    {"pwm_bound", (PyCFunction)Core_pwm_bound, METH_VARARGS,
     "pwm_bound(records) -> most PWM ticks step_batch(records) can emit."},
    {"step_batch", (PyCFunction)Core_step_batch, METH_VARARGS,
     "step_batch(records, pwm_out, status_out) -> ticks emitted."},
    {"bind_batch", (PyCFunction)(void (*)(void))Core_bind_batch, METH_VARARGS | METH_KEYWORDS,
     "bind_batch(records, pwm_out, status_out): the arrays step_bound(n) uses."},
    {"step_bound", (PyCFunction)Core_step_bound, METH_O,
     "step_bound(n) -> PWM ticks: step_batch over the first n bound records."},
    {NULL, NULL, 0, NULL},
};
