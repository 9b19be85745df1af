/*
 * handoff_py.c - the lockstep hand-off (sb_handoff.h) for a Segment object: the owner's
 * wait for the peer's step word, which drives the choice and publishes it, the peer's
 * wait for sensor records, which follows it, the capsule's wait_step, and the statistics.
 */
#include "module.h"

#include <math.h>

typedef struct step_ready_ctx {
    const _Atomic uint64_t *word;
    uint64_t at_least;
} step_ready_ctx;

static int step_ready(const void *p)
{
    const step_ready_ctx *c = p;
    return atomic_load_explicit(c->word, memory_order_acquire) >= c->at_least;
}

typedef struct records_ready_ctx {
    const _Atomic uint64_t *head;
    uint64_t tail;
} records_ready_ctx;

static int records_ready(const void *p)
{
    const records_ready_ctx *c = p;
    return atomic_load_explicit(c->head, memory_order_acquire) != c->tail;
}

/* SILBRIDGE_NO_DOORBELL: the waits before the doorbells (spin, yield, sleep), for A/B runs. */
static int old_wait(sb_ready_fn ready, const void *ctx, int64_t deadline_ns)
{
    double left_s = (double)(deadline_ns - sb_monotonic_ns()) / 1e9;
    return sb_wait_gil(ready, ctx, left_s > 0.0 ? left_s : 0.0, -1.0, -1.0, NULL);
}

/* Owner: wait for the peer's step, then count the step and publish a changed choice. */
static int owner_wait(SegmentObject *self, uint64_t at_least, int64_t deadline_ns)
{
    sb_seg_header *h = self->seg.hdr;
    sb_handoff *ho = &self->handoff;
    step_ready_ctx ctx = {sb_seg_word(h, SB_WORD_PEER_STEP), at_least};
    int arm = ho->choice.arm;
    int ok;
    if (sb_doorbells_off) return old_wait(step_ready, &ctx, deadline_ns);
    Py_BEGIN_ALLOW_THREADS
    sb_handoff_owner_hold(h, ho, arm);
    ok = sb_handoff_wait(&ho->stats, sb_segment_their_bell(&self->seg), step_ready, &ctx,
                         sb_handoff_spin_ns(arm, 1), deadline_ns);
    if (ok) {
        uint64_t trouble = sb_handoff_trouble(&ho->stats) +
                           atomic_load_explicit(&h->peer_trouble, memory_order_relaxed);
        int next = sb_choice_step(&ho->choice, sb_monotonic_ns(), trouble);
        if (next != arm) sb_handoff_owner_switch(h, ho, arm, next);
    }
    Py_END_ALLOW_THREADS
    return ok;
}

/* Peer: wait for sensor records the owner's way; publish our trouble when it grew. */
static int peer_wait(SegmentObject *self, int64_t deadline_ns)
{
    sb_seg_header *h = self->seg.hdr;
    sb_handoff *ho = &self->handoff;
    sb_ring *r = &self->rings[SB_RING_SENSORS];
    records_ready_ctx ctx = {&r->ctl->head, r->tail};
    uint32_t arm = atomic_load_explicit(&h->handoff_arm, memory_order_acquire);
    int ok;
    if (sb_doorbells_off) return old_wait(records_ready, &ctx, deadline_ns);
    Py_BEGIN_ALLOW_THREADS
    sb_handoff_peer_follow(h, ho, arm);
    ok = sb_handoff_wait(&ho->stats, sb_segment_their_bell(&self->seg), records_ready, &ctx,
                         sb_handoff_spin_ns((int)arm, 0), deadline_ns);
    Py_END_ALLOW_THREADS
    uint64_t trouble = sb_handoff_trouble(&ho->stats);
    if (trouble != ho->trouble_published) {
        atomic_store_explicit(&h->peer_trouble, trouble, memory_order_relaxed);
        ho->trouble_published = trouble;
    }
    return ok;
}

static int64_t deadline_after(double timeout_s)
{
    double ns = timeout_s > 0.0 && isfinite(timeout_s) ? timeout_s * 1e9 : 0.0;
    if (ns > 9e18) ns = 9e18;
    return sb_monotonic_ns() + (int64_t)ns;
}

int sb_handoff_wait_gil(SegmentObject *self, uint64_t at_least, double timeout_s)
{
    int64_t deadline = deadline_after(timeout_s);
    return self->seg.is_owner ? owner_wait(self, at_least, deadline)
                              : peer_wait(self, deadline);
}

/* sb_capi.wait_step (sb_capi.h): the owner's lockstep wait for another C extension. */
static int capi_wait_step(const sb_capi *api, uint64_t at_least, int64_t timeout_ns)
{
    SegmentObject *self = api->segment_object;
    if (sb_check_open(self)) return -1;
    if (!self->seg.is_owner) {
        PyErr_SetString(SB_ERR.role, "wait_step is the owner's (the bridge's) wait");
        return -1;
    }
    return owner_wait(self, at_least, sb_monotonic_ns() + (timeout_ns > 0 ? timeout_ns : 0));
}

void sb_handoff_fill_capi(SegmentObject *self, sb_capi *api)
{
    api->wait_step = capi_wait_step;
    api->segment_object = self;
}

/* Start afresh (create / attach): the owner's choice and its published arm. */
void sb_handoff_start(SegmentObject *self)
{
    sb_handoff_stop(self);
    memset(&self->handoff, 0, sizeof self->handoff);
    sb_choice_init(&self->handoff.choice, sb_monotonic_ns(), sb_handoff_env_arm());
    if (self->seg.is_owner) {
        atomic_store_explicit(&self->seg.hdr->stack_cpu, -1, memory_order_relaxed);
        atomic_store_explicit(&self->seg.hdr->handoff_arm, (uint32_t)self->handoff.choice.arm,
                              memory_order_release);
    }
}

/* The segment closes: a thread held on one CPU for STACK gets its CPUs back. */
void sb_handoff_stop(SegmentObject *self)
{
    sb_pin_release(&self->handoff.pin, -1);
}

static const char *const ARM_NAMES[SB_ARM_COUNT] = {"spin", "brief", "block", "stack"};

/* handoff_stats() -> dict: this process's hand-off waits and (owner) its choice. */
PyObject *sb_handoff_stats_dict(SegmentObject *self)
{
    if (sb_check_open(self)) return NULL;
    const sb_handoff_stats *st = &self->handoff.stats;
    const sb_handoff_choice *c = &self->handoff.choice;
    uint32_t arm = atomic_load_explicit(&self->seg.hdr->handoff_arm, memory_order_relaxed);
    return Py_BuildValue(
        "{sKsKsKsKsKsKsKsKsssOsKsKsKs(LLLL)sKsi}", "waits", (unsigned long long)st->waits,
        "wait_ns", (unsigned long long)st->wait_ns, "ready",
        (unsigned long long)st->ready, "spun", (unsigned long long)st->spun, "ran_out",
        (unsigned long long)st->ran_out, "preempted", (unsigned long long)st->preempted,
        "blocked", (unsigned long long)st->blocked, "timeouts",
        (unsigned long long)st->timeouts, "arm", arm < SB_ARM_COUNT ? ARM_NAMES[arm] : "?",
        "forced", c->forced >= 0 ? Py_True : Py_False, "windows",
        (unsigned long long)c->windows, "probes", (unsigned long long)c->probes, "switches",
        (unsigned long long)c->switches, "cost_ns", (long long)c->cost_ns[0],
        (long long)c->cost_ns[1], (long long)c->cost_ns[2], (long long)c->cost_ns[3],
        "peer_trouble",
        (unsigned long long)atomic_load_explicit(&self->seg.hdr->peer_trouble,
                                                 memory_order_relaxed),
        "held_cpu", self->handoff.pin.pinned ? self->handoff.pin.cpu : -1);
}
