/*
 * core_layout.c - what the compiled core declares, exported for Python to check against
 * its own copies: the C parameter table (fc_sil/params.py reads the declarations, tests
 * compare the two) and the layout of fc_core_status_t (tests compare every offset with
 * fc_sil.STATUS_DTYPE, and the record size with shm's).
 */
#include "core_object.h"

#include <stddef.h>

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

PyMethodDef fc_ext_layout_functions[] = {
    {"param_table", param_table, METH_NOARGS,
     "[(name, index, type, offset, min, max, default)] of the C parameter table."},
    {"status_layout", status_layout, METH_NOARGS, "Offsets and sizes of fc_core_status_t."},
    {NULL, NULL, 0, NULL},
};
