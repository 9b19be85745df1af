/*
 * core_fft.c - the in-flight FFT's results for logs (fc_fft.h): ArduCopter writes FTN1
 * (one row) and FTN2 (one row per peak slot, Id 0..2) at 10 Hz (Copter's
 * ten_hz_logging_loop, AP_GyroFFT::write_log_messages); so do we, as the /fc/ftn1 and
 * /fc/ftn2 rows of the run's log (tools/logs/ftn_log.py holds their numpy view).
 *
 * bind_fft_log(ftn1, ftn2) binds two bytearrays the log owns; the batch logger
 * (core_log.c) calls fc_ext_log_fft after each batch, which appends a set of rows when
 * the IMU clock crossed the next 100 ms mark and the FFT runs. ArduCopter sends no FFT
 * telemetry message to ground stations, only text: the pre-arm "FFT calibrating noise"
 * (fft_calibrating() here, fc_sil/prearm.py), "FFT: calibrated ..." once the noise
 * reference is learned (fft_calibration()) and FFT_OPTIONS bit 1's "Noise ... on motor"
 * (fft_esc_noise()); fc_sil/fft_notice.py words and sends them. Conversion only.
 */
#include "core_object.h"

#include <stddef.h>

#define FC_EXT_FTN_PERIOD_NS 100000000LL /* 10 Hz */

/* One FTN1 row (fields in ArduPilot's order; Tc is sim time, the core has no clock). */
typedef struct fc_ext_ftn1_row {
    int64_t sim_ns;
    float pk_avg_hz, bw_avg_hz;
    float snr_db[3];
    float fit_pct[3];
    uint32_t cycle_us;
    uint8_t health;
    uint8_t pad[3];
} fc_ext_ftn1_row_t;

/* One FTN2 row: one peak slot on the three axes. */
typedef struct fc_ext_ftn2_row {
    int64_t sim_ns;
    float pk_hz[3], bw_hz[3], energy[3];
    uint8_t id;
    uint8_t pad[3];
} fc_ext_ftn2_row_t;

_Static_assert(sizeof(fc_ext_ftn1_row_t) == 48, "FTN1 row layout is mirrored in ftn_log.py");
_Static_assert(sizeof(fc_ext_ftn2_row_t) == 48, "FTN2 row layout is mirrored in ftn_log.py");

/* The throttle the FFT's fallback reads: the mixer's, as a fraction of the PWM range. */
static float throttle_out(const fc_core_t *c)
{
    const float range_us = c->cfg.mix.pwm_max_us - c->cfg.mix.pwm_min_us;
    return range_us > 0.0f ? (c->mixer.throttle_us - c->cfg.mix.pwm_min_us) / range_us : 0.0f;
}

/* The rows as of now: one FTN1 and up to three FTN2 (slot 0 always, 1 and 2 when more
 * than one peak is tracked, as ArduPilot). Returns how many FTN2 rows. */
static int ftn_rows(const fc_core_t *c, int64_t sim_ns, fc_ext_ftn1_row_t *r1,
                    fc_ext_ftn2_row_t r2[FC_FFT_MAX_PEAKS])
{
    fc_fft_ftn1_t t;
    fc_fft_ftn1(&c->fft, throttle_out(c), &t);
    *r1 = (fc_ext_ftn1_row_t){.sim_ns = sim_ns, .pk_avg_hz = t.pk_avg_hz,
                              .bw_avg_hz = t.bw_avg_hz, .cycle_us = t.cycle_us,
                              .health = t.health};
    for (int a = 0; a < 3; a++) {
        r1->snr_db[a] = t.snr_db[a];
        r1->fit_pct[a] = t.fit_pct[a];
    }
    const int n = c->fft.tracked_peaks > 1 ? FC_FFT_MAX_PEAKS : 1;
    for (int i = 0; i < n; i++) {
        r2[i] = (fc_ext_ftn2_row_t){.sim_ns = sim_ns, .id = (uint8_t)i};
        fc_fft_ftn2(&c->fft, (unsigned)i, r2[i].pk_hz, r2[i].bw_hz, r2[i].energy);
    }
    return n;
}

int fc_ext_log_fft(CoreObject *self)
{
    const fc_core_t *c = &self->core;
    if (self->log_ftn1 == NULL || !c->fft.active || c->last_imu_ns < self->ftn_next_ns) {
        return 0;
    }
    /* the next mark on the 100 ms grid after this sample */
    self->ftn_next_ns = (c->last_imu_ns / FC_EXT_FTN_PERIOD_NS + 1) * FC_EXT_FTN_PERIOD_NS;
    fc_ext_ftn1_row_t r1;
    fc_ext_ftn2_row_t r2[FC_FFT_MAX_PEAKS];
    const int n = ftn_rows(c, c->last_imu_ns, &r1, r2);
    if (fc_ext_append_bytes(self->log_ftn1, &r1, (Py_ssize_t)sizeof r1) < 0) {
        return -1;
    }
    if (self->log_ftn2 != NULL
        && fc_ext_append_bytes(self->log_ftn2, r2, (Py_ssize_t)(sizeof r2[0]) * n) < 0) {
        return -1;
    }
    return 0;
}

void fc_ext_clear_fft_log(CoreObject *self)
{
    Py_CLEAR(self->log_ftn1);
    Py_CLEAR(self->log_ftn2);
}

static PyObject *Core_bind_fft_log(CoreObject *self, PyObject *args)
{
    PyObject *f1, *f2;
    if (!PyArg_ParseTuple(args, "OO", &f1, &f2)) {
        return NULL;
    }
    if ((f1 != Py_None && !PyByteArray_Check(f1)) || (f2 != Py_None && !PyByteArray_Check(f2))) {
        PyErr_SetString(PyExc_TypeError, "bind_fft_log: bytearrays or None");
        return NULL;
    }
    fc_ext_clear_fft_log(self);
    self->log_ftn1 = f1 == Py_None ? NULL : Py_NewRef(f1);
    self->log_ftn2 = f2 == Py_None ? NULL : Py_NewRef(f2);
    Py_RETURN_NONE;
}

/* fft_ftn() -> (ftn1 row bytes, ftn2 rows bytes): the rows as they would be logged now. */
static PyObject *Core_fft_ftn(CoreObject *self, PyObject *Py_UNUSED(unused))
{
    fc_ext_ftn1_row_t r1;
    fc_ext_ftn2_row_t r2[FC_FFT_MAX_PEAKS];
    const int n = ftn_rows(&self->core, self->core.last_imu_ns, &r1, r2);
    return Py_BuildValue("(y#y#)", (const char *)&r1, (Py_ssize_t)sizeof r1, (const char *)r2,
                         (Py_ssize_t)(sizeof r2[0]) * n);
}

/* fft_notch_freqs(throttle_out) -> tuple of Hz: what notch MODE 4 reads (fc_fft_notch_freqs). */
static PyObject *Core_fft_notch_freqs(CoreObject *self, PyObject *arg)
{
    const double thr = PyFloat_AsDouble(arg);
    if (thr == -1.0 && PyErr_Occurred()) {
        return NULL;
    }
    float f[FC_FFT_MAX_PEAKS];
    const unsigned n = fc_fft_notch_freqs(&self->core.fft, (float)thr, f);
    PyObject *t = PyTuple_New((Py_ssize_t)n);
    for (unsigned i = 0; t != NULL && i < n; i++) {
        PyTuple_SET_ITEM(t, (Py_ssize_t)i, PyFloat_FromDouble((double)f[i]));
    }
    return t;
}

/* fft_calibrating() -> bool: the FFT runs and still learns its noise reference
 * (ArduCopter's pre-arm "FFT calibrating noise"). */
static PyObject *Core_fft_calibrating(CoreObject *self, PyObject *Py_UNUSED(unused))
{
    return PyBool_FromLong(self->core.fft.active && self->core.fft.needs_calibration != 0);
}

/* fft_calibration() -> (sample kHz, half bin Hz, output Hz), the figures of ArduCopter's
 * "FFT: calibrated" text, or None while the FFT is off or still learning its noise. */
static PyObject *Core_fft_calibration(CoreObject *self, PyObject *Py_UNUSED(unused))
{
    const fc_fft_t *f = &self->core.fft;
    if (!f->active || f->needs_calibration != 0) {
        Py_RETURN_NONE;
    }
    fc_fft_calibration_t k;
    fc_fft_calibration(f, &k);
    return Py_BuildValue("(ddd)", (double)k.sample_khz, (double)k.half_bin_hz,
                         (double)k.output_hz);
}

_Static_assert(FC_FFT_ESC_MAX == FC_ESC_MAX, "the motor-noise check covers every ESC");

/* Each ESC's motor frequency as AP_ESC_Telem::get_motor_frequencies_hz gives it: in motor
 * order up to the last that ever reported, 0 Hz for none or stale. Returns how many. */
static unsigned motor_hz(const fc_core_t *c, float hz[FC_ESC_MAX])
{
    unsigned n = 0;
    for (unsigned i = 0; i < FC_ESC_MAX; i++) {
        const fc_esc_report_t *r = &c->esc.esc[i];
        const bool fresh = r->sim_ns >= 0 && c->last_imu_ns - r->sim_ns <= FC_ESC_RPM_TIMEOUT_NS;
        hz[i] = fresh ? r->rpm * (1.0f / 60.0f) : 0.0f;
        n = r->sim_ns >= 0 ? i + 1u : n;
    }
    return n;
}

/* fft_esc_noise(dt_s) -> [(motor 1.., dB, Hz), ...]: one FFT_OPTIONS bit 1 check
 * (fc_fft_esc_noise_check; call every FC_FFT_ESC_CHECK_S), the motors to warn about now. */
static PyObject *Core_fft_esc_noise(CoreObject *self, PyObject *arg)
{
    const double dt_s = PyFloat_AsDouble(arg);
    if (dt_s == -1.0 && PyErr_Occurred()) {
        return NULL;
    }
    fc_core_t *c = &self->core;
    bool fft_notch = false;
    for (int j = 0; j < FC_INS_NOTCHES; j++) {
        const fc_notch_config_t *n = &c->ins.notch[j].cfg;
        fft_notch = fft_notch || (n->enable && n->mode == FC_NOTCH_MODE_FFT);
    }
    float hz[FC_ESC_MAX];
    const unsigned n = motor_hz(c, hz);
    const unsigned warn = fc_fft_esc_noise_check(&c->fft, hz, n, c->in.armed != 0, fft_notch,
                                                 (float)dt_s);
    PyObject *out = PyList_New(0);
    for (unsigned i = 0; out != NULL && i < n; i++) {
        if (!(warn & (1u << i))) {
            continue;
        }
        PyObject *row = Py_BuildValue("(Idd)", i + 1u, (double)c->fft.esc_noise.energy_db[i],
                                      (double)hz[i]);
        if (row == NULL || PyList_Append(out, row) < 0) {
            Py_XDECREF(row);
            Py_CLEAR(out);
            break;
        }
        Py_DECREF(row);
    }
    return out;
}

PyMethodDef fc_ext_fft_methods[] = {
    {"fft_calibration", (PyCFunction)Core_fft_calibration, METH_NOARGS,
     "fft_calibration() -> (kHz, half bin Hz, output Hz) or None: the figures of "
     "ArduCopter's 'FFT: calibrated' text once the noise reference is learned."},
    {"fft_esc_noise", (PyCFunction)Core_fft_esc_noise, METH_O,
     "fft_esc_noise(dt_s) -> [(motor, dB, Hz)]: one FFT_OPTIONS bit 1 motor-noise check "
     "(every 0.2 s); the motors to warn about now."},
    {"bind_fft_log", (PyCFunction)Core_bind_fft_log, METH_VARARGS,
     "bind_fft_log(ftn1, ftn2): append FTN1/FTN2 rows (48 bytes each, ftn_log.py) at 10 Hz "
     "of IMU time to these bytearrays while the FFT runs; None, None: off."},
    {"fft_ftn", (PyCFunction)Core_fft_ftn, METH_NOARGS,
     "fft_ftn() -> (ftn1 row, ftn2 rows) as bytes: the FFT's log rows as of now."},
    {"fft_calibrating", (PyCFunction)Core_fft_calibrating, METH_NOARGS,
     "fft_calibrating() -> bool: FFT_ENABLE set and the noise reference not learned yet."},
    {"fft_notch_freqs", (PyCFunction)Core_fft_notch_freqs, METH_O,
     "fft_notch_freqs(throttle_out) -> (Hz, ...): the frequencies notch MODE 4 reads."},
    {NULL, NULL, 0, NULL},
};
