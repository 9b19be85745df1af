"""Comparisons that hold up: paired by seed, medians, a bootstrap interval, one verdict rule.

Every comparison of two controllers (Table 1's ours against ArduCopter or PX4, the nav
suite's) goes through `paired()`, so the rule that decides what a table may claim exists once.

Why paired: run i of every controller flies seed + i, the same wind, turbulence, vibration
and sensor-noise draws. The difference a - b on one seed cancels what that seed makes hard
for both, which is most of the spread between runs.
Why medians: per-run metrics are skewed. ArduCopter's hover p-p was 8.6 +- 9.4 us over 20
runs but 4.0 us in most: a few bad runs move a mean, and a comparison of means claimed a
win that the typical run did not show.

Method (constants below, declared once):
- pairs: the seeds with a finite value on both sides, in seed order (so the result does not
  depend on the order runs finished in); a seed with a value on one side only is listed in
  `unpaired_a` / `unpaired_b`, never dropped silently;
- d = a - b per pair; `median_a`, `median_b` are the medians over the paired seeds, `median_diff`
  the median of d;
- its 95 % interval: percentile bootstrap, RESAMPLES resamples of the n pairs with
  replacement, numpy's default_rng(RNG_SEED) started afresh for every comparison (the same
  data give the same interval, whatever else was compared before); the 2.5th and 97.5th
  percentiles (numpy's linear interpolation) of the resampled medians;
- verdict, for a metric where lower is better ("higher": signs flipped first):
    interval's upper end <= 0     "at or below" ("at or above" when higher is better)
    interval's lower end > 0      "loses by X", X = |median of d|
    otherwise                     "tie"
  with fewer than MIN_PAIRS pairs: "too few pairs". Five is the least n at which a
  unanimous sample is itself evidence: all of 4 differences share a sign by chance with
  probability 1/16 (above 5 %), all of 5 with 1/32;
  better=None (a metric with no better direction): "not judged", the figures only.
"""

from __future__ import annotations

import dataclasses
import math
import numbers

import numpy as np

RESAMPLES = 10_000
RNG_SEED = 27           # fixed: a table rebuilt from the same runs says the same thing
LEVEL = 0.95
MIN_PAIRS = 5

AT_OR_BELOW, TIE, LOSES, TOO_FEW, NO_PAIRS, NO_VERDICT = (
    "at_or_below", "tie", "loses", "too_few", "no_pairs", "none")


@dataclasses.dataclass(frozen=True)
class Paired:
    """One comparison of a against b (a - b), paired by seed."""

    n: int
    median_a: float | None
    median_b: float | None
    median_diff: float | None
    ci_low: float | None
    ci_high: float | None
    verdict: str                     # one of AT_OR_BELOW ... NO_VERDICT
    better: str | None               # "lower", "higher" or None
    unpaired_a: tuple = ()           # seeds with a finite value for a only
    unpaired_b: tuple = ()

    def as_dict(self) -> dict:
        """JSON form: ci95 [low, high] in place of ci_low, ci_high; seed lists."""
        d = dataclasses.asdict(self)
        d["ci95"] = None if self.ci_low is None else [self.ci_low, self.ci_high]
        del d["ci_low"], d["ci_high"]
        d["unpaired_a"], d["unpaired_b"] = list(self.unpaired_a), list(self.unpaired_b)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Paired":
        """Back from as_dict() (extra keys such as a table's "text" are ignored)."""
        lo, hi = d["ci95"] or (None, None)
        return cls(d["n"], d["median_a"], d["median_b"], d["median_diff"], lo, hi,
                   d["verdict"], d["better"], tuple(d["unpaired_a"]), tuple(d["unpaired_b"]))


def _finite(values: dict) -> dict:
    return {int(s): float(v) for s, v in values.items()
            if v is not None and isinstance(v, numbers.Real) and math.isfinite(v)}


def bootstrap_median_ci(d: np.ndarray, resamples: int = RESAMPLES, seed: int = RNG_SEED,
                        level: float = LEVEL) -> tuple[float, float]:
    """Percentile bootstrap interval of the median of d (see the module text)."""
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, len(d), size=(resamples, len(d)))
    medians = np.median(d[idx], axis=1)
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(medians, [tail, 100.0 - tail])
    return float(lo), float(hi)


def _verdict(n: int, lo: float, hi: float, better: str | None) -> str:
    if better is None:
        return NO_VERDICT
    if n < MIN_PAIRS:
        return TOO_FEW
    if better == "higher":      # "at least as good" means a - b >= 0: flip to the lower case
        lo, hi = -hi, -lo
    if hi <= 0.0:
        return AT_OR_BELOW
    if lo > 0.0:
        return LOSES
    return TIE


def paired(a: dict, b: dict, better: str | None = "lower") -> Paired:
    """a, b: {seed: value}; non-finite values count as missing. better: "lower", "higher"
    or None."""
    if better not in ("lower", "higher", None):
        raise ValueError(f"better must be 'lower', 'higher' or None, not {better!r}")
    a, b = _finite(a), _finite(b)
    seeds = sorted(set(a) & set(b))
    only_a = tuple(sorted(set(a) - set(b)))
    only_b = tuple(sorted(set(b) - set(a)))
    if not seeds:
        return Paired(0, None, None, None, None, None, NO_PAIRS, better, only_a, only_b)
    va = np.array([a[s] for s in seeds])
    vb = np.array([b[s] for s in seeds])
    d = va - vb
    lo, hi = bootstrap_median_ci(d)
    return Paired(n=len(seeds), median_a=float(np.median(va)), median_b=float(np.median(vb)),
                  median_diff=float(np.median(d)), ci_low=lo, ci_high=hi,
                  verdict=_verdict(len(seeds), lo, hi, better), better=better,
                  unpaired_a=only_a, unpaired_b=only_b)


def _num(fmt: str, v: float) -> str:
    text = fmt.format(v)
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def verdict_text(p: Paired, fmt: str = "{:.3g}", unit: str = "") -> str:
    """The words a table prints for p's verdict."""
    if p.verdict == AT_OR_BELOW:
        return "at or above" if p.better == "higher" else "at or below"
    if p.verdict == LOSES:
        return f"loses by {_num(fmt, abs(p.median_diff))}" + (f" {unit}" if unit else "")
    return {TIE: "tie", TOO_FEW: f"too few pairs ({p.n} < {MIN_PAIRS})",
            NO_PAIRS: "n/a", NO_VERDICT: "not judged"}[p.verdict]


def diff_text(p: Paired, fmt: str = "{:.3g}") -> str:
    """'median [low, high]' of the paired difference, or n/a."""
    if p.median_diff is None:
        return "n/a"
    return f"{_num(fmt, p.median_diff)} [{_num(fmt, p.ci_low)}, {_num(fmt, p.ci_high)}]"


def header(a: str, b: str) -> list[str]:
    """The column heads of `cells`."""
    return [f"{a} median", f"{b} median", f"{a} - {b}: median [95 % CI]", "pairs", "verdict"]


def cells(p: Paired, fmt: str = "{:.3g}", unit: str = "") -> list[str]:
    """One table row's cells for p, in the order of `header`."""
    med = ["n/a" if v is None else _num(fmt, v) for v in (p.median_a, p.median_b)]
    return med + [diff_text(p, fmt), str(p.n), verdict_text(p, fmt, unit)]


def method_dict() -> dict:
    """The declared method, for the JSON beside a table."""
    return {"pairing": "seed", "statistic": "median", "interval": "percentile bootstrap",
            "level": LEVEL, "resamples": RESAMPLES, "rng_seed": RNG_SEED,
            "min_pairs": MIN_PAIRS, "difference": "a - b"}


def method_line(a: str = "ours", b: str = "theirs") -> str:
    """One sentence for under a table: how its verdicts were reached."""
    return (f"Paired by seed: {a} - {b} per seed; median and its {LEVEL:.0%} percentile "
            f"bootstrap interval ({RESAMPLES:,} resamples, fixed RNG seed {RNG_SEED}). "
            f"\"at or below\" only when the interval's upper end is at or below 0, \"loses "
            f"by X\" when its lower end is above 0, else \"tie\"; fewer than {MIN_PAIRS} "
            f"pairs: no verdict.")
