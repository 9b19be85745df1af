/*
 * bench.c - C producer/consumer loops over one ring, run in two processes,
 * to show the ring's own ceiling next to the Python figures and to fuzz it
 * with millions of records (tests/shm/test_fuzz.py).
 *
 * Every record i carries i in sim_ns, (uint32)i in seq and five 64-bit
 * words derived from i in its payload, so the consumer detects a torn record
 * (fields from two different i) and a reordered one (i going backwards), and
 * checks that every gap in i is exactly what the ring counted as overwritten.
 * The loops release the GIL, are bounded by time, and sched_yield now and
 * then while they wait so a 2-core machine stays usable.
 */
#include "module.h"

#include <sched.h>
#include <stdlib.h>

#define BENCH_FLAG_END 0x8000u    /* last record of a run */
#define BENCH_POLLS_PER_YIELD 2048 /* empty polls between two sched_yield calls */
#define BENCH_MAX_BATCH 4096
#define BENCH_MAX_RTT_SAMPLES (1u << 22)

static const uint64_t GOLDEN = 0x9E3779B97F4A7C15ull;

static void bench_fill(sb_record *rec, uint64_t i)
{
    uint64_t w[5];
    rec->h.kind = SB_KIND_IMU;
    rec->h.flags = 0;
    rec->h.seq = (uint32_t)i;
    rec->h.sim_ns = (int64_t)i;
    rec->h.wall_ns = 0;
    for (int k = 0; k < 5; ++k) w[k] = i * GOLDEN + (uint64_t)k;
    memcpy(rec->u.raw, w, sizeof w);
}

/* 1 if the record is self-consistent (not torn). */
static int bench_intact(const sb_record *rec)
{
    uint64_t i = (uint64_t)rec->h.sim_ns;
    uint64_t w[5];
    memcpy(w, rec->u.raw, sizeof w);
    if (rec->h.kind != SB_KIND_IMU || rec->h.seq != (uint32_t)i) return 0;
    for (int k = 0; k < 5; ++k)
        if (w[k] != i * GOLDEN + (uint64_t)k) return 0;
    return 1;
}

/* Wait politely between empty polls: spin, and yield every so often. */
static void bench_idle(unsigned *polls)
{
    if (++*polls % BENCH_POLLS_PER_YIELD == 0) sched_yield();
    else sb_cpu_relax();
}

typedef struct stream_result {
    uint64_t records;
    int64_t elapsed_ns;
    uint64_t torn, reordered, lost_by_seq, overwritten;
    int timed_out;
} stream_result;

static void stream_produce(sb_ring *r, sb_record *buf, int64_t run_ns, uint64_t max_records,
                           uint64_t batch, int64_t idle_ns, stream_result *res)
{
    uint64_t i = 0;
    unsigned polls = 0;
    int64_t t0 = sb_monotonic_ns(), now = t0, stuck_since = t0;
    while (now - t0 < run_ns && i < max_records) {
        uint64_t n = batch < max_records - i ? batch : max_records - i;
        if (!r->overwrite) {
            uint64_t free_n = sb_ring_free(r, batch);
            if (free_n == 0) {
                bench_idle(&polls);
                now = sb_monotonic_ns();
                if (now - stuck_since > idle_ns) {
                    res->timed_out = 1;
                    break;
                }
                continue;
            }
            n = free_n < n ? free_n : n;
        }
        for (uint64_t k = 0; k < n; ++k) bench_fill(&buf[k], i + k);
        sb_ring_push_batch(r, buf, n, -1);
        i += n;
        now = stuck_since = sb_monotonic_ns();
    }
    res->elapsed_ns = sb_monotonic_ns() - t0;
    res->records = i;
    /* The end marker; it is the newest record, so it can never be lapped. */
    bench_fill(&buf[0], i);
    buf[0].h.flags = BENCH_FLAG_END;
    int64_t end_start = sb_monotonic_ns();
    while (sb_ring_push(r, &buf[0], -1) != SB_RING_OK) {
        bench_idle(&polls);
        if (sb_monotonic_ns() - end_start > idle_ns) {
            res->timed_out = 1;
            break;
        }
    }
}

static void stream_consume(sb_ring *r, sb_record *buf, int64_t idle_ns, uint64_t batch,
                           stream_result *res)
{
    uint64_t skipped0 = atomic_load_explicit(&r->ctl->overwritten, memory_order_relaxed);
    uint64_t expect = 0;
    int started = 0, done = 0;
    unsigned polls = 0;
    int64_t t0 = 0, last_rx = sb_monotonic_ns();
    while (!done) {
        uint64_t n = sb_ring_pop_batch(r, buf, batch);
        if (n == 0) {
            bench_idle(&polls);
            if (sb_monotonic_ns() - last_rx > idle_ns) {
                res->timed_out = 1;
                break;
            }
            continue;
        }
        last_rx = sb_monotonic_ns();
        if (!started) { /* every run numbers its records from 0 */
            started = 1;
            t0 = last_rx;
        }
        for (uint64_t k = 0; k < n; ++k) {
            const sb_record *rec = &buf[k];
            if (!bench_intact(rec)) {
                res->torn++;
                continue;
            }
            uint64_t i = (uint64_t)rec->h.sim_ns;
            if (i < expect) res->reordered++;
            else res->lost_by_seq += i - expect;
            expect = i + 1;
            if (rec->h.flags & BENCH_FLAG_END) {
                done = 1;
                break;
            }
            res->records++;
        }
    }
    res->elapsed_ns = started ? sb_monotonic_ns() - t0 : 0;
    res->overwritten = atomic_load_explicit(&r->ctl->overwritten, memory_order_relaxed) - skipped0;
}

static int ring_arg(PyObject *obj, RingObject **out)
{
    if (!PyObject_TypeCheck(obj, &SbRingType)) {
        PyErr_SetString(PyExc_TypeError, "expected a Ring (Segment.sensors / .actuators)");
        return -1;
    }
    *out = (RingObject *)obj;
    return sb_check_open((*out)->owner) ? -1 : 0;
}

PyObject *sb_bench_stream(PyObject *Py_UNUSED(module), PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"ring", "seconds", "batch", "idle_timeout_s", "max_records", NULL};
    PyObject *ring_obj;
    double seconds, idle_s = 10.0;
    Py_ssize_t batch = 64;
    unsigned long long max_records = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "Od|ndK", kwlist, &ring_obj, &seconds, &batch,
                                     &idle_s, &max_records))
        return NULL;
    if (max_records == 0) max_records = UINT64_MAX;
    RingObject *ring;
    if (ring_arg(ring_obj, &ring) < 0) return NULL;
    if (batch < 1 || batch > BENCH_MAX_BATCH) {
        PyErr_Format(PyExc_ValueError, "batch must be 1..%d", BENCH_MAX_BATCH);
        return NULL;
    }
    stream_result res = {0};
    int64_t run_ns = (int64_t)(seconds * 1e9), idle_ns = (int64_t)(idle_s * 1e9);
    int produce = ring->produces;
    sb_record *buf = malloc((size_t)batch * sizeof(sb_record));
    if (!buf) return PyErr_NoMemory();
    Py_BEGIN_ALLOW_THREADS
    if (produce) stream_produce(ring->r, buf, run_ns, max_records, (uint64_t)batch, idle_ns, &res);
    else stream_consume(ring->r, buf, idle_ns, (uint64_t)batch, &res);
    Py_END_ALLOW_THREADS
    free(buf);
    double rate = res.elapsed_ns > 0 ? (double)res.records * 1e9 / (double)res.elapsed_ns : 0.0;
    return Py_BuildValue("{sssKsLsdsKsKsKsKsO}", "role", produce ? "producer" : "consumer",
                         "records", (unsigned long long)res.records, "elapsed_ns",
                         (long long)res.elapsed_ns, "records_per_s", rate, "torn",
                         (unsigned long long)res.torn, "reordered",
                         (unsigned long long)res.reordered, "lost_by_seq",
                         (unsigned long long)res.lost_by_seq, "overwritten",
                         (unsigned long long)res.overwritten, "timed_out",
                         res.timed_out ? Py_True : Py_False);
}

/* ---------------------------------------------------------------- ping-pong */

typedef struct pingpong_result {
    uint64_t round_trips;
    int64_t elapsed_ns;
    uint64_t errors;
    int timed_out;
    int64_t *rtt_ns; /* initiator: one sample per round trip, up to the cap */
    uint64_t rtt_count;
} pingpong_result;

/* Pop one record, spinning politely; 0 on idle timeout. */
static int pop_wait(sb_ring *r, sb_record *rec, int64_t idle_ns)
{
    unsigned polls = 0;
    int64_t since = 0;
    while (sb_ring_pop(r, rec) != SB_RING_OK) {
        bench_idle(&polls);
        if ((polls & 255u) == 0) {
            int64_t now = sb_monotonic_ns();
            if (!since) since = now;
            else if (now - since > idle_ns) return 0;
        }
    }
    return 1;
}

static void pingpong_initiate(sb_ring *in, sb_ring *out, int64_t run_ns, int64_t idle_ns,
                              pingpong_result *res)
{
    sb_record rec, back;
    int64_t t0 = sb_monotonic_ns(), now = t0;
    uint64_t i = 0;
    while (now - t0 < run_ns) {
        bench_fill(&rec, i);
        int64_t sent = sb_monotonic_ns();
        sb_ring_push(out, &rec, -1);
        if (!pop_wait(in, &back, idle_ns)) {
            res->timed_out = 1;
            break;
        }
        now = sb_monotonic_ns();
        if (!bench_intact(&back) || (uint64_t)back.h.sim_ns != i) res->errors++;
        if (res->rtt_count < BENCH_MAX_RTT_SAMPLES) res->rtt_ns[res->rtt_count++] = now - sent;
        ++i;
    }
    res->round_trips = i;
    res->elapsed_ns = now - t0;
    bench_fill(&rec, i);
    rec.h.flags = BENCH_FLAG_END;
    sb_ring_push(out, &rec, -1);
    if (!res->timed_out && !pop_wait(in, &back, idle_ns)) res->timed_out = 1;
}

static void pingpong_echo(sb_ring *in, sb_ring *out, int64_t idle_ns, pingpong_result *res)
{
    sb_record rec;
    int64_t t0 = sb_monotonic_ns();
    for (;;) {
        if (!pop_wait(in, &rec, idle_ns)) {
            res->timed_out = 1;
            break;
        }
        if (!bench_intact(&rec)) res->errors++;
        sb_ring_push(out, &rec, -1);
        if (rec.h.flags & BENCH_FLAG_END) break;
        res->round_trips++;
    }
    res->elapsed_ns = sb_monotonic_ns() - t0;
}

PyObject *sb_bench_pingpong(PyObject *Py_UNUSED(module), PyObject *args, PyObject *kwargs)
{
    static char *kwlist[] = {"ring_in", "ring_out", "seconds", "idle_timeout_s", NULL};
    PyObject *in_obj, *out_obj;
    double seconds, idle_s = 10.0;
    if (!PyArg_ParseTupleAndKeywords(args, kwargs, "OOd|d", kwlist, &in_obj, &out_obj, &seconds,
                                     &idle_s))
        return NULL;
    RingObject *in, *out;
    if (ring_arg(in_obj, &in) < 0 || ring_arg(out_obj, &out) < 0) return NULL;
    if (in->produces || !out->produces) {
        PyErr_SetString(SB_ERR.role, "ring_in must be consumed and ring_out produced here");
        return NULL;
    }
    pingpong_result res = {0};
    int initiate = seconds > 0.0;
    if (initiate) {
        res.rtt_ns = malloc(BENCH_MAX_RTT_SAMPLES * sizeof(int64_t));
        if (!res.rtt_ns) return PyErr_NoMemory();
    }
    int64_t run_ns = (int64_t)(seconds * 1e9), idle_ns = (int64_t)(idle_s * 1e9);
    Py_BEGIN_ALLOW_THREADS
    if (initiate) pingpong_initiate(in->r, out->r, run_ns, idle_ns, &res);
    else pingpong_echo(in->r, out->r, idle_ns, &res);
    Py_END_ALLOW_THREADS
    PyObject *rtt = PyBytes_FromStringAndSize((const char *)res.rtt_ns,
                                              (Py_ssize_t)(res.rtt_count * sizeof(int64_t)));
    free(res.rtt_ns);
    if (!rtt) return NULL;
    double rate = res.elapsed_ns > 0 ? (double)res.round_trips * 1e9 / (double)res.elapsed_ns
                                     : 0.0;
    return Py_BuildValue("{sKsLsdsKsOsN}", "round_trips", (unsigned long long)res.round_trips,
                         "elapsed_ns", (long long)res.elapsed_ns, "round_trips_per_s", rate,
                         "errors", (unsigned long long)res.errors, "timed_out",
                         res.timed_out ? Py_True : Py_False, "rtt_ns", rtt);
}
