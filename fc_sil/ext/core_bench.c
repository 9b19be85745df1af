/*
 * core_bench.c - the micro-benchmark behind `silbridge fc-bench`: fc_core_imu_step and
 * fc_core_pwm_step timed in C, on a private core that is armed and flying (every block
 * runs), so the figure is the core's cost without the interpreter's.
 */
#include "core_object.h"

#include <math.h>

/* Parameters {index: value} for the bench's core (e.g. a notch switched on), each
 * through the core's own validation: a refused one is an error, not a silent default. */
static int bench_params(fc_core_t *c, PyObject *params)
{
    if (params == NULL || params == Py_None) {
        return 0;
    }
    if (!PyDict_Check(params)) {
        PyErr_SetString(PyExc_TypeError, "bench_steps params must be a dict {index: value}");
        return -1;
    }
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(params, &pos, &key, &value)) {
        const long index = PyLong_AsLong(key);
        const double v = PyFloat_AsDouble(value);
        if (PyErr_Occurred()) {
            return -1;
        }
        if (index < 0 || index > 65535 || fc_core_set_param(c, (uint16_t)index, (float)v) != FC_OK) {
            PyErr_Format(PyExc_ValueError, "bench_steps: parameter %ld = %g refused", index, v);
            return -1;
        }
    }
    return 0;
}

/* A hover with a small rate wobble at imu_hz and a barometer every 10th sample.
 * Bounded: n_imu and n_pwm calls. */
static PyObject *bench_steps(PyObject *module, PyObject *args, PyObject *kwds)
{
    (void)module;
    static char *kwlist[] = {"n_imu", "n_pwm", "imu_hz", "params", NULL};
    long long n_imu = 0, n_pwm = 0; /* missing ones fail the checks below */
    double imu_hz = 0.0;
    PyObject *params = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "|$LLdO", kwlist, &n_imu, &n_pwm, &imu_hz,
                                     &params)) {
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
    if (bench_params(c, params) != 0) {
        PyMem_Free(c);
        return NULL;
    }
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

/* The notch bank alone, at its worst: the centre moves at every 200 Hz update, so every
 * notch ramps its tuning on every sample (a throttle or ESC notch in a climb). */
static PyObject *bench_notch(PyObject *module, PyObject *args, PyObject *kwds)
{
    (void)module;
    static char *kwlist[] = {"n_imu", "imu_hz", "harmonics", "options", NULL};
    long long n_imu = 0; /* missing ones fail the checks below */
    double imu_hz = 0.0;
    unsigned long harmonics = 0;
    unsigned int options = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "|$LdkI", kwlist, &n_imu, &imu_hz, &harmonics,
                                     &options)) {
        return NULL;
    }
    if (n_imu < 1 || !(imu_hz > 0.0) || harmonics == 0 || harmonics > 0xFFFFul) {
        PyErr_SetString(PyExc_ValueError, "bench_notch needs n_imu >= 1, imu_hz > 0, harmonics 1..65535");
        return NULL;
    }
    fc_notch_t *n = PyMem_Malloc(sizeof *n);
    if (n == NULL) {
        return PyErr_NoMemory();
    }
    const fc_notch_config_t cfg = {true, FC_NOTCH_MODE_FIXED, (uint16_t)options,
                                   (uint32_t)harmonics, 40.0f, 20.0f, 40.0f, 0.0f, 1.0f};
    const float dt_s = (float)(1.0 / imu_hz);
    (void)fc_notch_init(n, &cfg, dt_s);
    const long long every = (long long)(0.005 * imu_hz + 0.5) > 0 ? (long long)(0.005 * imu_hz + 0.5) : 1;
    float v[3] = {0.0f, 0.0f, 0.0f};
    int64_t t0, t1;
    Py_BEGIN_ALLOW_THREADS  /* n is private to this call */
    t0 = fc_ext_monotonic_ns();
    for (long long i = 0; i < n_imu; i++) {
        if (i % every == 0) {
            /* 40..60 Hz and back over 1.3 s: every update moves, within the 5 % slew */
            const float hz = 50.0f + 10.0f * sinf((float)(i / every) * 0.025f);
            fc_notch_set_centers(n, 1, &hz, 0.005f);
        }
        const float x = 0.02f * sinf((float)(i & 1023) * (6.2831853f / 1024.0f));
        v[0] += x;
        v[1] -= x;
        v[2] = x;
        fc_notch_apply(n, v);
    }
    t1 = fc_ext_monotonic_ns();
    Py_END_ALLOW_THREADS
    const unsigned count = n->count;
    PyMem_Free(n);
    return Py_BuildValue("{s:d,s:I,s:d}", "notch_sample_ns", (double)(t1 - t0) / (double)n_imu,
                         "filters", count, "checksum", (double)(v[0] + v[1] + v[2]));
}

PyMethodDef fc_ext_bench_functions[] = {
    {"bench_steps", (PyCFunction)(void (*)(void))bench_steps, METH_VARARGS | METH_KEYWORDS,
     "bench_steps(n_imu=, n_pwm=, imu_hz=, params=None) -> {imu_step_ns, pwm_step_ns, ...} timed "
     "in C; params {index: value} set before the run."},
    {"bench_notch", (PyCFunction)(void (*)(void))bench_notch, METH_VARARGS | METH_KEYWORDS,
     "bench_notch(n_imu=, imu_hz=, harmonics=, options=0) -> {notch_sample_ns, filters}: the "
     "harmonic notch bank alone, retuned at every 200 Hz update, timed in C."},
    {NULL, NULL, 0, NULL},
};
