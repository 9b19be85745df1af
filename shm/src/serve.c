/*
 * serve.c - serve_polls: the FC process's lockstep loop in C (fc_sil/fc_loop.py run_fc).
 *
 * Per step the FC waits for the bridge's records (the hand-off, sb_handoff.h) and runs
 * its C poll (fc_sil's record router, called through its bound method: ~60 ns); between
 * two steps nothing else is due unless the FC loop says so (FcLoop.python_due: the sim
 * time of the first step whose poll Python must follow, and how many polls the log
 * allows), or the poll consumes a record of a kind Python must see (`python_kinds`, a
 * bitmask of sb_kind: the kinds whose steps `fly --processes 1` finishes in Python). The
 * kinds are read from what the poll took (`records`, the array it pops into): the bridge
 * may publish the steps the FC promised to answer with nothing without waiting
 * (FC_SYNC_NS, shm/lockstep.py), so the ring can hold more by the time the poll pops than
 * it did a moment before. A Python loop around the same wait and poll costs ~3-5 us of
 * interpreter a step, which at ~100x real time is a third of the step.
 */
#include "module.h"

#include <math.h>

/* The sim time Python gave as an int, or a float (inf: no limit). */
static int until_ns(PyObject *o, int64_t *out)
{
    if (PyLong_Check(o)) {
        *out = PyLong_AsLongLong(o);
        return *out == -1 && PyErr_Occurred() ? -1 : 0;
    }
    double d = PyFloat_AsDouble(o);
    if (d == -1.0 && PyErr_Occurred()) return -1;
    *out = !(d < 9.2e18) ? INT64_MAX : d <= -9.2e18 ? INT64_MIN : (int64_t)ceil(d);
    return 0;
}

static void beat(sb_seg_header *h)
{
    uint64_t v = atomic_load_explicit(&h->peer_heartbeat, memory_order_relaxed) + 1u;
    atomic_store_explicit(&h->peer_heartbeat, v, memory_order_release);
}

/* Does one of the first n records the poll took (`v`, 64-byte records) have a kind in mask? */
static int took_kinds_in(const Py_buffer *v, long long n, uint64_t mask)
{
    const long long cap = (long long)(v->len / (Py_ssize_t)sizeof(sb_record));
    return n > 0 && sb_records_any_kind(v->buf, (uint64_t)(n < cap ? n : cap), mask);
}

static PyObject *serve(SegmentObject *self, PyObject *const *args, const Py_buffer *took);

/* serve_polls(capsule, poll, until_ns, max_polls, timeout_s, python_kinds, records)
 *   -> (polls, last_n, timed_out) */
PyObject *sb_serve_polls(PyObject *Py_UNUSED(module), PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 7) {
        PyErr_SetString(PyExc_TypeError, "serve_polls(capsule, poll, until_ns, max_polls, "
                                         "timeout_s, python_kinds, records)");
        return NULL;
    }
    const sb_capi *api = PyCapsule_GetPointer(args[0], SB_CAPI_CAPSULE);
    if (api == NULL) return NULL;
    SegmentObject *self = api->segment_object;
    if (sb_check_open(self)) return NULL;
    if (self->seg.is_owner || !PyCallable_Check(args[1])) {
        PyErr_SetString(SB_ERR.role, "serve_polls is the FC's (the peer's) loop and needs its "
                                     "poll callable");
        return NULL;
    }
    Py_buffer took;
    if (PyObject_GetBuffer(args[6], &took, PyBUF_C_CONTIGUOUS) < 0) return NULL;
    if (took.len % (Py_ssize_t)sizeof(sb_record) != 0) {
        PyBuffer_Release(&took);
        PyErr_SetString(PyExc_ValueError, "serve_polls: records must be the poll's array of "
                                          "64-byte records");
        return NULL;
    }
    PyObject *r = serve(self, args, &took);
    PyBuffer_Release(&took);
    return r;
}

/* The loop itself, once the arguments are checked; `took`: where the poll puts its records. */
static PyObject *serve(SegmentObject *self, PyObject *const *args, const Py_buffer *took)
{
    int64_t until;
    if (until_ns(args[2], &until) < 0) return NULL;
    Py_ssize_t max_polls = PyLong_AsSsize_t(args[3]);
    double timeout_s = PyFloat_AsDouble(args[4]);
    uint64_t python_kinds = PyLong_AsUnsignedLongLongMask(args[5]);
    if (PyErr_Occurred()) return NULL;
    sb_seg_header *h = self->seg.hdr;
    const _Atomic uint64_t *stop = sb_seg_word(h, SB_WORD_STOP);
    const _Atomic uint64_t *acked = sb_seg_word(h, SB_WORD_PEER_STEP);
    int64_t end_ns = sb_monotonic_ns() + (int64_t)(timeout_s > 0.0 ? timeout_s * 1e9 : 0.0);
    Py_ssize_t polls = 0;
    long long last_n = 0;
    int timed_out = 0;
    while (polls < max_polls && !atomic_load_explicit(stop, memory_order_acquire)) {
        double left_s = (double)(end_ns - sb_monotonic_ns()) / 1e9;
        if (!sb_handoff_wait_gil(self, 0, left_s > 0.0 ? left_s : 0.0)) {
            timed_out = 1;
            break;
        }
        PyObject *r = PyObject_CallNoArgs(args[1]);
        if (r == NULL) return NULL;
        long long n = PyLong_AsLongLong(r);
        Py_DECREF(r);
        if (n == -1 && PyErr_Occurred()) return NULL;
        if (n > 0) {
            polls++;
            last_n = n;
            beat(h);
            if (took_kinds_in(took, n, python_kinds) ||
                (int64_t)atomic_load_explicit(acked, memory_order_relaxed) >= until)
                break;
        }
        if (PyErr_CheckSignals() < 0) return NULL;
    }
    return Py_BuildValue("(nLO)", polls, last_n, timed_out ? Py_True : Py_False);
}
