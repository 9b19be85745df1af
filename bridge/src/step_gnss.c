/*
 * step_gnss.c - the Kernel methods of the C GNSS (gnss_model.h): Python configures it once
 * (configure_gnss), gives it noise blocks (set_gnss_block) and hands the model's state to
 * it and back (gnss_take, gnss_give) as bridge/gnss_kernel.py decides: the stage makes
 * the epochs while it holds the state, Python's lowrate.Gnss does otherwise.
 */
#include "step_kernel.h"

/* configure_gnss(*, rate_hz, latency_ns, sigma_ned_m, tau_s, vel_sigma_m_s, m_per_rad_lat,
 * m_per_rad_lon, ground_alt_m, eph_cm, epv_cm, fix_type, satellites): lowrate.Gnss's
 * constants, in its units. The model stays off until gnss_take. */
PyObject *Kernel_configure_gnss(Kernel *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"rate_hz", "latency_ns", "sigma_ned_m", "tau_s", "vel_sigma_m_s",
                             "m_per_rad_lat", "m_per_rad_lon", "ground_alt_m", "eph_cm",
                             "epv_cm", "fix_type", "satellites", NULL};
    sb_gnss_cfg c;
    double rate;
    long long latency;
    int eph, epv, fix, sats;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "$dL(ddd)dddddiiii", kwlist, &rate,
                                     &latency, &c.sigma_ned_m[0], &c.sigma_ned_m[1],
                                     &c.sigma_ned_m[2], &c.tau_s, &c.vel_sigma_m_s,
                                     &c.m_per_rad_lat, &c.m_per_rad_lon, &c.ground_alt_m, &eph,
                                     &epv, &fix, &sats))
        return NULL;
    if (!(rate > 0.0) || !(c.tau_s > 0.0) || latency < 0 || eph < 0 || eph > 65535 ||
        epv < 0 || epv > 65535 || fix < 0 || fix > 255 || sats < 0 || sats > 255) {
        PyErr_SetString(PyExc_ValueError, "configure_gnss: rate_hz, tau_s > 0, latency_ns >= 0, "
                                          "eph_cm, epv_cm 0..65535, fix_type, satellites 0..255");
        return NULL;
    }
    c.latency_ns = latency;
    c.eph_cm = (uint16_t)eph;
    c.epv_cm = (uint16_t)epv;
    c.fix_type = (uint8_t)fix;
    c.satellites = (uint8_t)sats;
    sb_gnss_model *g = &self->stage.gnss;
    memset(g, 0, sizeof *g);
    sb_step_release(&self->gnss_noise);   /* the model points at no block now */
    g->c = c;
    sb_lowrate_start(&g->lr, rate);
    Py_RETURN_NONE;
}

/* set_gnss_block(block, pos): the (rows, 6) standard normals the epochs read from row pos
 * on (Python's NormalRows block, where its stream stands). */
PyObject *Kernel_set_gnss_block(Kernel *self, PyObject *args)
{
    PyObject *arr;
    Py_ssize_t pos;
    if (!PyArg_ParseTuple(args, "On", &arr, &pos))
        return NULL;
    return sb_step_set_noise(&self->stage.gnss.lr, &self->gnss_noise, arr, 6, pos,
                             "GNSS noise") < 0 ? NULL : Py_NewRef(Py_None);
}

/* gnss_take(m, err_ned_m or None, last_epoch_ns, seq): the stage makes the epochs from
 * epoch m on, with Python's model state and the GNSS records' next sequence number. */
PyObject *Kernel_gnss_take(Kernel *self, PyObject *args)
{
    long long m, last;
    unsigned long seq;
    PyObject *err;
    if (!PyArg_ParseTuple(args, "LOLk", &m, &err, &last, &seq))
        return NULL;
    sb_gnss_model *g = &self->stage.gnss;
    if (!g->lr.on || g->lr.noise == NULL || m < 1) {
        PyErr_SetString(PyExc_RuntimeError, "gnss_take: configure_gnss and set_gnss_block "
                                            "first, and m >= 1");
        return NULL;
    }
    double e[3] = {0.0, 0.0, 0.0};
    const int have = err != Py_None;
    if (have && !PyArg_ParseTuple(err, "ddd", &e[0], &e[1], &e[2]))
        return NULL;
    g->lr.m = m;
    g->lr.next_ns = sb_due_ns(m, g->lr.rate_hz);
    g->have_err = have;
    memcpy(g->err_ned_m, e, sizeof e);
    g->last_epoch_ns = last;
    g->lr.seq = (uint32_t)seq;
    g->in_c = 1;
    Py_RETURN_NONE;
}

/* gnss_give() -> (m, err_ned_m or None, last_epoch_ns, pos, seq): the state back to
 * Python, which makes the epochs from m on; the stage stops making them. */
PyObject *Kernel_gnss_give(Kernel *self, PyObject *Py_UNUSED(ignored))
{
    sb_gnss_model *g = &self->stage.gnss;
    if (!g->in_c) {
        PyErr_SetString(PyExc_RuntimeError, "gnss_give: the C GNSS is not on (gnss_take)");
        return NULL;
    }
    PyObject *err = g->have_err ? Py_BuildValue("(ddd)", g->err_ned_m[0], g->err_ned_m[1],
                                                g->err_ned_m[2])
                                : Py_NewRef(Py_None);
    if (err == NULL)
        return NULL;
    PyObject *state = Py_BuildValue("(LNLnk)", (long long)g->lr.m, err,
                                    (long long)g->last_epoch_ns, (Py_ssize_t)g->lr.pos,
                                    (unsigned long)g->lr.seq);
    if (state != NULL)   /* the stage stops only once Python has the state to go on with */
        g->in_c = 0;
    return state;
}

PyObject *Kernel_get_gnss_on(Kernel *self, void *closure)
{
    (void)closure;
    return PyBool_FromLong(self->stage.gnss.in_c);
}

PyObject *Kernel_get_gnss_seq(Kernel *self, void *closure)
{
    (void)closure;
    return PyLong_FromUnsignedLong(self->stage.gnss.lr.seq);
}
