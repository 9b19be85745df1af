/*
 * sb_capi.h - the shared-memory segment for another C extension (fc_sil's
 * Core.attach_io): Segment.c_capsule() hands out a PyCapsule named
 * SB_CAPI_CAPSULE holding an sb_capi, so a consumer loop can pop, push and set
 * lockstep words without a Python call per operation.
 *
 * Lifetime: the capsule keeps the Segment object alive, so `seg` and `rings`
 * stay valid memory; the mapping itself is gone once the segment is closed,
 * which a user checks before every use: seg->base == NULL means closed.
 * Roles: the user must honour the side it attached as (`is_owner`): the owner
 * produces the sensors ring and consumes the actuators ring, the peer the
 * other way round (sb_ring.h's single-producer/single-consumer rule).
 */
#ifndef SB_CAPI_H
#define SB_CAPI_H

#include <stdint.h>

#include "sb_ring.h"
#include "sb_segment.h"

#define SB_CAPI_CAPSULE "silbridge.shm.c_api"
#define SB_CAPI_VERSION 2u /* 2: wait_step */

typedef struct sb_capi {
    uint32_t version;     /* SB_CAPI_VERSION */
    int is_owner;         /* 1: the bridge's side */
    const sb_segment *seg; /* seg->base == NULL once closed */
    sb_ring *rings;       /* [SB_RING_COUNT]: this process's ring state */
    /* The owner's lockstep wait (what Segment.wait_word does for FC_SIM_NS in lockstep):
     * until the peer's step word >= at_least, at most timeout_ns. Call it with the GIL
     * held; it releases the GIL while it waits. 1: there; 0: timed out (look at the
     * peer, then wait again); -1: an exception is set. Every call counts as one step of
     * the hand-off's choice (sb_handoff_choice.h). */
    int (*wait_step)(const struct sb_capi *api, uint64_t at_least, int64_t timeout_ns);
    void *segment_object; /* the Segment the capsule keeps alive (wait_step's state) */
} sb_capi;

/* The lockstep word i of an open segment (release/acquire like Segment.set_word/word). */
static inline _Atomic uint64_t *sb_capi_word(const sb_capi *api, int i)
{
    return sb_seg_word(api->seg->hdr, (unsigned)i);
}

#endif
