/*
 * step_lockstep.c - the ring side of a one-process lockstep step (step_lockstep.h): plain
 * C over the segment's rings and words, the clock, and the caller's buffers. The same
 * operations, in the same order, as the Python path (bridge/bridge_loop.py), so the records,
 * the PWM and the trace bytes are the same.
 */
#define _GNU_SOURCE /* syscall() for the doorbell (sb_doorbell.h), clock_gettime */
#include "step_lockstep.h"

#include <math.h>
#include <string.h>
#include <time.h>

#include "sensor_stage.h"

static int64_t monotonic_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + (int64_t)ts.tv_nsec;
}

/* Append n records to the trace (the caller checked the room: sb_lockstep_room). */
static void trace_append(sb_lockstep *l, const sb_record *r, size_t n)
{
    memcpy(l->trace + l->io[SB_IO_TRACE_BYTES], r, n * sizeof *r);
    l->io[SB_IO_TRACE_BYTES] += (int64_t)(n * sizeof *r);
}

void sb_lockstep_publish(sb_lockstep *l, const sb_record *recs, size_t n, int64_t sim_ns)
{
    const sb_capi *api = l->api;
    trace_append(l, recs, n);
    (void)sb_ring_push_batch(&api->rings[SB_RING_SENSORS], recs, n, monotonic_ns());
    atomic_store_explicit(sb_capi_word(api, l->bridge_word), (uint64_t)sim_ns,
                          memory_order_release);
}

/* The Python path rings the doorbell after the push and after the word of every step. The
 * batch rings once, after both, and only before it waits:
 * a sleeping FC is not woken for a step the bridge does not wait for (it takes that step
 * with the next one), which saves a wake-up (a system call, and on two CPUs an interrupt
 * to the FC's) on three steps in five; a spinning FC sees the records without a ring. */
void sb_lockstep_ring(sb_lockstep *l)
{
    sb_bell_ring(sb_segment_my_bell(l->api->seg));
}

/* BridgeLoop._sample_errors's arithmetic, so the same doubles: Python's x ** 2 is libm's
 * pow, and this extension is built without FMA contraction (setup.py). */
static void sample_errors(sb_lockstep *l, const double *st, int64_t k, int64_t sim_ns)
{
    const int64_t every = l->io[SB_IO_ERR_EVERY];
    if (every <= 0 || k % every != 0 || sim_ns < l->io[SB_IO_ERR_FROM_NS])
        return;
    double *e = l->errors;
    const double er = st[ST_EULER] - e[SB_ERR_CMD_ROLL];
    const double ep = st[ST_EULER + 1] - e[SB_ERR_CMD_PITCH];
    const double alt = st[ST_HAGL] - e[SB_ERR_HOME_AGL];
    l->io[SB_IO_ERR_N]++;
    e[SB_ERR_ATT_SQ] += er * er + ep * ep;
    e[SB_ERR_ALT_SQ] += pow(alt - e[SB_ERR_CMD_ALT], 2.0);
}

void sb_lockstep_after_step(sb_lockstep *l, const double *state, int64_t k, int64_t sim_ns)
{
    sample_errors(l, state, k, sim_ns);
    const int64_t row = l->io[SB_IO_DONE];
    if (l->rotor != NULL && row >= 0 && (size_t)row < l->rotor_rows)
        memcpy(l->rotor + 4 * row, state + ST_OMEGA, 4 * sizeof *l->rotor);
}

/* Records of another kind than PWM in a collection (the FC's FAULT records): moved behind the
 * PWM records, order kept, for Python to route (bridge/fault_records.py) before the next step.
 * Returns the PWM records left in front. Rare: a fault switch, not a step. */
static uint64_t set_others_aside(sb_lockstep *l, sb_record *r, uint64_t n, size_t cap)
{
    sb_record *aside = r + n;   /* the pwm buffer's room past this collection */
    uint64_t m = 0, k = 0;
    for (uint64_t i = 0; i < n; i++) {
        if (r[i].h.kind == SB_KIND_PWM)
            r[m++] = r[i];
        else if (n + k < cap)
            aside[k++] = r[i];
    }
    memmove(r + m, aside, k * sizeof *r);
    l->io[SB_IO_OTHER_AT] = (int64_t)m;
    l->io[SB_IO_OTHER_N] = (int64_t)k;
    return m;
}

int sb_lockstep_must_wait(const sb_lockstep *l, const sb_record *recs, size_t n,
                          int64_t sim_ns, int last)
{
    return !l->overlap || last || sim_ns >= l->sync_ns || l->lead >= SB_LEAD_MAX ||
           sb_records_any_kind(recs, n, l->hand_on_kinds);
}

void sb_lockstep_skip(sb_lockstep *l, int64_t sim_ns)
{
    l->lead++;
    l->skipped_ns = sim_ns;
    l->io[SB_IO_OVERLAPPED]++;
}

void sb_lockstep_synced(sb_lockstep *l)
{
    /* after the acquire of FC_SIM_NS that saw this answer (wait_step): its promise is
     * visible; the FC writes the next one only after the bridge's next step */
    l->sync_ns = (int64_t)atomic_load_explicit(sb_seg_peer_sync(l->api->seg->hdr),
                                               memory_order_relaxed);
    l->lead = 0;
    l->skipped_ns = -1;
}

/* A PWM tick at or before a step the bridge did not wait for was due there: the FC's promise
 * was wrong, and the motors took that PWM a step or more late. Counted (Python raises). */
static void check_promise(sb_lockstep *l, const sb_record *pwm, uint64_t n)
{
    for (uint64_t i = 0; i < n; i++) {
        if (pwm[i].h.sim_ns <= l->skipped_ns)
            l->io[SB_IO_SYNC_BROKEN]++;
    }
}

/* At most as many records as the trace has room for: a lockstep poll answers one step. */
void sb_lockstep_collect(sb_lockstep *l)
{
    int64_t *io = l->io;
    const size_t room = sb_lockstep_room(l) / sizeof(sb_record);
    const size_t cap = l->pwm_cap < room ? l->pwm_cap : room;
    sb_record *pwm = l->pwm;
    /* half the buffer at most: the other half is where set_others_aside sorts */
    uint64_t n = sb_ring_pop_batch(&l->api->rings[SB_RING_ACTUATORS], pwm,
                                   cap < l->pwm_cap / 2 ? cap : l->pwm_cap / 2);
    if (n == 0)
        return;
    uint64_t other = 0;
    for (uint64_t i = 0; i < n; i++)
        other += pwm[i].h.kind != SB_KIND_PWM;
    if (other != 0)
        n = set_others_aside(l, pwm, n, l->pwm_cap);
    if (n == 0)
        return;
    if (l->skipped_ns >= 0)
        check_promise(l, pwm, n);
    const sb_record *last = &pwm[n - 1];
    for (int i = 0; i < 4; i++)
        io[SB_IO_PWM_US + i] = last->u.pwm.pwm_us[i];
    io[SB_IO_ARMED] = last->u.pwm.armed != 0;
    if (io[SB_IO_PWM_FIRST_SIM] < 0) {
        io[SB_IO_PWM_FIRST_SIM] = pwm[0].h.sim_ns;
        io[SB_IO_PWM_FIRST_WALL] = pwm[0].h.wall_ns;
    }
    io[SB_IO_PWM_LAST_SIM] = last->h.sim_ns;
    io[SB_IO_PWM_LAST_WALL] = last->h.wall_ns;
    io[SB_IO_PWM_RECEIVED] += (int64_t)n;
    for (uint64_t i = 0; i < n; i++)
        pwm[i].h.wall_ns = 0;   /* hashed without wall-clock stamps, as collect_pwm */
    trace_append(l, pwm, n);
}

int sb_lockstep_answered(sb_lockstep *l, int64_t sim_ns)
{
    const uint64_t fc_ns = atomic_load_explicit(sb_capi_word(l->api, l->fc_word),
                                                memory_order_acquire);
    if (fc_ns >= (uint64_t)sim_ns)
        return 1;
    l->io[SB_IO_FC_MISSED] = 1;
    return 0;
}
