/*
 * blake2b.c - BLAKE2b after RFC 7693 (blake2b.h). The block being filled is compressed
 * only when more bytes arrive, because the last block of a message is compressed with the
 * final flag set.
 */
#include "blake2b.h"

#include <string.h>

/* The initial state: SHA-512's initial hash value (RFC 7693, 2.6). */
static const uint64_t IV[8] = {
    0x6a09e667f3bcc908ULL, 0xbb67ae8584caa73bULL, 0x3c6ef372fe94f82bULL,
    0xa54ff53a5f1d36f1ULL, 0x510e527fade682d1ULL, 0x9b05688c2b3e6c1fULL,
    0x1f83d9abfb41bd6bULL, 0x5be0cd19137e2179ULL};

/* The message word schedule of each round (RFC 7693, 2.7); rounds 10 and 11 reuse 0, 1. */
static const uint8_t SIGMA[12][16] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15},
    {14, 10, 4, 8, 9, 15, 13, 6, 1, 12, 0, 2, 11, 7, 5, 3},
    {11, 8, 12, 0, 5, 2, 15, 13, 10, 14, 3, 6, 7, 1, 9, 4},
    {7, 9, 3, 1, 13, 12, 11, 14, 2, 6, 5, 10, 4, 0, 15, 8},
    {9, 0, 5, 7, 2, 4, 10, 15, 14, 1, 11, 12, 6, 8, 3, 13},
    {2, 12, 6, 10, 0, 11, 8, 3, 4, 13, 7, 5, 15, 14, 1, 9},
    {12, 5, 1, 15, 14, 13, 4, 10, 0, 7, 6, 3, 9, 2, 8, 11},
    {13, 11, 7, 14, 12, 1, 3, 9, 5, 0, 15, 4, 8, 6, 2, 10},
    {6, 15, 14, 9, 11, 3, 0, 8, 12, 2, 13, 7, 1, 4, 10, 5},
    {10, 2, 8, 4, 7, 6, 1, 5, 15, 11, 9, 14, 3, 12, 13, 0},
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15},
    {14, 10, 4, 8, 9, 15, 13, 6, 1, 12, 0, 2, 11, 7, 5, 3}};

static inline uint64_t rotr(uint64_t x, unsigned n)
{
    return (x >> n) | (x << (64u - n));
}

static inline uint64_t load_le64(const uint8_t *p)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    uint64_t v;
    memcpy(&v, p, sizeof v);   /* one load on a little-endian machine */
    return v;
#else
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--)
        v = (v << 8) | p[i];
    return v;
#endif
}

/* The mixing function G (RFC 7693, 3.1) on v[a], v[b], v[c], v[d] with words x, y. */
#define G(a, b, c, d, x, y)                   \
    do {                                      \
        v[a] = v[a] + v[b] + (x);             \
        v[d] = rotr(v[d] ^ v[a], 32);         \
        v[c] = v[c] + v[d];                   \
        v[b] = rotr(v[b] ^ v[c], 24);         \
        v[a] = v[a] + v[b] + (y);             \
        v[d] = rotr(v[d] ^ v[a], 16);         \
        v[c] = v[c] + v[d];                   \
        v[b] = rotr(v[b] ^ v[c], 63);         \
    } while (0)

/* The compression function F (RFC 7693, 3.2) of one block into h. */
static void compress(uint64_t h[8], const uint64_t t[2], const uint8_t *block, int last)
{
    uint64_t m[16], v[16];
    for (int i = 0; i < 16; i++)
        m[i] = load_le64(block + 8 * i);
    for (int i = 0; i < 8; i++) {
        v[i] = h[i];
        v[i + 8] = IV[i];
    }
    v[12] ^= t[0];
    v[13] ^= t[1];
    if (last)
        v[14] = ~v[14];
    /* The rounds written out: with constant indices the state stays in registers
     * (a loop over r, at -O2, reloads the schedule and runs at ~60 % of hashlib's speed). */
#define ROUND(r)                                                      \
    do {                                                              \
        G(0, 4, 8, 12, m[SIGMA[r][0]], m[SIGMA[r][1]]);               \
        G(1, 5, 9, 13, m[SIGMA[r][2]], m[SIGMA[r][3]]);               \
        G(2, 6, 10, 14, m[SIGMA[r][4]], m[SIGMA[r][5]]);              \
        G(3, 7, 11, 15, m[SIGMA[r][6]], m[SIGMA[r][7]]);              \
        G(0, 5, 10, 15, m[SIGMA[r][8]], m[SIGMA[r][9]]);              \
        G(1, 6, 11, 12, m[SIGMA[r][10]], m[SIGMA[r][11]]);            \
        G(2, 7, 8, 13, m[SIGMA[r][12]], m[SIGMA[r][13]]);             \
        G(3, 4, 9, 14, m[SIGMA[r][14]], m[SIGMA[r][15]]);             \
    } while (0)
    ROUND(0); ROUND(1); ROUND(2); ROUND(3); ROUND(4); ROUND(5);
    ROUND(6); ROUND(7); ROUND(8); ROUND(9); ROUND(10); ROUND(11);
#undef ROUND
    for (int i = 0; i < 8; i++)
        h[i] ^= v[i] ^ v[i + 8];
}

static void count(uint64_t t[2], uint64_t n)
{
    t[0] += n;
    if (t[0] < n)
        t[1]++;
}

int sb_blake2b_init(sb_blake2b *s, size_t digest_len)
{
    if (digest_len < 1 || digest_len > SB_BLAKE2B_MAX_DIGEST)
        return -1;
    memset(s, 0, sizeof *s);
    memcpy(s->h, IV, sizeof IV);
    /* The parameter block's first word: digest length, key length 0, fanout 1, depth 1. */
    s->h[0] ^= 0x01010000ULL ^ (uint64_t)digest_len;
    s->digest_len = digest_len;
    return 0;
}

void sb_blake2b_update(sb_blake2b *s, const void *data, size_t len)
{
    const uint8_t *p = data;
    while (len > 0) {
        if (s->buf_len == SB_BLAKE2B_BLOCK) {   /* full, and more follows: not the last */
            count(s->t, SB_BLAKE2B_BLOCK);
            compress(s->h, s->t, s->buf, 0);
            s->buf_len = 0;
        }
        if (s->buf_len == 0) {                  /* whole blocks straight from the input */
            while (len > SB_BLAKE2B_BLOCK) {
                count(s->t, SB_BLAKE2B_BLOCK);
                compress(s->h, s->t, p, 0);
                p += SB_BLAKE2B_BLOCK;
                len -= SB_BLAKE2B_BLOCK;
            }
        }
        size_t n = SB_BLAKE2B_BLOCK - s->buf_len;
        if (n > len)
            n = len;
        memcpy(s->buf + s->buf_len, p, n);
        s->buf_len += n;
        p += n;
        len -= n;
    }
}

void sb_blake2b_digest(const sb_blake2b *s, uint8_t *out)
{
    uint64_t h[8], t[2] = {s->t[0], s->t[1]};
    uint8_t block[SB_BLAKE2B_BLOCK] = {0};
    memcpy(h, s->h, sizeof h);
    memcpy(block, s->buf, s->buf_len);
    count(t, s->buf_len);
    compress(h, t, block, 1);
    for (size_t i = 0; i < s->digest_len; i++)
        out[i] = (uint8_t)(h[i / 8] >> (8 * (i % 8)));
}
