"""Lockstep over MAVLink HIL flies the same trajectory as over shared memory: same seed ->
same trace hash (bridge records + the PWM it receives) over shm, udp and tcp, with the FC in
the bridge's process and in its own."""

from __future__ import annotations

import pytest

from silbridge.tools.loop.flight import FlightOptions, fly_one_process, fly_two_processes

# S4: scripted attitude setpoints from the start, so SETPOINT records cross the link too.
_BASE = dict(scenario="S4", duration_s=1.5, seed=11, lockstep=True)


def _fly(transport: str, processes: int) -> dict:
    opts = FlightOptions(transport=transport, processes=processes,
                         instance=f"hiltest-{transport}-{processes}", **_BASE)
    fly = fly_one_process if processes == 1 else fly_two_processes
    return fly(opts, out=lambda line: None)


@pytest.mark.parametrize("processes", [1, 2])
def test_same_trace_hash_over_every_transport(processes):
    runs = {t: _fly(t, processes) for t in ("shm", "udp", "tcp")}
    hashes = {t: r["trace_hash"] for t, r in runs.items()}
    assert len(set(hashes.values())) == 1, hashes
    for t, r in runs.items():
        assert r["rates_hz"]["pwm"] == pytest.approx(400.0, rel=1e-3), t
        assert r["overwritten"] == 0 and r["rejected"] == 0, t
        assert not r["crashed"], t
