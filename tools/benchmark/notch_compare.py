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

PX4 v1.15 (MAVLink HIL) flies the same physics with its FFT-driven dynamic notch
(`px4_fft`: gyro_fft, IMU_GYRO_FFT_EN 1, and IMU_GYRO_DNF_EN bit 1), against ours with the
notch following our in-flight FFT (`ours_fft`: FFT_ENABLE 1, INS_HNTCH_MODE 4), each with the
tuned notch's bandwidth and gyro low-pass (ours also its harmonics; PX4 notches each peak its
FFT reports instead), and the same PX4 without the notch (`px4_off`) for what the notch buys
it. PX4's gyro is the HIL_SENSOR stream,
250 Hz (its IMU_INTEG_RATE, one sample per 4 ms lockstep step, the mean of our four 1 kHz
samples): its FFT sees up to 125 Hz, so a rotor's second harmonic (~162 Hz in hover) folds
back to ~88 Hz, beside the fundamental it is meant to find.

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

SIDES = ("ours", "ardupilot", "ardupilot_ref", "ours_fft", "px4_fft", "px4_off")
# Each other side against the side of ours set up the same way; and PX4's notch against
# none (px4_off: the same PX4 with IMU_GYRO_DNF_EN 0), what its FFT notch buys it at 250 Hz.
PAIRS = (("ours", "ardupilot"), ("ours", "ardupilot_ref"), ("ours_fft", "px4_fft"),
         ("px4_fft", "px4_off"))
FC_OF_SIDE = {"ours": "ours", "ardupilot": "ardupilot", "ardupilot_ref": "ardupilot",
              "ours_fft": "ours", "px4_fft": "px4", "px4_off": "px4"}
# The FFT-driven sides: both search from FFT_MINHZ_HZ (V2's hover rotor is ~81 Hz; a tuned
# FREQ would be the notch's floor, INS_HNTCH_FREQ x FM_RAT, and keep it from going lower).
# Ours: 256-sample windows at 1 kHz (3.9 Hz bins, as tests/fc_sil/test_fft_flight.py);
# PX4: its default 512-sample window at 250 Hz (0.5 Hz bins), its search capped below its
# 125 Hz Nyquist.
FFT_MINHZ_HZ = 50
OURS_FFT_WINDOW = 256
PX4_FFT_MAX_HZ = 120
PX4_DNF_FFT = 2                    # IMU_GYRO_DNF_EN bit 1: notches at gyro_fft's peaks
PX4_DNF_BW_MAX_HZ = 30.0           # IMU_GYRO_DNF_BW's range top (PX4 v1.15 parameters)
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


def ours_fft_params(notch: dict) -> dict:
    """Our notch following our in-flight FFT, with the tuned notch's width and harmonics
    (INS_HNTCH_REF 1: the FFT's frequency unscaled, as ArduPilot's FFT setup says)."""
    return {**notch, "INS_HNTCH_MODE": 4, "INS_HNTCH_REF": 1, "INS_HNTCH_FREQ": FFT_MINHZ_HZ,
            "FFT_ENABLE": 1, "FFT_MINHZ": FFT_MINHZ_HZ, "FFT_WINDOW_SIZE": OURS_FFT_WINDOW}


def px4_fft_params(notch: dict) -> dict:
    """PX4's FFT-driven dynamic notch with the tuned notch's width (within PX4's 5-30 Hz
    range for IMU_GYRO_DNF_BW) and gyro low-pass. PX4 puts one notch on each peak gyro_fft
    reports (up to three per axis) instead of on harmonics of one: IMU_GYRO_DNF_HMC is for
    its ESC-RPM notch only."""
    out = {"IMU_GYRO_FFT_EN": 1, "IMU_GYRO_FFT_MIN": FFT_MINHZ_HZ,
           "IMU_GYRO_FFT_MAX": PX4_FFT_MAX_HZ, "IMU_GYRO_DNF_EN": PX4_DNF_FFT,
           "IMU_GYRO_DNF_BW": min(float(notch["INS_HNTCH_BW"]), PX4_DNF_BW_MAX_HZ),
           "IMU_GYRO_DNF_MIN": FFT_MINHZ_HZ}
    if "INS_GYRO_FILTER" in notch:
        out["IMU_GYRO_CUTOFF"] = float(notch["INS_GYRO_FILTER"])
    return out


def side_params(notch: dict, expo: float) -> dict:
    """{side: FC parameters} for one scenario's notch."""
    ref = float(notch.get("INS_HNTCH_REF", 0.0))
    return {"ours": dict(notch), "ardupilot": dict(notch),
            "ardupilot_ref": {**notch, "INS_HNTCH_REF": round(hover_thrust(ref, expo), 3)},
            "ours_fft": ours_fft_params(notch), "px4_fft": px4_fft_params(notch),
            "px4_off": {**px4_fft_params(notch), "IMU_GYRO_DNF_EN": 0}}


def specs_for(scenario: str, params: dict, seeds: range, out: Path, *, sides=SIDES,
              arducopter: str | None = None, px4: str | None = None):
    """RunSpecs of one scenario: each side asked for on every seed, logs not kept."""
    from silbridge.tools.benchmark.campaign import make_specs

    specs = []
    for side in sides:
        specs += make_specs([scenario], len(seeds), DURATION_S, out, base_seed=seeds.start,
                            params=tuple(sorted(params[side].items())), variant=side,
                            windows=WINDOWS, keep_logs="none", fc=FC_OF_SIDE[side],
                            sitl=arducopter, px4=px4)
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


def flown_pairs(rows: list[dict], scenario: str) -> list[tuple[str, str]]:
    """The PAIRS with runs of both sides in the scenario."""
    flown = {r["side"] for r in rows if r["scenario"] == scenario}
    return [(o, t) for o, t in PAIRS if o in flown and t in flown]


def compare(rows: list[dict]) -> dict:
    """{scenario: {other side: {metric: Paired.as_dict() + text}}}, ours (set up as the
    other side is, PAIRS) - other."""
    out: dict = {}
    for sc in dict.fromkeys(r["scenario"] for r in rows):
        out[sc] = {}
        for ours, side in flown_pairs(rows, sc):
            out[sc][side] = {}
            for key, _label, unit, fmt in METRICS:
                p = paired(series(rows, ours, sc, key), series(rows, side, sc, key),
                           BETTER[key])
                out[sc][side][key] = p.as_dict() | {"text": verdict_text(p, fmt, unit)}
    return out
