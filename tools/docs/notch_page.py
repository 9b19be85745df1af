"""docs/notch-vs-arducopter.md: our harmonic notch against ArduCopter's and PX4's, written by
this command.

    python -m silbridge.tools.docs.notch_page --run --seeds 1-5 [--scenarios V2,V4]
    python -m silbridge.tools.docs.notch_page --run --seeds 6-10      # more seeds, merged
    python -m silbridge.tools.docs.notch_page --run --seeds 1-5 --sides ours_fft,px4_fft
    python -m silbridge.tools.docs.notch_page                         # the page from the runs

`--run` tunes each scenario's notch with `silbridge tune notch` (once: its notch.parm is kept
in --work), flies the sides asked for on the seeds asked for (tools/benchmark/notch_compare.py:
ours and ArduCopter with the tuned throttle notch, ours and PX4 with a notch following their
in-flight FFT), merges their figures into --work/runs.json, then writes the page from every run
there. Flying in parts keeps each part short enough to hold the machine's lock for; the page
is always judged from all the runs flown.
"""

from __future__ import annotations

import argparse
import datetime
import math
import statistics
import subprocess
import sys
from pathlib import Path

from silbridge.tools.benchmark import notch_compare as nc
from silbridge.tools.benchmark.paired_stats import MIN_PAIRS, Paired, cells, header, method_line
from silbridge.tools.docs.markdown_text import code

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_OUT = REPO_ROOT / "docs" / "notch-vs-arducopter.md"
PROG = "python -m silbridge.tools.docs.notch_page"
SIDE_LABELS = {"ours": "ours", "ardupilot": "ArduCopter",
               "ardupilot_ref": "ArduCopter, REF in its throttle",
               "ours_fft": "ours, notch on our FFT", "px4_fft": "PX4, notch on its FFT",
               "px4_off": "PX4, no notch"}
# Whose filtered gyro never reaches silbridge (the sides a gyro-noise target cannot judge).
FOREIGN = {"ardupilot": "ArduCopter", "ardupilot_ref": "ArduCopter", "px4_fft": "PX4"}
# The targets: at or below ArduCopter with its notch, in these metrics.
TARGETS = ("gyro_noise_dps", "pwm_pp_us")


def _seeds(text: str) -> range:
    a, _, b = text.partition("-")
    try:
        first, last = int(a), int(b or a)
    except ValueError:
        raise nc.NotchCompareError(f"--seeds wants A-B such as 1-5, not {text!r}") from None
    if not 1 <= first <= last:
        raise nc.NotchCompareError(f"--seeds {text}: give 1 <= A <= B")
    return range(first, last + 1)


def _sides(text: str) -> tuple[str, ...]:
    sides = tuple(s.strip() for s in text.split(",") if s.strip())
    unknown = [s for s in sides if s not in nc.SIDES]
    if unknown or not sides:
        raise nc.NotchCompareError(f"--sides {text!r}: choose from {', '.join(nc.SIDES)}")
    return sides


def tuned_notch(scenario: str, work: Path) -> dict:
    """The notch `silbridge tune notch` proposes for the scenario (seed 1), tuned once."""
    parm = work / f"tune-{scenario}" / "notch.parm"
    if not parm.exists():
        argv = [sys.executable, "-m", "silbridge", "tune", "notch", "--scenario", scenario,
                "--seed", "1", "--duration", f"{nc.DURATION_S:g}", "--out", str(parm.parent)]
        done = subprocess.run(argv, stdout=subprocess.DEVNULL)
        if done.returncode != 0 or not parm.exists():
            raise nc.NotchCompareError(f"`{' '.join(argv[2:])}` failed: fix that first")
    return nc.read_parm(parm)


def _thrust_expo(scenario: str) -> float:
    from silbridge.tools.autopilots.common.run import scenario_factory
    _sc, make_sim = scenario_factory(scenario, 1, None)
    return make_sim().fdm.model_constant("quadx/thrust-expo")


def fly(scenarios: list[str], seeds: range, work: Path, *, sides, arducopter: str | None,
        px4: str | None, jobs: int) -> None:
    from silbridge.tools.benchmark.campaign import run_campaign
    specs = []
    for sc in scenarios:
        params = nc.side_params(tuned_notch(sc, work), _thrust_expo(sc))
        specs += nc.specs_for(sc, params, seeds, work, sides=sides, arducopter=arducopter,
                              px4=px4)
    nc.merge_runs(work, run_campaign(specs, jobs=jobs, label="notch"))


def _ours_of(side: str) -> str:
    return next(o for o, t in nc.PAIRS if t == side)


def _against_ours(judged_sc: dict) -> list[str]:
    """The other sides judged against one of ours (not PX4 against itself)."""
    return [side for side in judged_sc if nc.FC_OF_SIDE[_ours_of(side)] == "ours"]


# What PX4's gyro_fft reported, read from PX4's own log (SDLOG_MODE 2, topic
# sensor_gyro_fft, the last 15 s of a 40 s flight) of seed 1 with the px4_fft parameters,
# against the rotor speed in our log; measured 2026-11-28 with PX4 v1.15.4 SITL.
PX4_FFT_SEEN = (
    "What PX4's FFT finds (its own log of seed 1, topic sensor_gyro_fft over the last 15 s; "
    "measured 2026-11-28): 250 Hz sampling, 0.49 Hz bins. In V2 its strongest peak is "
    "81.0 Hz on roll and pitch in every frame, the rotor's 81.0 Hz: the fold is too weak "
    "to matter. In V4 its strongest peak is 88.0 Hz on roll and pitch, the folded second "
    "harmonic, and the 81 Hz fundamental shows as a second peak in only 7 % (roll) and 30 % "
    "(pitch) of its frames: PX4's notch sits mostly on the fold, the line its 250 Hz gyro "
    "really carries, and on the fundamental now and then.")


def _px4_intro(rows: list[dict]) -> list[str]:
    """What the PX4 rows are, when there are any."""
    seeds = sorted({r["seed"] for r in rows if r["side"] == "px4_fft"})
    if not seeds:
        return []
    return [
        f"PX4 v1.15 flies seeds {', '.join(map(str, seeds))} over MAVLink HIL on the same "
        "physics with its FFT-driven dynamic notch (gyro_fft, IMU_GYRO_FFT_EN 1, "
        "IMU_GYRO_DNF_EN bit 1), against ours with the notch following our in-flight FFT "
        "(FFT_ENABLE 1, INS_HNTCH_MODE 4, INS_HNTCH_REF 1), both searching from "
        f"{nc.FFT_MINHZ_HZ} Hz, with the tuned notch's bandwidth (PX4's IMU_GYRO_DNF_BW "
        f"stops at {nc.PX4_DNF_BW_MAX_HZ:g} Hz) and gyro low-pass. PX4's gyro is the "
        "HIL_SENSOR stream: 250 Hz, one sample per 4 ms lockstep step, the mean of our four "
        "1 kHz samples. Its FFT therefore sees only up to 125 Hz: the hover rotor "
        "(~81 Hz) is inside, but the second harmonic (~162 Hz) folds back to ~88 Hz, "
        "beside the fundamental, attenuated about 7 dB by the four-sample mean. PX4 on a "
        "real board samples its gyro at 1-8 kHz and would not see the fold." + (
            " The same PX4 without the notch (IMU_GYRO_DNF_EN 0, `PX4, no notch`) shows what "
            "its notch buys it." if any(r["side"] == "px4_off" for r in rows) else ""),
        PX4_FFT_SEEN]


def _params_line(rows: list[dict], scenario: str, side: str) -> str:
    params = next(r["params"] for r in rows if r["scenario"] == scenario and r["side"] == side)
    return " ".join(f"{k}={v:g}" for k, v in sorted(params.items()))


def _table(rows: list[dict], scenario: str, side: str, judged: dict) -> list[str]:
    them, ours = SIDE_LABELS[side], _ours_of(side)
    lines = ["| " + " | ".join(["metric"] + header(SIDE_LABELS[ours], them)) + " |",
             "|---|---|---|---|---|---|"]
    for key, label, unit, fmt in nc.METRICS:
        p = Paired.from_dict(judged[key])
        row = cells(p, fmt, unit) if p.n else [_ours_only(rows, ours, scenario, key, fmt),
                                               "n/a", "n/a", "0", "not compared"]
        lines.append("| " + " | ".join([f"{label} ({unit})"] + row) + " |")
    return lines


def _ours_only(rows: list[dict], ours: str, scenario: str, key: str, fmt: str) -> str:
    vals = [v for v in nc.series(rows, ours, scenario, key).values()
            if v is not None and math.isfinite(v)]
    return fmt.format(statistics.median(vals)) if vals else "n/a"


def _targets(rows: list[dict], scenario: str, judged: dict) -> list[str]:
    out = []
    for side in _against_ours(judged):
        for key, label, unit, fmt in nc.METRICS:
            if key not in TARGETS:
                continue
            p = Paired.from_dict(judged[side][key])
            if not p.n and key == "gyro_noise_dps":
                ours = _ours_only(rows, _ours_of(side), scenario, key, fmt)
                verdict = (f"not measurable: {FOREIGN[side]}'s filtered gyro does not reach "
                           f"silbridge (ours: median {ours} {unit})")
            elif not p.n:
                verdict = "no pairs: no run of one side has it"
            elif p.verdict == "at_or_below":
                verdict = "met (at or below)"
            elif p.verdict == "loses":
                verdict = f"**not met: ours {judged[side][key]['text']}**"
            else:
                verdict = f"not shown: {judged[side][key]['text']}"
            out.append(f"- {scenario}, {label} against {SIDE_LABELS[side]}: {verdict}.")
    return out


def _losses(judged: dict) -> list[str]:
    """The metrics outside TARGETS that ours loses, per other side."""
    return [f"- {label} against {SIDE_LABELS[side]}: ours {judged[side][key]['text']}."
            for side in _against_ours(judged) for key, label, _u, _f in nc.METRICS
            if key not in TARGETS and judged[side][key]["verdict"] == "loses"]


def render(rows: list[dict], command: str, written: str) -> str:
    judged = nc.compare(rows)
    seeds = sorted({r["seed"] for r in rows if r["side"] == "ours"})
    w = nc.WINDOWS
    lines = [
        "# Our harmonic notch against ArduCopter's" + (" and PX4's" if _px4_intro(rows) else "")
        + ", under vibration", "",
        f"Written by a command, never by hand; regenerate it with {code(command)} (fly more "
        f"seeds with `--run --seeds A-B`; every run flown is in the judgement). What the "
        "scenarios and the notch are: [the vibrating world](explanation/vibrating-world.md), "
        "[set up the harmonic notch](howto/harmonic-notch.md); the metrics: "
        "[metrics](reference/metrics.md#noise-metrics). Written " + written + ".", "",
        f"Each scenario flies seeds {', '.join(map(str, seeds))}: our FC and ArduCopter 4.6 "
        f"SITL (JSON interface) on the same physics, vibration and sensor noise per seed; "
        f"{nc.DURATION_S:g} s from take-off, the hover scored over {w[2][0]:g}-{w[2][1]:g} s. "
        "The notch is the one `silbridge tune notch --scenario V --seed 1` proposes for our "
        "FC; ArduCopter gets the same parameters, once as they are and once with INS_HNTCH_REF "
        "in its own throttle unit (a fraction of full thrust, which its MOT_THST_EXPO curve "
        "maps to PWM; ours is a fraction of the PWM range), as ArduPilot's docs tell a tuner "
        "to set it: its hover thrust. INS_HNTCH_MODE 3 (ESC telemetry) is not compared: "
        "ArduCopter 4.6's JSON interface takes no rotor speed. Why ours loses where it "
        "does: [against ArduCopter's notch](howto/harmonic-notch.md#against-arducopters-notch).",
        "", *(line for part in _px4_intro(rows) for line in (part, ""))]
    for sc in judged:
        lines += [f"## {sc}", ""]
        for side in nc.SIDES:
            if any(r["scenario"] == sc and r["side"] == side for r in rows):
                lines.append(f"- {SIDE_LABELS[side]}: {code(_params_line(rows, sc, side))}")
        lines += ["", "Targets (issue 27: at or below the other FC with its notch, N >= 10):",
                  ""]
        lines += _targets(rows, sc, judged[sc]) + [""]
        losses = _losses(judged[sc])
        if losses:
            lines += ["Other metrics where ours loses:", ""] + losses + [""]
        for side in judged[sc]:
            ours = SIDE_LABELS[_ours_of(side)]
            lines += [f"**{ours[:1].upper() + ours[1:]} against "
                      f"{SIDE_LABELS[side]}, paired by seed**", ""]
            lines += _table(rows, sc, side, judged[sc][side]) + [""]
    lines += [method_line("ours", "the other FC"), "",
              "Gyro noise after filtering is n/a for ArduCopter and PX4: their filtered gyro "
              "never crosses the link silbridge sees ([metrics](reference/metrics.md#noise-"
              f"metrics)). Fewer than {MIN_PAIRS} pairs give no verdict; the issue asks for 10."]
    return "\n".join(lines).rstrip() + "\n"


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("--work", default="notch-out", metavar="DIR",
                   help="runs.json and the tuned notch.parm files (default %(default)s)")
    p.add_argument("--run", action="store_true", help="fly --seeds first, then write the page")
    p.add_argument("--seeds", default="1-10", metavar="A-B",
                   help="with --run: the seeds to fly (default %(default)s)")
    p.add_argument("--scenarios", default="V2,V4",
                   help="with --run: comma-separated scenarios (default %(default)s)")
    p.add_argument("--arducopter", default=None, metavar="PATH",
                   help="with --run: the arducopter SITL binary (default "
                        "$SILBRIDGE_ARDUCOPTER, then `arducopter` on PATH)")
    p.add_argument("--sides", default=",".join(nc.SIDES),
                   help="with --run: comma-separated sides to fly (default %(default)s)")
    p.add_argument("--px4", default=None, metavar="PATH",
                   help="with --run: the px4 SITL binary, etc/ beside its bin/ (default "
                        "$SILBRIDGE_PX4, then `px4` on PATH)")
    p.add_argument("--jobs", type=int, default=1,
                   help="with --run: runs at a time (default %(default)s)")
    p.add_argument("--out", default=str(DEFAULT_OUT), metavar="FILE",
                   help="the page to write (default %(default)s)")
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    work = Path(args.work)
    try:
        if args.run:
            sides = _sides(args.sides)
            arducopter = px4 = None
            if any(nc.FC_OF_SIDE[s] == "ardupilot" for s in sides):
                from silbridge.tools.autopilots.ardupilot.sitl import require_arducopter
                arducopter = require_arducopter(args.arducopter)
            if any(nc.FC_OF_SIDE[s] == "px4" for s in sides):
                from silbridge.tools.autopilots.px4.sitl import require_px4
                px4 = require_px4(args.px4)[0]
            scenarios = [s.strip() for s in args.scenarios.split(",") if s.strip()]
            fly(scenarios, _seeds(args.seeds), work, sides=sides, arducopter=arducopter,
                px4=px4, jobs=args.jobs)
        rows = nc.load_runs(work)
    except Exception as exc:  # noqa: BLE001 - only user-facing errors are shortened
        if getattr(exc, "user_facing", False):
            print(f"notch_page: error: {exc}", file=sys.stderr)
            return 2
        raise
    written = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    text = render(rows, f"{PROG} --run --seeds 1-10", written)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(f"wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
