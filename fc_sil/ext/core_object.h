/*
 * core_object.h - the Core object of silbridge.fc_sil._core and what its files share.
 *
 * The extension is one file per concept: core_object.c (life cycle, parameters, the
 * host's inputs), core_steps.c (single steps and the reads of state, for hosts and
 * tests without records), record_batch.c (record batches: the only place records meet
 * the core), core_log.c (log capture into bytearrays), record_router.c (the record
 * router: the whole FC poll over the shared-memory rings), sysidmethods.c (system identification),
 * core_layout.c and core_bench.c (module functions), coremodule.c (the type and the
 * module). Each file exports its NULL-terminated method table; coremodule.c joins them.
 *
 * Threading: every method runs with the GIL held, so a Core may be shared between a
 * control thread and, say, a MAVLink thread that sets parameters.
 */
#ifndef FC_CORE_OBJECT_H
#define FC_CORE_OBJECT_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <stdint.h>

#include "fc_core.h"
#include "sb_capi.h"
#include "sb_records.h"

/* attach_io(): the segment and where the C poll leaves its results (FcLoop's series
 * and counters). The counters live in a bound int64 array Python reads directly. */
enum {
    FC_IO_LAST_SIM_NS = 0, /* sim time of the last step the FC finished [ns] */
    FC_IO_LAST_K,          /* PWM records of the last poll */
    FC_IO_POLLS,           /* polls that consumed records */
    FC_IO_RECORDS,         /* records consumed */
    FC_IO_PWM_PUBLISHED,   /* PWM records pushed */
    FC_IO_N_LATENCY,       /* samples written to each statistics ring */
    FC_IO_N_PERIOD,
    FC_IO_N_E2E,
    FC_IO_TIMING,          /* 5 words: the last poll's /timing row (sim, imu wall, consume,
                            * pwm wall, period [ns]), for a per-cycle sink (fc_loop.py) */
    /* Written by Python: FC_SYNC_NS's two inputs (sb_segment.h sb_seg_peer_sync). */
    FC_IO_SYNC_UNTIL = FC_IO_TIMING + 5, /* the sim time of the first poll Python follows
                            * (FcLoop.python_due; 0 outside the serve loop: every poll) */
    FC_IO_HAND_ON_KINDS,   /* a bitmask of sb_kind: a poll taking one is followed by Python
                            * (shm/lockstep.py HAND_ON_KINDS) */
    FC_IO_WORDS
};

typedef struct fc_io_t {
    PyObject *capsule;        /* keeps the Segment alive (sb_capi.h) */
    const sb_capi *api;       /* NULL: not attached */
    int fc_sim_word;          /* lockstep word index of FC_SIM_NS */
    Py_buffer series[3];      /* int64 rings: latency, period, e2e [ns] */
    uint64_t series_mask;
    Py_buffer words_view;     /* int64[FC_IO_WORDS] */
    int64_t *words;
    int64_t prev_consume_ns;
} fc_io_t;

typedef struct CoreObject {
    PyObject_HEAD
    fc_core_t core;
    uint32_t pwm_seq;       /* seq of the next PWM record */
    uint32_t last_seq;      /* seq of the last consumed sensor record */
    uint64_t records_in;    /* records consumed by step_batch */
    uint64_t unknown_kind;  /* records of a kind the FC does not consume */
    int ignore_setpoints;   /* MAVLink control: scenario SETPOINT records are skipped */
    uint64_t setpoints_ignored;
    int64_t last_kind_ns[16]; /* sim time of the last record of each kind (-1: never) */
    sb_battery battery;       /* the latest BATTERY record's payload (the physics-side pack) */
    uint32_t battery_count;   /* BATTERY records consumed */
    double accel_sum[3];      /* raw IMU accel summed since take_accel_mean() [m/s^2] */
    uint32_t accel_n;
    /* bind_batch(): the poll loop's record, PWM and status arrays, held so step_bound(n)
     * costs no argument parsing or slicing per call (views[0] records, 1 PWM, 2 status). */
    Py_buffer bound[3];
    int have_bound;
    /* bind_log(): bytearrays step_bound appends each consumed record to (the queue of
     * its kind, or else the mixed stage), PWM records too when log_pwm, and the status
     * rows: a run's log then costs a memcpy per record and no Python per record. */
    PyObject *log_kind[16];
    PyObject *log_stage;
    PyObject *log_status;
    int log_pwm;
    int log_on;               /* any record queue bound */
    PyObject *log_timing;     /* bytearray: the /timing channel's queue (poll_io rows) */
    fc_io_t io;               /* attach_io(): the shared-memory poll loop in C (record_router.c) */
    PyObject *log_ftn1, *log_ftn2; /* bind_fft_log(): FTN1/FTN2 rows at 10 Hz (core_fft.c) */
    int64_t ftn_next_ns;      /* IMU time of the next FTN rows [ns] */
} CoreObject;

/* core_object.c: construction and clean-up (the type's tp_new and tp_dealloc). */
extern PyMethodDef fc_ext_object_methods[];
PyObject *fc_ext_core_new(PyTypeObject *type, PyObject *args, PyObject *kwds);
void fc_ext_core_dealloc(CoreObject *self);
int64_t fc_ext_monotonic_ns(void);

/* core_steps.c */
extern PyMethodDef fc_ext_step_methods[];

/* record_batch.c: consume n records at base; PWM records and status rows to the outputs
 * (cap rows); returns the PWM ticks emitted, or -1 with an exception set. */
extern PyMethodDef fc_ext_batch_methods[];
Py_ssize_t fc_ext_run_records(CoreObject *self, const unsigned char *base, Py_ssize_t n,
                              sb_record *pwm_out, fc_core_status_t *st_out, Py_ssize_t cap);
/* PWM ticks the bound outputs can hold: the smaller of the two arrays. */
Py_ssize_t fc_ext_bound_capacity(const CoreObject *self);
void fc_ext_unbind_batch(CoreObject *self);

/* core_log.c */
extern PyMethodDef fc_ext_log_methods[];
int fc_ext_append_bytes(PyObject *ba, const void *src, Py_ssize_t len);
/* Log one batch: its n records, its k PWM records (when log_pwm) and status rows;
 * -1 with an exception on failure. */
int fc_ext_log_batch(CoreObject *self, const unsigned char *recs, Py_ssize_t n,
                     const unsigned char *pwm, const fc_core_status_t *status, Py_ssize_t k);
void fc_ext_clear_log(CoreObject *self);

/* record_router.c: Core methods attach_io, poll_io; and the clean-up. */
extern PyMethodDef fc_ext_poll_methods[];
void fc_ext_detach_io(CoreObject *self);

/* sysidmethods.c: Core methods sysid_start, sysid_stop, sysid_sample. */
extern PyMethodDef fc_ext_sysid_methods[];

/* core_telem.c: Core methods vibration, esc_reports (what VIBRATION and
 * ESC_TELEMETRY_1_TO_4 carry to ground stations). */
extern PyMethodDef fc_ext_telem_methods[];

/* core_fft.c: Core methods bind_fft_log, fft_ftn, fft_notch_freqs; the FTN rows appended
 * after each logged batch (-1 with an exception on failure). */
extern PyMethodDef fc_ext_fft_methods[];
int fc_ext_log_fft(CoreObject *self);
void fc_ext_clear_fft_log(CoreObject *self);

/* core_layout.c and core_bench.c: module functions. */
extern PyMethodDef fc_ext_layout_functions[];
extern PyMethodDef fc_ext_bench_functions[];
extern PyMethodDef fc_ext_fft_bench_functions[]; /* fft_bench.c */

#endif /* FC_CORE_OBJECT_H */
