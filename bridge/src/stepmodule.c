/*
 * stepmodule.c - silbridge.bridge._step: one physics step of the bridge in one call.
 *
 * `Kernel.step(pwm)` writes the four pulse widths into JSBSim, runs it, reads the
 * state back through the property nodes' bound methods, and writes the step's
 * IMU, GT_ATT and GT_NAV records (64-byte sb_record slots) into the simulator's
 * step buffer, and the baro and magnetometer records when due. Done from Python
 * this costs ~6 us of interpreter work per step on top of JSBSim's ~5 us; here it
 * is the bare calls. What happens at 10 Hz or less or only on events (GNSS fixes,
 * setpoints, crash messages, noise blocks) stays in Python (bridge/simulator.py),
 * told by the returned flags.
 *
 * The maths are step_maths.c; the readable reference with the same interface is
 * bridge/step_python.py. Python objects the kernel calls are held as strong
 * references; the buffers it writes are held through Py_buffer views. The
 * methods that configure a kernel between steps are in step_config.c.
 */
#include "step_kernel.h"

void sb_step_release(Py_buffer *v)
{
    if (v->obj != NULL)
        PyBuffer_Release(v);
}

static int Kernel_traverse(Kernel *self, visitproc visit, void *arg)
{
    for (int f = 0; f < self->n_force_frames; f++)
        for (int i = 0; i < 3; i++)
            Py_VISIT(self->forces[f].set[i]);
    for (int i = 0; i < 4; i++)
        Py_VISIT(self->setters[i]);
    Py_VISIT(self->run);
    for (int i = 0; i < G_COUNT; i++)
        Py_VISIT(self->getters[i]);
    Py_VISIT(self->get_temp);
    return 0;
}

static int Kernel_clear(Kernel *self)
{
    for (int i = 0; i < 4; i++)
        Py_CLEAR(self->setters[i]);
    Py_CLEAR(self->run);
    for (int i = 0; i < G_COUNT; i++)
        Py_CLEAR(self->getters[i]);
    Py_CLEAR(self->get_temp);
    sb_step_clear_forces(self);
    return 0;
}

static void Kernel_dealloc(Kernel *self)
{
    PyObject_GC_UnTrack(self);
    Kernel_clear(self);
    sb_step_release(&self->buf_view);
    sb_step_release(&self->state_view);
    sb_step_release(&self->block_view);
    sb_step_release(&self->temps_view);
    sb_step_release(&self->baro.noise);
    sb_step_release(&self->mag.noise);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

int sb_step_take_callables(PyObject *seq, PyObject **out, Py_ssize_t n, const char *what)
{
    PyObject *fast = PySequence_Fast(seq, what);
    if (fast == NULL)
        return -1;
    if (PySequence_Fast_GET_SIZE(fast) != n) {
        PyErr_Format(PyExc_ValueError, "%s: need %zd callables, got %zd", what, n,
                     PySequence_Fast_GET_SIZE(fast));
        Py_DECREF(fast);
        return -1;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *f = PySequence_Fast_GET_ITEM(fast, i);
        if (!PyCallable_Check(f)) {
            PyErr_Format(PyExc_TypeError, "%s[%zd] is not callable", what, i);
            Py_DECREF(fast);
            return -1;
        }
        Py_INCREF(f);
        Py_XSETREF(out[i], f);
    }
    Py_DECREF(fast);
    return 0;
}

int sb_step_get_f64(PyObject *obj, Py_buffer *view, Py_ssize_t min_items, int writable,
                   const char *what)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0)
        return -1;
    if (view->itemsize != 8 || view->format == NULL || strcmp(view->format, "d") != 0 ||
        view->len / 8 < min_items) {
        PyErr_Format(PyExc_ValueError, "%s must be a contiguous float64 array of at least "
                     "%zd items", what, min_items);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* Kernel(buffer, setters, run, getters, state, consts, phase, dt_ns, flip_steps, scalar_imu,
 *        on_ground): on_ground is the contact state before the first step. */
static int Kernel_init(Kernel *self, PyObject *args, PyObject *kwds)
{
    PyObject *buf, *setters, *run, *getters, *state, *consts, *phase;
    long long dt_ns, flip_steps;
    int scalar_imu, on_ground;
    static char *kwlist[] = {"buffer", "setters", "run", "getters", "state", "consts",
                             "phase", "dt_ns", "flip_steps", "scalar_imu", "on_ground", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OOOOOOOLLpp", kwlist, &buf, &setters, &run,
                                     &getters, &state, &consts, &phase, &dt_ns, &flip_steps,
                                     &scalar_imu, &on_ground))
        return -1;
    if (self->buf_view.obj != NULL) {
        PyErr_SetString(PyExc_RuntimeError, "Kernel is already initialised");
        return -1;
    }
    if (sb_step_take_callables(setters, self->setters, 4, "setters") < 0 ||
        sb_step_take_callables(getters, self->getters, G_COUNT, "getters") < 0)
        return -1;
    if (!PyCallable_Check(run)) {
        PyErr_SetString(PyExc_TypeError, "run must be callable");
        return -1;
    }
    Py_INCREF(run);
    Py_XSETREF(self->run, run);
    if (PyObject_GetBuffer(buf, &self->buf_view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return -1;
    if (self->buf_view.len < 3 * (Py_ssize_t)sizeof(sb_record) ||
        ((uintptr_t)self->buf_view.buf & 7u) != 0) {
        PyErr_SetString(PyExc_ValueError, "buffer must be 8-byte aligned and hold >= 3 records");
        return -1;
    }
    self->slots = (sb_record *)self->buf_view.buf;
    self->n_slots = self->buf_view.len / (Py_ssize_t)sizeof(sb_record);
    if (sb_step_get_f64(state, &self->state_view, ST_COUNT, 1, "state") < 0)
        return -1;
    self->st = (double *)self->state_view.buf;
    Py_buffer cv, pv;
    if (sb_step_get_f64(consts, &cv, C_COUNT, 0, "consts") < 0)
        return -1;
    memcpy(self->c, cv.buf, sizeof self->c);
    PyBuffer_Release(&cv);
    if (sb_step_get_f64(phase, &pv, 4, 0, "phase") < 0)
        return -1;
    memcpy(self->phase, pv.buf, sizeof self->phase);
    PyBuffer_Release(&pv);
    if (dt_ns <= 0 || flip_steps <= 0) {
        PyErr_SetString(PyExc_ValueError, "dt_ns and flip_steps must be > 0");
        return -1;
    }
    self->imu.dt_s = self->c[C_DT_S];
    self->imu.inv_omega_max2 = self->c[C_INV_OMEGA_MAX2];
    self->imu.vib_accel = self->c[C_VIB_A];
    self->imu.vib_gyro = self->c[C_VIB_G];
    self->imu.range_accel = self->c[C_RANGE_A];
    self->imu.range_gyro = self->c[C_RANGE_G];
    self->dt_ns = dt_ns;
    self->flip_steps = flip_steps;
    self->scalar_imu = scalar_imu;
    self->next_slow_ns = 0;
    self->was_on_ground = on_ground;
    return 0;
}

/* Call a bound getter; -1 with an exception set on failure. */
static inline int get(Kernel *self, int i, double *out)
{
    PyObject *r = PyObject_CallNoArgs(self->getters[i]);
    if (r == NULL)
        return -1;
    *out = PyFloat_AsDouble(r);
    Py_DECREF(r);
    if (*out == -1.0 && PyErr_Occurred())
        return -1;
    return 0;
}

static inline void header(sb_record *r, uint16_t kind, uint32_t seq, int64_t sim_ns)
{
    r->h.kind = kind;
    r->h.flags = 0;
    r->h.seq = seq;
    r->h.sim_ns = sim_ns;
    r->h.wall_ns = 0;
}

static long step_seq(Kernel *self, PyObject *pwm, Py_ssize_t first);

/* Disturbance forces at the start time of step k into their frames' directions. */
static int apply_forces(Kernel *self, int64_t k)
{
    const double t_s = (double)((k - 1) * self->dt_ns) * 1e-9;
    for (int f = 0; f < self->n_force_frames; f++) {
        const force_frame_t *fr = &self->forces[f];
        double v[3] = {0.0, 0.0, 0.0};
        for (Py_ssize_t i = 0; i < fr->n; i++) {
            const force_item_t *it = &fr->items[i];
            const double f_n =
                it->c_n * (it->periodic ? sin(it->w_rad_s * (t_s - it->t_on_s) + it->phase_rad)
                                        : 1.0);
            v[0] += f_n * it->axis[0];
            v[1] += f_n * it->axis[1];
            v[2] += f_n * it->axis[2];
        }
        for (int j = 0; j < 3; j++) {
            PyObject *x = PyFloat_FromDouble(v[j]);
            if (x == NULL)
                return -1;
            PyObject *r = PyObject_CallOneArg(fr->set[j], x);
            Py_DECREF(x);
            if (r == NULL)
                return -1;
            Py_DECREF(r);
        }
    }
    return 0;
}

/* Run one step; write GT (and the scalar IMU) records from slot `first`; return flags. */
static long do_step(Kernel *self, PyObject *pwm, Py_ssize_t first)
{
    /* A tuple passes through PySequence_Fast untouched; lists work too. */
    PyObject *seq = PySequence_Fast(pwm, "pwm must be a sequence of 4 pulse widths [us]");
    if (seq == NULL)
        return -1;
    long flags = step_seq(self, seq, first);
    Py_DECREF(seq);
    return flags;
}

static long step_seq(Kernel *self, PyObject *pwm, Py_ssize_t first)
{
    if (PySequence_Fast_GET_SIZE(pwm) != 4) {
        PyErr_SetString(PyExc_TypeError, "pwm must hold 4 pulse widths [us]");
        return -1;
    }
    const int64_t k = self->step_index + 1;
    for (int i = 0; i < 4; i++) {
        PyObject *v = PySequence_Fast_GET_ITEM(pwm, i);
        double d = PyFloat_AsDouble(v);
        if (d == -1.0 && PyErr_Occurred())
            return -1;
        if (d != d) {   /* NaN: a bug upstream, never fly it */
            PyObject *lst = PySequence_List(pwm);
            PyErr_Format(PyExc_ValueError, "PWM command contains NaN at step %lld: %R",
                         (long long)k, lst);
            Py_XDECREF(lst);
            return -1;
        }
    }
    for (int i = 0; i < 4; i++) {
        PyObject *r = PyObject_CallOneArg(self->setters[i], PySequence_Fast_GET_ITEM(pwm, i));
        if (r == NULL)
            return -1;
        Py_DECREF(r);
    }
    if (self->n_force_frames && apply_forces(self, k) < 0)
        return -1;
    PyObject *r = PyObject_CallNoArgs(self->run);
    if (r == NULL)
        return -1;
    Py_DECREF(r);
    self->step_index = k;
    const int64_t sim_ns = k * self->dt_ns;

    double g[G_COUNT];
    for (int i = 0; i < G_COUNT; i++)
        if (get(self, i, &g[i]) < 0)
            return -1;
    const double *c = self->c;
    double *st = self->st;
    const double w[3] = {g[G_P], g[G_Q], g[G_R]};
    const double lbf = c[C_LBF_TO_M_S2];
    const double af[3] = {g[G_FBX] * lbf, g[G_FBY] * lbf, g[G_FBZ] * lbf};
    const double ft = c[C_FT_M];
    const double vn = g[G_VN] * ft, ve = g[G_VE] * ft, vd = g[G_VD] * ft;
    const double hagl_m = g[G_HAGL] * ft;
    const int on_ground = g[G_GEAR] > 0.0;
    st[ST_BARO_PA] += c[C_BARO_ALPHA] * (g[G_PRESSURE] * c[C_PSF_PA] - st[ST_BARO_PA]);
    double q[4];
    sb_quat_from_euler(g[G_PHI], g[G_THETA], g[G_PSI], q);
    const double pn = (g[G_LAT] - c[C_LAT0]) * c[C_M_LAT];
    const double pe = (g[G_LON] - c[C_LON0]) * c[C_M_LON];
    const double pd = sb_quant_down_m(c[C_AGL0] - hagl_m);

    long flags = 0;
    Py_ssize_t slot = first;
    if (self->scalar_imu) {
        if (!self->have_block || self->pos >= self->rows) {
            PyErr_SetString(PyExc_RuntimeError, "no IMU noise block: call set_block first");
            return -1;
        }
        const double *stoch = (const double *)self->block_view.buf + 6 * self->pos;
        const double temp_c = ((const double *)self->temps_view.buf)[self->pos];
        self->pos++;
        if (self->pos >= self->rows)
            flags |= F_BLOCK_DONE;
        double out[6];
        sb_imu_scalar(&self->imu, af, w, &g[G_O1], self->phase, stoch, self->injected, out);
        st[ST_TEMP_C] = temp_c;
        sb_record *rec = &self->slots[slot++];
        header(rec, SB_KIND_IMU, self->seq_imu++, sim_ns);
        for (int i = 0; i < 3; i++) {
            rec->u.imu.accel_frd_m_s2[i] = (float)out[i];
            rec->u.imu.gyro_frd_rad_s[i] = (float)out[i + 3];
        }
        rec->u.imu.temperature_c = (float)temp_c;
        rec->u.imu.sample_index = 0;
        rec->u.imu.samples_per_step = 1;
        rec->u.imu.reserved = 0;
    }
    if (slot + 4 > self->n_slots) {
        PyErr_SetString(PyExc_ValueError, "step buffer too small for the ground truth, "
                                          "baro and mag records");
        return -1;
    }
    sb_record *ra = &self->slots[slot++];
    header(ra, SB_KIND_GT_ATT, self->seq_att++, sim_ns);
    for (int i = 0; i < 4; i++)
        ra->u.gt_att.q_wxyz[i] = (float)q[i];
    for (int i = 0; i < 3; i++) {
        ra->u.gt_att.rates_frd_rad_s[i] = (float)w[i];
        ra->u.gt_att.specific_force_frd_m_s2[i] = (float)af[i];
    }
    sb_record *rn = &self->slots[slot++];
    header(rn, SB_KIND_GT_NAV, self->seq_nav++, sim_ns);
    memset(rn->u.raw, 0, sizeof rn->u.raw);
    rn->u.gt_nav.pos_ned_m[0] = pn;
    rn->u.gt_nav.pos_ned_m[1] = pe;
    rn->u.gt_nav.pos_ned_m[2] = pd;
    /* Truth as HIL_STATE_QUATERNION carries it (whole mm, whole cm/s) on every transport. */
    rn->u.gt_nav.vel_ned_m_s[0] = (float)sb_quant_velocity_m_s(vn);
    rn->u.gt_nav.vel_ned_m_s[1] = (float)sb_quant_velocity_m_s(ve);
    rn->u.gt_nav.vel_ned_m_s[2] = (float)sb_quant_velocity_m_s(vd);
    rn->u.gt_nav.on_ground = (uint8_t)on_ground;

    /* Leave the state for Python's low-rate sensors, summaries and the block IMU path. */
    for (int i = 0; i < 3; i++) {
        st[ST_W + i] = w[i];
        st[ST_F + i] = af[i];
    }
    st[ST_EULER] = g[G_PHI];
    st[ST_EULER + 1] = g[G_THETA];
    st[ST_EULER + 2] = g[G_PSI];
    st[ST_VEL] = vn;
    st[ST_VEL + 1] = ve;
    st[ST_VEL + 2] = vd;
    st[ST_LAT] = g[G_LAT];
    st[ST_LON] = g[G_LON];
    st[ST_HAGL] = hagl_m;
    for (int i = 0; i < 4; i++)
        st[ST_OMEGA + i] = g[G_O1 + i];
    st[ST_ON_GROUND] = on_ground;

    /* Ground contact and crash detection; Python words the messages. */
    st[ST_PREV_VD] = self->prev_vd;
    if (on_ground != self->was_on_ground) {
        flags |= F_GROUND_CHANGED;
        self->was_on_ground = on_ground;
    }
    self->prev_vd = vd;
    const double cos_tilt = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]);
    st[ST_COS_TILT] = cos_tilt;
    if (on_ground && cos_tilt < c[C_COS_CRASH_TILT])
        flags |= F_TIPPED;
    if (cos_tilt < 0.0) {
        if (++self->upside_down_steps >= self->flip_steps)
            flags |= F_FLIPPED;
    } else {
        self->upside_down_steps = 0;
    }
    if (hagl_m < c[C_STRIKE_AGL] && sb_rotor_strike(g[G_PHI], g[G_THETA], hagl_m))
        flags |= F_ROTOR_STRIKE;
    /* Baro then mag, when due (the contract's order: then GNSS, SETPOINT from Python). */
    if (self->baro.on && sim_ns >= self->baro.next_ns) {
        if (self->baro.pos >= self->baro.rows) {
            PyErr_SetString(PyExc_RuntimeError, "no baro noise: call set_baro_block first");
            return -1;
        }
        double temp_r;
        PyObject *t = PyObject_CallNoArgs(self->get_temp);
        if (t == NULL)
            return -1;
        temp_r = PyFloat_AsDouble(t);
        Py_DECREF(t);
        if (temp_r == -1.0 && PyErr_Occurred())
            return -1;
        lowrate_t *b = &self->baro;
        b->next_ns = sb_due_ns(++b->m, b->rate_hz);
        const double n = ((const double *)b->noise.buf)[b->pos++];
        if (b->pos >= b->rows)
            flags |= F_BARO_BLOCK_DONE;
        const double pa = st[ST_BARO_PA] + self->baro_offset_pa + self->baro_noise_pa * n;
        sb_record *r = &self->slots[slot++];
        header(r, SB_KIND_BARO, b->seq++, sim_ns);
        memset(r->u.raw, 0, sizeof r->u.raw);
        r->u.baro.pressure_pa = (float)sb_quant_pressure_pa(pa);
        r->u.baro.temperature_c = (float)(temp_r / 1.8 - 273.15);
    }
    if (self->mag.on && sim_ns >= self->mag.next_ns) {
        lowrate_t *m = &self->mag;
        if (m->pos >= m->rows) {
            PyErr_SetString(PyExc_RuntimeError, "no mag noise: call set_mag_block first");
            return -1;
        }
        m->next_ns = sb_due_ns(++m->m, m->rate_hz);
        const double *n = (const double *)m->noise.buf + 3 * m->pos++;
        if (m->pos >= m->rows)
            flags |= F_MAG_BLOCK_DONE;
        double b[3];
        sb_ned_to_frd(g[G_PHI], g[G_THETA], g[G_PSI], self->mag_field_ned, b);
        sb_record *r = &self->slots[slot++];
        header(r, SB_KIND_MAG, m->seq++, sim_ns);
        memset(r->u.raw, 0, sizeof r->u.raw);
        for (int i = 0; i < 3; i++)
            r->u.mag.field_frd_gauss[i] =
                (float)(b[i] + self->mag_offset[i] + self->mag_noise_gauss * n[i]);
    }
    if (sim_ns >= self->next_slow_ns)
        flags |= F_SLOW_DUE;
    else   /* nothing more this step: the last record closes it */
        self->slots[slot - 1].h.flags = SB_FLAG_STEP_END;
    return flags | (long)(slot - first);
}

static PyObject *Kernel_step(Kernel *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 1) {
        PyErr_SetString(PyExc_TypeError, "step(pwm) takes one tuple of 4 pulse widths");
        return NULL;
    }
    if (!self->scalar_imu) {
        PyErr_SetString(PyExc_RuntimeError, "this kernel writes no IMU: use step_gt(pwm, slot)");
        return NULL;
    }
    long f = do_step(self, args[0], 0);
    return f < 0 ? NULL : PyLong_FromLong(f);
}

static PyObject *Kernel_step_gt(Kernel *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "step_gt(pwm, slot)");
        return NULL;
    }
    if (self->scalar_imu) {
        PyErr_SetString(PyExc_RuntimeError, "this kernel writes the IMU: use step(pwm)");
        return NULL;
    }
    Py_ssize_t slot = PyLong_AsSsize_t(args[1]);
    if (slot == -1 && PyErr_Occurred())
        return NULL;
    if (slot < 0 || slot + 2 > self->n_slots) {
        PyErr_Format(PyExc_ValueError, "slot %zd outside the step buffer", slot);
        return NULL;
    }
    long f = do_step(self, args[0], slot);
    return f < 0 ? NULL : PyLong_FromLong(f);
}

static PyMethodDef Kernel_methods[] = {
    {"step", (PyCFunction)(void (*)(void))Kernel_step, METH_FASTCALL,
     "step(pwm) -> flags: run one physics step, write IMU, GT_ATT, GT_NAV from slot 0"},
    {"step_gt", (PyCFunction)(void (*)(void))Kernel_step_gt, METH_FASTCALL,
     "step_gt(pwm, slot) -> flags: run one physics step, write GT_ATT, GT_NAV at slot"},
    {"set_block", (PyCFunction)Kernel_set_block, METH_VARARGS,
     "set_block(block (rows, 6), temps (rows)): the next IMU noise rows"},
    {"set_injected", (PyCFunction)(void (*)(void))Kernel_set_injected, METH_FASTCALL,
     "set_injected(x, y, z): injected gyro bias FRD [rad/s]"},
    {"seqs", (PyCFunction)Kernel_seqs, METH_NOARGS,
     "records written: (imu, gt_att, gt_nav, baro, mag)"},
    {"configure_baro", (PyCFunction)Kernel_configure_baro, METH_VARARGS,
     "configure_baro(rate_hz, offset_pa, noise_pa, get_temp): sample the baro here"},
    {"configure_mag", (PyCFunction)Kernel_configure_mag, METH_VARARGS,
     "configure_mag(rate_hz, field_ned, offset, noise_gauss): sample the mag here"},
    {"set_baro_block", (PyCFunction)Kernel_set_baro_block, METH_O,
     "set_baro_block((rows, 1) float64 standard normals)"},
    {"set_mag_block", (PyCFunction)Kernel_set_mag_block, METH_O,
     "set_mag_block((rows, 3) float64 standard normals)"},
    {"set_forces", (PyCFunction)Kernel_set_forces, METH_O,
     "set_forces([(setters, [(c_n, w_rad_s, t_on_s, phase_rad, periodic, axis)])]): the "
     "disturbance forces written before each run() (bridge/disturbances.py)"},
    {NULL, NULL, 0, NULL}};

static PyTypeObject KernelType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "silbridge.bridge._step.Kernel",
    .tp_basicsize = sizeof(Kernel),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "One bridge physics step in C (see bridge/simulator.py)",
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)Kernel_init,
    .tp_dealloc = (destructor)Kernel_dealloc,
    .tp_traverse = (traverseproc)Kernel_traverse,
    .tp_clear = (inquiry)Kernel_clear,
    .tp_methods = Kernel_methods,
    .tp_getset = sb_step_getset,
};

static struct PyModuleDef stepmodule = {
    PyModuleDef_HEAD_INIT, "_step", "The bridge's per-step C kernel", -1, NULL,
    NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__step(void)
{
    if (PyType_Ready(&KernelType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&stepmodule);
    if (m == NULL)
        return NULL;
    Py_INCREF(&KernelType);
    if (PyModule_AddObject(m, "Kernel", (PyObject *)&KernelType) < 0) {
        Py_DECREF(&KernelType);
        Py_DECREF(m);
        return NULL;
    }
    struct { const char *name; long v; } ints[] = {
        {"F_SLOW_DUE", F_SLOW_DUE}, {"F_BLOCK_DONE", F_BLOCK_DONE},
        {"F_GROUND_CHANGED", F_GROUND_CHANGED}, {"F_TIPPED", F_TIPPED},
        {"F_FLIPPED", F_FLIPPED}, {"F_ROTOR_STRIKE", F_ROTOR_STRIKE},
        {"F_BARO_BLOCK_DONE", F_BARO_BLOCK_DONE}, {"F_MAG_BLOCK_DONE", F_MAG_BLOCK_DONE},
        {"ST_COUNT", ST_COUNT}, {"G_COUNT", G_COUNT}, {"C_COUNT", C_COUNT}};
    for (size_t i = 0; i < sizeof ints / sizeof ints[0]; i++)
        if (PyModule_AddIntConstant(m, ints[i].name, ints[i].v) < 0) {
            Py_DECREF(m);
            return NULL;
        }
    return m;
}
