/*
 * coremodule.c - silbridge.fc_sil._core: the C flight-controller core driven
 * from Python.
 *
 * `Core` wraps one fc_core_t. Its step_batch consumes a whole array of
 * 64-byte shared-memory records (shm/include/sb_records.h) in one call, so
 * the hot loop stays in C: IMU -> fc_core_imu_step, BARO/MAG/GNSS/GT/SETPOINT
 * to their inputs, and after each IMU sample every PWM tick now due is
 * stepped and written as one PWM record plus one status row (the layout of
 * fc_core_status_t, mirrored by fc_sil.STATUS_DTYPE). This file is the only
 * place where records meet the core: the core itself knows no records.
 *
 * Threading: every method runs with the GIL held, so a Core may be shared
 * between a control thread and, say, a MAVLink thread that sets parameters.
 */
#define FC_EXT_IMPORT_ARRAY
#include "ext_common.h"

#include <stddef.h>
#include <string.h>
#include <math.h>
#include <time.h>

#include "fc_core.h"
#include "sb_records.h"

#include "core_object.h"

const char *fc_ext_status_name(int status)
{
    switch (status) {
    case FC_OK:
        return "ok";
    case FC_ERR_ARG:
        return "invalid argument";
    case FC_ERR_RANGE:
        return "out of range";
    case FC_ERR_NONFINITE:
        return "not finite";
    case FC_ERR_INDEX:
        return "unknown parameter index";
    case FC_ERR_TYPE:
        return "not an integer";
    default:
        return "unknown status";
    }
}

void *fc_ext_state(Py_buffer *view, size_t size, const char *what)
{
    if (view->readonly || (size_t)view->len < size || ((uintptr_t)view->buf & 7u) != 0) {
        PyErr_Format(PyExc_ValueError,
                     "%s state needs a writable 8-byte aligned buffer of %zu bytes "
                     "(use the wrapper classes in silbridge.fc_sil.blocks)",
                     what, size);
        return NULL;
    }
    return view->buf;
}

int64_t fc_ext_monotonic_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + (int64_t)ts.tv_nsec;
}

/* ---- construction -------------------------------------------------------- */

static PyObject *Core_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    (void)args;
    (void)kwds;
    CoreObject *self = (CoreObject *)type->tp_alloc(type, 0);
    if (self != NULL) {
        fc_core_init(&self->core);
        for (int k = 0; k < 16; k++) {
            self->last_kind_ns[k] = -1;
        }
    }
    return (PyObject *)self;
}

static PyObject *Core_reset(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    fc_core_reset(&self->core);
    self->pwm_seq = 0;
    self->last_seq = 0;
    Py_RETURN_NONE;
}

/* ---- parameters ---------------------------------------------------------- */

static PyObject *Core_set_param(CoreObject *self, PyObject *args)
{
    int index;
    double value;
    if (!PyArg_ParseTuple(args, "id", &index, &value)) {
        return NULL;
    }
    if (index < 0 || index > 65535) {
        return PyLong_FromLong(FC_ERR_INDEX);
    }
    return PyLong_FromLong(fc_core_set_param(&self->core, (uint16_t)index, (float)value));
}

static PyObject *Core_get_param(CoreObject *self, PyObject *args)
{
    int index;
    if (!PyArg_ParseTuple(args, "i", &index)) {
        return NULL;
    }
    float value = 0.0f;
    if (index < 0 || index > 65535
        || fc_core_get_param(&self->core, (uint16_t)index, &value) != FC_OK) {
        PyErr_Format(PyExc_KeyError, "no C-core parameter with index %d", index);
        return NULL;
    }
    return PyFloat_FromDouble((double)value);
}

static PyObject *param_table(PyObject *module, PyObject *noargs)
{
    (void)module;
    (void)noargs;
    PyObject *list = PyList_New((Py_ssize_t)fc_param_count);
    if (list == NULL) {
        return NULL;
    }
    for (size_t i = 0; i < fc_param_count; i++) {
        const fc_param_info_t *p = &fc_param_table[i];
        PyObject *t = Py_BuildValue("(siiiddd)", p->name, (int)p->index, (int)p->type,
                                    (int)p->offset, (double)p->min_value,
                                    (double)p->max_value, (double)p->default_value);
        if (t == NULL) {
            Py_DECREF(list);
            return NULL;
        }
        PyList_SET_ITEM(list, (Py_ssize_t)i, t);
    }
    return list;
}

/* ---- inputs -------------------------------------------------------------- */

static PyObject *Core_set_setpoint_input(CoreObject *self, PyObject *args)
{
    int enabled;
    if (!PyArg_ParseTuple(args, "p", &enabled)) {
        return NULL;
    }
    self->ignore_setpoints = !enabled;
    Py_RETURN_NONE;
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

static PyObject *Core_set_armed(CoreObject *self, PyObject *args)
{
    int armed;
    if (!PyArg_ParseTuple(args, "p", &armed)) {
        return NULL;
    }
    fc_core_set_armed(&self->core, armed != 0);
    Py_RETURN_NONE;
}

static PyObject *Core_set_attitude_target(CoreObject *self, PyObject *args)
{
    double r, p;
    if (!PyArg_ParseTuple(args, "dd", &r, &p)) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_set_attitude_target(&self->core, (float)r, (float)p));
}

#define SCALAR_SETTER(pyname, cfunc)                                        \
    static PyObject *pyname(CoreObject *self, PyObject *args)               \
    {                                                                       \
        double v;                                                           \
        if (!PyArg_ParseTuple(args, "d", &v)) {                             \
            return NULL;                                                    \
        }                                                                   \
        return PyLong_FromLong(cfunc(&self->core, (float)v));               \
    }

SCALAR_SETTER(Core_set_yaw_target, fc_core_set_yaw_target)
SCALAR_SETTER(Core_set_yaw_rate_target, fc_core_set_yaw_rate_target)
SCALAR_SETTER(Core_set_altitude_target, fc_core_set_altitude_target)
SCALAR_SETTER(Core_set_climb_target, fc_core_set_climb_target)
SCALAR_SETTER(Core_set_throttle, fc_core_set_throttle)

static PyObject *Core_set_accel_ref(CoreObject *self, PyObject *args)
{
    float a[3];
    if (!PyArg_ParseTuple(args, "(fff)", &a[0], &a[1], &a[2])) {
        return NULL;
    }
    return PyLong_FromLong(fc_core_set_accel_ref(&self->core, a));
}

static PyObject *Core_inputs(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_core_inputs_t *in = &self->core.in;
    return Py_BuildValue("{s:O,s:O,s:i,s:d,s:d,s:d,s:d,s:d,s:d,s:d}", "armed",
                         in->armed ? Py_True : Py_False, "yaw_hold",
                         in->yaw_hold ? Py_True : Py_False, "alt_mode", (int)in->alt_mode,
                         "roll_target_rad", (double)in->roll_target_rad, "pitch_target_rad",
                         (double)in->pitch_target_rad, "yaw_target_rad",
                         (double)in->yaw_target_rad, "yaw_rate_target_rad_s",
                         (double)in->yaw_rate_target_rad_s, "alt_target_m",
                         (double)in->alt_target_m, "climb_target_m_s",
                         (double)in->climb_target_m_s, "throttle", (double)in->throttle);
}

/* ---- single steps (tests, hosts without records) ---------------------------- */

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

static PyObject *Core_status_bytes(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    return PyBytes_FromStringAndSize((const char *)&self->core.status,
                                     (Py_ssize_t)sizeof(fc_core_status_t));
}

static PyObject *Core_counters(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_core_t *c = &self->core;
    return Py_BuildValue("{s:K,s:K,s:K,s:K,s:K,s:K,s:K,s:L,s:K,s:O,s:d}", "imu",
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
                         "heading_offset_rad", (double)c->ahrs.heading_offset_rad);
}

static PyObject *Core_gnss(CoreObject *self, PyObject *noargs)
{
    (void)noargs;
    const fc_gnss_store_t *g = &self->core.gnss;
    if (!g->valid) {
        Py_RETURN_NONE;
    }
    return Py_BuildValue("{s:L,s:i,s:i,s:i,s:(ddd),s:i,s:i}", "sim_ns", (long long)g->sim_ns,
                         "lat_e7", g->lat_e7, "lon_e7", g->lon_e7, "alt_mm", g->alt_mm,
                         "vel_ned_m_s", (double)g->vel_ned_m_s[0], (double)g->vel_ned_m_s[1],
                         (double)g->vel_ned_m_s[2], "fix_type", (int)g->fix_type, "satellites",
                         (int)g->satellites);
}

/* ---- record batches ------------------------------------------------------- */

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

/* Consume n records at base; PWM records and status rows go to the outputs (cap rows).
 * Returns the PWM ticks emitted, or -1 with an exception set. */
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
        case SB_KIND_GNSS: {
            fc_gnss_store_t g;
            memset(&g, 0, sizeof g);
            g.sim_ns = r.h.sim_ns;
            g.lat_e7 = r.u.gnss.lat_e7;
            g.lon_e7 = r.u.gnss.lon_e7;
            g.alt_mm = r.u.gnss.alt_mm;
            memcpy(g.vel_ned_m_s, r.u.gnss.vel_ned_m_s, sizeof g.vel_ned_m_s);
            g.fix_type = r.u.gnss.fix_type;
            g.satellites = r.u.gnss.satellites;
            (void)fc_core_gnss_step(c, &g);
            break;
        }
        case SB_KIND_GT_ATT:
            (void)fc_core_gt_att_step(c, r.h.sim_ns, r.u.gt_att.q_wxyz);
            break;
        case SB_KIND_GT_NAV: {
            const float pos[3] = {(float)r.u.gt_nav.pos_ned_m[0], (float)r.u.gt_nav.pos_ned_m[1],
                                  (float)r.u.gt_nav.pos_ned_m[2]};
            (void)fc_core_gt_nav_step(c, r.h.sim_ns, pos, r.u.gt_nav.vel_ned_m_s);
            break;
        }
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

static void unbind(CoreObject *self)
{
    fc_ext_detach_io(self);   /* poll_io uses the bound arrays */
    if (self->have_bound) {
        for (int i = 0; i < 3; i++)
            PyBuffer_Release(&self->bound[i]);
        self->have_bound = 0;
    }
}

static PyObject *Core_bind_batch(CoreObject *self, PyObject *args)
{
    Py_buffer v[3];
    if (!PyArg_ParseTuple(args, "w*w*w*", &v[0], &v[1], &v[2])) {
        return NULL;
    }
    if (v[0].len % SB_RECORD_SIZE != 0) {
        PyErr_SetString(PyExc_ValueError, "records must be whole 64-byte slots");
        for (int i = 0; i < 3; i++)
            PyBuffer_Release(&v[i]);
        return NULL;
    }
    unbind(self);
    memcpy(self->bound, v, sizeof v);
    self->have_bound = 1;
    Py_RETURN_NONE;
}

/* Append len bytes to a bytearray (amortised growth); -1 with an exception on failure. */
int fc_ext_append_bytes(PyObject *ba, const void *src, Py_ssize_t len)
{
    if (len == 0)
        return 0;
    const Py_ssize_t old = PyByteArray_GET_SIZE(ba);
    if (PyByteArray_Resize(ba, old + len) < 0)
        return -1;
    memcpy(PyByteArray_AS_STRING(ba) + old, src, (size_t)len);
    return 0;
}

static void clear_log(CoreObject *self)
{
    for (int i = 0; i < 16; i++)
        Py_CLEAR(self->log_kind[i]);
    Py_CLEAR(self->log_stage);
    Py_CLEAR(self->log_status);
    Py_CLEAR(self->log_timing);
    self->log_pwm = 0;
    self->log_on = 0;
}

/* bind_log(kind_queues, stage, status, log_pwm, timing); bind_log(None) turns capture off.
 * timing: the /timing queue poll_io appends its row to (step_bound has no clock). */
static PyObject *Core_bind_log(CoreObject *self, PyObject *args)
{
    PyObject *kinds, *stage = Py_None, *st = Py_None, *timing = Py_None;
    int log_pwm = 0;
    if (!PyArg_ParseTuple(args, "O|OOpO", &kinds, &stage, &st, &log_pwm, &timing)) {
        return NULL;
    }
    if (kinds == Py_None) {
        clear_log(self);
        Py_RETURN_NONE;
    }
    if (!PyTuple_Check(kinds) || PyTuple_GET_SIZE(kinds) != 16) {
        PyErr_SetString(PyExc_TypeError, "bind_log: kind_queues must be a tuple of 16 "
                                         "(bytearray or None), one per record kind");
        return NULL;
    }
    PyObject *objs[19];
    for (int i = 0; i < 16; i++)
        objs[i] = PyTuple_GET_ITEM(kinds, i);
    objs[16] = stage;
    objs[17] = st;
    objs[18] = timing;
    for (int i = 0; i < 19; i++) {
        if (objs[i] != Py_None && !PyByteArray_Check(objs[i])) {
            PyErr_SetString(PyExc_TypeError, "bind_log: queues must be bytearrays or None");
            return NULL;
        }
    }
    clear_log(self);
    for (int i = 0; i < 16; i++)
        self->log_kind[i] = objs[i] == Py_None ? NULL : Py_NewRef(objs[i]);
    self->log_stage = stage == Py_None ? NULL : Py_NewRef(stage);
    self->log_status = st == Py_None ? NULL : Py_NewRef(st);
    self->log_timing = timing == Py_None ? NULL : Py_NewRef(timing);
    self->log_pwm = log_pwm;
    self->log_on = self->log_stage != NULL;
    for (int i = 0; i < 16; i++)
        self->log_on |= self->log_kind[i] != NULL;
    Py_RETURN_NONE;
}

/* Append whole records to their kind's queue (or the stage); -1 on failure. */
int fc_ext_log_records(CoreObject *self, const unsigned char *base, Py_ssize_t n)
{
    for (Py_ssize_t i = 0; i < n; i++) {
        const unsigned char *rec = base + (size_t)i * SB_RECORD_SIZE;
        uint16_t kind;
        memcpy(&kind, rec, sizeof kind);
        PyObject *dest = self->log_kind[kind & 15u];
        if (dest == NULL)
            dest = self->log_stage;
        if (dest != NULL && fc_ext_append_bytes(dest, rec, SB_RECORD_SIZE) < 0)
            return -1;
    }
    return 0;
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
                               self->bound[2].buf, out_capacity(&self->bound[1], &self->bound[2]));
    if (k < 0) {
        return NULL;
    }
    if (self->log_on && (fc_ext_log_records(self, self->bound[0].buf, n) < 0 ||
                         (self->log_pwm && fc_ext_log_records(self, self->bound[1].buf, k) < 0))) {
        return NULL;
    }
    if (self->log_status != NULL &&
        fc_ext_append_bytes(self->log_status, self->bound[2].buf,
                     k * (Py_ssize_t)sizeof(fc_core_status_t)) < 0) {
        return NULL;
    }
    return PyLong_FromSsize_t(k);
}

static void Core_dealloc(CoreObject *self)
{
    fc_ext_detach_io(self);
    unbind(self);
    clear_log(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

/* ---- micro-benchmark (silbridge fc-bench) ----------------------------------- */

/* Time fc_core_imu_step and fc_core_pwm_step in C, on a core that is armed and
 * flying (every block runs): a hover with a small rate wobble at imu_hz and a
 * barometer every 10th sample. Bounded: n_imu and n_pwm calls. */
static PyObject *bench_steps(PyObject *module, PyObject *args)
{
    (void)module;
    long long n_imu, n_pwm;
    double imu_hz;
    if (!PyArg_ParseTuple(args, "LLd", &n_imu, &n_pwm, &imu_hz)) {
        return NULL;
    }
    if (n_imu < 1 || n_pwm < 1 || !(imu_hz > 0.0)) {
        PyErr_SetString(PyExc_ValueError, "bench_steps needs n_imu, n_pwm >= 1 and imu_hz > 0");
        return NULL;
    }
    fc_core_t *c = PyMem_Malloc(sizeof *c);
    if (c == NULL) {
        return PyErr_NoMemory();
    }
    fc_core_init(c);
    fc_core_set_armed(c, true);
    (void)fc_core_set_altitude_target(c, 5.0f);
    const int64_t period_ns = (int64_t)(1e9 / imu_hz);
    float accel[3] = {0.0f, 0.0f, -9.80665f};
    float gyro[3] = {0.0f, 0.0f, 0.0f};
    uint16_t pwm[FC_MIXER_MOTORS];
    int64_t t = 0;
    /* Warm-up so the spool is in flight and the filters are primed. */
    for (int i = 0; i < 2000; i++, t += period_ns) {
        (void)fc_core_imu_step(c, t, accel, gyro);
        if (i % 10 == 0) {
            (void)fc_core_baro_step(c, t, 101325.0f);
        }
        int64_t tick;
        while (fc_core_pwm_due(c, &tick)) {
            (void)fc_core_pwm_step(c, tick, pwm);
        }
    }
    int64_t t0, t1, t2;
    Py_BEGIN_ALLOW_THREADS  /* c is private to this call */
    t0 = fc_ext_monotonic_ns();
    for (long long i = 0; i < n_imu; i++, t += period_ns) {
        const float ph = (float)(i & 1023) * (6.2831853f / 1024.0f);
        gyro[0] = 0.02f * sinf(ph);
        gyro[1] = 0.02f * cosf(ph);
        (void)fc_core_imu_step(c, t, accel, gyro);
    }
    t1 = fc_ext_monotonic_ns();
    for (long long i = 0; i < n_pwm; i++) {
        (void)fc_core_pwm_step(c, t, pwm);
    }
    t2 = fc_ext_monotonic_ns();
    Py_END_ALLOW_THREADS
    const unsigned long loops = (unsigned long)c->loop_count;
    const int spool = c->spool;
    PyMem_Free(c);
    return Py_BuildValue("{s:d,s:d,s:k,s:i}", "imu_step_ns", (double)(t1 - t0) / (double)n_imu,
                         "pwm_step_ns", (double)(t2 - t1) / (double)n_pwm, "rate_loops", loops,
                         "spool", spool);
}

/* ---- layout export (tests compare it with fc_sil.STATUS_DTYPE) ----------- */

static PyObject *status_layout(PyObject *module, PyObject *noargs)
{
    (void)module;
    (void)noargs;
    typedef struct {
        const char *name;
        size_t offset, size;
    } field_t;
#define F(name) {#name, offsetof(fc_core_status_t, name), sizeof(((fc_core_status_t *)0)->name)}
    static const field_t fields[] = {
        F(sim_ns), F(imu_sim_ns), F(q_est_wxyz), F(euler_est_rad), F(att_target_rad),
        F(att_error_frd_rad), F(rate_target_frd_rad_s), F(rate_frd_rad_s), F(pid_p), F(pid_i),
        F(pid_d), F(pid_ff), F(cp_us), F(cr_us), F(cy_us), F(throttle_us), F(motor_us), F(trust),
        F(gyro_bias_rad_s), F(blend_w), F(alt_est_m), F(climb_est_m_s), F(alt_target_m),
        F(climb_target_m_s), F(throttle), F(trim_us), F(loop_count), F(rejected_count),
        F(pwm_us), F(limited), F(sat_flags), F(armed), F(airborne), F(spool), F(reserved),
    };
#undef F
    const size_t n = sizeof(fields) / sizeof(fields[0]);
    PyObject *list = PyList_New((Py_ssize_t)n);
    if (list == NULL) {
        return NULL;
    }
    for (size_t i = 0; i < n; i++) {
        PyObject *t = Py_BuildValue("(snn)", fields[i].name, (Py_ssize_t)fields[i].offset,
                                    (Py_ssize_t)fields[i].size);
        if (t == NULL) {
            Py_DECREF(list);
            return NULL;
        }
        PyList_SET_ITEM(list, (Py_ssize_t)i, t);
    }
    return Py_BuildValue("{s:n,s:N,s:n,s:n}", "itemsize", (Py_ssize_t)sizeof(fc_core_status_t),
                         "fields", list, "sizeof_core", (Py_ssize_t)sizeof(fc_core_t),
                         "sizeof_record", (Py_ssize_t)sizeof(sb_record));
}

/* ---- type and module ------------------------------------------------------ */

static PyMethodDef Core_methods[] = {
    {"reset", (PyCFunction)Core_reset, METH_NOARGS, "Reset state and inputs; keep parameters."},
    {"bind_batch", (PyCFunction)Core_bind_batch, METH_VARARGS,
     "bind_batch(records, pwm_out, status_out): the arrays step_bound(n) uses."},
    {"bind_log", (PyCFunction)Core_bind_log, METH_VARARGS,
     "bind_log(kind_queues[16], stage, status, log_pwm): step_bound appends consumed "
     "records, PWM records (log_pwm) and status rows to these bytearrays; bind_log(None): off."},
    {"attach_io", (PyCFunction)fc_ext_attach_io, METH_VARARGS,
     "attach_io(segment._c_api(), fc_sim_word, latency, period, e2e, words): poll_io's "
     "segment, int64 statistics rings and counters (core_object.h); attach_io(None) detaches."},
    {"poll_io", (PyCFunction)fc_ext_poll_io, METH_NOARGS,
     "poll_io() -> records consumed: FcLoop.poll over shared memory in C (corepoll.c)."},
    {"step_bound", (PyCFunction)Core_step_bound, METH_O,
     "step_bound(n) -> PWM ticks: step_batch over the first n bound records."},
    {"set_param", (PyCFunction)Core_set_param, METH_VARARGS,
     "set_param(index, value) -> status code (0 ok)."},
    {"get_param", (PyCFunction)Core_get_param, METH_VARARGS, "get_param(index) -> float."},
    {"set_armed", (PyCFunction)Core_set_armed, METH_VARARGS, "set_armed(bool)."},
    {"last_seen", (PyCFunction)Core_last_seen, METH_NOARGS,
     "Sim time [ns] of the last record of each kind 0..15 (-1: never)."},
    {"take_accel_mean", (PyCFunction)Core_take_accel_mean, METH_NOARGS,
     "Mean raw IMU accel (FRD, m/s^2) since the last call, or None."},
    {"set_setpoint_input", (PyCFunction)Core_set_setpoint_input, METH_VARARGS,
     "set_setpoint_input(bool): consume (True, default) or skip scenario SETPOINT records."},
    {"set_attitude_target", (PyCFunction)Core_set_attitude_target, METH_VARARGS,
     "set_attitude_target(roll_rad, pitch_rad) -> status."},
    {"set_yaw_target", (PyCFunction)Core_set_yaw_target, METH_VARARGS,
     "set_yaw_target(yaw_rad) -> status (yaw angle mode)."},
    {"set_yaw_rate_target", (PyCFunction)Core_set_yaw_rate_target, METH_VARARGS,
     "set_yaw_rate_target(rad_s) -> status (yaw rate mode)."},
    {"set_altitude_target", (PyCFunction)Core_set_altitude_target, METH_VARARGS,
     "set_altitude_target(m) -> status."},
    {"set_climb_target", (PyCFunction)Core_set_climb_target, METH_VARARGS,
     "set_climb_target(m_s) -> status."},
    {"set_throttle", (PyCFunction)Core_set_throttle, METH_VARARGS,
     "set_throttle(0..1) -> status (direct throttle)."},
    {"set_accel_ref", (PyCFunction)Core_set_accel_ref, METH_VARARGS,
     "set_accel_ref((ax, ay, az) NED m/s^2) -> status (estimator acceleration reference)."},
    {"inputs", (PyCFunction)Core_inputs, METH_NOARGS, "Current inputs as a dict."},
    {"imu", (PyCFunction)Core_imu, METH_VARARGS, "imu(sim_ns, accel3, gyro3) -> status."},
    {"baro", (PyCFunction)Core_baro, METH_VARARGS, "baro(sim_ns, pressure_pa) -> status."},
    {"mag", (PyCFunction)Core_mag, METH_VARARGS, "mag(sim_ns, field3) -> status."},
    {"gt_att", (PyCFunction)Core_gt_att, METH_VARARGS, "gt_att(sim_ns, q_wxyz) -> status."},
    {"gt_nav", (PyCFunction)Core_gt_nav, METH_VARARGS,
     "gt_nav(sim_ns, pos_ned3, vel_ned3) -> status."},
    {"pwm_due", (PyCFunction)Core_pwm_due, METH_NOARGS, "Next due PWM tick [ns] or None."},
    {"pwm_step", (PyCFunction)Core_pwm_step, METH_VARARGS, "pwm_step(tick_ns) -> 4 PWM [us]."},
    {"status_bytes", (PyCFunction)Core_status_bytes, METH_NOARGS, "Last status snapshot."},
    {"counters", (PyCFunction)Core_counters, METH_NOARGS, "Step counters."},
    {"gnss", (PyCFunction)Core_gnss, METH_NOARGS, "Last GNSS fix or None."},
    {"pwm_bound", (PyCFunction)Core_pwm_bound, METH_VARARGS,
     "pwm_bound(records) -> most PWM ticks step_batch(records) can emit."},
    {"step_batch", (PyCFunction)Core_step_batch, METH_VARARGS,
     "step_batch(records, pwm_out, status_out) -> ticks emitted."},
    {"sysid_start", (PyCFunction)fc_ext_sysid_start, METH_NOARGS,
     "Start the SID_* sweep -> status code (FC_ERR_ARG: SID_AXIS 0 or bad sweep)."},
    {"sysid_stop", (PyCFunction)fc_ext_sysid_stop, METH_NOARGS, "Stop the sweep."},
    {"sysid_sample", (PyCFunction)fc_ext_sysid_sample, METH_NOARGS,
     "Sweep state and rate-loop signals of the latest step (sysidmethods.c)."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject CoreType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "silbridge.fc_sil._core.Core",
    .tp_basicsize = sizeof(CoreObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The C flight-controller core (fc_core_t); see silbridge.fc_sil.core.FlightCore.",
    .tp_new = Core_new,
    .tp_dealloc = (destructor)Core_dealloc,
    .tp_methods = Core_methods,
};

static PyMethodDef module_methods[] = {
    {"param_table", param_table, METH_NOARGS,
     "[(name, index, type, offset, min, max, default)] of the C parameter table."},
    {"status_layout", status_layout, METH_NOARGS, "Offsets and sizes of fc_core_status_t."},
    {"bench_steps", bench_steps, METH_VARARGS,
     "bench_steps(n_imu, n_pwm, imu_hz) -> {imu_step_ns, pwm_step_ns, ...} timed in C."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef moduledef = {
    PyModuleDef_HEAD_INIT, "_core", "The silbridge flight-controller core (C).", -1,
    module_methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__core(void)
{
    import_array();
    if (PyType_Ready(&CoreType) < 0) {
        return NULL;
    }
    PyObject *m = PyModule_Create(&moduledef);
    if (m == NULL) {
        return NULL;
    }
    if (PyModule_AddFunctions(m, fc_ext_block_methods) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    Py_INCREF(&CoreType);
    if (PyModule_AddObject(m, "Core", (PyObject *)&CoreType) < 0) {
        Py_DECREF(&CoreType);
        Py_DECREF(m);
        return NULL;
    }
    PyModule_AddIntConstant(m, "STATUS_SIZE", (long)sizeof(fc_core_status_t));
    PyModule_AddIntConstant(m, "FC_OK", FC_OK);
    PyModule_AddIntConstant(m, "FC_ERR_ARG", FC_ERR_ARG);
    PyModule_AddIntConstant(m, "FC_ERR_RANGE", FC_ERR_RANGE);
    PyModule_AddIntConstant(m, "FC_ERR_NONFINITE", FC_ERR_NONFINITE);
    PyModule_AddIntConstant(m, "FC_ERR_INDEX", FC_ERR_INDEX);
    PyModule_AddIntConstant(m, "FC_ERR_TYPE", FC_ERR_TYPE);
    return m;
}
