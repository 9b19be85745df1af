/*
 * step_lockstep.h - the ring side of a one-process lockstep step, plain C (no Python): what
 * BridgeLoop.publish_step and collect_pwm do around the kernel's step, for
 * step_batch.c, which runs the kernel and calls the FC's poll in between.
 *
 * After the kernel's step k: sb_lockstep_publish (the records to the trace and the sensor
 * ring, then BRIDGE_SIM_NS), sb_lockstep_after_step (the summary errors' sample, the rotor
 * row); after the FC's poll: sb_lockstep_collect (the PWM back) and sb_lockstep_answered.
 * Every buffer is the caller's (Python's arrays, bound once): no heap. The bridge owns the
 * segment (`is_owner`): it produces the sensors ring and consumes the actuators ring.
 */
#ifndef SB_STEP_LOCKSTEP_H
#define SB_STEP_LOCKSTEP_H

#include <stddef.h>
#include <stdint.h>

#include "sb_capi.h"
#include "sb_records.h"

/* The int64 words a batch reports through (Python reads them as _step.IO_*). */
enum {
    SB_IO_PWM_US = 0,         /* 0..3 the held pulse widths, motors 1..4 [us] */
    SB_IO_ARMED = 4,          /* the newest PWM record's armed byte */
    SB_IO_PWM_RECEIVED = 5,   /* PWM records collected (LoopStats.pwm_received) */
    SB_IO_PWM_FIRST_SIM = 6,  /* LoopStats.pwm_first_sim_ns (-1: none yet) */
    SB_IO_PWM_FIRST_WALL = 7,
    SB_IO_PWM_LAST_SIM = 8,
    SB_IO_PWM_LAST_WALL = 9,
    SB_IO_TRACE_BYTES = 10,   /* bytes of trace the last batch wrote */
    SB_IO_PENDING = 11,       /* flags of a step the kernel ran and Python must finish, or 0 */
    SB_IO_DONE = 12,          /* steps the last batch finished in C */
    SB_IO_FC_MISSED = 13,     /* 1: the FC did not answer the last step (a PeerLost) */
    SB_IO_POLLS = 14,         /* FC polls of the last batch that consumed records */
    SB_IO_LAST_POLL = 15,     /* records the newest of them consumed */
    SB_IO_ERR_EVERY = 16,     /* the summary errors are sampled every this many steps */
    SB_IO_ERR_FROM_NS = 17,   /*   from this sim time (the settle time) on */
    SB_IO_ERR_N = 18,         /*   samples taken (BridgeLoop._n_err) */
    SB_IO_OTHER_AT = 19,      /* the last collection's non-PWM records (FAULT): first slot */
    SB_IO_OTHER_N = 20,       /*   and count, in the pwm buffer; nonzero ends the batch */
    SB_IO_OVERLAPPED = 21,    /* steps published without waiting for the FC (FC_SYNC_NS) */
    SB_IO_SYNC_BROKEN = 22,   /* PWM records the FC emitted for a step it had promised to
                               * answer with none (its FC_SYNC_NS was wrong: an error) */
    SB_IO_WORDS = 23
};

/* The most steps the bridge publishes without waiting for the FC, whatever it promised: a
 * dozen PWM periods, a small share of the sensor ring (32 steps of ~6 records against the
 * 16384 slots of Segment.create's default; a full ring refuses records). */
#define SB_LEAD_MAX 32

/* The summary errors' sums and what they are taken against (BridgeLoop._sample_errors),
 * float64 slots of the `errors` buffer. */
enum {
    SB_ERR_ATT_SQ = 0,        /* sum of roll^2 + pitch^2 errors [rad^2] */
    SB_ERR_ALT_SQ = 1,        /* sum of altitude errors^2 [m^2] */
    SB_ERR_CMD_ROLL = 2,      /* the scenario's commanded roll [rad] */
    SB_ERR_CMD_PITCH = 3,     /* pitch [rad] */
    SB_ERR_CMD_ALT = 4,       /* height above home [m] */
    SB_ERR_HOME_AGL = 5,      /* the CG's height above ground at home [m] */
    SB_ERR_COUNT = 6
};

typedef struct {
    const sb_capi *api;       /* the bridge's (owner) side of the segment */
    int bridge_word, fc_word; /* lockstep word indices (shm/lockstep.py) */
    unsigned char *trace;     /* the bytes the trace hash is fed, in its order */
    size_t trace_len;
    sb_record *pwm;           /* where the PWM records are popped */
    size_t pwm_cap;
    int64_t *io;              /* int64[SB_IO_WORDS] */
    double *errors;           /* float64[SB_ERR_COUNT] */
    double *rotor;            /* float64 (rotor_rows, 4) rotor speeds per step [rad/s], or NULL */
    size_t rotor_rows;
    /* The FC in its own process: the steps it promised to answer with nothing (FC_SYNC_NS,
     * shm/lockstep.py) are published without a wait. */
    int overlap;              /* 1: take the FC's promise; 0: wait for every step */
    uint64_t hand_on_kinds;   /* a step carrying one of these sb_kind bits is waited for */
    int64_t sync_ns;          /* FC_SYNC_NS read after the last wait (0: wait) */
    int64_t lead;             /* steps published since the last wait */
    int64_t skipped_ns;       /* the newest of them (-1: none) */
} sb_lockstep;

/* Step k's n records: to the trace and the sensor ring, then the step word (the doorbell
 * is sb_lockstep_ring's, rung only before a wait). */
void sb_lockstep_publish(sb_lockstep *l, const sb_record *recs, size_t n, int64_t sim_ns);

/* Wake the FC if it sleeps on the segment's doorbell: before the bridge waits for it. */
void sb_lockstep_ring(sb_lockstep *l);

/* After step k's publish: the summary errors' sample (every io[ERR_EVERY]-th step from
 * io[ERR_FROM_NS]) and the rotor speeds' row, from the stage's state (ST_* slots). */
void sb_lockstep_after_step(sb_lockstep *l, const double *state, int64_t k, int64_t sim_ns);

/* BridgeLoop.collect_pwm: the actuator ring drained, the newest PWM held, the stamps
 * counted, the records traced with wall_ns zeroed. */
void sb_lockstep_collect(sb_lockstep *l);

/* Must the bridge wait for the FC's answer to this step (sim_ns, its n records)? Without
 * overlap, always; with it, at the step the FC's promise names or later, at a step carrying
 * a hand-on kind, at the batch's `last` step and after SB_LEAD_MAX steps unwaited. */
int sb_lockstep_must_wait(const sb_lockstep *l, const sb_record *recs, size_t n,
                          int64_t sim_ns, int last);

/* A step published without a wait. */
void sb_lockstep_skip(sb_lockstep *l, int64_t sim_ns);

/* After a wait the FC answered: its new promise read (and, after sb_lockstep_collect, the
 * check that nothing it emitted was due at a step the bridge did not wait for). */
void sb_lockstep_synced(sb_lockstep *l);

/* No promise held (a new batch: Python may have stepped the per-step way meanwhile). */
static inline void sb_lockstep_forget(sb_lockstep *l)
{
    l->sync_ns = 0;
    l->lead = 0;
    l->skipped_ns = -1;
}

/* 1 when the FC has answered through sim_ns (FC_SIM_NS), else 0 and io[FC_MISSED] set. */
int sb_lockstep_answered(sb_lockstep *l, int64_t sim_ns);

/* Trace bytes still free. */
static inline size_t sb_lockstep_room(const sb_lockstep *l)
{
    return l->trace_len - (size_t)l->io[SB_IO_TRACE_BYTES];
}

#endif /* SB_STEP_LOCKSTEP_H */
