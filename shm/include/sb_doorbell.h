/*
 * sb_doorbell.h - a blocking wake-up between the two processes of a segment.
 *
 * Why: a waiter that spins or sched_yields keeps its core. On a busy machine
 * (a browser, a compiler, other runs) the process it waits for then waits for
 * a time slice, and a lockstep hand-off every millisecond of sim time crawls
 * (issue 15: 160x slower with two busy loops on two cores). A waiter that
 * blocks gives its core away and is woken the moment its peer publishes.
 *
 * One doorbell per direction lives in the segment header: the owner rings
 * bells[SB_BELL_OWNER] after it publishes (a ring push, a lockstep word), the
 * peer waits on it, and the other way round. `seq` is a non-private futex
 * word (the segment is shared across processes); `waiters` counts processes
 * that are about to block or are blocked, so a publisher with nobody waiting
 * pays one fence and one load, never a system call.
 *
 * Ordering (Dekker): the waiter announces itself (waiters++, seq_cst), then
 * re-checks its condition, then sleeps only while `seq` still holds the value
 * it read before announcing; the publisher stores its data, fences (seq_cst),
 * and wakes only if it sees a waiter. Either the publisher sees the waiter
 * (it bumps seq, so the sleep returns at once or is woken) or the waiter's
 * re-check sees the data. No lost wake-up, no wake-up when nobody waits.
 *
 * sb_bell_ring is inline (the FC extension's C poll rings it too); the
 * blocking wait is shm/src/doorbell.c.
 */
#ifndef SB_DOORBELL_H
#define SB_DOORBELL_H

#include <limits.h>
#include <linux/futex.h>
#include <stdatomic.h>
#include <stdint.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "sb_ring.h"
#include "sb_wait.h"

enum { SB_BELL_OWNER = 0, SB_BELL_PEER = 1, SB_BELL_COUNT = 2 };

typedef struct sb_doorbell {
    _Alignas(SB_CACHE_LINE) _Atomic uint32_t seq; /* futex word: bumped on each wake */
    _Atomic uint32_t waiters;                     /* processes blocking on seq */
    _Atomic uint64_t wakes;                       /* FUTEX_WAKE calls made (statistics) */
    uint32_t pad[12];
} sb_doorbell;

_Static_assert(sizeof(sb_doorbell) == SB_CACHE_LINE, "one doorbell per cache line");
_Static_assert(sizeof(_Atomic uint32_t) == 4, "futex words are 32 bits");

/* After publishing: wake the other side if it waits. ~1 fence + 1 load otherwise. */
static inline void sb_bell_ring(sb_doorbell *b)
{
    atomic_thread_fence(memory_order_seq_cst);
    if (atomic_load_explicit(&b->waiters, memory_order_relaxed) == 0) return;
    atomic_fetch_add_explicit(&b->seq, 1u, memory_order_seq_cst);
    atomic_fetch_add_explicit(&b->wakes, 1u, memory_order_relaxed);
    syscall(SYS_futex, (uint32_t *)&b->seq, FUTEX_WAKE, INT_MAX, NULL, NULL, 0);
}

/* Block until ready(ctx) (1) or the deadline (0, CLOCK_MONOTONIC ns); no spinning.
 * Touches no Python state: call it without the GIL. */
int sb_bell_wait(sb_doorbell *b, sb_ready_fn ready, const void *ctx, int64_t deadline_ns);

/* sched_yield until yield_end_ns (an idle core gives a wake-up within a microsecond or
 * two, cheaper than a futex wake on a VM), then sb_bell_wait. A yield that lets another
 * thread run (it takes > 30 us) and after which our data is still missing means our core
 * is not free, where yielding keeps it from the peer: the next waits then block at once,
 * 16 after one such finding, doubling while the findings repeat, up to 1024 (doorbell.c). */
int sb_bell_wait_after_yield(sb_doorbell *b, sb_ready_fn ready, const void *ctx,
                             int64_t yield_end_ns, int64_t deadline_ns);

#endif /* SB_DOORBELL_H */
