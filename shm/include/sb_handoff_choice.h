/*
 * sb_handoff_choice.h - which way the lockstep hand-off waits, chosen by measuring it.
 *
 * Why: on the 2-core VM a futex hand-off costs ~30 us at idle (the woken core has to leave
 * its idle state) where a spinning waiter sees the other side's word within ~0.2 us; but
 * under load a spinner keeps a core from the very process it waits for, and one hand-off
 * then costs a time slice (C ping-pong, 8 + 2 us of work a step: idle 10.6 us/step
 * spinning, 74 blocking; one busy loop 78 spinning, 16 blocking; two busy loops 45
 * spinning, 47 blocking, 24 spinning 3 us then blocking). Whether a core is free cannot be
 * read cheaply and reliably (the run queue counts the pair itself, half of the time
 * blocked), so the segment's owner measures what each way of waiting achieves, wall time
 * per lockstep step, and keeps the fastest:
 *
 * - SPIN: spin up to SB_SPIN_LONG_NS, then block. While its spins end with data (no spin
 *   ran out, none was preempted: the "trouble" counts of both sides), no other way can be
 *   faster and none is tried. Trouble in more than 1/SB_TROUBLE_SHARE of a window's steps
 *   means someone else wants our cores: the other ways are measured.
 * - BRIEF: the owner spins SB_SPIN_BRIEF_NS (the FC's answer, when the FC runs on the other
 *   core), then blocks; the peer, whose wait spans the bridge's whole step, blocks at once.
 * - BLOCK: block at once.
 * - STACK: both sides held on the owner's CPU (sb_pin.h), block at once: a hand-off is two
 *   context switches in the guest, and the pair needs one CPU instead of two. When the
 *   other CPU is taken (a neighbour's work, or a VM host that takes vCPUs away), it beats
 *   the others by far: on the 2-core VM ~70x real time where the others fell to 10-25x.
 * A probe that wins is checked: the arm it replaced is measured again after one window.
 * Away from SPIN, every other probe measures SPIN (the way back); the rest take turns.
 * While another way than SPIN is in use, SPIN is measured again after a gap that starts at
 * SB_PROBE_GAP_MIN_NS and doubles (to SB_PROBE_GAP_MAX_NS: load on a shared machine comes
 * and goes in bursts) each time the choice holds; a
 * window much slower than the one before (the load changed) measures the others at once.
 *
 * A window is SB_WINDOW_MIN_NS long (a few time slices, so one preemption does not decide)
 * and at least SB_WINDOW_MIN_STEPS steps: a way of waiting that costs milliseconds a step
 * under load is not measured for long. Pure: no OS calls; the clock and the trouble counts
 * come in as arguments, so tests drive it with made-up times (tests/shm/test_handoff_choice.py).
 */
#ifndef SB_HANDOFF_CHOICE_H
#define SB_HANDOFF_CHOICE_H

#include <stdint.h>

enum sb_handoff_arm {
    SB_ARM_SPIN = 0, SB_ARM_BRIEF = 1, SB_ARM_BLOCK = 2, SB_ARM_STACK = 3, SB_ARM_COUNT = 4
};

#define SB_SPIN_LONG_NS 300000   /* covers the other side's step and its usual Python */
#define SB_SPIN_BRIEF_NS 5000    /* covers the FC's answer (~2 us) with a margin */
#define SB_WINDOW_MIN_STEPS 8u
#define SB_WINDOW_MIN_NS 3000000    /* ~1 CFS slice of a 3-task 2-core box, and more */
#define SB_PROBE_GAP_MIN_NS 25000000
#define SB_PROBE_GAP_MAX_NS 200000000
#define SB_TROUBLE_SHARE 32u        /* SPIN in trouble: > steps / 32 spins ran out or were preempted */
#define SB_SWITCH_GAIN_PCT 90       /* another arm wins when it costs < 90 % of the one in use */
#define SB_LEAVE_SPIN_PCT 70        /*   and < 70 % of SPIN: a wrong BLOCK on a free core costs
                                       ~7x a step, a wrong SPIN in a neighbour's burst ~3x */
#define SB_SLOWDOWN_PCT 150         /* a window > 150 % of the arm's last one: the load changed */

typedef struct sb_handoff_choice {
    int32_t arm;                        /* the way of waiting in use (sb_handoff_arm) */
    int32_t home;                       /* during a probe: the arm to compare it with; else -1 */
    int32_t forced;                     /* >= 0: always this arm, never measure (SILBRIDGE_HANDOFF) */
    int32_t next_probe_arm;             /* the probes take the other arms in turn... */
    int32_t last_probe;                 /* ...every other one SPIN while away from it */
    int32_t recheck;                    /* >= 0: the next probe measures this arm (the home
                                           a probe just replaced); -1: none */
    int64_t win_start_ns;               /* the measuring window: start [ns] */
    uint64_t win_steps;                 /*   steps ended in it */
    uint64_t win_trouble0;              /*   trouble count at its start */
    int64_t cost_ns[SB_ARM_COUNT];      /* wall time per step last measured per arm [ns]; 0 never */
    int64_t next_probe_ns;              /* earliest start of the next probe [ns] */
    int64_t probe_gap_ns;               /* the gap after which SPIN is measured again [ns] */
    uint64_t windows, probes, switches; /* statistics */
} sb_handoff_choice;

/* Spin budget of an arm for the owner's or the peer's waits [ns]. */
int64_t sb_handoff_spin_ns(int arm, int is_owner);

/* Start with SPIN (forced < 0) or always `forced`. */
void sb_choice_init(sb_handoff_choice *c, int64_t now_ns, int forced);

/* One lockstep step ended at now_ns; trouble: the running total of spins (both sides) that
 * ran out or were preempted. Returns the arm for the next wait. */
int sb_choice_step(sb_handoff_choice *c, int64_t now_ns, uint64_t trouble);

#endif /* SB_HANDOFF_CHOICE_H */
