/*
 * sb_segment.h - the shared-memory segment that the bridge (owner) creates
 * and the SIL FC (peer) attaches: a one-page header followed by the slots of
 * two rings (sensors: owner -> peer, actuators: peer -> owner).
 *
 * Publication: the owner creates the POSIX object exclusively (mode 0600),
 * takes an open-file-description write lock on it for its whole life, sizes
 * and fills it, and stores `magic` last with release. A peer trusts nothing
 * until it has read that magic with acquire. A crashed owner's lock vanishes
 * with its process, which is how a stale segment is told from a live one
 * (the pid is kept for messages and for the peer's cheap liveness check).
 *
 * Ownership of the header words: identity line and ring config - owner,
 * before publication; owner line - owner; peer line - peer; each lockstep
 * word - whichever side the protocol (shm/lockstep.py) names.
 *
 * All functions return an sb_seg_status; on failure `diag` says why.
 * This file and shm/src/segment.c are the only OS-facing code of the ring.
 */
#ifndef SB_SEGMENT_H
#define SB_SEGMENT_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "sb_doorbell.h"
#include "sb_records.h"
#include "sb_ring.h"

#define SB_SEG_MAGIC 0x314D485342494C53ull /* "SLIBSHM1" read little-endian */
#define SB_SEG_VERSION 5u /* 2: doorbells and the owner tag; 3: step words on the ring lines,
                             hand-off; 4: the FC's sync word (FC_SYNC_NS); 5: stack_cpu */
#define SB_SEG_WORDS 9u       /* lockstep word indices (shm/lockstep.py) */
#define SB_SEG_WORD_LINES 8u  /* header lines for words[]: one per index below 8; 0, 1 (unused
                                 there) and 8 live on the rings' lines */
#define SB_SEG_HEADER_BYTES 4096u
#define SB_SEG_NAME_MAX 64u
#define SB_SEG_PREFIX "/silbridge-"
#define SB_SEG_TAG_MAX 64u /* owner tag bytes, NUL included */
#define SB_SEG_TAG_ENV "SILBRIDGE_OWNER_TAG"

enum sb_seg_ring { SB_RING_SENSORS = 0, SB_RING_ACTUATORS = 1, SB_RING_COUNT = 2 };

/* The lockstep words the C side reads (shm/lockstep.py names all nine; tests/shm/
 * test_handoff.py checks these agree): each side's step word, the run mode, STOP, the FC's
 * promise. */
enum sb_seg_word_index {
    SB_WORD_OWNER_STEP = 0, /* BRIDGE_SIM_NS: on the sensor ring's producer line */
    SB_WORD_PEER_STEP = 1,  /* FC_SIM_NS: on the actuator ring's producer line */
    SB_WORD_RUN_MODE = 2,
    SB_WORD_STOP = 3,
    SB_WORD_PEER_SYNC = 8   /* FC_SYNC_NS: beside FC_SIM_NS (sb_seg_peer_sync) */
};
enum { SB_MODE_LOCKSTEP = 1 }; /* RUN_MODE value: the hand-off waits of sb_handoff.h apply */

enum sb_seg_status {
    SB_SEG_OK = 0,
    SB_SEG_E_NAME,        /* instance name invalid */
    SB_SEG_E_CONFIG,      /* slot counts invalid */
    SB_SEG_E_MISSING,     /* no segment with that name */
    SB_SEG_E_CREATING,    /* exists but not yet published (retry shortly) */
    SB_SEG_E_BUSY,        /* a live owner already holds that name */
    SB_SEG_E_STALE,       /* the owner is gone (crashed or closed without unlink) */
    SB_SEG_E_PERM,        /* permission denied */
    SB_SEG_E_MAGIC,       /* not a silbridge segment */
    SB_SEG_E_VERSION,     /* segment format version differs */
    SB_SEG_E_LAYOUT,      /* struct layout hash or size differs */
    SB_SEG_E_PEER_BUSY,   /* another live peer is attached */
    SB_SEG_E_OS           /* other system error, see diag.err_no */
};

typedef struct sb_seg_diag {
    int err_no;              /* errno of the failing call, 0 if none */
    int32_t pid;             /* owner (or busy peer) pid involved */
    uint32_t found_version;  /* version found in the segment */
    uint64_t found_magic;
    uint64_t found_hash;     /* layout hash found in the segment */
    char what[48];           /* failing call, e.g. "shm_open" */
} sb_seg_diag;

typedef struct sb_seg_header {
    /* Line 0: identity, immutable once magic is published. */
    _Atomic uint64_t magic;
    uint32_t version;
    uint32_t header_bytes;
    uint64_t layout_hash;
    uint64_t total_bytes;
    int64_t created_unix_ns; /* CLOCK_REALTIME at creation [ns] */
    int64_t created_mono_ns; /* CLOCK_MONOTONIC at creation [ns] */
    int32_t owner_pid;
    uint32_t pad0[3];
    /* Line 1: owner. */
    _Alignas(SB_CACHE_LINE) _Atomic uint64_t owner_heartbeat;
    _Atomic uint32_t owner_closed; /* 1 after the owner closed its mapping */
    uint32_t pad1[13];
    /* Line 2: peer. */
    _Alignas(SB_CACHE_LINE) _Atomic uint64_t peer_heartbeat;
    _Atomic uint64_t peer_attaches; /* how many times a peer attached */
    _Atomic int32_t peer_pid;       /* 0 until a peer attaches */
    _Atomic uint32_t peer_closed;   /* 1 after the peer closed its mapping */
    _Atomic uint64_t peer_trouble;  /* the peer's hand-off spins that ran out or lost their core */
    uint32_t pad2[8];
    /* Lines 3..10: lockstep words, one per line so their writers never share; use
     * sb_seg_word(): words[0] and words[1] are unused, those two (and word 8, FC_SYNC_NS)
     * live on the rings' lines. */
    struct {
        _Alignas(SB_CACHE_LINE) _Atomic uint64_t value;
    } words[SB_SEG_WORD_LINES];
    /* Lines 11..16: ring control blocks. */
    sb_ring_ctl rings[SB_RING_COUNT];
    /* Lines 17, 18: doorbells (sb_doorbell.h): [SB_BELL_OWNER] rung by the owner. */
    sb_doorbell bells[SB_BELL_COUNT];
    /* Line 19: who made it: $SILBRIDGE_OWNER_TAG of the owner at creation (a test session,
     * a CI job), so `silbridge clean` and leak checks can tell whose a leftover is. */
    _Alignas(SB_CACHE_LINE) char owner_tag[SB_SEG_TAG_MAX];
    /* Line 20: the lockstep hand-off's way of waiting (sb_handoff.h), written by the owner
     * when its choice changes, read by the peer before each wait; with the STACK way, the
     * CPU the owner holds its waiting thread on (-1: not yet), where the peer joins it. */
    _Alignas(SB_CACHE_LINE) _Atomic uint32_t handoff_arm;
    _Atomic int32_t stack_cpu;
    uint32_t pad3[14];
} sb_seg_header;

_Static_assert(sizeof(sb_seg_header) <= SB_SEG_HEADER_BYTES, "header fits its page");
_Static_assert(offsetof(sb_seg_header, owner_heartbeat) == 1 * SB_CACHE_LINE, "owner line");
_Static_assert(offsetof(sb_seg_header, peer_heartbeat) == 2 * SB_CACHE_LINE, "peer line");
_Static_assert(offsetof(sb_seg_header, words) == 3 * SB_CACHE_LINE, "words start on line 3");
_Static_assert(sizeof(((sb_seg_header *)0)->words[0]) == SB_CACHE_LINE, "one word per line");
_Static_assert(sizeof(_Atomic int32_t) == 4, "atomic pid is a plain int32");
_Static_assert(offsetof(sb_seg_header, bells) % SB_CACHE_LINE == 0, "bells on their own lines");
_Static_assert(offsetof(sb_seg_header, owner_tag) == 19 * SB_CACHE_LINE, "the tag stays on line 19");
_Static_assert(offsetof(sb_seg_header, handoff_arm) % SB_CACHE_LINE == 0, "hand-off on its line");

/* Process-local handle of a mapped segment. */
typedef struct sb_segment {
    sb_seg_header *hdr; /* == base */
    void *base;
    size_t size;
    int fd;
    int is_owner;
    int32_t opener_pid; /* a forked child that inherited the handle only unmaps it */
    uint64_t dev, ino; /* identity of the object, so close never unlinks a successor */
    char shm_name[sizeof(SB_SEG_PREFIX) + SB_SEG_NAME_MAX];
} sb_segment;

/* FNV-1a over sizeof/offsetof of every shared struct: equal hashes mean both
 * sides were built from the same layout. */
uint64_t sb_layout_hash(void);

/* Bytes a segment with these slot counts occupies. */
uint64_t sb_segment_bytes(uint64_t sensor_slots, uint64_t actuator_slots);

int sb_segment_create(sb_segment *seg, const char *name, uint64_t sensor_slots,
                      uint64_t actuator_slots, int overwrite, int replace_stale,
                      sb_seg_diag *diag);
int sb_segment_attach(sb_segment *seg, const char *name, sb_seg_diag *diag);
/* Unmap and mark this side closed (the owner's lock goes with its fd). */
void sb_segment_close(sb_segment *seg);
/* Owner: remove the name if it still refers to this object (before or after
 * close); a successor's segment under the same name is left alone. */
void sb_segment_unlink(const sb_segment *seg);
/* Remove a segment whose owner is gone. SB_SEG_OK if removed, E_MISSING if
 * none, E_BUSY if its owner lives. */
int sb_segment_remove_stale(const char *name, sb_seg_diag *diag);

/* What a segment's header says, read without attaching (`silbridge clean`, leak checks). */
typedef struct sb_seg_probe {
    int published;           /* magic present */
    uint32_t version;
    int32_t owner_pid;
    int owner_alive;         /* its owner lock is held and the owner did not close */
    int64_t created_unix_ns;
    uint64_t bytes;          /* size of the object */
    char tag[SB_SEG_TAG_MAX]; /* owner tag (version >= 2), "" if none */
} sb_seg_probe;
int sb_segment_probe(const char *name, sb_seg_probe *out, sb_seg_diag *diag);

/* FC_SYNC_NS, the FC's promise beside its step word (shm/lockstep.py): the sim time of the
 * next step whose answer the bridge must wait for. Every step before it the FC answers with
 * no record, and its Python does not act, so the bridge publishes them without waiting and the
 * FC computes while the bridge steps its physics. 0 (a new segment, an FC that makes no
 * promise): the bridge waits for every step. Stored before FC_SIM_NS (whose release orders
 * it), read after the acquire that saw it. */
static inline _Atomic uint64_t *sb_seg_peer_sync(sb_seg_header *h)
{
    return &h->rings[SB_RING_ACTUATORS].sync_word;
}

/* Lockstep word i (0..SB_SEG_WORDS-1): the two step words (and the FC's promise) sit beside
 * the heads of the rings their writers produce, so a hand-off moves one line besides the
 * records (sb_ring.h). */
static inline _Atomic uint64_t *sb_seg_word(sb_seg_header *h, unsigned i)
{
    if (i == SB_WORD_OWNER_STEP) return &h->rings[SB_RING_SENSORS].step_word;
    if (i == SB_WORD_PEER_STEP) return &h->rings[SB_RING_ACTUATORS].step_word;
    if (i == SB_WORD_PEER_SYNC) return sb_seg_peer_sync(h);
    return &h->words[i].value;
}

/* The doorbell this side rings after publishing / waits on for the other side. */
static inline sb_doorbell *sb_segment_my_bell(const sb_segment *seg)
{
    return &seg->hdr->bells[seg->is_owner ? SB_BELL_OWNER : SB_BELL_PEER];
}
static inline sb_doorbell *sb_segment_their_bell(const sb_segment *seg)
{
    return &seg->hdr->bells[seg->is_owner ? SB_BELL_PEER : SB_BELL_OWNER];
}

/* Liveness of the owner / the attached peer: pid exists, not marked closed,
 * and (seen from the other side) its lock is still held - one fcntl. */
int sb_segment_owner_alive(const sb_segment *seg);
int sb_segment_peer_alive(const sb_segment *seg);
int sb_pid_alive(int32_t pid);

/* CLOCK_MONOTONIC [ns], the clock of every record's wall_ns. */
int64_t sb_monotonic_ns(void);

#endif /* SB_SEGMENT_H */
