/*
 * doorbell.c - the blocking half of sb_doorbell.h: FUTEX_WAIT on the shared
 * doorbell word (OS-facing). The protocol and its ordering argument are in
 * the header.
 */
#define _GNU_SOURCE
#include "sb_doorbell.h"

#include <errno.h>
#include <sched.h>
#include <time.h>

#include "sb_segment.h"

/* A sleep never lasts longer than this, so a peer that died without ringing
 * (SIGKILL) is noticed by the caller's own checks within its time slice. */
#define SB_BELL_MAX_NAP_NS 50000000LL

int sb_bell_wait(sb_doorbell *b, sb_ready_fn ready, const void *ctx, int64_t deadline_ns)
{
    for (;;) {
        if (ready(ctx)) return 1;
        int64_t now = sb_monotonic_ns();
        if (now >= deadline_ns) return 0;
        uint32_t seen = atomic_load_explicit(&b->seq, memory_order_acquire);
        atomic_fetch_add_explicit(&b->waiters, 1u, memory_order_seq_cst);
        if (ready(ctx)) {
            atomic_fetch_sub_explicit(&b->waiters, 1u, memory_order_seq_cst);
            return 1;
        }
        int64_t nap = deadline_ns - now;
        if (nap > SB_BELL_MAX_NAP_NS) nap = SB_BELL_MAX_NAP_NS;
        struct timespec ts = {(time_t)(nap / 1000000000LL), (long)(nap % 1000000000LL)};
        /* Returns at once (EAGAIN) if seq moved since `seen`: a wake we would miss. */
        syscall(SYS_futex, (uint32_t *)&b->seq, FUTEX_WAIT, seen, &ts, NULL, 0);
        atomic_fetch_sub_explicit(&b->waiters, 1u, memory_order_seq_cst);
    }
}

/* A sched_yield that takes longer than this ran another thread on our core. */
#define SB_YIELD_BUSY_NS 30000LL
/* Then the next waits block at once: this many after the first such yield, twice as many
 * after each further one found by the next yielding wait, up to the most. One other
 * thread's time slice on an idle machine (a shell, a kernel worker, the hypervisor) then
 * costs ~16 futex hand-offs (~1-2 ms), not 1024 (~0.1 s); a lasting load still ends up
 * probing once per 1024 waits. A yielding wait that finds the core free halves the count. */
#define SB_YIELD_OFF_MIN 16
#define SB_YIELD_OFF_MAX 1024

/* Process-local (each process judges its own core): the waits left that block at once,
 * and how many the next busy finding buys. */
static int yield_off_waits;
static int yield_off_next = SB_YIELD_OFF_MIN;

/* Yield until ready (1), the end (0) or a yield that ran another thread while our data did
 * not come (-1). A slow yield after which the data is there ran the peer (the two of us
 * share a core for a moment): that hand-off worked, and is not load. */
static int yield_phase(sb_ready_fn ready, const void *ctx, int64_t end_ns)
{
    for (int64_t now = sb_monotonic_ns(); now < end_ns;) {
        if (ready(ctx)) return 1;
        sched_yield();
        int64_t after = sb_monotonic_ns();
        if (after - now > SB_YIELD_BUSY_NS) return ready(ctx) ? 1 : -1;
        now = after;
    }
    return 0;
}

int sb_bell_wait_after_yield(sb_doorbell *b, sb_ready_fn ready, const void *ctx,
                             int64_t yield_end_ns, int64_t deadline_ns)
{
    if (yield_off_waits > 0) {
        --yield_off_waits;
        return sb_bell_wait(b, ready, ctx, deadline_ns);
    }
    int r = yield_phase(ready, ctx, yield_end_ns < deadline_ns ? yield_end_ns : deadline_ns);
    if (r < 0) {
        yield_off_waits = yield_off_next;
        if (yield_off_next < SB_YIELD_OFF_MAX) yield_off_next *= 2;
    } else if (yield_off_next > SB_YIELD_OFF_MIN) {
        yield_off_next /= 2;
    }
    return r > 0 ? 1 : sb_bell_wait(b, ready, ctx, deadline_ns);
}
