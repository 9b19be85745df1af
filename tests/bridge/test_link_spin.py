"""When a foreign autopilot's lockstep link spins, and that the spin gives up.

bridge/link_spin.py: a campaign spins only when each concurrent run (autopilot plus
server) has two cores; a spin returns what the poll found, or None once its budget is
spent, so a silent peer is still slept on and timed out as before.
"""

from __future__ import annotations

import time

from silbridge.bridge import link_spin


def test_spin_only_where_every_run_has_two_cores(monkeypatch):
    monkeypatch.setattr(link_spin, "usable_cores", lambda: 2)
    assert link_spin.spin_budget_us(1) == link_spin.SPIN_US
    assert link_spin.spin_budget_us(2) == 0.0
    monkeypatch.setattr(link_spin, "usable_cores", lambda: 8)
    assert link_spin.spin_budget_us(4) == link_spin.SPIN_US
    assert link_spin.spin_budget_us(5) == 0.0
    monkeypatch.setattr(link_spin, "usable_cores", lambda: 1)
    assert link_spin.spin_budget_us(1) == 0.0


def test_spin_returns_what_came_or_gives_up():
    calls = []

    def late():
        calls.append(1)
        return "reply" if len(calls) == 50 else None

    assert link_spin.spin_poll(late, 1_000_000_000) == "reply" and len(calls) == 50
    t0 = time.monotonic_ns()
    assert link_spin.spin_poll(lambda: None, 2_000_000) is None
    assert time.monotonic_ns() - t0 >= 2_000_000
    calls.clear()
    assert link_spin.spin_poll(late, 0) is None and len(calls) == 1    # 0: one poll, no spin


def test_a_campaign_hands_the_spin_to_foreign_autopilot_runs_only(monkeypatch, tmp_path):
    from silbridge.tools.benchmark import campaign

    seen = []
    monkeypatch.setattr(campaign, "run_one", lambda spec: seen.append(spec) or
                        campaign.RunResult(spec=spec))
    specs = (campaign.make_specs(["S1"], 1, 10.0, tmp_path, fc="ardupilot")
             + campaign.make_specs(["S1"], 1, 10.0, tmp_path, fc="ours"))
    for cores, want in ((2, link_spin.SPIN_US), (1, 0.0)):
        seen.clear()
        monkeypatch.setattr(link_spin, "usable_cores", lambda: cores)
        campaign.run_campaign(specs, jobs=1, progress=False)
        assert [(s.fc, s.link_spin_us) for s in seen] == [("ardupilot", want), ("ours", 0.0)]
