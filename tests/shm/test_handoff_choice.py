"""The lockstep hand-off's way of waiting (shm/include/sb_handoff_choice.h), driven with
made-up clocks: a model machine says what a step costs with each way of waiting and how
often a spin runs out or loses its core, and the choice must keep to the fastest way, leave
spinning when load arrives, come back when it leaves, and not keep paying for its probes.

The model's figures are of the kind measured on the 2-core VM (C ping-pong, 8 + 2 us of
work a step): idle, spinning ~11 us a step and blocking ~70 (a futex wake of an idle core);
under a busy loop spinning costs hundreds of us a step and blocking ~16. STACK (both sides on
one CPU, sb_pin.h) costs the work and two context switches wherever it runs. HOST is the VM
whose host takes a vCPU away now and then (measured in 20 s flights of S1: 10-15x real time
instead of 70-110x, every way across two vCPUs slow, both processes on one vCPU ~70x).
"""

from __future__ import annotations

import pytest

from handoff_cffi import ffi, lib

SPIN, BRIEF, BLOCK, STACK = lib.SB_ARM_SPIN, lib.SB_ARM_BRIEF, lib.SB_ARM_BLOCK, lib.SB_ARM_STACK
US, MS = 1_000, 1_000_000

IDLE = {SPIN: 11 * US, BRIEF: 40 * US, BLOCK: 70 * US, STACK: 13 * US}
BUSY = {SPIN: 500 * US, BRIEF: 20 * US, BLOCK: 16 * US, STACK: 13 * US}
# A busy loop on each core: STACK shares one with a busy loop, blocking keeps both.
BUSY2 = {SPIN: 500 * US, BRIEF: 24 * US, BLOCK: 16 * US, STACK: 26 * US}
HOST = {SPIN: 1_200 * US, BRIEF: 250 * US, BLOCK: 240 * US, STACK: 15 * US}


class Machine:
    """Made-up wall clock and trouble count; `cost` per arm, `trouble_every`: one spin in
    this many runs out or is preempted while SPIN is in use (0: never)."""

    def __init__(self, forced: int = -1):
        self.c = ffi.new("sb_handoff_choice *")
        self.now = 0
        self.trouble = 0
        self.arm = None
        lib.sb_choice_init(self.c, self.now, forced)
        self.arm = self.c.arm
        self.steps_on = {SPIN: 0, BRIEF: 0, BLOCK: 0, STACK: 0}

    def run(self, cost: dict, duration_ns: int, trouble_every: int = 0) -> None:
        end = self.now + duration_ns
        while self.now < end:
            self.now += cost[self.arm]
            self.steps_on[self.arm] += 1
            if self.arm == SPIN and trouble_every and self.steps_on[SPIN] % trouble_every == 0:
                self.trouble += 1
            self.arm = lib.sb_choice_step(self.c, self.now, self.trouble)


def test_an_idle_machine_spins_and_never_probes():
    m = Machine()
    m.run(IDLE, 2_000 * MS)
    assert m.arm == SPIN
    assert m.c.probes == 0 and m.steps_on[BLOCK] == m.steps_on[BRIEF] == m.steps_on[STACK] == 0


def test_rare_trouble_while_spinning_is_not_load():
    m = Machine()
    m.run(IDLE, 2_000 * MS, trouble_every=lib.SB_TROUBLE_SHARE * 4)
    assert m.arm == SPIN and m.c.probes == 0


def test_load_arriving_moves_off_spinning_within_a_few_windows():
    m = Machine()
    m.run(IDLE, 100 * MS)
    spin_before = m.steps_on[SPIN]
    m.run(BUSY, 20 * MS, trouble_every=1)
    assert m.arm != SPIN
    # Spinning under load lasted a window or so, not the 20 ms.
    assert (m.steps_on[SPIN] - spin_before) * BUSY[SPIN] < 10 * MS
    m.run(BUSY, 200 * MS, trouble_every=1)
    assert m.arm == STACK            # the cheapest way under this load


def test_two_busy_loops_keep_blocking_across_both_cores():
    m = Machine()
    m.run(BUSY2, 1_000 * MS, trouble_every=1)
    assert m.arm == BLOCK


def test_a_host_that_takes_vcpus_away_moves_both_sides_onto_one_cpu_at_once():
    m = Machine()
    m.run(IDLE, 100 * MS)
    m.run(HOST, 50 * MS, trouble_every=1)
    # The first probe is STACK, and it wins: a window of SPIN (8 steps), one of STACK, the
    # recheck of SPIN, and STACK holds. Neither of the other ways was tried.
    assert m.arm == STACK and m.steps_on[BRIEF] == m.steps_on[BLOCK] == 0
    spin_before = m.steps_on[SPIN]
    m.run(HOST, 2_000 * MS, trouble_every=1)
    assert m.arm == STACK
    # What the SPIN probes cost: a window each, the gaps doubling to 200 ms.
    spin_time = (m.steps_on[SPIN] - spin_before) * HOST[SPIN]
    assert spin_time < 0.1 * 2_000 * MS, (m.steps_on, m.c.probes)


def test_lasting_load_probes_spinning_ever_more_rarely():
    m = Machine()
    m.run(BUSY, 10_000 * MS, trouble_every=1)
    assert m.arm == STACK
    # Time lost to SPIN probes: a window each, the gaps doubling from 25 ms to 200 ms.
    spin_time = m.steps_on[SPIN] * BUSY[SPIN]
    assert spin_time < 0.02 * 10_000 * MS, (m.steps_on, m.c.probes)
    probes_late = m.c.probes
    m.run(BUSY, 10_000 * MS, trouble_every=1)
    assert m.c.probes - probes_late <= 2 * (10_000 * MS // lib.SB_PROBE_GAP_MAX_NS) + 2


def test_load_leaving_brings_spinning_back():
    m = Machine()
    m.run(BUSY2, 3_000 * MS, trouble_every=1)
    assert m.arm == BLOCK
    m.run(IDLE, 100 * MS)
    # Blocking turned much slower: the probes came at once, not after the 200 ms gap.
    assert m.arm == SPIN


def test_load_leaving_brings_spinning_back_from_one_cpu_within_the_longest_gap():
    # STACK costs the same with the load gone, so no slowdown calls the probe early: SPIN
    # is measured again when the gap (200 ms at most) has passed, and wins.
    m = Machine()
    m.run(BUSY, 3_000 * MS, trouble_every=1)
    assert m.arm == STACK
    m.run(IDLE, lib.SB_PROBE_GAP_MAX_NS + 20 * MS)
    assert m.arm == SPIN


def test_a_forced_way_is_kept_whatever_it_costs():
    m = Machine(forced=BLOCK)
    m.run(IDLE, 500 * MS)
    assert m.arm == BLOCK and m.c.probes == 0 and m.steps_on[SPIN] == 0


@pytest.mark.parametrize("arm, owner, spins", [(SPIN, 1, True), (SPIN, 0, True),
                                                (BRIEF, 1, True), (BRIEF, 0, False),
                                                (BLOCK, 1, False), (BLOCK, 0, False),
                                                (STACK, 1, False), (STACK, 0, False)])
def test_spin_budgets(arm, owner, spins):
    # BRIEF: only the owner spins (the FC's answer is quick; the bridge's step is not).
    assert (lib.sb_handoff_spin_ns(arm, owner) > 0) == spins
