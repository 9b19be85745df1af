/*
 * segment.c - create, attach, close and clean up the shared-memory segment
 * (POSIX shm_open + mmap). See sb_segment.h for the protocol; the comments
 * here explain the races each step closes.
 */
#define _GNU_SOURCE /* F_OFD_SETLK / F_OFD_GETLK */
#include "sb_segment.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* A segment found unpublished is assumed to be mid-creation for this long;
 * older than that, its creator died between shm_open and publishing. */
#define SB_SEG_CREATING_GRACE_NS 2000000000LL
#define SB_SEG_CREATE_ATTEMPTS 8

static int64_t clock_ns(clockid_t clk)
{
    struct timespec ts;
    clock_gettime(clk, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

int64_t sb_monotonic_ns(void) { return clock_ns(CLOCK_MONOTONIC); }

static void fnv(uint64_t *h, uint64_t v)
{
    for (int i = 0; i < 8; ++i) {
        *h ^= (v >> (8 * i)) & 0xffu;
        *h *= 1099511628211ull;
    }
}

uint64_t sb_layout_hash(void)
{
    static const uint64_t facts[] = {
        SB_RECORDS_VERSION, SB_RECORD_SIZE, SB_KIND_COUNT, SB_SEG_WORDS, SB_SEG_HEADER_BYTES,
        sizeof(sb_record), sizeof(sb_header), offsetof(sb_header, kind),
        offsetof(sb_header, flags), offsetof(sb_header, seq), offsetof(sb_header, sim_ns),
        offsetof(sb_header, wall_ns), offsetof(sb_record, u),
        offsetof(sb_imu, accel_frd_m_s2), offsetof(sb_imu, gyro_frd_rad_s),
        offsetof(sb_imu, temperature_c), offsetof(sb_imu, sample_index),
        offsetof(sb_imu, samples_per_step), offsetof(sb_baro, pressure_pa),
        offsetof(sb_baro, temperature_c), offsetof(sb_mag, field_frd_gauss),
        offsetof(sb_gnss, lat_e7), offsetof(sb_gnss, lon_e7), offsetof(sb_gnss, alt_mm),
        offsetof(sb_gnss, vel_ned_m_s), offsetof(sb_gnss, eph_cm), offsetof(sb_gnss, epv_cm),
        offsetof(sb_gnss, fix_type), offsetof(sb_gnss, satellites),
        offsetof(sb_gt_att, q_wxyz), offsetof(sb_gt_att, rates_frd_rad_s),
        offsetof(sb_gt_att, specific_force_frd_m_s2), offsetof(sb_gt_nav, pos_ned_m),
        offsetof(sb_gt_nav, vel_ned_m_s), offsetof(sb_gt_nav, on_ground),
        offsetof(sb_pwm, pwm_us), offsetof(sb_pwm, channel_count), offsetof(sb_pwm, armed),
        offsetof(sb_pwm, fc_step_seq), offsetof(sb_pwm, imu_sim_ns),
        offsetof(sb_setpoint, roll_rad), offsetof(sb_setpoint, pitch_rad),
        offsetof(sb_setpoint, yaw_rad), offsetof(sb_setpoint, altitude_m),
        offsetof(sb_setpoint, mask), sizeof(sb_ring_ctl), offsetof(sb_ring_ctl, capacity),
        offsetof(sb_ring_ctl, slots_offset), offsetof(sb_ring_ctl, overwrite),
        offsetof(sb_ring_ctl, stride), offsetof(sb_ring_ctl, head),
        offsetof(sb_ring_ctl, rejected), offsetof(sb_ring_ctl, tail),
        offsetof(sb_ring_ctl, overwritten), sizeof(sb_seg_header),
        offsetof(sb_seg_header, version), offsetof(sb_seg_header, layout_hash),
        offsetof(sb_seg_header, total_bytes), offsetof(sb_seg_header, created_unix_ns),
        offsetof(sb_seg_header, owner_pid), offsetof(sb_seg_header, owner_heartbeat),
        offsetof(sb_seg_header, owner_closed), offsetof(sb_seg_header, peer_heartbeat),
        offsetof(sb_seg_header, peer_attaches), offsetof(sb_seg_header, peer_pid),
        offsetof(sb_seg_header, peer_closed), offsetof(sb_seg_header, words),
        offsetof(sb_seg_header, rings), SB_SEG_TAG_MAX, sizeof(sb_doorbell),
        offsetof(sb_seg_header, bells), offsetof(sb_doorbell, seq),
        offsetof(sb_doorbell, waiters), offsetof(sb_seg_header, owner_tag),
        offsetof(sb_ring_ctl, step_word), offsetof(sb_ring_ctl, sync_word),
        offsetof(sb_seg_header, peer_trouble),
        offsetof(sb_seg_header, handoff_arm), offsetof(sb_seg_header, stack_cpu),
        SB_WORD_OWNER_STEP, SB_WORD_PEER_STEP,
    };
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < sizeof facts / sizeof facts[0]; ++i) fnv(&h, facts[i]);
    return h;
}

static uint64_t page_align(uint64_t n) { return (n + 4095u) & ~(uint64_t)4095u; }

uint64_t sb_segment_bytes(uint64_t sensor_slots, uint64_t actuator_slots)
{
    return SB_SEG_HEADER_BYTES + page_align(sensor_slots * SB_RECORD_SIZE) +
           page_align(actuator_slots * SB_RECORD_SIZE);
}

static int fail(sb_seg_diag *d, int status, const char *what)
{
    d->err_no = errno;
    snprintf(d->what, sizeof d->what, "%s", what);
    return status;
}

static int errno_status(int e)
{
    if (e == ENOENT) return SB_SEG_E_MISSING;
    if (e == EACCES || e == EPERM) return SB_SEG_E_PERM;
    return SB_SEG_E_OS;
}

/* Instance names become file names under /dev/shm: keep them tame. */
static int make_shm_name(char *out, size_t cap, const char *name)
{
    size_t n = strlen(name);
    if (n == 0 || n > SB_SEG_NAME_MAX || name[0] == '.') return -1;
    for (size_t i = 0; i < n; ++i) {
        char c = name[i];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                 c == '_' || c == '-' || c == '.';
        if (!ok) return -1;
    }
    snprintf(out, cap, "%s%s", SB_SEG_PREFIX, name);
    return 0;
}

/* Open-file-description locks belong to the open file, not the process, and
 * vanish when their holder exits (before it is even reaped): exactly "is that
 * side still there?", immune to pid reuse and zombies. The owner locks byte
 * 0 for its life, the attached peer byte 1. */
enum { LOCK_OWNER_BYTE = 0, LOCK_PEER_BYTE = 1 };

static int lock_exclusive(int fd, int byte)
{
    struct flock fl = {.l_type = F_WRLCK, .l_whence = SEEK_SET, .l_start = byte, .l_len = 1};
    return fcntl(fd, F_OFD_SETLK, &fl);
}

static int lock_held_by_other(int fd, int byte)
{
    struct flock fl = {.l_type = F_WRLCK, .l_whence = SEEK_SET, .l_start = byte, .l_len = 1};
    if (fcntl(fd, F_OFD_GETLK, &fl) != 0) return 1; /* cannot tell: assume alive */
    return fl.l_type != F_UNLCK;
}

int sb_pid_alive(int32_t pid)
{
    if (pid <= 0) return 0;
    return kill((pid_t)pid, 0) == 0 || errno == EPERM;
}

static int same_object(const char *shm_name, const struct stat *st)
{
    int fd = shm_open(shm_name, O_RDONLY, 0);
    if (fd < 0) return 0;
    struct stat now;
    int same = fstat(fd, &now) == 0 && now.st_dev == st->st_dev && now.st_ino == st->st_ino;
    close(fd);
    return same;
}

static void read_identity(int fd, const struct stat *st, sb_seg_diag *d, uint64_t *magic)
{
    *magic = 0;
    if ((size_t)st->st_size < sizeof(sb_seg_header)) return;
    sb_seg_header *h = mmap(NULL, sizeof *h, PROT_READ, MAP_SHARED, fd, 0);
    if (h == MAP_FAILED) return;
    *magic = atomic_load_explicit(&h->magic, memory_order_acquire);
    d->found_magic = *magic;
    if (*magic == SB_SEG_MAGIC) d->pid = h->owner_pid;
    munmap(h, sizeof *h);
}

/* The name exists: decide between busy (live owner), mid-creation and
 * stale, and remove it when stale and allowed. Returns SB_SEG_OK when the
 * caller should retry creating. */
static int handle_existing(const char *shm_name, int replace_stale, sb_seg_diag *d)
{
    int fd = shm_open(shm_name, O_RDWR, 0);
    if (fd < 0) return errno == ENOENT ? SB_SEG_OK : fail(d, errno_status(errno), "shm_open");
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int s = fail(d, SB_SEG_E_OS, "fstat");
        close(fd);
        return s;
    }
    uint64_t magic;
    read_identity(fd, &st, d, &magic);
    if (lock_exclusive(fd, LOCK_OWNER_BYTE) != 0) {
        int busy = errno == EAGAIN || errno == EACCES;
        /* Held, but by a process the dead owner forked (it inherited the open
         * file): the owner itself is gone, so the segment is stale. */
        int orphan = busy && magic == SB_SEG_MAGIC && !sb_pid_alive(d->pid);
        if (!orphan) {
            int s = busy ? SB_SEG_E_BUSY : fail(d, SB_SEG_E_OS, "fcntl");
            close(fd);
            return s;
        }
    }
    /* We hold the lock, so no owner does. An unpublished object may still be
     * a creator between shm_open and its own lock: give it a grace period. */
    if (magic != SB_SEG_MAGIC) {
        int64_t age_ns = clock_ns(CLOCK_REALTIME) -
                         ((int64_t)st.st_ctim.tv_sec * 1000000000LL + st.st_ctim.tv_nsec);
        if (magic == 0 && age_ns < SB_SEG_CREATING_GRACE_NS) {
            close(fd);
            return SB_SEG_E_CREATING;
        }
    }
    if (!replace_stale) {
        close(fd);
        return SB_SEG_E_STALE;
    }
    /* Unlink only the object we hold locked, never a successor's. */
    int status = SB_SEG_OK;
    if (same_object(shm_name, &st) && shm_unlink(shm_name) != 0 && errno != ENOENT)
        status = fail(d, errno_status(errno), "shm_unlink");
    close(fd);
    return status;
}

static int map_fd(sb_segment *seg, int fd, size_t size, sb_seg_diag *d)
{
    void *base = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (base == MAP_FAILED) return fail(d, errno_status(errno), "mmap");
    struct stat st;
    fstat(fd, &st);
    seg->base = base;
    seg->hdr = (sb_seg_header *)base;
    seg->size = size;
    seg->fd = fd;
    seg->dev = (uint64_t)st.st_dev;
    seg->ino = (uint64_t)st.st_ino;
    seg->opener_pid = (int32_t)getpid();
    return SB_SEG_OK;
}

static int create_new(sb_segment *seg, int fd, uint64_t sensor_slots, uint64_t actuator_slots,
                      int overwrite, sb_seg_diag *d)
{
    if (lock_exclusive(fd, LOCK_OWNER_BYTE) != 0) return fail(d, SB_SEG_E_BUSY, "fcntl");
    /* The umask must not widen or narrow what we promise: owner rw only. */
    if (fchmod(fd, 0600) != 0) return fail(d, errno_status(errno), "fchmod");
    uint64_t total = sb_segment_bytes(sensor_slots, actuator_slots);
    if (ftruncate(fd, (off_t)total) != 0) return fail(d, errno_status(errno), "ftruncate");
    int s = map_fd(seg, fd, (size_t)total, d);
    if (s != SB_SEG_OK) return s;
    sb_seg_header *h = seg->hdr; /* ftruncate zero-filled it */
    h->version = SB_SEG_VERSION;
    h->header_bytes = SB_SEG_HEADER_BYTES;
    h->layout_hash = sb_layout_hash();
    h->total_bytes = total;
    h->created_unix_ns = clock_ns(CLOCK_REALTIME);
    h->created_mono_ns = clock_ns(CLOCK_MONOTONIC);
    h->owner_pid = (int32_t)getpid();
    const char *tag = getenv(SB_SEG_TAG_ENV);
    if (tag) snprintf(h->owner_tag, sizeof h->owner_tag, "%s", tag);
    uint64_t off = SB_SEG_HEADER_BYTES;
    sb_ring_ctl_init(&h->rings[SB_RING_SENSORS], sensor_slots, off, overwrite);
    off += page_align(sensor_slots * SB_RECORD_SIZE);
    sb_ring_ctl_init(&h->rings[SB_RING_ACTUATORS], actuator_slots, off, overwrite);
    atomic_store_explicit(&h->magic, SB_SEG_MAGIC, memory_order_release);
    seg->is_owner = 1;
    return SB_SEG_OK;
}

int sb_segment_create(sb_segment *seg, const char *name, uint64_t sensor_slots,
                      uint64_t actuator_slots, int overwrite, int replace_stale,
                      sb_seg_diag *diag)
{
    memset(seg, 0, sizeof *seg);
    memset(diag, 0, sizeof *diag);
    seg->fd = -1;
    if (make_shm_name(seg->shm_name, sizeof seg->shm_name, name) != 0) return SB_SEG_E_NAME;
    if (!sb_ring_capacity_ok(sensor_slots) || !sb_ring_capacity_ok(actuator_slots))
        return SB_SEG_E_CONFIG;
    for (int attempt = 0; attempt < SB_SEG_CREATE_ATTEMPTS; ++attempt) {
        int fd = shm_open(seg->shm_name, O_RDWR | O_CREAT | O_EXCL, 0600);
        if (fd >= 0) {
            int s = create_new(seg, fd, sensor_slots, actuator_slots, overwrite, diag);
            if (s == SB_SEG_OK) return s;
            if (seg->base) munmap(seg->base, seg->size);
            seg->base = NULL;
            shm_unlink(seg->shm_name);
            close(fd);
            return s;
        }
        if (errno != EEXIST) return fail(diag, errno_status(errno), "shm_open");
        int s = handle_existing(seg->shm_name, replace_stale, diag);
        if (s != SB_SEG_OK) return s;
    }
    return fail(diag, SB_SEG_E_BUSY, "create (contended)");
}

static int check_identity(const sb_seg_header *h, size_t size, sb_seg_diag *d)
{
    uint64_t magic = atomic_load_explicit(&h->magic, memory_order_acquire);
    d->found_magic = magic;
    if (magic == 0) return SB_SEG_E_CREATING;
    if (magic != SB_SEG_MAGIC) return SB_SEG_E_MAGIC;
    d->found_version = h->version;
    d->found_hash = h->layout_hash;
    d->pid = h->owner_pid;
    if (h->version != SB_SEG_VERSION) return SB_SEG_E_VERSION;
    if (h->layout_hash != sb_layout_hash() || h->total_bytes != size) return SB_SEG_E_LAYOUT;
    return SB_SEG_OK;
}

/* Claim the peer slot: the peer lock decides (a previous peer that exited,
 * even unreaped, has released it); the pid is for messages. A lock still
 * held although the previous peer's pid is gone belongs to a child it forked:
 * that peer is dead, so attach without the lock (liveness then rests on our
 * pid, which sb_segment_peer_alive checks as well). */
static int claim_peer(sb_segment *seg, sb_seg_diag *d)
{
    sb_seg_header *h = seg->hdr;
    int32_t old = atomic_load_explicit(&h->peer_pid, memory_order_acquire);
    if (lock_exclusive(seg->fd, LOCK_PEER_BYTE) != 0) {
        d->pid = old;
        if (errno != EAGAIN && errno != EACCES) return fail(d, SB_SEG_E_OS, "fcntl");
        if (old == 0 || sb_pid_alive(old)) return SB_SEG_E_PEER_BUSY;
    }
    if (!atomic_compare_exchange_strong(&h->peer_pid, &old, (int32_t)getpid())) {
        d->pid = old;
        return SB_SEG_E_PEER_BUSY;
    }
    atomic_store_explicit(&h->peer_closed, 0u, memory_order_release);
    atomic_fetch_add_explicit(&h->peer_attaches, 1u, memory_order_acq_rel);
    return SB_SEG_OK;
}

int sb_segment_attach(sb_segment *seg, const char *name, sb_seg_diag *diag)
{
    memset(seg, 0, sizeof *seg);
    memset(diag, 0, sizeof *diag);
    seg->fd = -1;
    if (make_shm_name(seg->shm_name, sizeof seg->shm_name, name) != 0) return SB_SEG_E_NAME;
    int fd = shm_open(seg->shm_name, O_RDWR, 0);
    if (fd < 0) return fail(diag, errno_status(errno), "shm_open");
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int s = fail(diag, SB_SEG_E_OS, "fstat");
        close(fd);
        return s;
    }
    if ((size_t)st.st_size < sizeof(sb_seg_header)) {
        close(fd);
        return SB_SEG_E_CREATING;
    }
    int s = map_fd(seg, fd, (size_t)st.st_size, diag);
    if (s == SB_SEG_OK) s = check_identity(seg->hdr, seg->size, diag);
    /* The owner's lock alone is not enough: a bridge replacing this stale segment holds
     * its lock for a moment (handle_existing) before unlinking it; its dead owner's pid
     * tells (as sb_segment_owner_alive and the probe do). */
    if (s == SB_SEG_OK && !sb_segment_owner_alive(seg))
        s = SB_SEG_E_STALE;
    if (s == SB_SEG_OK) s = claim_peer(seg, diag);
    if (s != SB_SEG_OK) {
        if (seg->base) munmap(seg->base, seg->size);
        seg->base = NULL;
        seg->hdr = NULL;
        close(fd);
        seg->fd = -1;
    }
    return s;
}

void sb_segment_unlink(const sb_segment *seg)
{
    struct stat st = {0};
    st.st_dev = (dev_t)seg->dev;
    st.st_ino = (ino_t)seg->ino;
    if (seg->is_owner && seg->opener_pid == (int32_t)getpid() && same_object(seg->shm_name, &st))
        shm_unlink(seg->shm_name);
}

void sb_segment_close(sb_segment *seg)
{
    if (!seg->base) return;
    sb_seg_header *h = seg->hdr;
    if (seg->opener_pid != (int32_t)getpid()) {
        /* Inherited across fork: the opener still uses the segment. */
    } else if (seg->is_owner) {
        atomic_store_explicit(&h->owner_closed, 1u, memory_order_release);
    } else if (atomic_load_explicit(&h->peer_pid, memory_order_acquire) == (int32_t)getpid()) {
        atomic_store_explicit(&h->peer_closed, 1u, memory_order_release);
    }
    munmap(seg->base, seg->size);
    close(seg->fd); /* drops the owner's lock */
    seg->base = NULL;
    seg->hdr = NULL;
    seg->fd = -1;
}

int sb_segment_remove_stale(const char *name, sb_seg_diag *diag)
{
    char shm_name[sizeof(SB_SEG_PREFIX) + SB_SEG_NAME_MAX];
    memset(diag, 0, sizeof *diag);
    if (make_shm_name(shm_name, sizeof shm_name, name) != 0) return SB_SEG_E_NAME;
    int fd = shm_open(shm_name, O_RDONLY, 0);
    if (fd < 0) return fail(diag, errno_status(errno), "shm_open");
    close(fd);
    int s = handle_existing(shm_name, 1, diag);
    return s;
}

int sb_segment_owner_alive(const sb_segment *seg)
{
    if (!seg->base) return 0;
    if (atomic_load_explicit(&seg->hdr->owner_closed, memory_order_acquire)) return 0;
    if (seg->is_owner) return 1;
    return sb_pid_alive(seg->hdr->owner_pid) && lock_held_by_other(seg->fd, LOCK_OWNER_BYTE);
}

int sb_segment_peer_alive(const sb_segment *seg)
{
    if (!seg->base) return 0;
    const sb_seg_header *h = seg->hdr;
    int32_t pid = atomic_load_explicit(&h->peer_pid, memory_order_acquire);
    if (pid == 0 || atomic_load_explicit(&h->peer_closed, memory_order_acquire)) return 0;
    if (!seg->is_owner) return 1;
    return sb_pid_alive(pid) && lock_held_by_other(seg->fd, LOCK_PEER_BYTE);
}

int sb_segment_probe(const char *name, sb_seg_probe *out, sb_seg_diag *diag)
{
    char shm_name[sizeof(SB_SEG_PREFIX) + SB_SEG_NAME_MAX];
    memset(out, 0, sizeof *out);
    memset(diag, 0, sizeof *diag);
    if (make_shm_name(shm_name, sizeof shm_name, name) != 0) return SB_SEG_E_NAME;
    int fd = shm_open(shm_name, O_RDONLY, 0);
    if (fd < 0) return fail(diag, errno_status(errno), "shm_open");
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int s = fail(diag, SB_SEG_E_OS, "fstat");
        close(fd);
        return s;
    }
    out->bytes = (uint64_t)st.st_size;
    /* The identity line and the owner line are where they were in version 1 too. */
    if ((size_t)st.st_size >= sizeof(sb_seg_header)) {
        sb_seg_header *h = mmap(NULL, sizeof *h, PROT_READ, MAP_SHARED, fd, 0);
        if (h != MAP_FAILED) {
            out->published = atomic_load_explicit(&h->magic, memory_order_acquire) ==
                             SB_SEG_MAGIC;
            if (out->published) {
                out->version = h->version;
                out->owner_pid = h->owner_pid;
                out->created_unix_ns = h->created_unix_ns;
                if (h->version >= 2) {
                    memcpy(out->tag, h->owner_tag, sizeof out->tag);
                    out->tag[sizeof out->tag - 1] = 0;
                }
                out->owner_alive =
                    !atomic_load_explicit(&h->owner_closed, memory_order_acquire) &&
                    lock_held_by_other(fd, LOCK_OWNER_BYTE) && sb_pid_alive(h->owner_pid);
            }
            munmap(h, sizeof *h);
        }
    }
    if (!out->published) {
        /* Mid-creation (young) or a creator that died before publishing (old). */
        int64_t age_ns = clock_ns(CLOCK_REALTIME) -
                         ((int64_t)st.st_ctim.tv_sec * 1000000000LL + st.st_ctim.tv_nsec);
        out->owner_alive = age_ns < SB_SEG_CREATING_GRACE_NS || lock_held_by_other(fd, 0);
        out->created_unix_ns = (int64_t)st.st_ctim.tv_sec * 1000000000LL + st.st_ctim.tv_nsec;
    }
    close(fd);
    return SB_SEG_OK;
}
