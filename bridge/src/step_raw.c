/*
 * step_raw.c - Kernel.bind_imu_raw / take_imu_raw: the CPython side of the chip's raw
 * samples (imu_raw.h). Python owns the rows (a numpy array of the log's 32-byte rows,
 * tools/logs/imu_raw_log.py) and takes what the steps wrote after each step or batch.
 */
#include "step_kernel.h"

/* bind_imu_raw(rows): write the chip's ODR samples into rows from the next step on;
 * None stops. Only a stage that runs the chip (vibration on) has them. */
PyObject *Kernel_bind_imu_raw(Kernel *self, PyObject *rows)
{
    sb_sensor_stage *s = &self->stage;
    sb_imu_raw_bind(&s->raw, NULL, 0, 1, self->dt_ns, 0.0, NULL, 0.0, 0.0);
    sb_step_release(&self->raw_view);
    if (rows == Py_None)
        Py_RETURN_NONE;
    if (s->c.vib.on == 0.0 || !s->scalar_imu) {
        PyErr_SetString(PyExc_ValueError, "raw IMU samples need the chip: a stage with "
                        "vibration on and one IMU sample per step");
        return NULL;
    }
    if (PyObject_GetBuffer(rows, &self->raw_view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    const Py_ssize_t cap = self->raw_view.len / (Py_ssize_t)sizeof(sb_imu_raw_row);
    if (cap < s->chip_n || ((uintptr_t)self->raw_view.buf & 7u) != 0) {
        sb_step_release(&self->raw_view);
        PyErr_Format(PyExc_ValueError, "rows must be 8-byte aligned and hold >= %d rows of "
                     "%zu bytes", s->chip_n, sizeof(sb_imu_raw_row));
        return NULL;
    }
    sb_imu_raw_bind(&s->raw, (sb_imu_raw_row *)self->raw_view.buf, (size_t)cap, s->chip_n,
                    self->dt_ns, s->c.imu.dt_s, s->c.imu_rot_on != 0.0 ? s->c.imu_rot : NULL,
                    s->c.imu.range_accel, s->c.imu.range_gyro);
    Py_RETURN_NONE;
}

/* take_imu_raw() -> (rows written since the last take, samples dropped in all). */
PyObject *Kernel_take_imu_raw(Kernel *self, PyObject *unused)
{
    (void)unused;
    const size_t n = sb_imu_raw_take(&self->stage.raw);
    return Py_BuildValue("(nK)", (Py_ssize_t)n, (unsigned long long)self->stage.raw.dropped);
}
