/*
 * ringobject.c - the Python Ring type: one side of one SPSC ring.
 *
 * The hot verbs (try_push, try_pop, push_batch, pop_batch, pop_into) take
 * METH_O / METH_FASTCALL, read record memory in place (np.void, bytes,
 * C-contiguous arrays) and allocate nothing but their result, so a
 * single-record call costs a few hundred nanoseconds.
 */
#include "module.h"

#define SB_KIND_CHECK(k) ((k) > SB_KIND_NONE && (k) < SB_KIND_COUNT)

static const char *const RING_NAMES[SB_RING_COUNT] = {"sensors", "actuators"};

PyObject *sb_ring_object_new(SegmentObject *seg, int index)
{
    RingObject *self = PyObject_New(RingObject, &SbRingType);
    if (!self) return NULL;
    Py_INCREF(seg);
    self->owner = seg;
    self->r = &seg->rings[index];
    self->index = index;
    /* The owner produces sensors, the peer produces actuators. */
    self->produces = (index == SB_RING_SENSORS) == (seg->seg.is_owner != 0);
    return (PyObject *)self;
}

static void Ring_dealloc(RingObject *self)
{
    Py_XDECREF(self->owner);
    PyObject_Free(self);
}

static int check_side(RingObject *self, int want_producer)
{
    if (sb_check_open(self->owner)) return -1;
    if (self->produces == want_producer) return 0;
    PyErr_Format(SB_ERR.role,
                 "the %s ring is %s by this process, not %s: the bridge (segment owner) pushes "
                 "sensors and pops actuators, the FC (peer) does the opposite",
                 RING_NAMES[self->index], self->produces ? "produced" : "consumed",
                 want_producer ? "produced" : "consumed");
    return -1;
}

static int check_kinds(const uint8_t *data, Py_ssize_t n)
{
    for (Py_ssize_t i = 0; i < n; ++i) {
        uint16_t kind;
        memcpy(&kind, data + i * SB_RECORD_SIZE, sizeof kind);
        if (!SB_KIND_CHECK(kind)) {
            PyErr_Format(SB_ERR.kind,
                         "record %zd has unknown kind %u: set `kind` to a silbridge.shm.records.Kind "
                         "(1..%d); if a new kind was added, rebuild both sides",
                         i, (unsigned)kind, SB_KIND_COUNT - 1);
            return -1;
        }
    }
    return 0;
}

static int parse_stamp(PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames, int *stamp)
{
    static const char *const names[] = {"stamp"};
    PyObject *val = NULL;
    if (sb_parse_kw(args, nargs, kwnames, names, &val, 1) < 0) return -1;
    *stamp = 1;
    if (val) {
        int t = PyObject_IsTrue(val);
        if (t < 0) return -1;
        *stamp = t;
    }
    return 0;
}

/* try_push(record, *, stamp=True) -> bool */
static PyObject *Ring_try_push(RingObject *self, PyObject *const *args, Py_ssize_t nargs,
                               PyObject *kwnames)
{
    if (nargs != 1) {
        PyErr_SetString(PyExc_TypeError, "try_push(record, *, stamp=True) takes one record");
        return NULL;
    }
    int stamp = 1;
    if (kwnames && parse_stamp(args, nargs, kwnames, &stamp) < 0) return NULL;
    if (check_side(self, 1) < 0) return NULL;
    PyObject *obj = args[0];
    const uint8_t *data;
    Py_ssize_t len;
    Py_buffer view = {0};
    int have_view = 0;
    if (PyArray_IsScalar(obj, Void)) {
        PyVoidScalarObject *v = (PyVoidScalarObject *)obj;
        data = (const uint8_t *)v->obval;
        len = (Py_ssize_t)PyDataType_ELSIZE(v->descr);
    } else if (PyBytes_CheckExact(obj)) {
        data = (const uint8_t *)PyBytes_AS_STRING(obj);
        len = PyBytes_GET_SIZE(obj);
    } else {
        if (PyObject_GetBuffer(obj, &view, PyBUF_C_CONTIGUOUS) < 0) return NULL;
        have_view = 1;
        data = view.buf;
        len = view.len;
    }
    PyObject *res = NULL;
    if (len != SB_RECORD_SIZE) {
        PyErr_Format(PyExc_ValueError,
                     "a record is %u bytes, got %zd: pass one element of a "
                     "silbridge.shm.records dtype array, or 64 bytes",
                     SB_RECORD_SIZE, len);
    } else if (check_kinds(data, 1) == 0) {
        int rc = sb_ring_push(self->r, (const sb_record *)data, stamp ? sb_monotonic_ns() : -1);
        sb_bell_ring(sb_segment_my_bell(&self->owner->seg));
        res = rc == SB_RING_OK ? Py_True : Py_False;
        Py_INCREF(res);
    }
    if (have_view) PyBuffer_Release(&view);
    return res;
}

/* push_batch(records, *, stamp=True) -> int written */
static PyObject *Ring_push_batch(RingObject *self, PyObject *const *args, Py_ssize_t nargs,
                                 PyObject *kwnames)
{
    if (nargs != 1) {
        PyErr_SetString(PyExc_TypeError, "push_batch(records, *, stamp=True) takes one array");
        return NULL;
    }
    int stamp = 1;
    if (kwnames && parse_stamp(args, nargs, kwnames, &stamp) < 0) return NULL;
    if (check_side(self, 1) < 0) return NULL;
    PyObject *obj = args[0];
    PyArrayObject *arr = NULL;
    Py_buffer view = {0};
    const uint8_t *data;
    Py_ssize_t n;
    if (PyArray_Check(obj)) {
        if (PyArray_ITEMSIZE((PyArrayObject *)obj) != SB_RECORD_SIZE) {
            PyErr_Format(PyExc_ValueError,
                         "records are %u bytes, the array's itemsize is %zd: use a "
                         "silbridge.shm.records dtype",
                         SB_RECORD_SIZE, (Py_ssize_t)PyArray_ITEMSIZE((PyArrayObject *)obj));
            return NULL;
        }
        arr = PyArray_GETCONTIGUOUS((PyArrayObject *)obj); /* new ref; a copy only if strided */
        if (!arr) return NULL;
        data = (const uint8_t *)PyArray_BYTES(arr);
        n = PyArray_SIZE(arr);
    } else {
        if (PyObject_GetBuffer(obj, &view, PyBUF_C_CONTIGUOUS) < 0) return NULL;
        if (view.len % SB_RECORD_SIZE) {
            PyBuffer_Release(&view);
            PyErr_Format(PyExc_ValueError, "%zd bytes is not a whole number of %u-byte records",
                         view.len, SB_RECORD_SIZE);
            return NULL;
        }
        data = view.buf;
        n = view.len / SB_RECORD_SIZE;
    }
    PyObject *res = NULL;
    if (check_kinds(data, n) == 0) {
        uint64_t k = sb_ring_push_batch(self->r, (const sb_record *)data, (uint64_t)n,
                                        stamp ? sb_monotonic_ns() : -1);
        sb_bell_ring(sb_segment_my_bell(&self->owner->seg));
        res = PyLong_FromUnsignedLongLong(k);
    }
    if (arr) Py_DECREF(arr);
    else PyBuffer_Release(&view);
    return res;
}

/* try_pop() -> np.void (RECORD_DTYPE) | None */
static PyObject *Ring_try_pop(RingObject *self, PyObject *Py_UNUSED(ignored))
{
    if (check_side(self, 0) < 0) return NULL;
    sb_record rec;
    if (sb_ring_pop(self->r, &rec) != SB_RING_OK) Py_RETURN_NONE;
    return PyArray_Scalar(&rec, SB_RECORD_DESCR, NULL);
}

/* pop_batch(max_n) -> ndarray[RECORD_DTYPE] of length 0..max_n */
static PyObject *Ring_pop_batch(RingObject *self, PyObject *arg)
{
    Py_ssize_t max_n = PyLong_AsSsize_t(arg);
    if (max_n == -1 && PyErr_Occurred()) return NULL;
    if (max_n < 0) {
        PyErr_SetString(PyExc_ValueError, "pop_batch(max_n) needs max_n >= 0");
        return NULL;
    }
    if (check_side(self, 0) < 0) return NULL;
    uint64_t avail = sb_ring_available(self->r);
    npy_intp n = (npy_intp)(avail < (uint64_t)max_n ? avail : (uint64_t)max_n);
    Py_INCREF(SB_RECORD_DESCR);
    PyArrayObject *out = (PyArrayObject *)PyArray_NewFromDescr(&PyArray_Type, SB_RECORD_DESCR, 1,
                                                              &n, NULL, NULL, 0, NULL);
    if (!out) return NULL;
    uint64_t got = sb_ring_pop_batch(self->r, (sb_record *)PyArray_DATA(out), (uint64_t)n);
    if ((npy_intp)got == n) return (PyObject *)out;
    /* Some records were lapped while we copied: hand back the valid prefix. */
    PyObject *part = PySequence_GetSlice((PyObject *)out, 0, (Py_ssize_t)got);
    Py_DECREF(out);
    return part;
}

/* pop_into(out) -> int: fill a preallocated C-contiguous 64-byte-record array. */
static PyObject *Ring_pop_into(RingObject *self, PyObject *arg)
{
    if (!PyArray_Check(arg)) {
        PyErr_SetString(PyExc_TypeError, "pop_into(out) needs a numpy array of 64-byte records");
        return NULL;
    }
    PyArrayObject *out = (PyArrayObject *)arg;
    if (PyArray_ITEMSIZE(out) != SB_RECORD_SIZE || !PyArray_IS_C_CONTIGUOUS(out) ||
        !PyArray_ISWRITEABLE(out)) {
        PyErr_SetString(PyExc_ValueError,
                        "pop_into(out) needs a writeable C-contiguous array with a 64-byte "
                        "record dtype (e.g. np.empty(n, RECORD_DTYPE))");
        return NULL;
    }
    if (check_side(self, 0) < 0) return NULL;
    uint64_t got = sb_ring_pop_batch(self->r, (sb_record *)PyArray_DATA(out),
                                     (uint64_t)PyArray_SIZE(out));
    return PyLong_FromUnsignedLongLong(got);
}

static PyObject *Ring_available(RingObject *self, PyObject *Py_UNUSED(ignored))
{
    if (check_side(self, 0) < 0) return NULL;
    return PyLong_FromUnsignedLongLong(sb_ring_available(self->r));
}

/* free_slots() -> int: pushes that would succeed now (producer side). */
static PyObject *Ring_free_slots(RingObject *self, PyObject *Py_UNUSED(ignored))
{
    if (check_side(self, 1) < 0) return NULL;
    if (self->r->overwrite) return PyLong_FromUnsignedLongLong(self->r->mask + 1u);
    return PyLong_FromUnsignedLongLong(sb_ring_free(self->r, self->r->mask + 1u));
}

typedef struct ring_ready_ctx {
    const _Atomic uint64_t *head;
    uint64_t tail;
} ring_ready_ctx;

static int ring_ready(const void *p)
{
    const ring_ready_ctx *c = p;
    return atomic_load_explicit(c->head, memory_order_acquire) != c->tail;
}

/* poll() -> bool: a record is available now (never waits). */
static PyObject *Ring_poll(RingObject *self, PyObject *Py_UNUSED(ignored))
{
    if (check_side(self, 0) < 0) return NULL;
    return PyBool_FromLong(atomic_load_explicit(&self->r->ctl->head, memory_order_acquire) !=
                           self->r->tail);
}

/* wait(timeout_s, *, spin_s=20e-6, yield_s=200e-6) -> bool */
static PyObject *Ring_wait(RingObject *self, PyObject *const *args, Py_ssize_t nargs,
                           PyObject *kwnames)
{
    static const char *const names[] = {"spin_s", "yield_s"};
    PyObject *kw[2] = {NULL, NULL};
    if (nargs != 1) {
        PyErr_SetString(PyExc_TypeError, "wait(timeout_s, *, spin_s=..., yield_s=...)");
        return NULL;
    }
    if (kwnames && sb_parse_kw(args, nargs, kwnames, names, kw, 2) < 0) return NULL;
    if (check_side(self, 0) < 0) return NULL;
    ring_ready_ctx ctx = {&self->r->ctl->head, self->r->tail};
    if (ring_ready(&ctx)) Py_RETURN_TRUE;
    double timeout_s = PyFloat_AsDouble(args[0]);
    double spin_s = kw[0] ? PyFloat_AsDouble(kw[0]) : -1.0;
    double yield_s = kw[1] ? PyFloat_AsDouble(kw[1]) : -1.0;
    if (PyErr_Occurred()) return NULL;
    if (self->index == SB_RING_SENSORS && sb_in_lockstep(self->owner))
        return PyBool_FromLong(sb_handoff_wait_gil(self->owner, 0, timeout_s));
    int ok = sb_wait_gil(ring_ready, &ctx, timeout_s, spin_s, yield_s,
                         sb_segment_their_bell(&self->owner->seg));
    if (ok < 0) return NULL;
    return PyBool_FromLong(ok);
}

static PyObject *Ring_stats(RingObject *self, PyObject *Py_UNUSED(ignored))
{
    if (sb_check_open(self->owner)) return NULL;
    sb_ring_stats s = sb_ring_stats_read(self->r->ctl);
    return Py_BuildValue("{sKsKsKsKsK}", "written", (unsigned long long)s.written, "read",
                         (unsigned long long)s.read, "overwritten",
                         (unsigned long long)s.overwritten, "rejected",
                         (unsigned long long)s.rejected, "available",
                         (unsigned long long)s.available);
}

static PyObject *Ring_get_name(RingObject *self, void *Py_UNUSED(c))
{
    return PyUnicode_FromString(RING_NAMES[self->index]);
}

static PyObject *Ring_get_capacity(RingObject *self, void *Py_UNUSED(c))
{
    return PyLong_FromUnsignedLongLong(self->r->mask + 1u);
}

static PyObject *Ring_get_overwrite(RingObject *self, void *Py_UNUSED(c))
{
    return PyBool_FromLong(self->r->overwrite);
}

static PyObject *Ring_get_produces(RingObject *self, void *Py_UNUSED(c))
{
    return PyBool_FromLong(self->produces);
}

static PyObject *Ring_get_segment(RingObject *self, void *Py_UNUSED(c))
{
    Py_INCREF(self->owner);
    return (PyObject *)self->owner;
}

static PyObject *Ring_repr(RingObject *self)
{
    return PyUnicode_FromFormat("<Ring %s of %R, %llu slots, %s here>", RING_NAMES[self->index],
                                self->owner->name, (unsigned long long)(self->r->mask + 1u),
                                self->produces ? "produced" : "consumed");
}

static PyMethodDef Ring_methods[] = {
    {"try_push", (PyCFunction)(void (*)(void))Ring_try_push, METH_FASTCALL | METH_KEYWORDS,
     "try_push(record, *, stamp=True) -> bool. Push one 64-byte record (np.void or bytes). "
     "False when the ring is full and does not overwrite (counted as rejected). stamp sets "
     "wall_ns to CLOCK_MONOTONIC at publish."},
    {"push_batch", (PyCFunction)(void (*)(void))Ring_push_batch, METH_FASTCALL | METH_KEYWORDS,
     "push_batch(records, *, stamp=True) -> int. Push an array of 64-byte records; returns "
     "how many were written (the rest rejected when the ring does not overwrite)."},
    {"try_pop", (PyCFunction)Ring_try_pop, METH_NOARGS,
     "try_pop() -> np.void (RECORD_DTYPE) or None when empty."},
    {"pop_batch", (PyCFunction)Ring_pop_batch, METH_O,
     "pop_batch(max_n) -> RECORD_DTYPE array of 0..max_n records."},
    {"pop_into", (PyCFunction)Ring_pop_into, METH_O,
     "pop_into(out) -> int. Fill a preallocated 64-byte-record array; returns the count."},
    {"available", (PyCFunction)Ring_available, METH_NOARGS,
     "available() -> int. Records waiting for this consumer."},
    {"free_slots", (PyCFunction)Ring_free_slots, METH_NOARGS,
     "free_slots() -> int. Producer side: pushes that would succeed now (the capacity when "
     "the ring overwrites)."},
    {"poll", (PyCFunction)Ring_poll, METH_NOARGS,
     "poll() -> bool. True when a record is waiting; never blocks."},
    {"wait", (PyCFunction)(void (*)(void))Ring_wait, METH_FASTCALL | METH_KEYWORDS,
     "wait(timeout_s, *, spin_s=20e-6, yield_s=200e-6) -> bool. Wait for a record: spin, "
     "then sched_yield, then sleep (GIL released while yielding and sleeping). In lockstep "
     "the FC's wait for sensor records is the hand-off (sb_handoff.h; spin_s, yield_s unused)."},
    {"stats", (PyCFunction)Ring_stats, METH_NOARGS,
     "stats() -> dict(written, read, overwritten, rejected, available)."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef Ring_getset[] = {
    {"name", (getter)Ring_get_name, NULL, "'sensors' or 'actuators'", NULL},
    {"capacity", (getter)Ring_get_capacity, NULL, "slots (a power of two)", NULL},
    {"overwrite", (getter)Ring_get_overwrite, NULL, "True: a full ring overwrites", NULL},
    {"produces", (getter)Ring_get_produces, NULL, "True if this process pushes", NULL},
    {"segment", (getter)Ring_get_segment, NULL, "the Segment this ring belongs to", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

PyTypeObject SbRingType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "silbridge.shm._ring.Ring",
    .tp_basicsize = sizeof(RingObject),
    .tp_dealloc = (destructor)Ring_dealloc,
    .tp_repr = (reprfunc)Ring_repr,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "One side of a single-producer single-consumer ring in a shared segment. "
              "Get it as Segment.sensors or Segment.actuators.",
    .tp_methods = Ring_methods,
    .tp_getset = Ring_getset,
};
