/*
 * sb_pin.h - hold one thread on one CPU while the lockstep hand-off's STACK way of waiting
 * is in use (sb_handoff_choice.h), and give the thread its CPUs back afterwards.
 *
 * Why: the two lockstep processes on two vCPUs of a VM need both vCPUs at once. When the
 * host takes one away now and then, a step waits for it, and a waiter that gave up its
 * spin sleeps on a vCPU that then halts: waking it costs hundreds of microseconds, the
 * other side's spin runs out meanwhile and it sleeps too, and the pair ends up waking each
 * other for every step (measured on the 2-core VM: 10-25x real time in such a run, 70-110x
 * in the runs around it). Both processes on one CPU hand a step over with two context
 * switches inside the guest (a few us each) and need only that one vCPU: about 70x in the
 * same sitting, whatever the other vCPU does.
 *
 * The mask is kept as plain words so that this header does not need _GNU_SOURCE; pin.c
 * checks that a cpu_set_t fits.
 */
#ifndef SB_PIN_H
#define SB_PIN_H

#include <stdint.h>
#include <sys/types.h>

#define SB_PIN_MASK_WORDS 16 /* 1024 CPUs, glibc's cpu_set_t */

typedef struct sb_pin {
    int pinned;  /* 1 while the thread is held on `cpu` */
    int failed;  /* the last attempt was refused (the CPU is not ours): not tried again
                    until released */
    int cpu;     /* the CPU held on (or refused) */
    pid_t tid;   /* the thread held: its CPUs go back to it from whichever thread releases */
    uint64_t allowed[SB_PIN_MASK_WORDS]; /* its CPUs before */
} sb_pin;

/* Hold the calling thread on the CPU it runs on. Returns that CPU, or -1 (not held). */
int sb_pin_here(sb_pin *p);

/* Hold the calling thread on `cpu` (it moves there). 0: held; -1: refused. */
int sb_pin_to(sb_pin *p, int cpu);

/* Give the held thread its CPUs back (nothing if not held). away_from >= 0: first move it
 * off that CPU when it has another, so that two threads that shared it run apart again at
 * once instead of waiting for the scheduler's balancing. */
void sb_pin_release(sb_pin *p, int away_from);

#endif /* SB_PIN_H */
