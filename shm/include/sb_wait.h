/*
 * sb_wait.h - waiting for the other process without starving a small box.
 *
 * A wait has three phases: spin (cheapest wake-up, burns the core), then
 * sched_yield (lets every other runnable thread in first), then sleep in
 * growing steps. On a 2-core machine two processes that only spin starve
 * everything else, and pure sleeping costs ~60-100 us per wake-up; the
 * phases bound both. The spin phase runs with the caller's locks held (it is
 * short); the binding releases the GIL around sb_wait_block only.
 */
#ifndef SB_WAIT_H
#define SB_WAIT_H

#include <stdint.h>

typedef int (*sb_ready_fn)(const void *ctx); /* non-zero when the wait is over */

typedef struct sb_wait_policy {
    int64_t spin_ns;      /* spin this long first */
    int64_t yield_ns;     /* then sched_yield until this long after the start */
    int64_t sleep_min_ns; /* then sleep, starting with this step */
    int64_t sleep_max_ns; /* and doubling up to this step */
} sb_wait_policy;

/* Defaults: 20 us spin, yield until 200 us, then sleeps of 50 us doubling to
 * 1 ms. A long idle wait then costs ~900 wake-ups/s, ~2 % of a core on the
 * 2-core VM (a 200 us cap cost ~10 %: wake-ups are dear there); the price is
 * that a consumer which fell asleep may wake up to ~1 ms after its data.
 * Latency-critical callers pass a yield phase as long as their period. */
sb_wait_policy sb_wait_default_policy(void);

/* Spin phase: returns 1 as soon as ready(ctx), 0 when spin_ns (measured from
 * start_ns) or the deadline passed. */
int sb_wait_spin(sb_ready_fn ready, const void *ctx, const sb_wait_policy *p, int64_t start_ns,
                 int64_t deadline_ns);

/* Yield, then sleep phase, until ready(ctx) (1) or the deadline (0). Touches
 * no Python state: safe without the GIL. */
int sb_wait_block(sb_ready_fn ready, const void *ctx, const sb_wait_policy *p, int64_t start_ns,
                  int64_t deadline_ns);

/* One CPU hint that we are spinning (PAUSE / YIELD). */
static inline void sb_cpu_relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

#endif /* SB_WAIT_H */
