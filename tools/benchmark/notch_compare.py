"""Our harmonic notch against ArduCopter's on the same vibrating physics, paired by seed.

The notch of each scenario is the one `silbridge tune notch --scenario V --seed 1` proposes
for our FC (tools/tune/tune_notch_propose.py). ArduCopter 4.6 flies the same physics and seeds
with the same INS_HNTCH_* values twice:

- `ardupilot`: the numbers as they are;
- `ardupilot_ref`: INS_HNTCH_REF in ArduCopter's own throttle unit. Both FCs place the
  throttle notch at FREQ x sqrt(throttle / REF), but the throttle differs: ours is the mixer's
  output as a fraction of the PWM range (the unit of our MOT_THST_HOVER), ArduCopter's is
  `motors->get_throttle_out()`, a fraction of full thrust, which MOT_THST_EXPO maps to PWM
  (thrust = expo t^2 + (1 - expo) t at PWM fraction t). With our REF its notch would sit
  at FREQ x sqrt(thrust(REF) / REF) at hover (67 Hz for the 81 Hz of V2); ArduPilot's docs
  tell a tuner to set REF to the hover thrust (MOT_THST_HOVER), which this row does.

The runs: N seeds per scenario and side, `duration_s` each, scored over WINDOWS. Each call
of `run_seeds` flies a range of seeds and merges its per-run figures into OUT/runs.json, so a
long comparison can be flown in parts (each part under the machine's lock) and judged once.
"""

from __future__ import annotations

import json
import math
import numbers
from pathlib import Path

from silbridge.tools.benchmark.paired_stats import paired, verdict_text
from silbridge.tools.benchmark.table1 import scenario_key
from silbridge.tools.benchmark.table1_compare import BETTER

SIDES = ("ours", "ardupilot", "ardupilot_ref")
DURATION_S = 40.0
# Take-off and settling are over by 20 s for both controllers (ArduCopter climbs the 10 m
# at its 2.5 m/s; ours follows the scenario's scripted take-off); the hover is scored.
WINDOWS = ((0.0, 5.0), (5.0, 20.0), (20.0, 40.0), (30.0, 40.0))
RUNS_FILE = "runs.json"

# What the page compares, in its order: (metric, label, unit, format).
METRICS = (
    ("gyro_noise_dps", "gyro noise after filtering", "deg/s", "{:.3f}"),
    ("pwm_pp_us", "hover PWM p-p", "us", "{:.1f}"),
    ("motor_noise_us", "motor noise", "us", "{:.2f}"),
    ("att_rms_deg", "attitude RMS", "deg", "{:.3f}"),
    ("att_p95_deg", "attitude P95", "deg", "{:.3f}"),
    ("sat_pct", "saturation", "%", "{:.2f}"),
    ("gyro_in_noise_dps", "gyro noise in (the IMU as read)", "deg/s", "{:.2f}"),
)


class NotchCompareError(Exception):
    user_facing = True


def read_parm(path: Path) -> dict:
    """NAME VALUE lines of a .parm file (comments and blank lines skipped)."""
    out = {}
    for line in path.read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if len(words) >= 2:
            value = float(words[1])
            out[words[0]] = int(value) if value.is_integer() else value
    return out


def hover_thrust(pwm_fraction: float, expo: float) -> float:
    """ArduCopter's throttle_out (fraction of full thrust) at a PWM fraction, through
    MOT_THST_EXPO's curve (AP_MotorsMulticopter's thrust linearisation, inverted)."""
    return expo * pwm_fraction ** 2 + (1.0 - expo) * pwm_fraction


def side_params(notch: dict, expo: float) -> dict:
    """{side: FC parameters} for one scenario's notch."""
    ref = float(notch.get("INS_HNTCH_REF", 0.0))
    return {"ours": dict(notch), "ardupilot": dict(notch),
            "ardupilot_ref": {**notch, "INS_HNTCH_REF": round(hover_thrust(ref, expo), 3)}}


def specs_for(scenario: str, params: dict, seeds: range, out: Path, arducopter: str):
    """RunSpecs of one scenario: every side on every seed, logs not kept."""
    from silbridge.tools.benchmark.campaign import make_specs

    specs = []
    for side in SIDES:
        specs += make_specs([scenario], len(seeds), DURATION_S, out, base_seed=seeds.start,
                            params=tuple(sorted(params[side].items())), variant=side,
                            windows=WINDOWS, keep_logs="none",
                            fc="ours" if side == "ours" else "ardupilot", sitl=arducopter)
    return specs


def merge_runs(out: Path, results) -> list[dict]:
    """Add the results' rows to OUT/runs.json (a side, scenario and seed flown again
    replaces its row) and return every row."""
    path = out / RUNS_FILE
    rows = json.loads(path.read_text()) if path.exists() else []
    index = {(r["side"], r["scenario"], r["seed"]): r for r in rows}
    for r in results:
        metrics = {k: float(v) if math.isfinite(v) else None for k, v in r.metrics.items()
                   if isinstance(v, numbers.Real) and not isinstance(v, bool)}
        row = {"side": r.spec.variant, "scenario": scenario_key(r.spec.scenario),
               "seed": int(r.spec.seed), "params": dict(r.spec.params), "metrics": metrics}
        index[(row["side"], row["scenario"], row["seed"])] = row
    rows = sorted(index.values(), key=lambda r: (r["scenario"], r["side"], r["seed"]))
    out.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(rows, indent=1) + "\n")
    return rows


def load_runs(out: Path) -> list[dict]:
    path = out / RUNS_FILE
    if not path.exists():
        raise NotchCompareError(f"{path} is missing: fly the runs first (--run)")
    return json.loads(path.read_text())


def series(rows, side: str, scenario: str, key: str) -> dict:
    """{seed: one side's value of a metric} in one scenario."""
    return {r["seed"]: r["metrics"].get(key) for r in rows
            if r["side"] == side and r["scenario"] == scenario}


def compare(rows: list[dict]) -> dict:
    """{scenario: {other side: {metric: Paired.as_dict() + text}}}, ours - other."""
    out: dict = {}
    for sc in dict.fromkeys(r["scenario"] for r in rows):
        out[sc] = {}
        for side in SIDES[1:]:
            out[sc][side] = {}
            for key, _label, unit, fmt in METRICS:
                p = paired(series(rows, "ours", sc, key), series(rows, side, sc, key),
                           BETTER[key])
                out[sc][side][key] = p.as_dict() | {"text": verdict_text(p, fmt, unit)}
    return out
