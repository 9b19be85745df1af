/*
 * blake2b.h - BLAKE2b (RFC 7693), unkeyed, digests of 1..64 bytes: the run's trace hash in
 * C, so that the two-process bridge can hash a step's records while it waits for the FC's
 * answer (step_batch.c) instead of after its batch. The digest is the one Python's
 * hashlib.blake2b(digest_size=n) gives for the same bytes (tests/bridge/test_blake2b.py).
 * Plain C, no allocation; one user at a time.
 */
#ifndef SB_BLAKE2B_H
#define SB_BLAKE2B_H

#include <stddef.h>
#include <stdint.h>

#define SB_BLAKE2B_BLOCK 128
#define SB_BLAKE2B_MAX_DIGEST 64

typedef struct {
    uint64_t h[8];                     /* the chained state */
    uint64_t t[2];                     /* bytes compressed so far (128-bit counter) */
    uint8_t buf[SB_BLAKE2B_BLOCK];     /* the last, not yet compressed, block */
    size_t buf_len;
    size_t digest_len;
} sb_blake2b;

/* A fresh state for digests of digest_len bytes (1..64); -1 if out of range. */
int sb_blake2b_init(sb_blake2b *s, size_t digest_len);

void sb_blake2b_update(sb_blake2b *s, const void *data, size_t len);

/* The digest of everything given so far into out[digest_len]; s itself is left as it was,
 * so more bytes may follow (as hashlib's digest()). */
void sb_blake2b_digest(const sb_blake2b *s, uint8_t *out);

#endif /* SB_BLAKE2B_H */
