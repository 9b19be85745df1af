/*
 * sb_ring.h - single-producer single-consumer ring of 64-byte records that
 * lives in shared memory and is used from two processes.
 *
 * Ownership rule (who writes what):
 *   producer: the slots, ctl->head, ctl->rejected, ctl->step_word, ctl->sync_word
 *   consumer: ctl->tail, ctl->overwritten
 *   segment owner, once, before the segment is published: the config line
 * Each side keeps its own index and a cached copy of the other's in its
 * process-local sb_ring handle; the shared copy of the other's index is
 * reloaded (acquire) only when the ring looks empty (consumer) or full
 * (producer). Counters are free-running uint64; a slot is `index & mask`.
 *
 * Two modes, fixed at creation:
 *   overwrite = 0: a full ring refuses the push (counted as rejected).
 *   overwrite = 1: the producer never looks at the consumer and never blocks.
 *     A consumer that falls a lap behind loses the oldest records; it notices
 *     by re-reading head after copying a slot (a seqlock-style check), counts
 *     the loss as overwritten and resynchronises, so it never returns a torn
 *     or reordered record. For that check to be exact the producer publishes
 *     head at least every `stride` records and issues a release fence before
 *     it overwrites a slot; a record is therefore trusted only while fewer
 *     than `lap = capacity - stride` newer records have been published.
 *     As in any seqlock, a slot copy may overlap the producer rewriting that
 *     slot; the head re-read after the copy finds exactly those copies and
 *     they are discarded, never returned (tests/shm/test_two_process.py
 *     fails without the check).
 *
 * Everything here is static inline and OS-free; sb_segment.h maps memory.
 */
#ifndef SB_RING_H
#define SB_RING_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "sb_records.h"

#define SB_CACHE_LINE 64u
#define SB_RING_MIN_SLOTS 4u
#define SB_RING_MAX_SLOTS (1u << 24)
#define SB_RING_MAX_STRIDE 64u

/* Status codes of the ring verbs. */
enum sb_ring_status {
    SB_RING_OK = 0,
    SB_RING_EMPTY = 1, /* nothing to pop */
    SB_RING_FULL = 2   /* overwrite = 0 and no free slot: push refused */
};

typedef struct sb_ring_ctl {
    /* Line 0: configuration, immutable once the segment is published. */
    uint64_t capacity;     /* slots, a power of two */
    uint64_t slots_offset; /* byte offset of slot 0 from the segment base */
    uint32_t overwrite;    /* 1: overwrite the oldest when full; 0: refuse */
    uint32_t stride;       /* overwrite mode: head is published at least every stride records */
    uint8_t pad0[SB_CACHE_LINE - 24];
    /* Line 1: written by the producer only. */
    _Alignas(SB_CACHE_LINE) _Atomic uint64_t head; /* records published, free-running */
    _Atomic uint64_t rejected;                     /* pushes refused (full, overwrite = 0) */
    /* The producer's lockstep word (sb_segment.h sb_seg_word: the sensor ring's is
     * BRIDGE_SIM_NS, the actuator ring's FC_SIM_NS), on the head's line: a lockstep
     * hand-off (records, then the word) moves this one line and the records' slots. */
    _Atomic uint64_t step_word;
    /* The producer's next sync (sb_segment.h sb_seg_peer_sync: the actuator ring's is the
     * FC's FC_SYNC_NS; the sensor ring's is unused), stored before step_word, on its line:
     * the waiter reads both with the one line it moves. */
    _Atomic uint64_t sync_word;
    uint8_t pad1[SB_CACHE_LINE - 32];
    /* Line 2: written by the consumer only. */
    _Alignas(SB_CACHE_LINE) _Atomic uint64_t tail; /* records popped or skipped */
    _Atomic uint64_t overwritten;                  /* records skipped because they were lapped */
    uint8_t pad2[SB_CACHE_LINE - 16];
} sb_ring_ctl;

_Static_assert(ATOMIC_LLONG_LOCK_FREE == 2, "the ring needs lock-free 64-bit atomics");
_Static_assert(sizeof(_Atomic uint64_t) == 8, "atomic counters must be plain 8-byte words");
_Static_assert(sizeof(sb_ring_ctl) == 3 * SB_CACHE_LINE, "ring control is three cache lines");
_Static_assert(offsetof(sb_ring_ctl, head) == 1 * SB_CACHE_LINE, "head on its own line");
_Static_assert(offsetof(sb_ring_ctl, tail) == 2 * SB_CACHE_LINE, "tail on its own line");
_Static_assert(offsetof(sb_ring_ctl, step_word) / SB_CACHE_LINE ==
                   offsetof(sb_ring_ctl, head) / SB_CACHE_LINE,
               "the producer's lockstep word shares the head's line");
_Static_assert(offsetof(sb_ring_ctl, sync_word) / SB_CACHE_LINE ==
                   offsetof(sb_ring_ctl, head) / SB_CACHE_LINE,
               "the producer's sync word shares the head's line");

/* Process-local view of one ring. Producer fields and consumer fields are
 * used by the side that plays that role; both are loaded from shared memory
 * at attach so a restarted process continues where its predecessor stopped. */
typedef struct sb_ring {
    sb_ring_ctl *ctl;
    sb_record *slots;
    uint64_t mask;     /* capacity - 1 */
    uint64_t lap;      /* newest-minus-oldest distance within which a slot is trusted */
    uint32_t stride;   /* 1 .. SB_RING_MAX_STRIDE */
    int overwrite;
    uint64_t head;       /* producer: own index */
    uint64_t tail_cache; /* producer: last tail seen */
    uint64_t tail;       /* consumer: own index */
    uint64_t head_cache; /* consumer: last head seen */
} sb_ring;

/* Publish-stride for a capacity: small against the ring so the trusted lap
 * stays close to the capacity, large enough to amortise batch publishing. */
static inline uint32_t sb_ring_stride_for(uint64_t capacity)
{
    uint64_t s = capacity / 8u;
    if (s > SB_RING_MAX_STRIDE) s = SB_RING_MAX_STRIDE;
    return s < 1u ? 1u : (uint32_t)s;
}

static inline int sb_ring_capacity_ok(uint64_t capacity)
{
    return capacity >= SB_RING_MIN_SLOTS && capacity <= SB_RING_MAX_SLOTS &&
           (capacity & (capacity - 1u)) == 0u;
}

/* Owner only, before publication: zero the counters and fix the config. */
static inline void sb_ring_ctl_init(sb_ring_ctl *ctl, uint64_t capacity, uint64_t slots_offset,
                                    int overwrite)
{
    memset(ctl, 0, sizeof *ctl);
    ctl->capacity = capacity;
    ctl->slots_offset = slots_offset;
    ctl->overwrite = overwrite ? 1u : 0u;
    ctl->stride = overwrite ? sb_ring_stride_for(capacity) : 1u;
}

/* Either side: bind a local handle to a published ring in a mapping at base. */
static inline void sb_ring_bind(sb_ring *r, sb_ring_ctl *ctl, void *base)
{
    r->ctl = ctl;
    r->slots = (sb_record *)((uint8_t *)base + ctl->slots_offset);
    r->mask = ctl->capacity - 1u;
    r->overwrite = ctl->overwrite != 0u;
    r->stride = ctl->stride;
    r->lap = r->overwrite ? ctl->capacity - ctl->stride : ctl->capacity;
    r->head = atomic_load_explicit(&ctl->head, memory_order_acquire);
    r->tail = atomic_load_explicit(&ctl->tail, memory_order_acquire);
    r->tail_cache = r->tail;
    r->head_cache = r->head;
}

/* ---------------------------------------------------------------- producer */

/* Free slots for the producer (overwrite = 0), reloading tail only when the
 * cache shows fewer than `want`. */
static inline uint64_t sb_ring_free(sb_ring *r, uint64_t want)
{
    uint64_t cap = r->mask + 1u;
    uint64_t free_n = cap - (r->head - r->tail_cache);
    if (free_n < want) {
        r->tail_cache = atomic_load_explicit(&r->ctl->tail, memory_order_acquire);
        free_n = cap - (r->head - r->tail_cache);
    }
    return free_n;
}

static inline void sb_ring_count_rejected_(sb_ring *r, uint64_t n)
{
    uint64_t v = atomic_load_explicit(&r->ctl->rejected, memory_order_relaxed);
    atomic_store_explicit(&r->ctl->rejected, v + n, memory_order_relaxed);
}

/* Copy n records into consecutive slots from index `from` (wrapping), then
 * overwrite wall_ns with stamp_ns when stamp_ns >= 0. Does not publish. */
static inline void sb_ring_fill_(sb_ring *r, uint64_t from, const sb_record *src, uint64_t n,
                                 int64_t stamp_ns)
{
    uint64_t cap = r->mask + 1u;
    uint64_t i0 = from & r->mask;
    uint64_t first = n < cap - i0 ? n : cap - i0;
    memcpy(&r->slots[i0], src, first * sizeof(sb_record));
    memcpy(&r->slots[0], src + first, (n - first) * sizeof(sb_record));
    if (stamp_ns >= 0) {
        for (uint64_t k = 0; k < n; ++k) r->slots[(from + k) & r->mask].h.wall_ns = stamp_ns;
    }
}

/* Push one record; stamp_ns >= 0 replaces its wall_ns in the slot.
 * Returns SB_RING_OK or SB_RING_FULL (overwrite = 0 only). */
static inline int sb_ring_push(sb_ring *r, const sb_record *rec, int64_t stamp_ns)
{
    if (!r->overwrite) {
        if (sb_ring_free(r, 1u) == 0u) {
            sb_ring_count_rejected_(r, 1u);
            return SB_RING_FULL;
        }
    } else {
        /* The previous head store must be visible before this slot, which a
         * lapped consumer may be copying, starts to change. */
        atomic_thread_fence(memory_order_release);
    }
    sb_ring_fill_(r, r->head, rec, 1u, stamp_ns);
    r->head += 1u;
    atomic_store_explicit(&r->ctl->head, r->head, memory_order_release);
    return SB_RING_OK;
}

/* Push up to n records; returns how many were written (n in overwrite mode;
 * the free slots otherwise, the rest counted as rejected). */
static inline uint64_t sb_ring_push_batch(sb_ring *r, const sb_record *src, uint64_t n,
                                          int64_t stamp_ns)
{
    if (!r->overwrite) {
        uint64_t free_n = sb_ring_free(r, n);
        uint64_t k = n < free_n ? n : free_n;
        if (k) {
            sb_ring_fill_(r, r->head, src, k, stamp_ns);
            r->head += k;
            atomic_store_explicit(&r->ctl->head, r->head, memory_order_release);
        }
        if (k < n) sb_ring_count_rejected_(r, n - k);
        return k;
    }
    for (uint64_t done = 0; done < n;) {
        uint64_t k = n - done < r->stride ? n - done : r->stride;
        atomic_thread_fence(memory_order_release);
        sb_ring_fill_(r, r->head, src + done, k, stamp_ns);
        r->head += k;
        atomic_store_explicit(&r->ctl->head, r->head, memory_order_release);
        done += k;
    }
    return n;
}

/* ---------------------------------------------------------------- consumer */

static inline void sb_ring_skip_(sb_ring *r, uint64_t n)
{
    uint64_t v = atomic_load_explicit(&r->ctl->overwritten, memory_order_relaxed);
    atomic_store_explicit(&r->ctl->overwritten, v + n, memory_order_relaxed);
    r->tail += n;
}

/* If head has run more than a lap ahead, skip the lost records. */
static inline void sb_ring_resync_(sb_ring *r, uint64_t head)
{
    if (head - r->tail > r->lap) sb_ring_skip_(r, head - r->tail - r->lap);
}

static inline void sb_ring_copy_out_(const sb_ring *r, uint64_t from, sb_record *dst, uint64_t n)
{
    uint64_t cap = r->mask + 1u;
    uint64_t i0 = from & r->mask;
    uint64_t first = n < cap - i0 ? n : cap - i0;
    memcpy(dst, &r->slots[i0], first * sizeof(sb_record));
    memcpy(dst + first, &r->slots[0], (n - first) * sizeof(sb_record));
}

/* After copying records [from, from + n), return how many leading ones may
 * have been overwritten while we copied (overwrite mode only). */
static inline uint64_t sb_ring_lapped_(sb_ring *r, uint64_t from, uint64_t n)
{
    /* The fence keeps the slot reads before the head reload (seqlock read side). */
    atomic_thread_fence(memory_order_acquire);
    uint64_t head = atomic_load_explicit(&r->ctl->head, memory_order_acquire);
    r->head_cache = head;
    if (head - from <= r->lap) return 0u;
    uint64_t bad = head - from - r->lap;
    return bad < n ? bad : n;
}

/* Pop up to max_n records into dst; returns how many. */
static inline uint64_t sb_ring_pop_batch(sb_ring *r, sb_record *dst, uint64_t max_n)
{
    if (max_n == 0u) return 0u;
    for (;;) {
        if (r->head_cache - r->tail < max_n)
            r->head_cache = atomic_load_explicit(&r->ctl->head, memory_order_acquire);
        if (r->overwrite) sb_ring_resync_(r, r->head_cache);
        uint64_t avail = r->head_cache - r->tail;
        uint64_t n = avail < max_n ? avail : max_n;
        if (n == 0u) return 0u;
        sb_ring_copy_out_(r, r->tail, dst, n);
        uint64_t bad = r->overwrite ? sb_ring_lapped_(r, r->tail, n) : 0u;
        if (bad == n) {
            /* Every copied record was lapped: jump to the oldest trusted one. */
            sb_ring_resync_(r, r->head_cache);
            continue;
        }
        if (bad) {
            sb_ring_skip_(r, bad);
            n -= bad;
            memmove(dst, dst + bad, n * sizeof(sb_record));
        }
        r->tail += n;
        atomic_store_explicit(&r->ctl->tail, r->tail, memory_order_release);
        return n;
    }
}

/* Pop one record; SB_RING_OK or SB_RING_EMPTY. */
static inline int sb_ring_pop(sb_ring *r, sb_record *dst)
{
    return sb_ring_pop_batch(r, dst, 1u) ? SB_RING_OK : SB_RING_EMPTY;
}

/* Records the consumer could pop now (reloads head). */
static inline uint64_t sb_ring_available(sb_ring *r)
{
    uint64_t head = atomic_load_explicit(&r->ctl->head, memory_order_acquire);
    r->head_cache = head;
    uint64_t n = head - r->tail;
    return n < r->lap ? n : r->lap;
}

/* --------------------------------------------------------------- counters */

typedef struct sb_ring_stats {
    uint64_t written;     /* records published */
    uint64_t read;        /* records popped */
    uint64_t overwritten; /* records lost to laps, counted or still pending */
    uint64_t rejected;    /* pushes refused (overwrite = 0) */
    uint64_t available;   /* records waiting */
} sb_ring_stats;

/* A consistent-enough snapshot from either side; written == read +
 * overwritten + available whenever neither side is mid-operation. */
static inline sb_ring_stats sb_ring_stats_read(const sb_ring_ctl *ctl)
{
    sb_ring_stats s;
    uint64_t lap = ctl->overwrite ? ctl->capacity - ctl->stride : ctl->capacity;
    uint64_t tail = atomic_load_explicit(&ctl->tail, memory_order_acquire);
    uint64_t skipped = atomic_load_explicit(&ctl->overwritten, memory_order_acquire);
    uint64_t head = atomic_load_explicit(&ctl->head, memory_order_acquire);
    uint64_t behind = head - tail;
    s.written = head;
    s.read = tail - skipped;
    s.rejected = atomic_load_explicit(&ctl->rejected, memory_order_relaxed);
    s.available = behind < lap ? behind : lap;
    s.overwritten = skipped + (behind - s.available);
    return s;
}

#endif /* SB_RING_H */
