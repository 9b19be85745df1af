"""GNSS fixes released by the kernel (Kernel.hold, sensor_stage.c sb_held) against their
release in Python: the same records, byte for byte, at the same steps; a step that only
releases a fix then needs no Python, so a lockstep batch runs on through it."""

from __future__ import annotations

import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind


def _records(hold: bool, steps: int, overrides=None) -> list[bytes]:
    sim = Simulator(load_scenario("S1", overrides=overrides))
    sim._hold_gnss = hold
    pwm = (sim.hover_pwm_us + 20.0,) * 4
    return [bytes(sim.step(pwm)) for _ in range(steps)]


@pytest.mark.parametrize("latency_s, steps", [
    (None, 1500),    # the default 110 ms: a fix is held across the next epoch
    (1.5, 3500),     # 15 fixes under way: more than the kernel holds, the rest wait in Python
])
def test_fixes_the_kernel_releases_are_the_ones_python_released(latency_s, steps):
    over = None if latency_s is None else {"gnss.latency_s": latency_s}
    held, python = _records(True, steps, over), _records(False, steps, over)
    gnss = sum(int.from_bytes(r[i:i + 2], "little") == Kind.GNSS
               for r in python for i in range(0, len(r), 64))
    assert gnss >= 10
    assert held == python


def test_hold_refuses_a_wrong_size_and_a_full_queue():
    sim = Simulator(load_scenario("S1"))
    with pytest.raises(ValueError):
        sim.kernel.hold(10**9, bytes(63))
    for i in range(8):
        sim.kernel.hold(10**9 + i, bytes(64))
    assert sim.kernel.held == 8
    with pytest.raises(RuntimeError):
        sim.kernel.hold(2 * 10**9, bytes(64))
