/*
 * step_json.c - silbridge.bridge._step.json_reply: a physics step's records ->
 * ArduPilot SITL's JSON state line, in one call.
 *
 * ArduPilot SITL's JSON interface is a lockstep round trip per 1 ms physics
 * frame, so every microsecond between its servo packet and our reply is a
 * microsecond of SITL's frame time. Done in Python (tests/bridge/json_reply_oracle.py
 * reads the records with struct, averages the IMU, converts the quaternion and
 * %-formats the line) this costs ~10 us per packet on the 2-core VM, as much as
 * the JSBSim step itself; here it is ~1 us. The Python path stays as the readable
 * reference: tests/bridge/test_json_reply.py checks the two lines are the
 * same bytes.
 *
 * The numbers are formatted by CPython's own float formatter (repr, with its
 * ".0", for the timestamp; %.9g / %.12g for the rest), so the bytes equal the Python
 * reference's exactly, not merely the values.
 */
#include "step_kernel.h"

/* The reply's values, in the line's order (bridge/autopilots/ardupilot/json_protocol.py _STATE_FMT). */
enum { V_TIME, V_GYRO, V_ACCEL = 4, V_POS = 7, V_EULER = 10, V_QUAT = 13, V_VEL = 17, V_COUNT = 20 };

/* Keys and separators before each value; digits per value (0 = repr). */
static const char *const LEAD[V_COUNT] = {
    "\n{\"timestamp\":", "{\"gyro\":[" /* after "imu": */, ",", ",", "],\"accel_body\":[", ",", ",",
    "]},\"position\":[", ",", ",", "],\"attitude\":[", ",", ",", "],\"quaternion\":[", ",", ",", ",",
    "],\"velocity\":[", ",", ","};
static const int DIGITS[V_COUNT] = {0, 9, 9, 9, 9, 9, 9, 12, 12, 12, 9, 9, 9, 9, 9, 9, 9, 12, 12, 12};

/* Fill v from the step's records: IMU* (averaged), then GT_ATT, GT_NAV. -1 with
 * ValueError if the records break that order (simulator.py and this file disagree). */
static int read_step(const sb_record *r, Py_ssize_t n, double t_s, double *v)
{
    double a[3] = {0, 0, 0}, g[3] = {0, 0, 0};
    Py_ssize_t i = 0;
    for (; i < n && r[i].h.kind == SB_KIND_IMU; i++)
        for (int k = 0; k < 3; k++) {
            a[k] += r[i].u.imu.accel_frd_m_s2[k];
            g[k] += r[i].u.imu.gyro_frd_rad_s[k];
        }
    Py_ssize_t imu = i;
    if (i + 1 >= n || r[i].h.kind != SB_KIND_GT_ATT || r[i + 1].h.kind != SB_KIND_GT_NAV) {
        PyErr_SetString(PyExc_ValueError,
                        "json_reply: step records out of contract order (IMU*, GT_ATT, GT_NAV): "
                        "bridge/simulator.py and bridge/src/step_json.c disagree");
        return -1;
    }
    const sb_gt_att *att = &r[i].u.gt_att;
    const sb_gt_nav *nav = &r[i + 1].u.gt_nav;
    v[V_TIME] = t_s;
    if (imu) {
        /* the mean of the step's samples: a boxcar decimation, as an IMU FIFO read */
        double k = 1.0 / (double)imu;
        for (int j = 0; j < 3; j++) {
            v[V_GYRO + j] = g[j] * k;
            v[V_ACCEL + j] = a[j] * k;
        }
    } else {
        /* an IMU slower than the physics: truth this step (its sample comes later) */
        for (int j = 0; j < 3; j++) {
            v[V_GYRO + j] = att->rates_frd_rad_s[j];
            v[V_ACCEL + j] = att->specific_force_frd_m_s2[j];
        }
    }
    double w = att->q_wxyz[0], x = att->q_wxyz[1], y = att->q_wxyz[2], z = att->q_wxyz[3];
    /* ZYX Euler of the body FRD -> NED quaternion, as euler_from_quat in Python */
    double sp = 2.0 * (w * y - z * x);
    v[V_EULER] = atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
    v[V_EULER + 1] = asin(sp < -1.0 ? -1.0 : (sp > 1.0 ? 1.0 : sp));
    v[V_EULER + 2] = atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
    for (int j = 0; j < 4; j++)
        v[V_QUAT + j] = att->q_wxyz[j];
    for (int j = 0; j < 3; j++) {
        v[V_POS + j] = nav->pos_ned_m[j];
        v[V_VEL + j] = nav->vel_ned_m_s[j];
    }
    return 0;
}

/* json_reply(records, sim_ns) -> bytes, or None if a value is not finite (the
 * caller raises: SITL's atof would read NaN as 0 or garbage). */
PyObject *sb_step_json_reply(PyObject *mod, PyObject *const *args, Py_ssize_t nargs)
{
    (void)mod;
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "json_reply(records, sim_ns) takes 2 arguments");
        return NULL;
    }
    long long sim_ns = PyLong_AsLongLong(args[1]);
    if (sim_ns == -1 && PyErr_Occurred())
        return NULL;
    Py_buffer view;
    if (PyObject_GetBuffer(args[0], &view, PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    double v[V_COUNT];
    int rc = view.len % SB_RECORD_SIZE ? -2
             : read_step((const sb_record *)view.buf, view.len / SB_RECORD_SIZE,
                         (double)sim_ns / 1e9, v);
    PyBuffer_Release(&view);
    if (rc == -2)
        PyErr_SetString(PyExc_ValueError, "json_reply: records buffer is not whole 64-byte slots");
    if (rc)
        return NULL;
    for (int i = 0; i < V_COUNT; i++)
        if (!isfinite(v[i]))
            Py_RETURN_NONE;
    char line[1024];
    size_t len = 0;
    for (int i = 0; i < V_COUNT; i++) {
        size_t lead = strlen(LEAD[i]);
        if (i == V_GYRO) {   /* the imu object opens here */
            memcpy(line + len, ",\"imu\":", 7);
            len += 7;
        }
        memcpy(line + len, LEAD[i], lead);
        len += lead;
        char *num = DIGITS[i] ? PyOS_double_to_string(v[i], 'g', DIGITS[i], 0, NULL)
                              : PyOS_double_to_string(v[i], 'r', 0, Py_DTSF_ADD_DOT_0, NULL);
        if (num == NULL)
            return NULL;
        size_t nl = strlen(num);
        memcpy(line + len, num, nl);   /* <= 25 chars each: 20 * (25 + 20) < 1024 */
        len += nl;
        PyMem_Free(num);
    }
    memcpy(line + len, "]}\n", 3);
    len += 3;
    return PyBytes_FromStringAndSize(line, (Py_ssize_t)len);
}
