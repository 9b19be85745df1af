/*
 * sb_handoff.h - the lockstep hand-off: how one side waits for the other's step.
 *
 * In lockstep (the RUN_MODE word says so) the bridge (owner) waits for FC_SIM_NS and the
 * FC (peer) for the sensor records of the next step, millions of times a run. Each wait
 * spins up to the budget of the way of waiting in use (sb_handoff_choice.h), watching the
 * clock: a spin that was preempted (the clock jumped) or ran out stops and the wait blocks
 * on the other side's doorbell (sb_doorbell.h, no lost wake-up). The owner chooses the
 * way by measuring its steps and publishes it in the segment header (`handoff_arm`); the
 * peer follows it and publishes how many of its spins ran out or were preempted
 * (`peer_trouble`), which the owner's choice counts with its own.
 *
 * Waits outside lockstep (real time, tests, tools) keep sb_bell_wait_after_yield.
 * Nothing here holds or touches the GIL: the callers release it around sb_handoff_wait.
 */
#ifndef SB_HANDOFF_H
#define SB_HANDOFF_H

#include <stdint.h>

#include "sb_doorbell.h"
#include "sb_handoff_choice.h"
#include "sb_pin.h"
#include "sb_wait.h"

/* A spin's clock readings more than this apart: the thread was off its core meanwhile,
 * for another task (a time slice, ~1 ms or more). Shorter gaps are interrupts and a VM's
 * exits, which blocking would not help: at 20 us they counted as trouble ~50 times in a
 * 20 s flight on the 2-core VM, and each sent a waiter to sleep on a vCPU that then took
 * hundreds of us to wake. */
#define SB_HANDOFF_GAP_NS 500000
/* SILBRIDGE_HANDOFF=spin|brief|block|stack fixes the owner's way (A/B runs, odd machines);
 * unset or "auto": measured. */
#define SB_HANDOFF_ENV "SILBRIDGE_HANDOFF"

/* What one process's hand-off waits did (statistics; `trouble` feeds the choice). */
typedef struct sb_handoff_stats {
    uint64_t waits;     /* hand-off waits */
    uint64_t ready;     /* the data was there before any spin */
    uint64_t spun;      /* ended by data while spinning */
    uint64_t ran_out;   /* spun the whole budget, then blocked */
    uint64_t preempted; /* the spin lost its core, then blocked */
    uint64_t blocked;   /* blocked on the doorbell (ran_out, preempted, or no spin) */
    uint64_t timeouts;  /* reached the deadline without data */
    uint64_t wait_ns;   /* time spent in waits that did not find the data at once [ns] */
} sb_handoff_stats;

/* One process's side of the hand-off of one segment (kept in its Segment object). */
typedef struct sb_handoff {
    sb_handoff_stats stats;
    sb_handoff_choice choice; /* the owner's; the peer follows the header's handoff_arm */
    uint64_t trouble_published; /* peer: the trouble count last stored in the header */
    sb_pin pin;               /* the waiting thread, held on one CPU while the arm is STACK */
} sb_handoff;

/* The arm SILBRIDGE_HANDOFF names, or -1 (auto). */
int sb_handoff_env_arm(void);

/* Spin up to spin_ns for ready(ctx), then block on bell until it or the deadline.
 * 1: ready; 0: the deadline passed. */
int sb_handoff_wait(sb_handoff_stats *st, sb_doorbell *bell, sb_ready_fn ready, const void *ctx,
                    int64_t spin_ns, int64_t deadline_ns);

struct sb_seg_header;

/* STACK (sb_handoff_choice.h, sb_pin.h). Owner, before a wait: with STACK in use, hold the
 * waiting thread on its CPU and name that CPU in the header (once per STACK period). */
void sb_handoff_owner_hold(struct sb_seg_header *h, sb_handoff *ho, int arm);
/* Owner: its choice moved from `from` to `to`: leaving STACK gives its CPUs back and takes
 * the CPU's name out of the header; then the new way is published. */
void sb_handoff_owner_switch(struct sb_seg_header *h, sb_handoff *ho, int from, int to);
/* Peer, before a wait: join the owner's CPU while the way is STACK, leave it after. */
void sb_handoff_peer_follow(struct sb_seg_header *h, sb_handoff *ho, uint32_t arm);

static inline uint64_t sb_handoff_trouble(const sb_handoff_stats *st)
{
    return st->ran_out + st->preempted;
}

#endif /* SB_HANDOFF_H */
