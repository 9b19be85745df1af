/*
 * handoff_choice.c - the lockstep hand-off's way of waiting, chosen by measuring
 * (sb_handoff_choice.h says why and how). Pure C: no OS calls, no globals.
 */
#include "sb_handoff_choice.h"

#include <string.h>

int64_t sb_handoff_spin_ns(int arm, int is_owner)
{
    if (arm == SB_ARM_SPIN) return SB_SPIN_LONG_NS;
    if (arm == SB_ARM_BRIEF && is_owner) return SB_SPIN_BRIEF_NS;
    return 0;
}

void sb_choice_init(sb_handoff_choice *c, int64_t now_ns, int forced)
{
    memset(c, 0, sizeof *c);
    c->forced = forced >= 0 && forced < SB_ARM_COUNT ? forced : -1;
    c->arm = c->forced >= 0 ? c->forced : SB_ARM_SPIN;
    c->home = -1;
    c->next_probe_arm = SB_ARM_STACK; /* the first probe: the way that needs one CPU only */
    c->last_probe = -1;
    c->recheck = -1;
    c->win_start_ns = now_ns;
    c->probe_gap_ns = SB_PROBE_GAP_MIN_NS;
    c->next_probe_ns = now_ns;
}

/* The arm the next probe measures: the home a probe just replaced, else SPIN every other
 * time while away from it, else the other arms in turn. */
static int probe_arm(sb_handoff_choice *c)
{
    int p;
    if (c->recheck >= 0) {
        p = c->recheck;
        c->recheck = -1;
    } else if (c->arm != SB_ARM_SPIN && c->last_probe != SB_ARM_SPIN) {
        p = SB_ARM_SPIN;
    } else {
        p = c->next_probe_arm;
        while (p == c->arm || (p == SB_ARM_SPIN && c->arm != SB_ARM_SPIN))
            p = (p + 1) % SB_ARM_COUNT;
        c->next_probe_arm = (p + 1) % SB_ARM_COUNT;
    }
    c->last_probe = p;
    return p;
}

/* A probe's window closed: keep the probed arm if it clearly beat the one before it. */
static void end_probe(sb_handoff_choice *c, int64_t now_ns)
{
    int probed = c->arm, home = c->home;
    c->home = -1;
    int gain_pct = home == SB_ARM_SPIN ? SB_LEAVE_SPIN_PCT : SB_SWITCH_GAIN_PCT;
    if (c->cost_ns[probed] * 100 < c->cost_ns[home] * gain_pct) {
        /* Conditions changed, or the home's last window was a bad one (a neighbour's
         * burst): measure the old home again after one window of the new arm. */
        c->switches++;
        c->probe_gap_ns = SB_PROBE_GAP_MIN_NS;
        c->recheck = home;
        c->next_probe_ns = now_ns;
        return;
    }
    c->arm = home;
    c->probe_gap_ns *= 2;
    if (c->probe_gap_ns > SB_PROBE_GAP_MAX_NS) c->probe_gap_ns = SB_PROBE_GAP_MAX_NS;
    c->next_probe_ns = now_ns + c->probe_gap_ns;
}

/* A window of the arm in use closed: measure another arm now? SPIN is left alone while
 * its spins end with data; the others are questioned after the gap, or sooner when the
 * window turned much slower than the one before (the load changed). */
static int want_probe(const sb_handoff_choice *c, int64_t now_ns, int64_t cost, int64_t prev,
                      uint64_t steps, uint64_t trouble)
{
    int slowed = prev > 0 && cost * 100 > prev * SB_SLOWDOWN_PCT;
    int due = now_ns >= c->next_probe_ns;
    int soon = now_ns >= c->next_probe_ns - c->probe_gap_ns + SB_PROBE_GAP_MIN_NS;
    if (c->arm == SB_ARM_SPIN && trouble * SB_TROUBLE_SHARE <= steps) return 0;
    return due || (slowed && soon);
}

static int close_window(sb_handoff_choice *c, int64_t now_ns, uint64_t trouble)
{
    int64_t span = now_ns - c->win_start_ns;
    uint64_t steps = c->win_steps, trouble_n = trouble - c->win_trouble0;
    int64_t cost = span / (int64_t)steps, prev = c->cost_ns[c->arm];
    c->cost_ns[c->arm] = cost > 0 ? cost : 1;
    c->windows++;
    c->win_start_ns = now_ns;
    c->win_steps = 0;
    c->win_trouble0 = trouble;
    if (c->home >= 0) {
        end_probe(c, now_ns);
    } else if (want_probe(c, now_ns, cost, prev, steps, trouble_n)) {
        c->home = c->arm;
        c->arm = probe_arm(c);
        c->probes++;
    }
    return c->arm;
}

int sb_choice_step(sb_handoff_choice *c, int64_t now_ns, uint64_t trouble)
{
    if (c->forced >= 0) return c->forced;
    if (c->windows == 0 && c->win_steps == 0) c->win_trouble0 = trouble;
    c->win_steps++;
    int64_t span = now_ns - c->win_start_ns;
    int full = c->win_steps >= SB_WINDOW_MIN_STEPS && span >= SB_WINDOW_MIN_NS;
    return full ? close_window(c, now_ns, trouble) : c->arm;
}
