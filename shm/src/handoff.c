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
