/*
 * hash_worker.c - the trace hash's thread (hash_worker.h).
 */
#include "hash_worker.h"

static void *run(void *arg)
{
    sb_hash_worker *w = arg;
    pthread_mutex_lock(&w->mu);
    for (;;) {
        while (w->data == NULL && !w->stop)
            pthread_cond_wait(&w->posted, &w->mu);
        if (w->data == NULL)      /* stopped, and nothing left to hash */
            break;
        const unsigned char *data = w->data;
        const size_t len = w->len;
        /* the caller waits for data == NULL before it touches the state or the bytes */
        pthread_mutex_unlock(&w->mu);
        sb_blake2b_update(w->state, data, len);
        pthread_mutex_lock(&w->mu);
        w->data = NULL;
        pthread_cond_signal(&w->idle);
    }
    pthread_mutex_unlock(&w->mu);
    return NULL;
}

int sb_hash_worker_start(sb_hash_worker *w, sb_blake2b *state)
{
    w->state = state;
    w->data = NULL;
    w->len = 0;
    w->stop = 0;
    w->running = 0;
    if (pthread_mutex_init(&w->mu, NULL) != 0)
        return -1;
    if (pthread_cond_init(&w->posted, NULL) != 0) {
        pthread_mutex_destroy(&w->mu);
        return -1;
    }
    if (pthread_cond_init(&w->idle, NULL) != 0) {
        pthread_cond_destroy(&w->posted);
        pthread_mutex_destroy(&w->mu);
        return -1;
    }
    if (pthread_create(&w->thread, NULL, run, w) != 0) {
        pthread_cond_destroy(&w->idle);
        pthread_cond_destroy(&w->posted);
        pthread_mutex_destroy(&w->mu);
        return -1;
    }
    w->running = 1;
    return 0;
}

/* With w->mu held: until the thread has no job. */
static void wait_locked(sb_hash_worker *w)
{
    while (w->data != NULL)
        pthread_cond_wait(&w->idle, &w->mu);
}

void sb_hash_worker_post(sb_hash_worker *w, const void *data, size_t len)
{
    if (len == 0)
        return;
    pthread_mutex_lock(&w->mu);
    wait_locked(w);
    w->data = data;
    w->len = len;
    pthread_cond_signal(&w->posted);
    pthread_mutex_unlock(&w->mu);
}

void sb_hash_worker_wait(sb_hash_worker *w)
{
    if (!w->running)
        return;
    pthread_mutex_lock(&w->mu);
    wait_locked(w);
    pthread_mutex_unlock(&w->mu);
}

void sb_hash_worker_stop(sb_hash_worker *w)
{
    if (!w->running)
        return;
    pthread_mutex_lock(&w->mu);
    wait_locked(w);
    w->stop = 1;
    pthread_cond_signal(&w->posted);
    pthread_mutex_unlock(&w->mu);
    pthread_join(w->thread, NULL);
    pthread_cond_destroy(&w->idle);
    pthread_cond_destroy(&w->posted);
    pthread_mutex_destroy(&w->mu);
    w->running = 0;
}
