/*
 * handoff.c - the spinning half of a lockstep hand-off wait (sb_handoff.h); the blocking
 * half is sb_bell_wait (doorbell.c). OS-facing: the clock and the environment.
 */
#define _GNU_SOURCE /* syscall() in sb_doorbell.h */
#include "sb_handoff.h"

#include <stdlib.h>
#include <string.h>

#include "sb_segment.h"

/* The clock is read once every this many checks: a read costs ~20 ns, a pause ~10-40. */
#define SB_HANDOFF_CHECKS_PER_READ 16

int sb_handoff_env_arm(void)
{
    const char *v = getenv(SB_HANDOFF_ENV);
    if (v == NULL) return -1;
    if (strcmp(v, "spin") == 0) return SB_ARM_SPIN;
    if (strcmp(v, "brief") == 0) return SB_ARM_BRIEF;
    if (strcmp(v, "block") == 0) return SB_ARM_BLOCK;
    if (strcmp(v, "stack") == 0) return SB_ARM_STACK;
    return -1;
}

/* 1 ready, 0 the budget ran out, -1 the thread lost its core while spinning. */
static int spin(sb_ready_fn ready, const void *ctx, int64_t start_ns, int64_t end_ns)
{
    for (int64_t prev = start_ns;;) {
        for (int i = 0; i < SB_HANDOFF_CHECKS_PER_READ; ++i) {
            if (ready(ctx)) return 1;
            sb_cpu_relax();
        }
        int64_t now = sb_monotonic_ns();
        if (now - prev > SB_HANDOFF_GAP_NS) return ready(ctx) ? 1 : -1;
        if (now >= end_ns) return ready(ctx);
        prev = now;
    }
}

int sb_handoff_wait(sb_handoff_stats *st, sb_doorbell *bell, sb_ready_fn ready, const void *ctx,
                    int64_t spin_ns, int64_t deadline_ns)
{
    st->waits++;
    if (ready(ctx)) {
        st->ready++;
        return 1;
    }
    int64_t start = sb_monotonic_ns();
    if (spin_ns > 0) {
        int64_t end = start + spin_ns < deadline_ns ? start + spin_ns : deadline_ns;
        int r = spin(ready, ctx, start, end);
        if (r > 0) {
            st->spun++;
            st->wait_ns += (uint64_t)(sb_monotonic_ns() - start);
            return 1;
        }
        if (r < 0) st->preempted++;
        else st->ran_out++;
    }
    st->blocked++;
    int ok = sb_bell_wait(bell, ready, ctx, deadline_ns);
    if (!ok) st->timeouts++;
    st->wait_ns += (uint64_t)(sb_monotonic_ns() - start);
    return ok;
}

/* The STACK way (sb_pin.h): the owner holds its waiting thread on the CPU it runs on and
 * names it in the header; the peer joins it there, and leaves it when the way changes. The
 * system calls come once per change of the way, not per wait. */

void sb_handoff_owner_hold(sb_seg_header *h, sb_handoff *ho, int arm)
{
    if (arm != SB_ARM_STACK || ho->pin.pinned || ho->pin.failed) return;
    int cpu = sb_pin_here(&ho->pin);
    if (cpu >= 0) atomic_store_explicit(&h->stack_cpu, cpu, memory_order_release);
}

void sb_handoff_owner_switch(sb_seg_header *h, sb_handoff *ho, int from, int to)
{
    if (from == SB_ARM_STACK) {
        atomic_store_explicit(&h->stack_cpu, -1, memory_order_relaxed);
        sb_pin_release(&ho->pin, -1);
    }
    atomic_store_explicit(&h->handoff_arm, (uint32_t)to, memory_order_release);
}

void sb_handoff_peer_follow(sb_seg_header *h, sb_handoff *ho, uint32_t arm)
{
    if (arm != SB_ARM_STACK) {
        if (ho->pin.pinned) sb_pin_release(&ho->pin, ho->pin.cpu);   /* apart again at once */
        return;
    }
    int cpu = atomic_load_explicit(&h->stack_cpu, memory_order_acquire);
    if (cpu < 0 || (ho->pin.cpu == cpu && (ho->pin.pinned || ho->pin.failed))) return;
    (void)sb_pin_to(&ho->pin, cpu);
}
