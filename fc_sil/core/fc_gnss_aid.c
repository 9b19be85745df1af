/*
 * fc_gnss_aid.c - the delta-velocity history and the fix comparison of the
 * GNSS-aided acceleration compensation (see fc_gnss_aid.h).
 */
#include "fc_gnss_aid.h"

#include "fc_math.h"

#define SLOT_MASK ((int64_t)(FC_GNSS_AID_SLOTS - 1))
/* Fix intervals outside this range are not compared: shorter ones amplify the
 * velocity noise (it is divided by T), longer ones mean fixes were lost. */
#define FC_GNSS_AID_MIN_DT_NS 20000000LL
#define FC_GNSS_AID_MAX_DT_NS 1000000000LL
/* At least this share of the interval must be in the history (a fix whose
 * epoch is a few samples newer than the last IMU sample is still usable). */
#define FC_GNSS_AID_MIN_COVER 0.8f

_Static_assert((FC_GNSS_AID_SLOTS & (FC_GNSS_AID_SLOTS - 1)) == 0,
               "FC_GNSS_AID_SLOTS must be a power of two");

static float *slot(fc_gnss_aid_t *g, int64_t k)
{
    return g->dv_ned_m_s[k & SLOT_MASK];
}

void fc_gnss_aid_forget_fix(fc_gnss_aid_t *g)
{
    g->have_prev = false;
    g->epoch_prev_ns = 0;
    for (int i = 0; i < 3; i++) {
        g->vel_prev_ned_m_s[i] = 0.0f;
    }
}

void fc_gnss_aid_reset(fc_gnss_aid_t *g)
{
    for (int k = 0; k < FC_GNSS_AID_SLOTS; k++) {
        for (int i = 0; i < 3; i++) {
            g->dv_ned_m_s[k][i] = 0.0f;
        }
    }
    g->newest_slot = 0;
    g->start_ns = 0;
    g->end_ns = 0;
    g->have_history = false;
    fc_gnss_aid_forget_fix(g);
}

/* Make slot k the newest, clearing the slots in between. */
static void advance_to(fc_gnss_aid_t *g, int64_t k)
{
    if (k <= g->newest_slot) {
        return;
    }
    const int64_t n = (k - g->newest_slot < FC_GNSS_AID_SLOTS) ? k - g->newest_slot
                                                                : FC_GNSS_AID_SLOTS;
    for (int64_t j = k - n + 1; j <= k; j++) {
        float *s = slot(g, j);
        s[0] = s[1] = s[2] = 0.0f;
    }
    g->newest_slot = k;
}

void fc_gnss_aid_add_imu(fc_gnss_aid_t *g, int64_t t0_ns, int64_t t1_ns, const float q_wxyz[4],
                         const float accel_frd_m_s2[3])
{
    if (t0_ns < 0 || t1_ns <= t0_ns || !fc_finite3(accel_frd_m_s2)) {
        return;
    }
    /* A gap (time the history has no sample for) restarts the history: a sum
     * over it would read as zero specific force, i.e. free fall. */
    if (!g->have_history || t0_ns != g->end_ns) {
        const int64_t k0 = t0_ns / FC_GNSS_AID_SLOT_NS;
        g->newest_slot = k0 - FC_GNSS_AID_SLOTS; /* advance_to clears every slot */
        advance_to(g, k0);
        g->start_ns = t0_ns;
        g->have_history = true;
    }
    float f_ned[3];
    fc_quat_rotate(q_wxyz, accel_frd_m_s2, f_ned);
    /* Spread the sample's f dt over the slots it covers, by overlap. */
    int64_t a = t0_ns;
    while (a < t1_ns) {
        const int64_t k = a / FC_GNSS_AID_SLOT_NS;
        const int64_t slot_end = (k + 1) * FC_GNSS_AID_SLOT_NS;
        const int64_t b = (t1_ns < slot_end) ? t1_ns : slot_end;
        advance_to(g, k);
        const float part_s = (float)(b - a) * 1e-9f;
        float *s = slot(g, k);
        for (int i = 0; i < 3; i++) {
            s[i] += f_ned[i] * part_s;
        }
        a = b;
    }
    g->end_ns = t1_ns;
    const int64_t oldest_kept = (g->newest_slot - FC_GNSS_AID_SLOTS + 1) * FC_GNSS_AID_SLOT_NS;
    if (g->start_ns < oldest_kept) {
        g->start_ns = oldest_kept;
    }
}

/* Sum of R f dt over [a, b] from the history (partial slots pro rata of the
 * part of the slot that holds data); *covered_s gets the duration summed. */
static void history_sum(fc_gnss_aid_t *g, int64_t a, int64_t b, float out[3], float *covered_s)
{
    out[0] = out[1] = out[2] = 0.0f;
    *covered_s = 0.0f;
    if (a < g->start_ns) {
        a = g->start_ns;
    }
    if (b > g->end_ns) {
        b = g->end_ns;
    }
    if (b <= a) {
        return;
    }
    for (int64_t k = a / FC_GNSS_AID_SLOT_NS; k * FC_GNSS_AID_SLOT_NS < b; k++) {
        const int64_t s0 = k * FC_GNSS_AID_SLOT_NS;
        const int64_t s1 = s0 + FC_GNSS_AID_SLOT_NS;
        const int64_t f0 = (s0 > g->start_ns) ? s0 : g->start_ns; /* filled part */
        const int64_t f1 = (s1 < g->end_ns) ? s1 : g->end_ns;
        const int64_t o0 = (f0 > a) ? f0 : a;                     /* wanted part */
        const int64_t o1 = (f1 < b) ? f1 : b;
        if (o1 <= o0 || f1 <= f0) {
            continue;
        }
        const float share = (float)(o1 - o0) / (float)(f1 - f0);
        const float *s = slot(g, k);
        for (int i = 0; i < 3; i++) {
            out[i] += share * s[i];
        }
        *covered_s += (float)(o1 - o0) * 1e-9f;
    }
}

fc_status_t fc_gnss_aid_fix(fc_gnss_aid_t *g, int64_t epoch_ns, const float vel_ned_m_s[3],
                            float f_imu_ned_m_s2[3], float f_gnss_ned_m_s2[3])
{
    if (!fc_finite3(vel_ned_m_s)) {
        return FC_ERR_NONFINITE;
    }
    const bool had_prev = g->have_prev;
    const int64_t t0 = g->epoch_prev_ns;
    float v0[3] = {g->vel_prev_ned_m_s[0], g->vel_prev_ned_m_s[1], g->vel_prev_ned_m_s[2]};
    g->have_prev = true;
    g->epoch_prev_ns = epoch_ns;
    for (int i = 0; i < 3; i++) {
        g->vel_prev_ned_m_s[i] = vel_ned_m_s[i];
    }
    const int64_t span_ns = epoch_ns - t0;
    if (!had_prev || !g->have_history || span_ns < FC_GNSS_AID_MIN_DT_NS
        || span_ns > FC_GNSS_AID_MAX_DT_NS) {
        return FC_ERR_ARG;
    }
    float dv_imu[3], covered_s;
    history_sum(g, t0, epoch_ns, dv_imu, &covered_s);
    const float span_s = (float)span_ns * 1e-9f;
    if (covered_s < FC_GNSS_AID_MIN_COVER * span_s) {
        return FC_ERR_ARG;
    }
    /* NED gravity is +g down; the specific force is acceleration minus gravity. */
    const float g_ned[3] = {0.0f, 0.0f, FC_GRAVITY_M_S2};
    for (int i = 0; i < 3; i++) {
        f_imu_ned_m_s2[i] = dv_imu[i] / covered_s;
        f_gnss_ned_m_s2[i] = (vel_ned_m_s[i] - v0[i]) / span_s - g_ned[i];
    }
    return FC_OK;
}
