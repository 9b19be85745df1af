/*
 * fft_bench.c - the in-flight FFT's cost for `silbridge fc-bench`: each IMU sample's
 * fc_fft_push + fc_fft_step timed on its own in C, on a gyro stream with a rotor line
 * and noise, so the report shows the mean and the worst single call (the point of
 * spreading the work: no step pays for a whole FFT).
 */
#include "core_object.h"

#include <math.h>

static int cmp_i64(const void *a, const void *b)
{
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* A 97 Hz rotor line with its second harmonic on roll and pitch and a small
 * deterministic noise (an LCG: the bench must not depend on a seed elsewhere); the
 * first FC_BENCH_STILL_S are noise only, the vehicle on the ground while the FFT learns
 * its noise reference. */
#define FC_BENCH_STILL_S 3.0
static void gyro_sample(long long i, double imu_hz, uint32_t *lcg, float g[3])
{
    const double t = (double)i / imu_hz;
    const double on = t >= FC_BENCH_STILL_S ? 1.0 : 0.0;
    const double line = on * 0.05 * sin(2.0 * M_PI * 97.0 * t) + on * 0.08 * sin(4.0 * M_PI * 97.0 * t);
    for (int a = 0; a < 3; a++) {
        *lcg = *lcg * 1664525u + 1013904223u;
        const double noise = ((double)(*lcg >> 8) / 16777216.0 - 0.5) * 0.004;
        g[a] = (float)((a < 2 ? line : 0.3 * line) + noise);
    }
}

/* bench_fft(n_imu=, imu_hz=, window=, overlap=) -> {mean_ns, p99_ns, p999_ns, max_ns,
 * max_units, frames, tracked_hz}: per-call times of push + step, the clock's own cost
 * included; max_ns also holds whatever preempted the process. */
static PyObject *bench_fft(PyObject *module, PyObject *args, PyObject *kwds)
{
    (void)module;
    static char *kwlist[] = {"n_imu", "imu_hz", "window", "overlap", NULL};
    long long n = 0;
    double imu_hz = 0.0, overlap = 0.5;
    int window = 32;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "|$Ldid", kwlist, &n, &imu_hz, &window,
                                     &overlap)) {
        return NULL;
    }
    if (n < 1 || !(imu_hz > 0.0)) {
        PyErr_SetString(PyExc_ValueError, "bench_fft needs n_imu >= 1 and imu_hz > 0");
        return NULL;
    }
    fc_fft_t *f = PyMem_Malloc(sizeof *f);
    int64_t *dt = PyMem_Malloc(sizeof(int64_t) * (size_t)n);
    if (f == NULL || dt == NULL) {
        PyMem_Free(f);
        PyMem_Free(dt);
        return PyErr_NoMemory();
    }
    const fc_fft_config_t cfg = {.enable = true, .min_hz = 40.0f, .max_hz = 450.0f,
                                 .window_size = (uint16_t)window,
                                 .window_overlap = (float)overlap, .freq_hover_hz = 80.0f,
                                 .thr_ref = 0.35f, .snr_ref_db = 25.0f, .att_ref_db = 15.0f,
                                 .bw_hover_hz = 20.0f, .hmnc_fit_pct = 10.0f, .harmonics = 3,
                                 .notches = 1};
    fc_fft_init(f, &cfg, (float)imu_hz, (float)imu_hz);
    uint32_t lcg = 12345u;
    float g[3];
    double sum = 0.0;
    Py_BEGIN_ALLOW_THREADS /* f and dt are private to this call */
    for (long long i = 0; i < n; i++) {
        gyro_sample(i, imu_hz, &lcg, g);
        const int64_t t0 = fc_ext_monotonic_ns();
        fc_fft_push(f, g);
        fc_fft_step(f);
        dt[i] = fc_ext_monotonic_ns() - t0;
        sum += (double)dt[i];
    }
    qsort(dt, (size_t)n, sizeof dt[0], cmp_i64);
    Py_END_ALLOW_THREADS
    PyObject *res = Py_BuildValue("{s:d,s:L,s:L,s:L,s:k,s:k,s:d}", "mean_ns", sum / (double)n,
                                  "p99_ns", (long long)dt[(n * 99) / 100], "p999_ns",
                                  (long long)dt[(n * 999) / 1000], "max_ns",
                                  (long long)dt[n - 1], "max_units",
                                  (unsigned long)f->max_units, "frames",
                                  (unsigned long)f->frames_done, "tracked_hz",
                                  (double)fc_fft_center_freq_hz(f, 0.35f));
    PyMem_Free(f);
    PyMem_Free(dt);
    return res;
}

PyMethodDef fc_ext_fft_bench_functions[] = {
    {"bench_fft", (PyCFunction)(void (*)(void))bench_fft, METH_VARARGS | METH_KEYWORDS,
     "bench_fft(n_imu=, imu_hz=, window=32, overlap=0.5) -> {mean_ns, p99_ns, p999_ns, max_ns, "
     "max_units, frames, tracked_hz}: the in-flight FFT's push + step per IMU sample."},
    {NULL, NULL, 0, NULL},
};
