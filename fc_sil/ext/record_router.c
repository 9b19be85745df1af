/*
 * record_router.c - the record router: FcLoop.poll (fc_sil/fc_loop.py) in one C call,
 * for the shared-memory transport.
 *
 * Core.attach_io(segment_capsule, fc_sim_word=, latency_ns=, period_ns=, e2e_ns=, words=)
 * (FlightCore.attach_router) binds the segment (shm/include/sb_capi.h, the peer's side),
 * FcLoop's three int64 statistics rings and an int64[FC_IO_WORDS] array of counters
 * (core_object.h; the C poll carries on from their values). Core.poll_io() then does what
 * FcLoop's Python poll does for the MAVLink HIL links, with the same clock readings in
 * the same places: pop every waiting sensor record into the bound record array
 * (bind_batch), stamp the consume time, route them to the core (record_batch.c), push
 * the PWM records, stamp the publish time, acknowledge the lockstep step (FC_SIM_NS) when
 * the batch ends one, store latency / loop period / end-to-end latency and the /timing
 * row, and append the logged records and that row to the bound log queues (bind_log).
 * About 1 us of interpreter work per poll becomes ~0.1 us. Python still runs the
 * supervisor (modes, arming) after each poll that consumed something.
 *
 * Safety: the capsule keeps the Segment object alive; a closed segment is
 * refused before any ring is touched (api->seg->base == NULL).
 */
#include "core_object.h"

#include <string.h>

static void release_series(fc_io_t *io)
{
    for (int i = 0; i < 3; i++) {
        if (io->series[i].obj != NULL)
            PyBuffer_Release(&io->series[i]);
    }
    if (io->words_view.obj != NULL)
        PyBuffer_Release(&io->words_view);
}

void fc_ext_detach_io(CoreObject *self)
{
    fc_io_t *io = &self->io;
    release_series(io);
    Py_CLEAR(io->capsule);
    memset(io, 0, sizeof *io);
}

/* attach_io(capsule, fc_sim_word=, latency_ns=, period_ns=, e2e_ns=, words=);
 * attach_io(None) detaches. */
static PyObject *Core_attach_io(CoreObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"segment", "fc_sim_word", "latency_ns", "period_ns", "e2e_ns",
                             "words", NULL};
    PyObject *cap, *arr[3] = {NULL, NULL, NULL}, *words = NULL;
    int word = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O|$iOOOO", kwlist, &cap, &word, &arr[0],
                                     &arr[1], &arr[2], &words))
        return NULL;
    fc_ext_detach_io(self);
    if (cap == Py_None)
        Py_RETURN_NONE;
    const sb_capi *api = PyCapsule_GetPointer(cap, SB_CAPI_CAPSULE);
    if (api == NULL)
        return NULL;
    if (api->version != SB_CAPI_VERSION || api->is_owner) {
        PyErr_SetString(PyExc_ValueError, "attach_io needs the FC (peer) side of a segment "
                                          "built with the same shm version");
        return NULL;
    }
    if (word < 0 || (unsigned)word >= SB_SEG_WORDS || words == NULL || arr[0] == NULL ||
        arr[1] == NULL || arr[2] == NULL) {
        PyErr_SetString(PyExc_ValueError, "attach_io(capsule, fc_sim_word=, latency_ns=, "
                                          "period_ns=, e2e_ns=, words=)");
        return NULL;
    }
    if (!self->have_bound) {
        PyErr_SetString(PyExc_RuntimeError, "attach_io needs bind_batch(records, pwm, status)");
        return NULL;
    }
    fc_io_t *io = &self->io;
    Py_ssize_t len = -1;
    for (int i = 0; i < 3; i++) {
        Py_buffer *v = &io->series[i];
        if (PyObject_GetBuffer(arr[i], v, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
            fc_ext_detach_io(self);
            return NULL;
        }
        const Py_ssize_t n = v->len / 8;
        if (v->itemsize != 8 || n < 1 || (n & (n - 1)) != 0 || (len >= 0 && n != len)) {
            PyErr_SetString(PyExc_ValueError, "statistics rings must be int64 arrays of one "
                                              "power-of-two length");
            fc_ext_detach_io(self);
            return NULL;
        }
        len = n;
    }
    io->series_mask = (uint64_t)len - 1u;
    Py_buffer *wv = &io->words_view;
    if (PyObject_GetBuffer(words, wv, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        fc_ext_detach_io(self);
        return NULL;
    }
    if (wv->itemsize != 8 || wv->len < (Py_ssize_t)(8 * FC_IO_WORDS)) {
        PyErr_Format(PyExc_ValueError, "words must be an int64 array of %d", FC_IO_WORDS);
        fc_ext_detach_io(self);
        return NULL;
    }
    io->words = wv->buf;
    io->capsule = Py_NewRef(cap);
    io->api = api;
    io->fc_sim_word = word;
    Py_RETURN_NONE;
}

static inline void series_add(fc_io_t *io, int i, int64_t v)
{
    int64_t *n = &io->words[FC_IO_N_LATENCY + i];
    ((int64_t *)io->series[i].buf)[(uint64_t)*n & io->series_mask] = v;
    (*n)++;
}

/* FC_SYNC_NS with this poll's answer (sb_segment.h sb_seg_peer_sync): the sim time of the
 * next step the bridge must wait for. The core emits nothing before its next PWM tick
 * (fc_core_pwm_due: at the first IMU sample at or after it), and Python acts at its due poll
 * (FC_IO_SYNC_UNTIL) and after a poll that took a record of FC_IO_HAND_ON_KINDS: that one
 * promises nothing (0), for Python may change the core or send FAULT records before the next
 * poll. Before the first IMU sample there is no tick yet: 0. */
static uint64_t next_sync(const CoreObject *self, const sb_record *recs, uint64_t n)
{
    const int64_t *w = self->io.words;
    const fc_core_t *c = &self->core;
    const int64_t tick = c->have_imu ? c->next_pwm_ns : 0;
    const int64_t sync = w[FC_IO_SYNC_UNTIL] < tick ? w[FC_IO_SYNC_UNTIL] : tick;
    /* 0 already (outside the serve loop, `fly --processes 1`): no kinds to look at */
    if (sync <= 0 || sb_records_any_kind(recs, n, (uint64_t)w[FC_IO_HAND_ON_KINDS]))
        return 0;
    return (uint64_t)sync;
}

static PyObject *Core_poll_io(CoreObject *self, PyObject *Py_UNUSED(unused))
{
    fc_io_t *io = &self->io;
    if (io->api == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "poll_io needs attach_io(segment capsule, ...)");
        return NULL;
    }
    if (io->api->seg->base == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "the segment is closed");
        return NULL;
    }
    sb_ring *sensors = &io->api->rings[SB_RING_SENSORS];
    sb_ring *actuators = &io->api->rings[SB_RING_ACTUATORS];
    sb_record *recs = self->bound[0].buf;
    const uint64_t cap = (uint64_t)(self->bound[0].len / SB_RECORD_SIZE);
    const uint64_t n = sb_ring_pop_batch(sensors, recs, cap);
    if (n == 0)
        return PyLong_FromLong(0);
    const int64_t consume = fc_ext_monotonic_ns();
    sb_record *pwm = self->bound[1].buf;
    const Py_ssize_t k = fc_ext_run_records(self, (const unsigned char *)recs, (Py_ssize_t)n,
                                            pwm, self->bound[2].buf, fc_ext_bound_capacity(self));
    if (k < 0)
        return NULL;
    const sb_header *newest = &recs[n - 1].h;
    int64_t pwm_wall = 0;
    if (k > 0) {
        (void)sb_ring_push_batch(actuators, pwm, (uint64_t)k, fc_ext_monotonic_ns());
        pwm_wall = fc_ext_monotonic_ns();
        io->words[FC_IO_PWM_PUBLISHED] += k;
        series_add(io, 2, pwm_wall - newest->wall_ns);
    }
    if (newest->flags & SB_FLAG_STEP_END) {
        io->words[FC_IO_LAST_SIM_NS] = newest->sim_ns;
        /* the promise first: the step word's release publishes it with the answer */
        atomic_store_explicit(sb_seg_peer_sync(io->api->seg->hdr), next_sync(self, recs, n),
                              memory_order_relaxed);
        atomic_store_explicit(sb_capi_word(io->api, io->fc_sim_word), (uint64_t)newest->sim_ns,
                              memory_order_release);
    }
    if (k > 0 || (newest->flags & SB_FLAG_STEP_END))
        sb_bell_ring(sb_segment_my_bell(io->api->seg)); /* the bridge may be blocked on it */
    series_add(io, 0, consume - newest->wall_ns);
    int64_t period = 0;
    if (io->prev_consume_ns) {
        period = consume - io->prev_consume_ns;
        series_add(io, 1, period);
    }
    io->prev_consume_ns = consume;
    io->words[FC_IO_POLLS]++;
    io->words[FC_IO_RECORDS] += (int64_t)n;
    io->words[FC_IO_LAST_K] = k;
    int64_t *row = &io->words[FC_IO_TIMING]; /* a per-cycle sink reads it (fc_loop.py) */
    row[0] = newest->sim_ns;
    row[1] = newest->wall_ns;
    row[2] = consume;
    row[3] = pwm_wall;
    row[4] = period;
    /* The log: records and PWM to their kinds' queues, status rows, the /timing row. */
    if (fc_ext_log_batch(self, (const unsigned char *)recs, (Py_ssize_t)n,
                         (const unsigned char *)pwm, self->bound[2].buf, k) < 0)
        return NULL;
    if (self->log_timing != NULL &&
        fc_ext_append_bytes(self->log_timing, row, 5 * sizeof *row) < 0)
        return NULL;
    return PyLong_FromUnsignedLongLong(n);
}

PyMethodDef fc_ext_poll_methods[] = {
    {"attach_io", (PyCFunction)(void (*)(void))Core_attach_io, METH_VARARGS | METH_KEYWORDS,
     "attach_io(segment.c_capsule(), fc_sim_word=, latency_ns=, period_ns=, e2e_ns=, words=): "
     "poll_io's segment, int64 statistics rings and counters (core_object.h); "
     "attach_io(None) detaches."},
    {"poll_io", (PyCFunction)Core_poll_io, METH_NOARGS,
     "poll_io() -> records consumed: FcLoop.poll over shared memory in C (record_router.c)."},
    {NULL, NULL, 0, NULL},
};
