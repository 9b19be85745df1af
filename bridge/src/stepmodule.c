/*
 * stepmodule.c - silbridge.bridge._step: one physics step of the bridge in one call.
 *
 * `Kernel.step(pwm)` writes the four pulse widths into JSBSim, runs it, reads the
 * FDM sample back through the property nodes (from C: step_native.c), and the sensor stage
 * (sensor_stage.c, plain C) writes the step's IMU, GT_ATT and GT_NAV records (64-byte
 * sb_record slots) into the simulator's step buffer, and the baro and magnetometer
 * records when due. Done from Python this costs ~6 us of interpreter work per step on
 * top of JSBSim's ~5 us; here it is the bare calls. What happens at 10 Hz or less or
 * only on events (GNSS fixes, setpoints, crash messages, noise blocks) stays in Python
 * (bridge/simulator.py), told by the returned flags.
 *
 * This file is the Python type: construction and argument checks (the getters and
 * constants arrive in dicts keyed by the names of the stage's tables, exported as
 * SAMPLE_FIELDS and CONST_FIELDS), the step methods' entry points, the module. The
 * step is step_run.c; the readable oracle with the same interface is
 * tests/bridge/step_kernel_oracle.py. Python objects the kernel calls are held as strong
 * references; the buffers it writes are held through Py_buffer views. The methods that
 * configure a kernel between steps are in step_config.c and step_forces.c.
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
        Py_VISIT(self->setters[i].obj);
    Py_VISIT(self->run.obj);
    for (int i = 0; i < SB_FDM_SAMPLE_FIELD_COUNT; i++)
        Py_VISIT(self->getters[i].obj);
    for (int i = 0; i < 4; i++)
        Py_VISIT(self->pack_torque[i].obj);
    return sb_batch_traverse(&self->batch, visit, arg);
}

static int Kernel_clear(Kernel *self)
{
    for (int i = 0; i < 4; i++)
        sb_call_clear(&self->setters[i]);
    sb_call_clear(&self->run);
    for (int i = 0; i < SB_FDM_SAMPLE_FIELD_COUNT; i++)
        sb_call_clear(&self->getters[i]);
    /* The C++ nodes lived on through those Python nodes: never call them after this. */
    self->jsb = (sb_jsb_api){0};
    for (int i = 0; i < 4; i++)
        sb_call_clear(&self->pack_torque[i]);
    sb_step_clear_forces(self);
    sb_batch_clear(&self->batch);
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
    sb_step_release(&self->baro_noise);
    sb_step_release(&self->mag_noise);
    sb_step_release(&self->gnss_noise);
    sb_step_release(&self->raw_view);
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

/* A {name: value} dict that names every entry of `table` once and nothing else. */
static int check_names(PyObject *dict, const sb_named_double *table, int n, const char *what)
{
    if (!PyDict_Check(dict)) {
        PyErr_Format(PyExc_TypeError, "%s must be a dict keyed by name", what);
        return -1;
    }
    for (int i = 0; i < n; i++)
        if (PyDict_GetItemString(dict, table[i].name) == NULL) {
            PyErr_Format(PyExc_KeyError, "%s lacks %s", what, table[i].name);
            return -1;
        }
    if (PyDict_Size(dict) == n)
        return 0;
    PyObject *key = NULL, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(dict, &pos, &key, &value)) {
        int known = 0;
        for (int i = 0; i < n && !known; i++)
            known = PyUnicode_Check(key) &&
                    PyUnicode_CompareWithASCIIString(key, table[i].name) == 0;
        if (!known)
            break;
    }
    PyErr_Format(PyExc_KeyError, "%s: unknown name %R", what, key);
    return -1;
}

/* getters {sample field name: callable} -> self->getters in SB_FDM_SAMPLE_FIELDS order. */
static int take_getters(Kernel *self, PyObject *getters)
{
    if (check_names(getters, SB_FDM_SAMPLE_FIELDS, SB_FDM_SAMPLE_FIELD_COUNT, "getters") < 0)
        return -1;
    for (int i = 0; i < SB_FDM_SAMPLE_FIELD_COUNT; i++) {
        PyObject *f = PyDict_GetItemString(getters, SB_FDM_SAMPLE_FIELDS[i].name);
        if (!PyCallable_Check(f)) {
            PyErr_Format(PyExc_TypeError, "getter %s is not callable",
                         SB_FDM_SAMPLE_FIELDS[i].name);
            return -1;
        }
        sb_call_set(&self->getters[i], f);
    }
    return 0;
}

/* consts {constant name: float} -> the named fields of *c. */
static int take_consts(sb_stage_consts *c, PyObject *consts)
{
    if (check_names(consts, SB_STAGE_CONST_FIELDS, SB_STAGE_CONST_FIELD_COUNT, "consts") < 0)
        return -1;
    for (int i = 0; i < SB_STAGE_CONST_FIELD_COUNT; i++) {
        const double v =
            PyFloat_AsDouble(PyDict_GetItemString(consts, SB_STAGE_CONST_FIELDS[i].name));
        if (v == -1.0 && PyErr_Occurred())
            return -1;
        memcpy((char *)c + SB_STAGE_CONST_FIELDS[i].offset, &v, sizeof v);
    }
    return 0;
}

/* The step buffer and the state array the stage writes. */
static int take_buffers(Kernel *self, PyObject *buf, PyObject *state)
{
    if (PyObject_GetBuffer(buf, &self->buf_view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return -1;
    if (self->buf_view.len < 3 * (Py_ssize_t)sizeof(sb_record) ||
        ((uintptr_t)self->buf_view.buf & 7u) != 0) {
        PyErr_SetString(PyExc_ValueError, "buffer must be 8-byte aligned and hold >= 3 records");
        return -1;
    }
    self->slots = (sb_record *)self->buf_view.buf;
    self->n_slots = self->buf_view.len / (Py_ssize_t)sizeof(sb_record);
    return sb_step_get_f64(state, &self->state_view, ST_COUNT, 1, "state");
}

/* Kernel(buffer, setters, run, getters, state, consts, phase, dt_ns, flip_steps, scalar_imu,
 *        on_ground): getters and consts are dicts keyed by the names in SAMPLE_FIELDS and
 *        CONST_FIELDS; on_ground is the contact state before the first step. */
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
    if (dt_ns <= 0 || flip_steps <= 0) {
        PyErr_SetString(PyExc_ValueError, "dt_ns and flip_steps must be > 0");
        return -1;
    }
    PyObject *set[4] = {NULL, NULL, NULL, NULL};
    const int taken = sb_step_take_callables(setters, set, 4, "setters");
    for (int i = 0; i < 4; i++) {
        sb_call_set(&self->setters[i], set[i]);
        Py_XDECREF(set[i]);
    }
    if (taken < 0 || take_getters(self, getters) < 0)
        return -1;
    if (!PyCallable_Check(run)) {
        PyErr_SetString(PyExc_TypeError, "run must be callable");
        return -1;
    }
    sb_call_set(&self->run, run);
    sb_stage_consts c;
    Py_buffer pv;
    if (take_consts(&c, consts) < 0 || take_buffers(self, buf, state) < 0 ||
        sb_step_get_f64(phase, &pv, 4, 0, "phase") < 0)
        return -1;
    sb_sensor_stage_init(&self->stage, &c, (double *)self->state_view.buf,
                         (const double *)pv.buf, flip_steps, scalar_imu, on_ground);
    PyBuffer_Release(&pv);
    self->dt_ns = dt_ns;
    return 0;
}

static PyObject *Kernel_step(Kernel *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 1) {
        PyErr_SetString(PyExc_TypeError, "step(pwm) takes one tuple of 4 pulse widths");
        return NULL;
    }
    if (!self->stage.scalar_imu) {
        PyErr_SetString(PyExc_RuntimeError, "this kernel writes no IMU: use step_gt(pwm, slot)");
        return NULL;
    }
    long f = sb_step_run(self, args[0], 0);
    return f < 0 ? NULL : PyLong_FromLong(f);
}

static PyObject *Kernel_step_gt(Kernel *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "step_gt(pwm, slot)");
        return NULL;
    }
    if (self->stage.scalar_imu) {
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
    long f = sb_step_run(self, args[0], slot);
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
     "configure_baro(rate_hz, offset_pa, noise_pa): sample the baro here"},
    {"configure_mag", (PyCFunction)Kernel_configure_mag, METH_VARARGS,
     "configure_mag(rate_hz, field_ned, offset, noise_gauss): sample the mag here"},
    {"set_baro_block", (PyCFunction)Kernel_set_baro_block, METH_O,
     "set_baro_block((rows, 1) float64 standard normals)"},
    {"set_mag_block", (PyCFunction)Kernel_set_mag_block, METH_O,
     "set_mag_block((rows, 3) float64 standard normals)"},
    {"configure_gnss", (PyCFunction)(void (*)(void))Kernel_configure_gnss,
     METH_VARARGS | METH_KEYWORDS, "configure_gnss(*, rate_hz, latency_ns, ...): the C GNSS's "
     "constants (step_gnss.c)"},
    {"set_gnss_block", (PyCFunction)Kernel_set_gnss_block, METH_VARARGS,
     "set_gnss_block((rows, 6) float64 standard normals, pos)"},
    {"gnss_take", (PyCFunction)Kernel_gnss_take, METH_VARARGS,
     "gnss_take(m, err_ned_m or None, last_epoch_ns, seq): the stage makes the epochs"},
    {"gnss_give", (PyCFunction)Kernel_gnss_give, METH_NOARGS,
     "gnss_give() -> (m, err_ned_m or None, last_epoch_ns, pos, seq): Python makes them"},
    {"hold", (PyCFunction)Kernel_hold, METH_VARARGS,
     "hold(due_ns, record): a 64-byte record written at the first step at or after due_ns"},
    {"set_forces", (PyCFunction)Kernel_set_forces, METH_O,
     "set_forces([(setters, [(c_n, w_rad_s, t_on_s, phase_rad, periodic, axis)])]): the "
     "disturbance forces written before each run() (bridge/disturbances.py)"},
    {"bind_lockstep", (PyCFunction)(void (*)(void))Kernel_bind_lockstep,
     METH_VARARGS | METH_KEYWORDS,
     "bind_lockstep(segment, fc_poll, trace, pwm, io, errors, rotor, bridge_word, fc_word): "
     "what "
     "run_batch needs (step_batch.c)"},
    {"bind_imu_raw", (PyCFunction)Kernel_bind_imu_raw, METH_O,
     "bind_imu_raw(rows or None): the chip's ODR samples into rows (step_raw.c)"},
    {"take_imu_raw", (PyCFunction)Kernel_take_imu_raw, METH_NOARGS,
     "take_imu_raw() -> (rows written since the last take, samples dropped)"},
    {"run_batch", (PyCFunction)Kernel_run_batch, METH_O,
     "run_batch(n) -> steps done: up to n lockstep steps of bridge and in-process FC"},
    {"finish_step", (PyCFunction)Kernel_finish_step, METH_O,
     "finish_step(count) -> steps done: the step run_batch left to Python, finished"},
    {"set_imu_fault", (PyCFunction)(void (*)(void))Kernel_set_imu_fault,
     METH_VARARGS | METH_KEYWORDS,
     "set_imu_fault(sensor, stuck, bias, sigma, clip): the gyro's or accel's faults"},
    {"set_baro_fault", (PyCFunction)(void (*)(void))Kernel_set_baro_fault,
     METH_VARARGS | METH_KEYWORDS,
     "set_baro_fault(stuck, offset_m, drift_m_s): the baro's faults as altitude errors"},
    {"set_mag_fault", (PyCFunction)(void (*)(void))Kernel_set_mag_fault,
     METH_VARARGS | METH_KEYWORDS,
     "set_mag_fault(off, offset_gauss): the magnetometer silent, its offset"},
    {"set_fault_seed", (PyCFunction)Kernel_set_fault_seed, METH_O,
     "set_fault_seed(seed): the noisy-axis faults' generator"},
    {"configure_battery", (PyCFunction)(void (*)(void))Kernel_configure_battery,
     METH_VARARGS | METH_KEYWORDS,
     "configure_battery(torque, cells, capacity_mah, ...): the pack the step runs (battery.h)"},
    {"write_battery", (PyCFunction)Kernel_write_battery, METH_O,
     "write_battery(slot) -> records written (0, 1): the due report on a step Python finishes"},
    {"battery_state", (PyCFunction)Kernel_battery_state, METH_NOARGS,
     "battery_state() -> (voltage_v, current_a, consumed_mah, remaining, temperature_c, "
     "lowest_cell_v, reports, next_ns) at the last report"},
    {"battery_solve", (PyCFunction)Kernel_battery_solve, METH_O,
     "battery_solve(esc_w) -> (voltage_v, current_a): the pack under that load now"},
    {"battery_esc_power", (PyCFunction)Kernel_battery_esc_power, METH_O,
     "battery_esc_power(omega_rad_s 4) -> each ESC's input power now [W]"},
    {"set_battery_cell", (PyCFunction)Kernel_set_battery_cell, METH_VARARGS,
     "set_battery_cell(cell, offset_v, r_scale): a weak cell (0.0, 1.0: healthy)"},
    {"battery_lose_charge", (PyCFunction)Kernel_battery_lose_charge, METH_O,
     "battery_lose_charge(fraction): that fraction of every cell's charge gone"},
    {"set_imbalance_scale", (PyCFunction)Kernel_set_imbalance_scale, METH_VARARGS,
     "set_imbalance_scale(motor 0..3, scale): a damaged prop's vibration"},
    {"bind_native", (PyCFunction)Kernel_bind_native, METH_NOARGS,
     "bind_native() -> None, or why not: read and write JSBSim's nodes from C, past their "
     "Python methods (the same values)"},
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

static PyMethodDef module_methods[] = {
    {"json_reply", (PyCFunction)(void (*)(void))sb_step_json_reply, METH_FASTCALL,
     "json_reply(records, sim_ns) -> bytes | None: the ArduPilot SITL JSON state line of a "
     "step's records (None if a value is not finite)"},
    {"imu_noise_rows", (PyCFunction)sb_step_imu_noise_rows, METH_VARARGS,
     "imu_noise_rows(inc, white, temps, turn_on, tempco, temp_ref_c, last, slow, out): the "
     "IMU's noise rows of a block, as bridge/imu.py's numpy did them (imu_noise.h)"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef stepmodule = {
    PyModuleDef_HEAD_INIT, "_step", "The bridge's per-step C kernel", -1, module_methods,
    NULL, NULL, NULL, NULL};

/* module.NAME = the names of a table, in its order: what Python's dicts are keyed by. */
static int add_names(PyObject *m, const char *attr, const sb_named_double *table, int n)
{
    PyObject *t = PyTuple_New(n);
    if (t == NULL)
        return -1;
    for (int i = 0; i < n; i++) {
        PyObject *name = PyUnicode_FromString(table[i].name);
        if (name == NULL) {
            Py_DECREF(t);
            return -1;
        }
        PyTuple_SET_ITEM(t, i, name);
    }
    if (PyModule_AddObject(m, attr, t) < 0) {
        Py_DECREF(t);
        return -1;
    }
    return 0;
}

PyMODINIT_FUNC PyInit__step(void)
{
    if (PyType_Ready(&KernelType) < 0 || PyType_Ready(&SbBlake2bType) < 0)
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
    Py_INCREF(&SbBlake2bType);
    if (PyModule_AddObject(m, "Blake2b", (PyObject *)&SbBlake2bType) < 0) {
        Py_DECREF(&SbBlake2bType);
        Py_DECREF(m);
        return NULL;
    }
    struct { const char *name; long v; } ints[] = {
        {"F_SLOW_DUE", F_SLOW_DUE}, {"F_BLOCK_DONE", F_BLOCK_DONE},
        {"F_GNSS_BLOCK_DONE", F_GNSS_BLOCK_DONE},
        {"F_GROUND_CHANGED", F_GROUND_CHANGED}, {"F_TIPPED", F_TIPPED},
        {"F_FLIPPED", F_FLIPPED}, {"F_ROTOR_STRIKE", F_ROTOR_STRIKE},
        {"F_BARO_BLOCK_DONE", F_BARO_BLOCK_DONE}, {"F_MAG_BLOCK_DONE", F_MAG_BLOCK_DONE},
        {"ST_W", ST_W}, {"ST_F", ST_F}, {"ST_EULER", ST_EULER}, {"ST_VEL", ST_VEL},
        {"ST_LAT", ST_LAT}, {"ST_LON", ST_LON}, {"ST_HAGL", ST_HAGL}, {"ST_OMEGA", ST_OMEGA},
        {"ST_ON_GROUND", ST_ON_GROUND}, {"ST_BARO_PA", ST_BARO_PA}, {"ST_TEMP_C", ST_TEMP_C},
        {"ST_PREV_VD", ST_PREV_VD}, {"ST_COS_TILT", ST_COS_TILT}, {"ST_COUNT", ST_COUNT},
        {"IO_PWM_US", SB_IO_PWM_US}, {"IO_ARMED", SB_IO_ARMED},
        {"IO_PWM_RECEIVED", SB_IO_PWM_RECEIVED}, {"IO_PWM_FIRST_SIM", SB_IO_PWM_FIRST_SIM},
        {"IO_PWM_FIRST_WALL", SB_IO_PWM_FIRST_WALL}, {"IO_PWM_LAST_SIM", SB_IO_PWM_LAST_SIM},
        {"IO_PWM_LAST_WALL", SB_IO_PWM_LAST_WALL}, {"IO_TRACE_BYTES", SB_IO_TRACE_BYTES},
        {"IO_PENDING", SB_IO_PENDING}, {"IO_DONE", SB_IO_DONE},
        {"IO_FC_MISSED", SB_IO_FC_MISSED}, {"IO_POLLS", SB_IO_POLLS},
        {"IO_LAST_POLL", SB_IO_LAST_POLL}, {"IO_ERR_EVERY", SB_IO_ERR_EVERY},
        {"IO_ERR_FROM_NS", SB_IO_ERR_FROM_NS}, {"IO_ERR_N", SB_IO_ERR_N},
        {"IO_OTHER_AT", SB_IO_OTHER_AT}, {"IO_OTHER_N", SB_IO_OTHER_N},
        {"IO_OVERLAPPED", SB_IO_OVERLAPPED}, {"IO_SYNC_BROKEN", SB_IO_SYNC_BROKEN},
        {"ERR_ATT_SQ", SB_ERR_ATT_SQ}, {"ERR_ALT_SQ", SB_ERR_ALT_SQ},
        {"ERR_CMD_ROLL", SB_ERR_CMD_ROLL}, {"ERR_CMD_PITCH", SB_ERR_CMD_PITCH},
        {"ERR_CMD_ALT", SB_ERR_CMD_ALT}, {"ERR_HOME_AGL", SB_ERR_HOME_AGL},
        {"ERR_COUNT", SB_ERR_COUNT},
        {"IO_WORDS", SB_IO_WORDS}, {"HELD_MAX", SB_HELD_MAX}};
    for (size_t i = 0; i < sizeof ints / sizeof ints[0]; i++)
        if (PyModule_AddIntConstant(m, ints[i].name, ints[i].v) < 0) {
            Py_DECREF(m);
            return NULL;
        }
    if (add_names(m, "SAMPLE_FIELDS", SB_FDM_SAMPLE_FIELDS, SB_FDM_SAMPLE_FIELD_COUNT) < 0 ||
        add_names(m, "CONST_FIELDS", SB_STAGE_CONST_FIELDS, SB_STAGE_CONST_FIELD_COUNT) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
