/*
 * core_bench.c - the micro-benchmark behind `silbridge fc-bench`: fc_core_imu_step and
 * fc_core_pwm_step timed in C, on a private core that is armed and flying (every block
 * runs), so the figure is the core's cost without the interpreter's.
 */
#include "core_object.h"

#include <math.h>

/* A hover with a small rate wobble at imu_hz and a barometer every 10th sample.
 * Bounded: n_imu and n_pwm calls. */
static PyObject *bench_steps(PyObject *module, PyObject *args, PyObject *kwds)
{
    (void)module;
    static char *kwlist[] = {"n_imu", "n_pwm", "imu_hz", NULL};
    long long n_imu, n_pwm;
    double imu_hz;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "$LLd", kwlist, &n_imu, &n_pwm, &imu_hz)) {
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

PyMethodDef fc_ext_bench_functions[] = {
    {"bench_steps", (PyCFunction)(void (*)(void))bench_steps, METH_VARARGS | METH_KEYWORDS,
     "bench_steps(n_imu=, n_pwm=, imu_hz=) -> {imu_step_ns, pwm_step_ns, ...} timed in C."},
    {NULL, NULL, 0, NULL},
};
