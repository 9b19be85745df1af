/*
 * step_batch.c - N lockstep steps of bridge and in-process FC in one call (`silbridge fly
 * --processes 1`): Kernel.bind_lockstep, run_batch and finish_step, the CPython side.
 * It runs the kernel's step (step_run.c) and calls the FC's poll; the ring side of each
 * step is plain C (step_lockstep.c).
 *
 * One step, as the Python path (publish_step, FcLoop.poll, collect_pwm) does it, in the
 * same order: the kernel's step with the held PWM -> its records to the trace and the
 * sensor ring, BRIDGE_SIM_NS -> the errors' sample, the rotor row -> the FC's C poll
 * (Core.poll_io, the record router) -> the PWM back, traced with wall_ns zeroed ->
 * FC_SIM_NS checked. The trace holds the bytes the trace hash would have been fed step by
 * step: blake2b hashes a stream, so Python hashing the batch's trace once gives the digest;
 * with a trace hash bound (`trace_hash`, a _step.Blake2b) the batch hashes them itself,
 * each step's while the FC in its own process computes its answer.
 *
 * With the FC in its own process, a step waits for its answer only where the FC's promise
 * (FC_SYNC_NS, shm/lockstep.py; `hand_on_kinds` bound) does not cover it: the steps the FC
 * answers with nothing are published and the next one stepped while the FC computes them.
 * The batch's last step is always waited for, so Python finds everything answered.
 *
 * A step whose kernel flags need Python (noise refills, a GNSS fix or setpoint due, ground
 * contact, crashes: the F_* flags above the count byte) ends the batch right after the
 * kernel ran it: io[PENDING] holds its flags, Python does its part (Simulator.step_batch:
 * _after_step) and finish_step(count) does the rest. Python chooses N so that every other
 * step with Python work (a disturbance switch, the FC supervisor's and the log's due polls,
 * the start-up checks) is the last of a batch.
 *
 * The FC's poll is called through its bound method's vectorcall entry (step_call.h): the
 * record router lives in another extension; one vectorcall a step is not worth a capsule
 * of function pointers.
 * No heap in the step: the buffers are the caller's; the four PWM floats the setters take
 * are rebuilt only when the command changes.
 */
#include "step_kernel.h"

void sb_batch_clear(sb_batch *b)
{
    Py_CLEAR(b->capsule);
    sb_call_clear(&b->fc_poll);
    for (int i = 0; i < 4; i++)
        Py_CLEAR(b->pwm_obj[i]);
    sb_step_release(&b->trace);
    sb_step_release(&b->pwm);
    sb_step_release(&b->io);
    sb_step_release(&b->rotor);
    sb_step_release(&b->errors);
    Py_CLEAR(b->hash_obj);
    b->hash = NULL;
    memset(&b->ls, 0, sizeof b->ls);
}

int sb_batch_traverse(sb_batch *b, visitproc visit, void *arg)
{
    Py_VISIT(b->capsule);
    Py_VISIT(b->fc_poll.obj);
    Py_VISIT(b->hash_obj);
    return 0;
}

/* A writable C-contiguous buffer of at least min_bytes, whole `item`-byte items. */
static int take_buffer(PyObject *obj, Py_buffer *v, Py_ssize_t min_bytes, Py_ssize_t item,
                       const char *what)
{
    if (PyObject_GetBuffer(obj, v, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return -1;
    if (v->len < min_bytes || v->len % item != 0 || ((uintptr_t)v->buf & 7u) != 0) {
        PyErr_Format(PyExc_ValueError, "%s must be an 8-byte aligned writable buffer of "
                     "%zd-byte items, at least %zd bytes", what, item, min_bytes);
        PyBuffer_Release(v);
        return -1;
    }
    return 0;
}

/* The buffers' views, and the plain-C state pointing into them. */
static int take_buffers(Kernel *self, PyObject *trace, PyObject *pwm, PyObject *io,
                        PyObject *errors, PyObject *rotor)
{
    sb_batch *b = &self->batch;
    const Py_ssize_t rec = (Py_ssize_t)sizeof(sb_record);
    if (take_buffer(trace, &b->trace, rec * (self->n_slots + 16), 1, "trace") < 0 ||
        take_buffer(pwm, &b->pwm, rec, rec, "pwm") < 0 ||
        take_buffer(io, &b->io, 8 * SB_IO_WORDS, 8, "io") < 0 ||
        sb_step_get_f64(errors, &b->errors, SB_ERR_COUNT, 1, "errors") < 0 ||
        (rotor != Py_None && take_buffer(rotor, &b->rotor, 32, 32, "rotor") < 0))
        return -1;
    sb_lockstep *l = &b->ls;
    l->trace = b->trace.buf;
    l->trace_len = (size_t)b->trace.len;
    l->pwm = b->pwm.buf;
    l->pwm_cap = (size_t)(b->pwm.len / rec);
    l->io = b->io.buf;
    l->errors = b->errors.buf;
    l->rotor = b->rotor.obj != NULL ? b->rotor.buf : NULL;
    l->rotor_rows = b->rotor.obj != NULL ? (size_t)(b->rotor.len / 32) : 0;
    return 0;
}

/* bind_lockstep(segment, fc_poll, trace, pwm, io, errors, rotor, bridge_word, fc_word,
 *               trace_hash=None, hand_on_kinds=None) */
PyObject *Kernel_bind_lockstep(Kernel *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"segment", "fc_poll", "trace", "pwm", "io", "errors", "rotor",
                             "bridge_word", "fc_word", "trace_hash", "hand_on_kinds", NULL};
    PyObject *cap, *poll, *trace, *pwm, *io, *errors, *rotor, *hash = Py_None;
    PyObject *kinds = Py_None;
    int bw, fw;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OOOOOOOii|OO", kwlist, &cap, &poll, &trace,
                                     &pwm, &io, &errors, &rotor, &bw, &fw, &hash, &kinds))
        return NULL;
    uint64_t kind_mask = 0;
    if (kinds != Py_None) {
        kind_mask = PyLong_AsUnsignedLongLong(kinds);
        if (PyErr_Occurred())
            return NULL;
    }
    sb_blake2b *hash_state = hash == Py_None ? NULL : sb_step_hash_state(hash);
    if (hash != Py_None && hash_state == NULL)
        return NULL;
    sb_batch *b = &self->batch;
    sb_batch_clear(b);
    const sb_capi *api = PyCapsule_GetPointer(cap, SB_CAPI_CAPSULE);
    if (api == NULL)
        return NULL;
    if (api->version != SB_CAPI_VERSION || !api->is_owner || bw < 0 || fw < 0 ||
        bw >= (int)SB_SEG_WORDS || fw >= (int)SB_SEG_WORDS ||
        (poll != Py_None && !PyCallable_Check(poll))) {
        PyErr_SetString(PyExc_ValueError, "bind_lockstep needs the bridge (owner) side of a "
                        "segment of this shm version, the FC's poll (None: the FC runs in its "
                        "own process) and two word indices");
        return NULL;
    }
    if (take_buffers(self, trace, pwm, io, errors, rotor) < 0) {
        sb_batch_clear(b);
        return NULL;
    }
    b->capsule = Py_NewRef(cap);
    if (hash_state != NULL) {
        b->hash_obj = Py_NewRef(hash);
        b->hash = hash_state;
    }
    sb_call_set(&b->fc_poll, poll == Py_None ? NULL : poll);
    b->ls.api = api;
    b->ls.bridge_word = bw;
    b->ls.fc_word = fw;
    /* the FC's promise (FC_SYNC_NS) matters only to a bridge that waits for it */
    b->ls.overlap = poll == Py_None && kinds != Py_None;
    b->ls.hand_on_kinds = kind_mask;
    sb_lockstep_forget(&b->ls);
    Py_RETURN_NONE;
}

/* The held pulse widths (io) as the float objects the setters take. */
static int held_pwm(sb_batch *b, const int64_t *io)
{
    for (int i = 0; i < 4; i++) {
        if (b->pwm_obj[i] != NULL && b->pwm_held[i] == io[SB_IO_PWM_US + i])
            continue;
        PyObject *f = PyFloat_FromDouble((double)io[SB_IO_PWM_US + i]);
        if (f == NULL)
            return -1;
        Py_XSETREF(b->pwm_obj[i], f);
        b->pwm_held[i] = io[SB_IO_PWM_US + i];
    }
    return 0;
}

/* How long one wait for an FC in its own process lasts before Python looks at that FC
 * (PeerWatch; the same slice as bridge_driver.py _wait_lockstep). */
#define SB_FC_WAIT_SLICE_NS 20000000

/* The FC's poll of this step; 0, or -1 with its exception set. */
static int fc_poll(sb_batch *b, int64_t *io)
{
    PyObject *r = sb_call0(&b->fc_poll);
    if (r == NULL)
        return -1;
    const long n = PyLong_AsLong(r);
    Py_DECREF(r);
    if (n == -1 && PyErr_Occurred())
        return -1;
    if (n > 0) {
        io[SB_IO_POLLS]++;
        io[SB_IO_LAST_POLL] = n;
    }
    return 0;
}

/* The batch's trace bytes not hashed yet into the bound trace hash (if any). Called right
 * after a step's publish, before the wait for the FC's answer: in two-process mode the FC
 * computes meanwhile, so the hash costs the step nothing. (One process has no such wait:
 * it binds no hash, and Python hashes the batch's trace once, bridge/bridge_loop.py.) */
static void hash_trace(sb_batch *b)
{
    const size_t used = (size_t)b->ls.io[SB_IO_TRACE_BYTES];
    if (b->hash == NULL || used <= b->hashed)
        return;
    sb_blake2b_update(b->hash, b->ls.trace + b->hashed, used - b->hashed);
    b->hashed = used;
}

/* The rest of a step the kernel has run, its `count` records in the slots: published, the
 * FC polled, the PWM collected. 1, 0 the FC did not answer, -1 error. `last`: the batch
 * ends with this step, so the FC in its own process must have answered it (Python looks). */
static int finish(Kernel *self, size_t count, int last)
{
    sb_lockstep *l = &self->batch.ls;
    const int64_t k = self->step_index, sim_ns = k * self->dt_ns;
    sb_lockstep_publish(l, self->slots, count, sim_ns);
    hash_trace(&self->batch);
    sb_lockstep_after_step(l, self->stage.state, k, sim_ns);
    const int own_process = self->batch.fc_poll.obj == NULL;
    if (own_process && !sb_lockstep_must_wait(l, self->slots, count, sim_ns, last)) {
        /* the FC promised no answer here: it computes this step while the next is stepped */
        sb_lockstep_skip(l, sim_ns);
        l->io[SB_IO_DONE]++;
        return 1;
    }
    sb_lockstep_ring(l);
    if (own_process) {
        /* The FC in its own process: the lockstep hand-off (shm/include/sb_handoff.h). Not
         * answered within a slice: the step ends the batch unanswered (io FC_MISSED) and
         * Python looks at the FC, then waits on and collects (bridge_driver.py). */
        const int w = l->api->wait_step(l->api, (uint64_t)sim_ns, SB_FC_WAIT_SLICE_NS);
        if (w < 0)
            return -1;
        if (w == 0) {
            l->io[SB_IO_DONE]++;
            l->io[SB_IO_FC_MISSED] = 1;
            return 0;
        }
    } else if (fc_poll(&self->batch, l->io) < 0) {
        return -1;
    }
    sb_lockstep_collect(l);
    if (own_process)
        sb_lockstep_synced(l);
    l->io[SB_IO_DONE]++;
    return sb_lockstep_answered(l, sim_ns);
}

/* One lockstep step: 1 done, 0 the kernel flagged Python work (io PENDING) or the FC did
 * not answer, -1 error. `last`: the batch's last step. */
static int batch_step(Kernel *self, int last)
{
    int64_t *io = self->batch.ls.io;
    if (held_pwm(&self->batch, io) < 0)
        return -1;
    const long flags = sb_step_run_items(self, self->batch.pwm_obj, 0);
    if (flags < 0)
        return -1;
    if (flags & F_PYTHON_MASK) {
        io[SB_IO_PENDING] = flags;
        return 0;
    }
    return finish(self, (size_t)(flags & 0xFF), last);
}

/* The batch's checks: bound, an IMU-writing kernel, an open segment. */
static int batch_ready(Kernel *self)
{
    const sb_lockstep *l = &self->batch.ls;
    if (l->api == NULL || !self->stage.scalar_imu) {
        PyErr_SetString(PyExc_RuntimeError, "run_batch needs bind_lockstep() and a kernel "
                                            "that writes the IMU (one sample per step)");
        return -1;
    }
    if (l->api->seg->base == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "the segment is closed");
        return -1;
    }
    return 0;
}

/* run_batch(n) -> steps done (io: what happened; see SB_IO_*). */
PyObject *Kernel_run_batch(Kernel *self, PyObject *arg)
{
    const Py_ssize_t n = PyLong_AsSsize_t(arg);
    if ((n == -1 && PyErr_Occurred()) || batch_ready(self) < 0)
        return NULL;
    sb_lockstep *l = &self->batch.ls;
    int64_t *io = l->io;
    io[SB_IO_TRACE_BYTES] = io[SB_IO_PENDING] = io[SB_IO_DONE] = 0;
    io[SB_IO_FC_MISSED] = io[SB_IO_POLLS] = io[SB_IO_OTHER_N] = 0;
    io[SB_IO_OVERLAPPED] = io[SB_IO_SYNC_BROKEN] = 0;
    self->batch.hashed = 0;
    /* Python may have stepped the per-step way since the last batch: no promise is held */
    sb_lockstep_forget(l);
    /* The steps this batch can take, known before the first (its last must be answered): a
     * step needs room for its records and the PWM of a poll (16: many per step). */
    const size_t step_bytes = (size_t)(self->n_slots + 16) * sizeof(sb_record);
    Py_ssize_t steps = n;
    if (l->rotor != NULL && (Py_ssize_t)l->rotor_rows < steps)
        steps = (Py_ssize_t)l->rotor_rows;
    if ((Py_ssize_t)(l->trace_len / step_bytes) < steps)
        steps = (Py_ssize_t)(l->trace_len / step_bytes);
    for (Py_ssize_t k = 0; k < steps && sb_lockstep_room(l) >= step_bytes; k++) {
        const int rc = batch_step(self, k + 1 == steps);
        if (rc < 0)
            return NULL;
        if (rc == 0 || io[SB_IO_OTHER_N] != 0)     /* a FAULT for Python before the next step */
            break;
    }
    hash_trace(&self->batch);   /* the last PWM: the hash is whole when Python looks */
    return PyLong_FromLongLong(io[SB_IO_DONE]);
}

/* finish_step(count) -> steps done: the step run_batch left pending, once Python has done
 * its part (its `count` records in the slots now), finished as batch_step finishes its own
 * (run_batch left it a step's room in the trace). */
PyObject *Kernel_finish_step(Kernel *self, PyObject *arg)
{
    const Py_ssize_t count = PyLong_AsSsize_t(arg);
    if ((count == -1 && PyErr_Occurred()) || batch_ready(self) < 0)
        return NULL;
    int64_t *io = self->batch.ls.io;
    if (io[SB_IO_PENDING] == 0 || count < 0 || count > self->n_slots) {
        PyErr_SetString(PyExc_RuntimeError, "finish_step(count) finishes the step run_batch "
                                            "left pending, with at most a step buffer's records");
        return NULL;
    }
    io[SB_IO_PENDING] = 0;
    if (finish(self, (size_t)count, 1) < 0)
        return NULL;
    hash_trace(&self->batch);
    return PyLong_FromLongLong(io[SB_IO_DONE]);
}
