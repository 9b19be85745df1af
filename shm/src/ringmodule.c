/*
 * ringmodule.c - module init of silbridge.shm._ring and the helpers the
 * object files share: status-to-exception mapping, keyword parsing for
 * METH_FASTCALL, and waiting with the GIL released while yielding/sleeping.
 */
#define SB_MODULE_MAIN
#include "module.h"

#include <stdlib.h>

#include <math.h>

sb_errors SB_ERR;
PyArray_Descr *SB_RECORD_DESCR;

PyObject *sb_raise_status(int status, PyObject *name, const sb_seg_diag *d)
{
    PyObject *info = Py_BuildValue("{sisisIsKsKss}", "errno", d->err_no, "pid", (int)d->pid,
                                   "found_version", (unsigned)d->found_version, "found_magic",
                                   (unsigned long long)d->found_magic, "found_hash",
                                   (unsigned long long)d->found_hash, "what", d->what);
    if (!info) return NULL;
    PyObject *exc = PyObject_CallFunction(SB_ERR.from_status, "iOO", status, name, info);
    Py_DECREF(info);
    if (!exc) return NULL;
    PyErr_SetObject((PyObject *)Py_TYPE(exc), exc);
    Py_DECREF(exc);
    return NULL;
}

int sb_parse_kw(PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames,
                const char *const *names, PyObject **out, int n_names)
{
    if (!kwnames) return 0;
    Py_ssize_t nkw = PyTuple_GET_SIZE(kwnames);
    for (Py_ssize_t k = 0; k < nkw; ++k) {
        PyObject *key = PyTuple_GET_ITEM(kwnames, k);
        int found = 0;
        for (int j = 0; j < n_names; ++j) {
            if (PyUnicode_CompareWithASCIIString(key, names[j]) == 0) {
                out[j] = args[nargs + k];
                found = 1;
                break;
            }
        }
        if (!found) {
            PyErr_Format(PyExc_TypeError, "unexpected keyword argument %R", key);
            return -1;
        }
    }
    return 0;
}

static int64_t seconds_to_ns(double s, int64_t fallback)
{
    if (s < 0.0 || isnan(s)) return fallback;
    if (s > 9.0e9) return INT64_MAX / 2; /* "forever", without overflow in sums */
    return (int64_t)(s * 1e9);
}

/* SILBRIDGE_NO_DOORBELL=1 at import: waits yield and sleep as before the doorbells (for
 * A/B measurements, tools/load_bench.py --ab); publishers still ring (nobody waits). */
int sb_doorbells_off = 0;

int sb_wait_gil(sb_ready_fn ready, const void *ctx, double timeout_s, double spin_s,
                double yield_s, sb_doorbell *bell)
{
    if (sb_doorbells_off) bell = NULL;
    sb_wait_policy p = sb_wait_default_policy();
    p.spin_ns = seconds_to_ns(spin_s, p.spin_ns);
    p.yield_ns = seconds_to_ns(yield_s, p.yield_ns);
    if (p.yield_ns < p.spin_ns) p.yield_ns = p.spin_ns;
    int64_t start = sb_monotonic_ns();
    int64_t deadline = start + seconds_to_ns(timeout_s < 0.0 ? 0.0 : timeout_s, 0);
    if (sb_wait_spin(ready, ctx, &p, start, deadline)) return 1;
    if (sb_monotonic_ns() >= deadline) return 0;
    int ok;
    Py_BEGIN_ALLOW_THREADS
    /* With the other side's doorbell: yield while that is cheap, then block until it
     * publishes (no sleep steps: a waiter that keeps its core on a busy machine starves
     * the peer it waits for, sb_doorbell.h). */
    ok = bell ? sb_bell_wait_after_yield(bell, ready, ctx, start + p.yield_ns, deadline)
              : sb_wait_block(ready, ctx, &p, start, deadline);
    Py_END_ALLOW_THREADS
    return ok;
}

/* -------------------------------------------------------- module functions */

static PyObject *mod_layout_hash(PyObject *Py_UNUSED(m), PyObject *Py_UNUSED(a))
{
    return PyLong_FromUnsignedLongLong(sb_layout_hash());
}

static PyObject *mod_monotonic_ns(PyObject *Py_UNUSED(m), PyObject *Py_UNUSED(a))
{
    return PyLong_FromLongLong(sb_monotonic_ns());
}

/* spin_until(deadline_ns) -> now_ns: spin on CLOCK_MONOTONIC until deadline_ns with the GIL
 * released. A real-time loop spins the last part of each period (bridge/pacing.py); spun in
 * Python, the GIL stays with the spinner, and at --speed 5 and up (no sleep left in a period)
 * the process's MAVLink server thread waited a switch interval (5 ms) for every GIL take:
 * its streams went out up to 3 s of sim time apart and commands took effect seconds late. */
static PyObject *mod_spin_until(PyObject *Py_UNUSED(m), PyObject *arg)
{
    long long deadline = PyLong_AsLongLong(arg);
    if (deadline == -1 && PyErr_Occurred()) return NULL;
    int64_t now;
    Py_BEGIN_ALLOW_THREADS
    for (now = sb_monotonic_ns(); now < deadline; now = sb_monotonic_ns()) sb_cpu_relax();
    Py_END_ALLOW_THREADS
    return PyLong_FromLongLong(now);
}

static PyObject *mod_segment_bytes(PyObject *Py_UNUSED(m), PyObject *args)
{
    unsigned long long s, a;
    if (!PyArg_ParseTuple(args, "KK", &s, &a)) return NULL;
    return PyLong_FromUnsignedLongLong(sb_segment_bytes(s, a));
}

static PyObject *mod_remove_stale(PyObject *Py_UNUSED(m), PyObject *name)
{
    const char *cname = PyUnicode_AsUTF8(name);
    if (!cname) return NULL;
    sb_seg_diag diag;
    int s = sb_segment_remove_stale(cname, &diag);
    if (s == SB_SEG_OK) Py_RETURN_TRUE;
    if (s == SB_SEG_E_MISSING) Py_RETURN_FALSE;
    return sb_raise_status(s, name, &diag);
}

/* probe(name) -> dict | None: a segment's header, read without attaching. */
static PyObject *mod_probe(PyObject *Py_UNUSED(m), PyObject *name)
{
    const char *cname = PyUnicode_AsUTF8(name);
    if (!cname) return NULL;
    sb_seg_diag diag;
    sb_seg_probe pr;
    int s;
    Py_BEGIN_ALLOW_THREADS
    s = sb_segment_probe(cname, &pr, &diag);
    Py_END_ALLOW_THREADS
    if (s == SB_SEG_E_MISSING) Py_RETURN_NONE;
    if (s != SB_SEG_OK) return sb_raise_status(s, name, &diag);
    return Py_BuildValue("{sOsIsisOsLsKss}", "published", pr.published ? Py_True : Py_False,
                         "version", pr.version, "owner_pid", (int)pr.owner_pid, "owner_alive",
                         pr.owner_alive ? Py_True : Py_False, "created_unix_ns",
                         (long long)pr.created_unix_ns, "bytes", (unsigned long long)pr.bytes,
                         "tag", pr.tag);
}

/* The layout of the shared structs as this build sees them, for the tests. */
static PyObject *mod_layout(PyObject *Py_UNUSED(m), PyObject *Py_UNUSED(a))
{
    return Py_BuildValue(
        "{snsnsnsnsnsnsnsnsnsnsnsnsnsnsn}", "sizeof_record", (Py_ssize_t)sizeof(sb_record),
        "sizeof_header", (Py_ssize_t)sizeof(sb_header), "sizeof_ring_ctl",
        (Py_ssize_t)sizeof(sb_ring_ctl), "sizeof_seg_header", (Py_ssize_t)sizeof(sb_seg_header),
        "ring_head", (Py_ssize_t)offsetof(sb_ring_ctl, head), "ring_tail",
        (Py_ssize_t)offsetof(sb_ring_ctl, tail), "seg_owner_line",
        (Py_ssize_t)offsetof(sb_seg_header, owner_heartbeat), "seg_peer_line",
        (Py_ssize_t)offsetof(sb_seg_header, peer_heartbeat), "seg_words",
        (Py_ssize_t)offsetof(sb_seg_header, words), "seg_rings",
        (Py_ssize_t)offsetof(sb_seg_header, rings), "header_bytes",
        (Py_ssize_t)SB_SEG_HEADER_BYTES, "words", (Py_ssize_t)SB_SEG_WORDS, "kind_count",
        (Py_ssize_t)SB_KIND_COUNT, "records_version", (Py_ssize_t)SB_RECORDS_VERSION,
        "seg_version", (Py_ssize_t)SB_SEG_VERSION);
}

/* The lockstep words and values the C side uses by number (shm/lockstep.py names them). */
static PyObject *mod_lockstep_layout(PyObject *Py_UNUSED(m), PyObject *Py_UNUSED(a))
{
    return Py_BuildValue(
        "{snsnsnsnsnsnsnsnsn}", "owner_step_word", (Py_ssize_t)SB_WORD_OWNER_STEP,
        "peer_step_word", (Py_ssize_t)SB_WORD_PEER_STEP, "peer_sync_word",
        (Py_ssize_t)SB_WORD_PEER_SYNC, "ring_sync_word", (Py_ssize_t)offsetof(sb_ring_ctl, sync_word),
        "run_mode_word",
        (Py_ssize_t)SB_WORD_RUN_MODE, "stop_word", (Py_ssize_t)SB_WORD_STOP, "mode_lockstep",
        (Py_ssize_t)SB_MODE_LOCKSTEP, "ring_step_word", (Py_ssize_t)offsetof(sb_ring_ctl, step_word),
        "seg_handoff_arm", (Py_ssize_t)offsetof(sb_seg_header, handoff_arm));
}

static PyMethodDef module_methods[] = {
    {"layout_hash", mod_layout_hash, METH_NOARGS, "layout_hash() -> int (this build)"},
    {"layout", mod_layout, METH_NOARGS, "layout() -> dict of sizeof/offsetof of shared structs"},
    {"lockstep_layout", mod_lockstep_layout, METH_NOARGS,
     "lockstep_layout() -> dict: the lockstep word indices and values the C side uses, and "
     "where the step words and the hand-off's way of waiting live"},
    {"monotonic_ns", mod_monotonic_ns, METH_NOARGS, "CLOCK_MONOTONIC [ns], the wall_ns clock"},
    {"spin_until", mod_spin_until, METH_O,
     "spin_until(deadline_ns) -> now_ns: spin on CLOCK_MONOTONIC, the GIL released"},
    {"segment_bytes", mod_segment_bytes, METH_VARARGS,
     "segment_bytes(sensor_slots, actuator_slots) -> int"},
    {"probe", mod_probe, METH_O,
     "probe(name) -> dict | None: header of segment `name` read without attaching (owner_pid, "
     "owner_alive, tag, created_unix_ns, version, published, bytes); None if missing"},
    {"remove_stale", mod_remove_stale, METH_O,
     "remove_stale(name) -> bool: remove the segment if its owner is gone"},
    {"serve_polls", (PyCFunction)(void (*)(void))sb_serve_polls, METH_FASTCALL,
     "serve_polls(capsule, poll, until_ns, max_polls, timeout_s, python_kinds, records) -> "
     "(polls, last_n, timed_out): the FC's lockstep loop (shm/src/serve.c): wait for the "
     "bridge's records (the hand-off), call poll(), until the FC's step word reaches until_ns "
     "(int, or float inf), a poll took a record whose kind is in the bitmask python_kinds "
     "(read from `records`, the array of 64-byte records poll() pops into), max_polls polls "
     "that consumed records, STOP, or timeout_s; timed_out: the last wait saw no record."},
    {"c_stream_bench", (PyCFunction)(void (*)(void))sb_bench_stream,
     METH_VARARGS | METH_KEYWORDS,
     "c_stream_bench(ring, seconds, batch=64, idle_timeout_s=10.0, max_records=0) -> dict: C "
     "producer (for seconds or max_records, 0 = no limit) or consumer (until the producer's end "
     "marker) by the ring's role, with sequence and checksum verification"},
    {"c_pingpong_bench", (PyCFunction)(void (*)(void))sb_bench_pingpong,
     METH_VARARGS | METH_KEYWORDS,
     "c_pingpong_bench(ring_in, ring_out, seconds, idle_timeout_s=10.0) -> dict: C ping-pong; "
     "seconds > 0 initiates, seconds == 0 echoes until the initiator ends"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef ring_module = {
    PyModuleDef_HEAD_INIT, "_ring",
    "SPSC rings of 64-byte records in POSIX shared memory (C11 atomics).", -1, module_methods,
};

static int load_errors(void)
{
    PyObject *m = PyImport_ImportModule("silbridge.shm.errors");
    if (!m) return -1;
    SB_ERR.closed = PyObject_GetAttrString(m, "SegmentClosedError");
    SB_ERR.role = PyObject_GetAttrString(m, "RingRoleError");
    SB_ERR.kind = PyObject_GetAttrString(m, "RecordKindError");
    SB_ERR.from_status = PyObject_GetAttrString(m, "from_status");
    Py_DECREF(m);
    return (SB_ERR.closed && SB_ERR.role && SB_ERR.kind &&
            SB_ERR.from_status) ? 0 : -1;
}

static int load_record_dtype(void)
{
    PyObject *m = PyImport_ImportModule("silbridge.shm.records");
    if (!m) return -1;
    PyObject *dt = PyObject_GetAttrString(m, "RECORD_DTYPE");
    Py_DECREF(m);
    if (!dt) return -1;
    int ok = PyArray_DescrConverter(dt, &SB_RECORD_DESCR);
    Py_DECREF(dt);
    if (!ok) return -1;
    if (PyDataType_ELSIZE(SB_RECORD_DESCR) != SB_RECORD_SIZE) {
        PyErr_SetString(PyExc_ImportError,
                        "silbridge.shm.records.RECORD_DTYPE does not match sb_records.h: rebuild "
                        "the extension (setup.py build_ext --inplace)");
        return -1;
    }
    return 0;
}

PyMODINIT_FUNC PyInit__ring(void)
{
    import_array();
    if (load_errors() < 0 || load_record_dtype() < 0) return NULL;
    const char *off = getenv("SILBRIDGE_NO_DOORBELL");
    sb_doorbells_off = off != NULL && off[0] != '\0' && off[0] != '0';
    if (PyType_Ready(&SbSegmentType) < 0 || PyType_Ready(&SbRingType) < 0) return NULL;
    PyObject *m = PyModule_Create(&ring_module);
    if (!m) return NULL;
    Py_INCREF(&SbSegmentType);
    Py_INCREF(&SbRingType);
    if (PyModule_AddObject(m, "SegmentBase", (PyObject *)&SbSegmentType) < 0 ||
        PyModule_AddObject(m, "Ring", (PyObject *)&SbRingType) < 0 ||
        PyModule_AddIntConstant(m, "RECORD_SIZE", SB_RECORD_SIZE) < 0 ||
        PyModule_AddIntConstant(m, "WORDS", SB_SEG_WORDS) < 0 ||
        PyModule_AddIntConstant(m, "KIND_COUNT", SB_KIND_COUNT) < 0 ||
        PyModule_AddIntConstant(m, "MIN_SLOTS", SB_RING_MIN_SLOTS) < 0 ||
        PyModule_AddIntConstant(m, "MAX_SLOTS", SB_RING_MAX_SLOTS) < 0 ||
        PyModule_AddStringConstant(m, "SHM_PREFIX", SB_SEG_PREFIX) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    /* Status codes, so errors.from_status can name them. */
    static const struct { const char *name; int value; } codes[] = {
        {"E_NAME", SB_SEG_E_NAME},       {"E_CONFIG", SB_SEG_E_CONFIG},
        {"E_MISSING", SB_SEG_E_MISSING}, {"E_CREATING", SB_SEG_E_CREATING},
        {"E_BUSY", SB_SEG_E_BUSY},       {"E_STALE", SB_SEG_E_STALE},
        {"E_PERM", SB_SEG_E_PERM},       {"E_MAGIC", SB_SEG_E_MAGIC},
        {"E_VERSION", SB_SEG_E_VERSION}, {"E_LAYOUT", SB_SEG_E_LAYOUT},
        {"E_PEER_BUSY", SB_SEG_E_PEER_BUSY}, {"E_OS", SB_SEG_E_OS},
    };
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; ++i) {
        if (PyModule_AddIntConstant(m, codes[i].name, codes[i].value) < 0) {
            Py_DECREF(m);
            return NULL;
        }
    }
    return m;
}
