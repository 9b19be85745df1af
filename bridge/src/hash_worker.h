/*
 * hash_worker.h - a BLAKE2b state fed on a thread of its own: the one-process lockstep
 * hands each batch's trace to it and steps the next batch while it hashes (a free core
 * does the 3-4 % of the loop's time the hash took on the loop's own thread; the bytes and
 * their order are the same, so the digest is). One job at a time: a new one, and any use
 * of the state, first waits for the one before. The caller owns the bytes of a job and
 * leaves them unchanged until the next post or wait returns. Plain C and pthreads.
 */
#ifndef SB_HASH_WORKER_H
#define SB_HASH_WORKER_H

#include <pthread.h>
#include <stddef.h>

#include "blake2b.h"

typedef struct {
    sb_blake2b *state;         /* the state the jobs update, the caller's */
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t posted;     /* a job or the stop for the thread */
    pthread_cond_t idle;       /* the job is done, for the caller */
    const unsigned char *data; /* the job: NULL when there is none */
    size_t len;
    int stop;
    int running;               /* the thread was started and not joined */
} sb_hash_worker;

/* Start the thread that updates *state; -1 (nothing started) if it cannot be created. */
int sb_hash_worker_start(sb_hash_worker *w, sb_blake2b *state);

/* Hash data[0..len) next, on the thread; returns once the job before is done and this
 * one is posted. */
void sb_hash_worker_post(sb_hash_worker *w, const void *data, size_t len);

/* Return once no job is pending (the state holds every byte posted). */
void sb_hash_worker_wait(sb_hash_worker *w);

/* Finish the pending job, stop and join the thread; a worker never started is left as is. */
void sb_hash_worker_stop(sb_hash_worker *w);

#endif /* SB_HASH_WORKER_H */
