/*
 * segobject.c - the Python SegmentBase type: one process's mapping of a
 * segment, its two ring handles, heartbeats and lockstep words.
 * silbridge.shm.segment.Segment subclasses it with the create/attach
 * class methods and the context manager.
 */
#include "module.h"

#include <float.h>
#include <math.h>
#include <unistd.h>

static PyObject *Seg_new(PyTypeObject *type, PyObject *Py_UNUSED(a), PyObject *Py_UNUSED(k))
{
    SegmentObject *self = (SegmentObject *)type->tp_alloc(type, 0);
    if (!self) return NULL;
    memset(&self->seg, 0, sizeof self->seg);
    self->seg.fd = -1;
    Py_INCREF(Py_None);
    self->name = Py_None;
    return (PyObject *)self;
}

static int Seg_traverse(SegmentObject *self, visitproc visit, void *arg)
{
    Py_VISIT(self->dict);
    return 0;
}

static int Seg_clear(SegmentObject *self)
{
    Py_CLEAR(self->dict);
    return 0;
}

static void Seg_dealloc(SegmentObject *self)
{
    PyObject_GC_UnTrack(self);
    sb_handoff_stop(self);
    sb_segment_close(&self->seg);
    Seg_clear(self);
    Py_CLEAR(self->name);
    /* A Python subclass's dealloc decrefs its heap type after this returns. */
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static void bind_rings(SegmentObject *self)
{
    for (int i = 0; i < SB_RING_COUNT; ++i)
        sb_ring_bind(&self->rings[i], &self->seg.hdr->rings[i], self->seg.base);
}

static int check_unopened(SegmentObject *self)
{
    if (!self->seg.base) return 0;
    PyErr_SetString(PyExc_RuntimeError, "this Segment object is already open");
    return -1;
}

/* _create(name, sensor_slots, actuator_slots, overwrite, replace_stale) */
static PyObject *Seg_create(SegmentObject *self, PyObject *args)
{
    PyObject *name;
    unsigned long long sensor_slots, actuator_slots;
    int overwrite, replace_stale;
    if (!PyArg_ParseTuple(args, "UKKpp", &name, &sensor_slots, &actuator_slots, &overwrite,
                          &replace_stale))
        return NULL;
    if (check_unopened(self) < 0) return NULL;
    const char *cname = PyUnicode_AsUTF8(name);
    if (!cname) return NULL;
    sb_seg_diag diag;
    int s;
    Py_BEGIN_ALLOW_THREADS
    s = sb_segment_create(&self->seg, cname, sensor_slots, actuator_slots, overwrite,
                          replace_stale, &diag);
    Py_END_ALLOW_THREADS
    if (s != SB_SEG_OK) return sb_raise_status(s, name, &diag);
    Py_INCREF(name);
    Py_SETREF(self->name, name);
    bind_rings(self);
    sb_handoff_start(self);
    Py_RETURN_NONE;
}

/* _attach(name): one attempt; the Python side retries until its timeout. */
static PyObject *Seg_attach(SegmentObject *self, PyObject *name)
{
    if (!PyUnicode_Check(name)) {
        PyErr_SetString(PyExc_TypeError, "the instance name must be a str");
        return NULL;
    }
    if (check_unopened(self) < 0) return NULL;
    const char *cname = PyUnicode_AsUTF8(name);
    if (!cname) return NULL;
    sb_seg_diag diag;
    int s = sb_segment_attach(&self->seg, cname, &diag);
    if (s != SB_SEG_OK) return sb_raise_status(s, name, &diag);
    Py_INCREF(name);
    Py_SETREF(self->name, name);
    bind_rings(self);
    sb_handoff_start(self);
    Py_RETURN_NONE;
}

static PyObject *Seg_close(SegmentObject *self, PyObject *Py_UNUSED(ignored))
{
    sb_handoff_stop(self);
    sb_segment_close(&self->seg);
    Py_RETURN_NONE;
}

static void capi_free(PyObject *capsule)
{
    PyMem_Free(PyCapsule_GetPointer(capsule, SB_CAPI_CAPSULE));
    Py_XDECREF((PyObject *)PyCapsule_GetContext(capsule));
}

/* c_capsule() -> the segment for other C extensions (sb_capi.h); fc_sil/fc_transport.py. */
static PyObject *Seg_c_capsule(SegmentObject *self, PyObject *Py_UNUSED(ignored))
{
    if (sb_check_open(self)) return NULL;
    sb_capi *api = PyMem_Malloc(sizeof *api);
    if (!api) return PyErr_NoMemory();
    api->version = SB_CAPI_VERSION;
    api->is_owner = self->seg.is_owner;
    api->seg = &self->seg;
    api->rings = self->rings;
    sb_handoff_fill_capi(self, api);
    PyObject *cap = PyCapsule_New(api, SB_CAPI_CAPSULE, capi_free);
    if (!cap) {
        PyMem_Free(api);
        return NULL;
    }
    Py_INCREF(self);
    if (PyCapsule_SetContext(cap, self) < 0) {   /* the capsule keeps the segment alive */
        Py_DECREF(self);
        Py_DECREF(cap);
        return NULL;
    }
    return cap;
}

static PyObject *Seg_unlink(SegmentObject *self, PyObject *Py_UNUSED(ignored))
{
    if (!self->seg.is_owner) {
        PyErr_SetString(SB_ERR.role, "only the segment owner (the bridge) unlinks the segment");
        return NULL;
    }
    sb_segment_unlink(&self->seg);
    Py_RETURN_NONE;
}

static PyObject *Seg_beat(SegmentObject *self, PyObject *Py_UNUSED(ignored))
{
    if (sb_check_open(self)) return NULL;
    sb_seg_header *h = self->seg.hdr;
    _Atomic uint64_t *mine = self->seg.is_owner ? &h->owner_heartbeat : &h->peer_heartbeat;
    uint64_t v = atomic_load_explicit(mine, memory_order_relaxed) + 1u;
    atomic_store_explicit(mine, v, memory_order_release);
    return PyLong_FromUnsignedLongLong(v);
}

static PyObject *Seg_peer_heartbeat(SegmentObject *self, PyObject *Py_UNUSED(ignored))
{
    if (sb_check_open(self)) return NULL;
    sb_seg_header *h = self->seg.hdr;
    _Atomic uint64_t *theirs = self->seg.is_owner ? &h->peer_heartbeat : &h->owner_heartbeat;
    return PyLong_FromUnsignedLongLong(atomic_load_explicit(theirs, memory_order_acquire));
}

static PyObject *Seg_peer_alive(SegmentObject *self, PyObject *Py_UNUSED(ignored))
{
    if (sb_check_open(self)) return NULL;
    return PyBool_FromLong(self->seg.is_owner ? sb_segment_peer_alive(&self->seg)
                                              : sb_segment_owner_alive(&self->seg));
}

static int word_index(PyObject *obj, Py_ssize_t *i)
{
    *i = PyLong_AsSsize_t(obj);
    if (*i == -1 && PyErr_Occurred()) return -1;
    if (*i < 0 || *i >= (Py_ssize_t)SB_SEG_WORDS) {
        PyErr_Format(PyExc_IndexError, "lockstep word index %zd out of range 0..%u", *i,
                     SB_SEG_WORDS - 1);
        return -1;
    }
    return 0;
}

static PyObject *Seg_set_word(SegmentObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    Py_ssize_t i;
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "set_word(i, value)");
        return NULL;
    }
    if (word_index(args[0], &i) < 0) return NULL;
    unsigned long long v = PyLong_AsUnsignedLongLong(args[1]);
    if (v == (unsigned long long)-1 && PyErr_Occurred()) return NULL;
    if (sb_check_open(self)) return NULL;
    atomic_store_explicit(sb_seg_word(self->seg.hdr, (unsigned)i), v, memory_order_release);
    sb_bell_ring(sb_segment_my_bell(&self->seg));
    Py_RETURN_NONE;
}

static PyObject *Seg_word(SegmentObject *self, PyObject *arg)
{
    Py_ssize_t i;
    if (word_index(arg, &i) < 0) return NULL;
    if (sb_check_open(self)) return NULL;
    return PyLong_FromUnsignedLongLong(
        atomic_load_explicit(sb_seg_word(self->seg.hdr, (unsigned)i), memory_order_acquire));
}

typedef struct word_ready_ctx {
    const _Atomic uint64_t *word;
    uint64_t at_least;
} word_ready_ctx;

static int word_ready(const void *p)
{
    const word_ready_ctx *c = p;
    return atomic_load_explicit(c->word, memory_order_acquire) >= c->at_least;
}

/* wait_word(i, at_least, timeout_s, *, spin_s=..., yield_s=...) -> bool */
static PyObject *Seg_wait_word(SegmentObject *self, PyObject *const *args, Py_ssize_t nargs,
                               PyObject *kwnames)
{
    static const char *const names[] = {"spin_s", "yield_s"};
    PyObject *kw[2] = {NULL, NULL};
    Py_ssize_t i;
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "wait_word(i, at_least, timeout_s)");
        return NULL;
    }
    if (kwnames && sb_parse_kw(args, nargs, kwnames, names, kw, 2) < 0) return NULL;
    if (word_index(args[0], &i) < 0) return NULL;
    unsigned long long at_least = PyLong_AsUnsignedLongLong(args[1]);
    double timeout_s = PyFloat_AsDouble(args[2]);
    double spin_s = kw[0] ? PyFloat_AsDouble(kw[0]) : -1.0;
    double yield_s = kw[1] ? PyFloat_AsDouble(kw[1]) : -1.0;
    if (PyErr_Occurred()) return NULL;
    if (sb_check_open(self)) return NULL;
    word_ready_ctx ctx = {sb_seg_word(self->seg.hdr, (unsigned)i), at_least};
    if (self->seg.is_owner && i == SB_WORD_PEER_STEP && sb_in_lockstep(self))
        return PyBool_FromLong(sb_handoff_wait_gil(self, at_least, timeout_s));
    if (word_ready(&ctx)) Py_RETURN_TRUE;
    int ok = sb_wait_gil(word_ready, &ctx, timeout_s, spin_s, yield_s,
                         sb_segment_their_bell(&self->seg));
    if (ok < 0) return NULL;
    return PyBool_FromLong(ok);
}

static PyObject *Seg_handoff_stats(SegmentObject *self, PyObject *Py_UNUSED(ignored))
{
    return sb_handoff_stats_dict(self);
}

static PyObject *Seg_get_sensors(SegmentObject *self, void *Py_UNUSED(c))
{
    if (sb_check_open(self)) return NULL;
    return sb_ring_object_new(self, SB_RING_SENSORS);
}

static PyObject *Seg_get_actuators(SegmentObject *self, void *Py_UNUSED(c))
{
    if (sb_check_open(self)) return NULL;
    return sb_ring_object_new(self, SB_RING_ACTUATORS);
}

static PyObject *Seg_get_peer_pid(SegmentObject *self, void *Py_UNUSED(c))
{
    if (sb_check_open(self)) return NULL;
    sb_seg_header *h = self->seg.hdr;
    int32_t pid = self->seg.is_owner ? atomic_load_explicit(&h->peer_pid, memory_order_acquire)
                                     : h->owner_pid;
    return PyLong_FromLong(pid);
}

static PyObject *Seg_get_info(SegmentObject *self, void *Py_UNUSED(c))
{
    if (sb_check_open(self)) return NULL;
    sb_seg_header *h = self->seg.hdr;
    const sb_doorbell *b = h->bells;
    return Py_BuildValue(
        "{sisisKsLsLsKsKsKsKsisOsss(II)s(KK)}", "owner_pid", (int)h->owner_pid, "peer_pid",
        (int)atomic_load_explicit(&h->peer_pid, memory_order_acquire), "peer_attaches",
        (unsigned long long)atomic_load_explicit(&h->peer_attaches, memory_order_acquire),
        "created_unix_ns", (long long)h->created_unix_ns, "created_mono_ns",
        (long long)h->created_mono_ns, "total_bytes", (unsigned long long)h->total_bytes,
        "layout_hash", (unsigned long long)h->layout_hash, "sensor_slots",
        (unsigned long long)h->rings[SB_RING_SENSORS].capacity, "actuator_slots",
        (unsigned long long)h->rings[SB_RING_ACTUATORS].capacity, "version", (int)h->version,
        "overwrite", h->rings[SB_RING_SENSORS].overwrite ? Py_True : Py_False, "owner_tag",
        h->owner_tag, "bell_waiters",
        atomic_load_explicit(&b[SB_BELL_OWNER].waiters, memory_order_acquire),
        atomic_load_explicit(&b[SB_BELL_PEER].waiters, memory_order_acquire), "bell_wakes",
        (unsigned long long)atomic_load_explicit(&b[SB_BELL_OWNER].wakes, memory_order_relaxed),
        (unsigned long long)atomic_load_explicit(&b[SB_BELL_PEER].wakes, memory_order_relaxed));
}

static PyObject *Seg_get_is_owner(SegmentObject *self, void *Py_UNUSED(c))
{
    return PyBool_FromLong(self->seg.is_owner);
}

static PyObject *Seg_get_closed(SegmentObject *self, void *Py_UNUSED(c))
{
    return PyBool_FromLong(self->seg.base == NULL);
}

static PyObject *Seg_get_name(SegmentObject *self, void *Py_UNUSED(c))
{
    Py_INCREF(self->name);
    return self->name;
}

static PyObject *Seg_get_shm_name(SegmentObject *self, void *Py_UNUSED(c))
{
    return PyUnicode_FromString(self->seg.shm_name);
}

static PyMethodDef Seg_methods[] = {
    {"_create", (PyCFunction)Seg_create, METH_VARARGS,
     "_create(name, sensor_slots, actuator_slots, overwrite, replace_stale)"},
    {"_attach", (PyCFunction)Seg_attach, METH_O, "_attach(name): one attempt"},
    {"close", (PyCFunction)Seg_close, METH_NOARGS,
     "close(): unmap and mark this side closed (idempotent)."},
    {"unlink", (PyCFunction)Seg_unlink, METH_NOARGS,
     "unlink(): owner only; remove the name if it still refers to this segment."},
    {"c_capsule", (PyCFunction)Seg_c_capsule, METH_NOARGS,
     "c_capsule() -> capsule: the segment for another C extension (shm/include/sb_capi.h)."},
    {"beat", (PyCFunction)Seg_beat, METH_NOARGS,
     "beat() -> int: bump this side's heartbeat counter."},
    {"peer_heartbeat", (PyCFunction)Seg_peer_heartbeat, METH_NOARGS,
     "peer_heartbeat() -> int: the other side's heartbeat counter."},
    {"peer_alive", (PyCFunction)Seg_peer_alive, METH_NOARGS,
     "peer_alive() -> bool: the other side's process exists and has not closed."},
    {"set_word", (PyCFunction)(void (*)(void))Seg_set_word, METH_FASTCALL,
     "set_word(i, value): store lockstep word i (uint64) with release."},
    {"word", (PyCFunction)Seg_word, METH_O, "word(i) -> int: load lockstep word i with acquire."},
    {"wait_word", (PyCFunction)(void (*)(void))Seg_wait_word, METH_FASTCALL | METH_KEYWORDS,
     "wait_word(i, at_least, timeout_s, *, spin_s=20e-6, yield_s=200e-6) -> bool: wait until "
     "word i >= at_least (spin, yield, sleep; GIL released while yielding and sleeping). In "
     "lockstep the owner's wait for FC_SIM_NS is the hand-off (sb_handoff.h; spin_s and "
     "yield_s unused)."},
    {"handoff_stats", (PyCFunction)Seg_handoff_stats, METH_NOARGS,
     "handoff_stats() -> dict: this process's lockstep hand-off waits (waits, ready, spun, "
     "ran_out, preempted, blocked, timeouts), the way of waiting in use (arm) and, in the "
     "owner, its choice (windows, probes, switches, cost_ns per arm; shm/include/sb_handoff.h)."},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef Seg_getset[] = {
    {"sensors", (getter)Seg_get_sensors, NULL, "Ring: owner -> peer", NULL},
    {"actuators", (getter)Seg_get_actuators, NULL, "Ring: peer -> owner", NULL},
    {"peer_pid", (getter)Seg_get_peer_pid, NULL, "pid of the other side (0: none yet)", NULL},
    {"info", (getter)Seg_get_info, NULL, "header fields as a dict", NULL},
    {"is_owner", (getter)Seg_get_is_owner, NULL, "True in the process that created it", NULL},
    {"closed", (getter)Seg_get_closed, NULL, "True once closed (or never opened)", NULL},
    {"name", (getter)Seg_get_name, NULL, "instance name", NULL},
    {"shm_name", (getter)Seg_get_shm_name, NULL, "POSIX shared-memory object name", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

PyTypeObject SbSegmentType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "silbridge.shm._ring.SegmentBase",
    .tp_basicsize = sizeof(SegmentObject),
    .tp_dictoffset = offsetof(SegmentObject, dict),
    .tp_new = Seg_new,
    .tp_dealloc = (destructor)Seg_dealloc,
    .tp_traverse = (traverseproc)Seg_traverse,
    .tp_clear = (inquiry)Seg_clear,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE | Py_TPFLAGS_HAVE_GC,
    .tp_doc = "A mapped silbridge segment (use silbridge.shm.Segment.create / attach).",
    .tp_methods = Seg_methods,
    .tp_getset = Seg_getset,
};
