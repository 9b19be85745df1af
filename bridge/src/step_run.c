/*
 * step_run.c - one physics step of the bridge kernel (stepmodule.c has the Python
 * object around it): write the pulse widths and the disturbance forces into JSBSim,
 * run it, read the state back through the bound getters, and write the step's
 * records (scalar IMU, GT_ATT, GT_NAV, then baro and mag when due) into the step
 * buffer. The returned flags tell Python what it handles itself (bridge/simulator.py).
 *
 * Built with -ffp-contract=off like the whole extension: every double must be the
 * one bridge/step_python.py computes (tests/bridge/test_step_kernel.py).
 */
#include "step_kernel.h"

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
long sb_step_run(Kernel *self, PyObject *pwm, Py_ssize_t first)
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
