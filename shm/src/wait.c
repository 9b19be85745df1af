/*
 * wait.c - the spin / yield / sleep phases of sb_wait.h (OS-facing).
 */
#define _GNU_SOURCE
#include "sb_wait.h"

#include <sched.h>
#include <time.h>

#include "sb_segment.h"

/* The clock is read once every this many spin iterations: clock_gettime
 * costs ~20 ns, a pause ~10-40 ns. */
#define SB_SPIN_CHECK_EVERY 16

sb_wait_policy sb_wait_default_policy(void)
{
    sb_wait_policy p = {20000, 200000, 50000, 1000000};
    return p;
}

int sb_wait_spin(sb_ready_fn ready, const void *ctx, const sb_wait_policy *p, int64_t start_ns,
                 int64_t deadline_ns)
{
    int64_t spin_end = start_ns + p->spin_ns;
    if (spin_end > deadline_ns) spin_end = deadline_ns;
    for (;;) {
        for (int i = 0; i < SB_SPIN_CHECK_EVERY; ++i) {
            if (ready(ctx)) return 1;
            sb_cpu_relax();
        }
        if (sb_monotonic_ns() >= spin_end) return ready(ctx);
    }
}

int sb_wait_block(sb_ready_fn ready, const void *ctx, const sb_wait_policy *p, int64_t start_ns,
                  int64_t deadline_ns)
{
    int64_t yield_end = start_ns + p->yield_ns;
    int64_t step = p->sleep_min_ns > 0 ? p->sleep_min_ns : 1000;
    for (;;) {
        if (ready(ctx)) return 1;
        int64_t now = sb_monotonic_ns();
        if (now >= deadline_ns) return 0;
        if (now < yield_end) {
            sched_yield();
            continue;
        }
        int64_t nap = deadline_ns - now < step ? deadline_ns - now : step;
        struct timespec ts = {(time_t)(nap / 1000000000LL), (long)(nap % 1000000000LL)};
        nanosleep(&ts, NULL);
        if (step < p->sleep_max_ns) step = step * 2 < p->sleep_max_ns ? step * 2 : p->sleep_max_ns;
    }
}
