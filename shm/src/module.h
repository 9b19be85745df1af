/*
 * module.h - what the files of the CPython extension silbridge.shm._ring
 * share: the two object types, the exception classes looked up from
 * silbridge.shm.errors at import, and the numpy record dtype.
 *
 * Threading: a Segment and its rings are used from one thread per ring side
 * (the process loop). Waits release the GIL only while yielding or sleeping.
 */
#ifndef SB_MODULE_H
#define SB_MODULE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define NPY_NO_DEPRECATED_API NPY_1_22_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL SB_RING_ARRAY_API
#ifndef SB_MODULE_MAIN
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>
#include <numpy/arrayscalars.h>

#if NPY_ABI_VERSION < 0x02000000 /* numpy < 2 headers */
#define PyDataType_ELSIZE(d) ((d)->elsize)
#endif

#include "sb_capi.h"
#include "sb_doorbell.h"
#include "sb_handoff.h"
#include "sb_ring.h"
#include "sb_segment.h"
#include "sb_wait.h"

typedef struct SegmentObject {
    PyObject_HEAD
    sb_segment seg;           /* seg.base == NULL: never opened or closed */
    sb_ring rings[SB_RING_COUNT]; /* the process-local ring state lives here, once */
    sb_handoff handoff;       /* this process's lockstep hand-off waits (sb_handoff.h) */
    PyObject *name;           /* instance name (str) */
    PyObject *dict;           /* so the Python subclass can keep attributes */
} SegmentObject;

typedef struct RingObject {
    PyObject_HEAD
    SegmentObject *owner; /* strong reference: keeps the mapping alive */
    sb_ring *r;           /* &owner->rings[index] */
    int index;            /* SB_RING_SENSORS or SB_RING_ACTUATORS */
    int produces;         /* 1 if this process is the ring's producer */
} RingObject;

extern PyTypeObject SbSegmentType;
extern PyTypeObject SbRingType;

/* Exception classes from silbridge.shm.errors, plus its factory for
 * segment status codes; filled by the module init. */
typedef struct sb_errors {
    PyObject *closed;
    PyObject *role;
    PyObject *kind;
    PyObject *from_status; /* callable(code, name, diag_dict) -> exception */
} sb_errors;
extern sb_errors SB_ERR;

/* RECORD_DTYPE from silbridge.shm.records (a new reference is handed to
 * numpy each time an array is made). */
extern PyArray_Descr *SB_RECORD_DESCR;

/* Raise the exception for a segment status code. Returns NULL. */
PyObject *sb_raise_status(int status, PyObject *name, const sb_seg_diag *diag);

/* RingObject for ring `index` of an open segment (new reference). */
PyObject *sb_ring_object_new(SegmentObject *seg, int index);

/* Raise SegmentClosedError and return 1 when the segment is closed. */
static inline int sb_check_open(const SegmentObject *seg)
{
    if (seg->seg.base) return 0;
    PyErr_SetString(SB_ERR.closed, "the segment is closed; attach or create it again");
    return 1;
}

/* Waiting with the GIL: spin holding it, then, with it released, block on `bell`
 * (the other side's doorbell) or, with bell NULL, yield and sleep. */
int sb_wait_gil(sb_ready_fn ready, const void *ctx, double timeout_s, double spin_s,
                double yield_s, sb_doorbell *bell);

/* In lockstep (the RUN_MODE word), wait for the other side's step with the GIL released:
 * the owner for the peer's step word >= at_least (counted as a step of its choice), the
 * peer for a record in the sensor ring (at_least unused). 1 / 0 as sb_handoff_wait. */
int sb_handoff_wait_gil(SegmentObject *self, uint64_t at_least, double timeout_s);
extern int sb_doorbells_off; /* SILBRIDGE_NO_DOORBELL at import: the old yield/sleep waits */
static inline int sb_in_lockstep(const SegmentObject *self)
{
    return !sb_doorbells_off &&
           atomic_load_explicit(sb_seg_word(self->seg.hdr, SB_WORD_RUN_MODE),
                                memory_order_relaxed) == SB_MODE_LOCKSTEP;
}

void sb_handoff_start(SegmentObject *self);                  /* at create / attach */
void sb_handoff_stop(SegmentObject *self);                   /* at close: CPUs given back */
void sb_handoff_fill_capi(SegmentObject *self, sb_capi *api); /* the capsule's wait_step */
PyObject *sb_handoff_stats_dict(SegmentObject *self);         /* Segment.handoff_stats() */

/* serve_polls (serve.c): the FC process's lockstep loop of waits and C polls. */
PyObject *sb_serve_polls(PyObject *module, PyObject *const *args, Py_ssize_t nargs);

/* Parse the keyword arguments of a METH_FASTCALL | METH_KEYWORDS call:
 * names[i] is filled into out[i] (borrowed) when given. */
int sb_parse_kw(PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames,
                const char *const *names, PyObject **out, int n_names);

/* The C benchmark loops (bench.c). */
PyObject *sb_bench_stream(PyObject *module, PyObject *args, PyObject *kwargs);
PyObject *sb_bench_pingpong(PyObject *module, PyObject *args, PyObject *kwargs);

#endif /* SB_MODULE_H */
