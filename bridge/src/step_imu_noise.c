/*
 * step_imu_noise.c - silbridge.bridge._step.imu_noise_rows, the Python face of
 * imu_noise.h: numpy arrays in, the walk's last row and the two outputs written in place.
 */
#include "step_kernel.h"

#include "imu_noise.h"

/* imu_noise_rows(inc, white, temps, turn_on, tempco, temp_ref_c, last, slow, out): inc,
 * white, slow, out (rows, 6) float64, temps (rows), turn_on, tempco, last (6); C-contiguous. */
PyObject *sb_step_imu_noise_rows(PyObject *mod, PyObject *args)
{
    (void)mod;
    PyObject *o[8];
    double ref;
    if (!PyArg_ParseTuple(args, "OOOOOdOOO", &o[0], &o[1], &o[2], &o[3], &o[4], &ref, &o[5],
                          &o[6], &o[7]))
        return NULL;
    static const char *what[8] = {"inc", "white", "temps", "turn_on", "tempco", "last",
                                  "slow", "out"};
    static const int writable[8] = {0, 0, 0, 0, 0, 1, 1, 1};
    Py_buffer v[8];
    int got = 0;
    PyObject *ret = NULL;
    for (; got < 8; got++)
        if (sb_step_get_f64(o[got], &v[got], 0, writable[got], what[got]) < 0)
            goto done;
    const Py_ssize_t n = v[0].len / 8;
    if (n % 6 != 0 || v[1].len != v[0].len || v[6].len != v[0].len || v[7].len != v[0].len ||
        v[2].len / 8 != n / 6 || v[3].len != 48 || v[4].len != 48 || v[5].len != 48) {
        PyErr_SetString(PyExc_ValueError, "imu_noise_rows: inc, white, slow, out (rows, 6), "
                                          "temps (rows), turn_on, tempco, last (6)");
        goto done;
    }
    sb_imu_noise_rows((size_t)(n / 6), v[0].buf, v[1].buf, v[2].buf, v[3].buf, v[4].buf, ref,
                      v[5].buf, v[6].buf, v[7].buf);
    ret = Py_NewRef(Py_None);
done:
    for (int i = 0; i < got; i++)
        PyBuffer_Release(&v[i]);
    return ret;
}
