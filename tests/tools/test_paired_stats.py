"""The one verdict rule of every cross-controller comparison (tools/benchmark/paired_stats.py),
on constructed per-seed data whose answer is known: a clear win, a tie, a loss, pairing by
seed, unpaired seeds reported, and a bootstrap that gives the same interval every time."""

import numpy as np
import pytest

from silbridge.tools.benchmark import paired_stats as ps
from silbridge.tools.benchmark.paired_stats import paired, verdict_text

SEEDS = range(1, 13)


def _noise(scale: float, seed: int = 5) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, scale, len(SEEDS))


def test_a_clear_win_is_at_or_below():
    theirs = {s: 10.0 + 3.0 * k for k, s in enumerate(SEEDS)}       # seeds differ a lot
    ours = {s: v - 1.0 + e for (s, v), e in zip(theirs.items(), _noise(0.1))}
    p = paired(ours, theirs)
    assert p.verdict == ps.AT_OR_BELOW and verdict_text(p) == "at or below"
    assert p.n == 12 and p.ci_high <= 0.0
    assert p.median_diff == pytest.approx(-1.0, abs=0.1)


def test_a_spread_of_wins_and_losses_is_a_tie():
    theirs = {s: 5.0 for s in SEEDS}
    ours = {s: 5.0 + d for s, d in zip(SEEDS, [1, -1] * 6)}
    p = paired(ours, theirs)
    assert p.verdict == ps.TIE and verdict_text(p) == "tie"
    assert p.ci_low < 0.0 < p.ci_high


def test_a_clear_loss_says_by_how_much():
    theirs = {s: 4.0 for s in SEEDS}
    ours = {s: 5.2 + e for s, e in zip(SEEDS, _noise(0.05))}
    p = paired(ours, theirs)
    assert p.verdict == ps.LOSES and p.ci_low > 0.0
    assert verdict_text(p, "{:.1f}", "us") == "loses by 1.2 us"


def test_a_mean_that_favours_ours_is_not_a_win_when_the_typical_run_loses():
    # The case: their mean is pulled up by two bad seeds, their typical run is lower.
    theirs = {s: 4.0 for s in SEEDS} | {3: 40.0, 9: 35.0}
    ours = {s: 5.2 for s in SEEDS}
    assert np.mean(list(ours.values())) < np.mean(list(theirs.values()))
    assert paired(ours, theirs).verdict == ps.LOSES


def test_pairing_is_by_seed_not_by_position():
    # Same values, listed in different orders: paired by seed they are equal seed for seed.
    ours = {s: float(s) for s in SEEDS}
    theirs = {s: float(s) for s in reversed(SEEDS)}
    p = paired(ours, theirs)
    assert p.median_diff == 0.0 and (p.ci_low, p.ci_high) == (0.0, 0.0)
    assert p.verdict == ps.AT_OR_BELOW


def test_unpaired_seeds_are_reported_not_dropped_silently():
    ours = {s: 1.0 for s in SEEDS} | {13: 1.0}
    theirs = {s: 2.0 for s in SEEDS if s != 4} | {4: float("nan"), 20: 2.0}
    p = paired(ours, theirs)
    assert p.n == 11
    assert p.unpaired_a == (4, 13) and p.unpaired_b == (20,)
    d = p.as_dict()
    assert d["unpaired_a"] == [4, 13] and d["unpaired_b"] == [20] and len(d["ci95"]) == 2


def test_too_few_pairs_make_no_claim():
    p = paired({1: 1.0, 2: 1.0, 3: 1.0, 4: 1.0}, {1: 2.0, 2: 2.0, 3: 2.0, 4: 2.0})
    assert p.verdict == ps.TOO_FEW and "too few pairs" in verdict_text(p)
    assert paired({1: 1.0}, {2: 1.0}).verdict == ps.NO_PAIRS


def test_higher_is_better_flips_the_rule():
    theirs = {s: 50.0 for s in SEEDS}
    faster = {s: 80.0 + e for s, e in zip(SEEDS, _noise(1.0))}
    assert verdict_text(paired(faster, theirs, "higher")) == "at or above"
    assert paired(theirs, faster, "higher").verdict == ps.LOSES
    assert paired(faster, theirs, None).verdict == ps.NO_VERDICT


def test_the_bootstrap_is_deterministic_and_order_free():
    ours = {s: v for s, v in zip(SEEDS, _noise(1.0, seed=1))}
    theirs = {s: v for s, v in zip(SEEDS, _noise(1.0, seed=2))}
    first = paired(ours, theirs)
    np.random.seed(123)                                  # global RNG state must not matter
    again = paired(dict(reversed(list(ours.items()))), theirs)
    assert (first.ci_low, first.ci_high) == (again.ci_low, again.ci_high)
    d = np.array([ours[s] - theirs[s] for s in SEEDS])
    assert ps.bootstrap_median_ci(d) == (first.ci_low, first.ci_high)
    assert first.ci_low <= first.median_diff <= first.ci_high
    assert ps.method_dict()["resamples"] == ps.RESAMPLES == 10_000
