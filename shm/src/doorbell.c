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

/* A sched_yield that takes longer than this ran another thread: the machine is busy. */
#define SB_YIELD_BUSY_NS 30000LL
/* After that, this many waits block at once without yielding first. */
#define SB_YIELD_OFF_WAITS 1024

/* Waits left that skip the yield phase (process-local: each process judges its own cores). */
static int yield_off_waits;

int sb_bell_wait_after_yield(sb_doorbell *b, sb_ready_fn ready, const void *ctx,
                             int64_t yield_end_ns, int64_t deadline_ns)
{
    if (yield_off_waits > 0) {
        --yield_off_waits;
    } else {
        int64_t end = yield_end_ns < deadline_ns ? yield_end_ns : deadline_ns;
        for (int64_t now = sb_monotonic_ns(); now < end;) {
            if (ready(ctx)) return 1;
            sched_yield();
            int64_t after = sb_monotonic_ns();
            if (after - now > SB_YIELD_BUSY_NS) {
                yield_off_waits = SB_YIELD_OFF_WAITS;
                break;
            }
            now = after;
        }
    }
    return sb_bell_wait(b, ready, ctx, deadline_ns);
}
