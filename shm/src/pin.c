/*
 * pin.c - see sb_pin.h. OS-facing: sched_getcpu, sched_{get,set}affinity, gettid.
 */
#define _GNU_SOURCE
#include "sb_pin.h"

#include <sched.h>
#include <string.h>
#include <unistd.h>

_Static_assert(sizeof(cpu_set_t) <= sizeof(((sb_pin *)0)->allowed), "a cpu_set_t fits");

static int hold(sb_pin *p, int cpu)
{
    cpu_set_t before, one;
    pid_t tid = gettid();
    p->failed = 0;
    p->cpu = cpu;
    if (cpu < 0 || cpu >= CPU_SETSIZE || sched_getaffinity(tid, sizeof before, &before) != 0 ||
        !CPU_ISSET(cpu, &before)) {
        p->failed = 1;
        return -1;
    }
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    if (sched_setaffinity(tid, sizeof one, &one) != 0) {
        p->failed = 1;
        return -1;
    }
    memcpy(p->allowed, &before, sizeof before);
    p->tid = tid;
    p->pinned = 1;
    return 0;
}

int sb_pin_here(sb_pin *p)
{
    if (p->pinned) return p->cpu;
    int cpu = sched_getcpu();
    return hold(p, cpu) == 0 ? cpu : -1;
}

int sb_pin_to(sb_pin *p, int cpu)
{
    if (p->pinned && p->cpu == cpu) return 0;
    sb_pin_release(p, -1);
    return hold(p, cpu);
}

void sb_pin_release(sb_pin *p, int away_from)
{
    p->failed = 0;
    if (!p->pinned) return;
    cpu_set_t allowed;
    memcpy(&allowed, p->allowed, sizeof allowed);
    if (away_from >= 0 && away_from < CPU_SETSIZE && CPU_ISSET(away_from, &allowed) &&
        CPU_COUNT(&allowed) > 1) {
        cpu_set_t elsewhere;
        memcpy(&elsewhere, &allowed, sizeof elsewhere);
        CPU_CLR(away_from, &elsewhere);
        (void)sched_setaffinity(p->tid, sizeof elsewhere, &elsewhere);
    }
    (void)sched_setaffinity(p->tid, sizeof allowed, &allowed);
    p->pinned = 0;
}
