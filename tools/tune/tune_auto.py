"""`silbridge tune auto`: search the rate and attitude gains and filter cutoffs.

Objective: S4 tracking, the attitude RMS against the command (the metric
`att_rms_cmd_deg` when tools/benchmark/metrics.py provides it, else `att_rms_deg`),
minimised. Constraints (optuna's constrained TPE; a trial is feasible when
every value is <= 0): phase margin >= PM_MIN and gain margin >= GM_MIN on
every tuned axis, measured by a mixer-input sweep flight of the candidate
(tune_sysid.py; a margin the sweep could not find counts as failed), no
saturation on S1 or S4, and S1 PWM peak-to-peak no higher than the defaults'
(smoothness may not be traded for tracking). Each trial flies S1 and S4 once
(campaign RunSpecs, metrics from their logs as Table 1 computes them) and one
sweep per tuned axis, all on fixed seeds, in parallel on a persistent pool
(tune_exec.py). The defaults are trial 0, so the search starts from them.

Then the best feasible trial is checked: Table 1 (S1, S4, `runs` seeds)
before and after, and both sweeps per axis. A candidate whose check misses a
target (margins, S1 p-p, S4 RMS no better) is reported as such, and the next
best is tried (up to CHECKS candidates). Every `compare` set (e.g. the .parm
`tune anchor` writes from ArduCopter's AUTOTUNE) is scored the same way on the same
seeds (tune_compare.py), and the tuned set must beat each of them on S4 too.

What is searched, and why the input shaping is in it. Against the raw command, most of
S4's error is not the loop's: with the defaults the true attitude follows the FC's
shaped target to ~0.75 deg RMS, while the shaped target itself lags the 20-35 deg steps
and ramps by ~5 deg RMS. A search of the loop gains alone can only work on the 15 %;
the rest is the shaper's (ATC_ACCEL_R/P_MAX, how fast the target may accelerate, and
ATC_INPUT_TC, how it closes on the command). ArduCopter's AUTOTUNE itself sets
ATC_ACCEL_*_MAX (from the acceleration the airframe showed it), so those belong to a
tune on any reading; ATC_INPUT_TC is the pilot's feel in ArduCopter and AUTOTUNE leaves
it, so `input_tc=False` (`--keep-input-tc`) searches without it, for a comparison with
AUTOTUNE's gains that changes only what AUTOTUNE changes. Neither enters the margins
(the shaper sits on the command path, outside the loop the sweep breaks), nor S1's
p-p in a hover (no command to shape beyond the position loop's small tilts); S4's p-p
rises with a faster shaper and is reported, not constrained (the issue's smoothness
figure is S1's), and saturation stays a constraint on both.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from silbridge.fc_sil import params as P

from silbridge.tools.benchmark.campaign import RunSpec, run_one
from silbridge.tools.tune import tune_defaults as D
from silbridge.tools.tune.tune_sysid import SweepConfig, TuneError, summarise_axis, sysid_task

PM_MIN = D.PM_MIN_DEG
GM_MIN = D.GM_MIN_DB
CHECKS = 3
TRACK_KEYS = ("att_rms_cmd_deg", "att_rms_deg")
SMOOTH_KEY = "pwm_pp_us"
SAT_KEY = "sat_pct"
_ABBR = {"roll": "RLL", "pitch": "PIT", "yaw": "YAW"}
CONSTRAINT_NAMES = ("phase_margin", "gain_margin", "saturation", "s1_pwm_pp")

# name pattern -> (low, high, log scale). Gains bracket ArduCopter's usual values
# for a 450 mm quad on both sides of our defaults. The measurement-path cutoffs
# (INS_GYRO_FILTER, FLTD) start at the defaults' 20 Hz: a sweep of the defaults
# shows the loop already short of phase there (PM ~30 deg at ~5.6 Hz, of which the
# 20 Hz gyro Butterworth takes ~23 deg), so lower cutoffs can only lose margin.
_RATE_SPACE = {"P": (0.04, 0.4, True), "I": (0.04, 0.6, True), "D": (0.0005, 0.012, True),
               "FF": (0.0, 0.15, False), "FLTD": (20.0, 80.0, True),
               "FLTT": (10.0, 80.0, True)}
_YAW_SPACE = {"P": (0.05, 0.6, True), "I": (0.005, 0.1, True), "D": (0.0, 0.01, False),
              "FF": (0.0, 0.15, False), "FLTE": (1.0, 10.0, True)}
# Angle P up to 24: ArduCopter's AUTOTUNE saved 22-24 on this airframe (the declared range
# is ArduCopter's, up to its AUTOTUNE_SP_MAX 40); the margins constraint bounds it anyway.
_ANG_SPACE = (3.0, 24.0, True)
_GYRO_SPACE = (20.0, 80.0, True)
# Shaping (see the module docstring): acceleration limits from ArduCopter's "very slow"
# preset (30000) up to past AUTOTUNE's ~283000 on this airframe; ATC_INPUT_TC over
# ArduCopter's "very crisp" (0.05) to "soft" (0.2).
_ACCEL_SPACE = (30000.0, 360000.0, True)
_INPUT_TC_SPACE = (0.05, 0.2, True)


def _pitch_twin(name: str) -> str:
    """The pitch parameter of a roll one (ATC_RAT_RLL_P -> ATC_RAT_PIT_P,
    ATC_ACCEL_R_MAX -> ATC_ACCEL_P_MAX); any other name is its own."""
    return name.replace("_RLL_", "_PIT_").replace("ATC_ACCEL_R_", "ATC_ACCEL_P_")


def tied_twins(space) -> dict[str, str]:
    """Roll name -> its pitch twin, for the names of `space` that have one in it."""
    return {n: _pitch_twin(n) for n in space if _pitch_twin(n) != n and _pitch_twin(n) in space}


def search_space(axes, input_tc: bool = True) -> dict[str, tuple[float, float, bool]]:
    """Parameter -> (low, high, log) for the tuned axes. Yaw's heading P stays as is:
    0 means rate damping only (no heading hold), a different controller, not a gain."""
    space = {}
    for axis in axes:
        a = _ABBR[axis]
        for term, rng in (_YAW_SPACE if axis == "yaw" else _RATE_SPACE).items():
            space[f"ATC_RAT_{a}_{term}"] = rng
        if axis != "yaw":
            space[f"ATC_ANG_{a}_P"] = _ANG_SPACE
            space[f"ATC_ACCEL_{a[0]}_MAX"] = _ACCEL_SPACE
    space["INS_GYRO_FILTER"] = _GYRO_SPACE
    if input_tc and set(axes) - {"yaw"}:
        space["ATC_INPUT_TC"] = _INPUT_TC_SPACE
    for name, (lo, hi, log) in space.items():      # stay inside the declared ranges
        d = P.BY_NAME[name]
        space[name] = (max(lo, d.min), min(hi, d.max), log)
    return space


@dataclass(frozen=True)
class AutoConfig:
    axes: tuple = ("roll", "pitch")
    trials: int = D.AUTO_TRIALS
    runs: int = D.AUTO_RUNS        # seeds per scenario in the before/after Table 1
    seed: int = 1
    batch: int = D.AUTO_BATCH      # trials evaluated together (keeps every worker busy)
    base_params: tuple = ()        # fixed overrides under the search ((name, value), ...)
    sweep: SweepConfig = field(default_factory=lambda: SweepConfig(
        f_start_hz=1.0, t_fade_in_s=3.0, t_rec_s=25.0, sweep_at_s=12.0))
    check_sweep: SweepConfig = field(default_factory=SweepConfig)
    pm_min: float = PM_MIN
    gm_min: float = GM_MIN
    # Search flights are shorter than Table 1's 120 s (same warm-up and transient, an
    # analysis window of 30-70 s: four S4 doublets); every trial uses the same windows,
    # the defaults included, and the before/after check flies the full protocol.
    search_duration_s: float = 70.0
    # Roll and pitch share one set of values (the model's Ixx and Iyy differ by 3 %, its
    # arms not at all): half the dimensions for the same trials. Both are still swept.
    tie_roll_pitch: bool = True
    input_tc: bool = True          # ATC_INPUT_TC in the search (module docstring)
    compare: tuple = ()            # ((label, ((name, value), ...)), ...) scored beside


def track_key(metrics: dict) -> str:
    for k in TRACK_KEYS:
        if k in metrics:
            return k
    raise KeyError(f"none of {TRACK_KEYS} in the run's metrics")


def auto_task(task: tuple):
    """Executor task: ("flight", RunSpec) -> metrics | ("sweep", sysid task) -> FRFs.
    A candidate that crashes the vehicle (a flight, or a sweep) is an answer, not an
    error: {"failed": reason} (a flight) or (key, None) (a sweep)."""
    kind, payload = task
    if kind == "flight":
        res = run_one(payload)
        if res.summary.get("crashed") or res.problems:
            why = "crashed" if res.summary.get("crashed") else res.problems[0]
            return {"failed": f"{payload.scenario}: {why}"}
        return res.metrics
    try:
        return sysid_task(payload)
    except TuneError as exc:
        return (payload[0], payload[1]), {"failed": str(exc)}


def _spec(scenario: str, seed: int, params: dict, work: Path, tag: str,
          duration_s: float = 120.0) -> RunSpec:
    windows = RunSpec.windows
    if duration_s < windows[2][1]:
        windows = ((0.0, 10.0), (10.0, 30.0), (30.0, duration_s),
                   (max(30.0, duration_s - 30.0), duration_s))
    return RunSpec(scenario=scenario, run_index=seed, seed=seed, duration_s=duration_s,
                   log_path=str(work / f"{tag}_{scenario}_s{seed}.mcap"),
                   params=tuple(sorted(params.items())), keep_log=False, variant=tag,
                   windows=windows)


def evaluate(pool, candidates: list[dict], cfg: AutoConfig, work: Path, tag: str) -> list[dict]:
    """S1 and S4 (seed cfg.seed) and one mixer sweep per tuned axis, per candidate."""
    tasks, where = [], []
    for ci, params in enumerate(candidates):
        for sc in ("S1", "S4"):
            tasks.append(("flight", _spec(sc, cfg.seed, params, work, f"{tag}{ci}",
                                          cfg.search_duration_s)))
            where.append((ci, sc))
        for axis in cfg.axes:
            tasks.append(("sweep", (axis, "output", cfg.sweep, params)))
            where.append((ci, axis))
    out = [{"params": c, "margins": {}} for c in candidates]
    for (ci, key), res in zip(where, pool.map(auto_task, tasks)):
        if key in ("S1", "S4"):
            out[ci][key] = res
            if "failed" in res:
                out[ci]["failed"] = res["failed"]
        else:
            (axis, _inj), frfs = res
            if "failed" in frfs:
                out[ci]["failed"] = frfs["failed"]
                out[ci]["margins"][axis] = {}
            else:
                out[ci]["margins"][axis] = summarise_axis(axis, frfs, None, cfg.sweep).summary
    return out


def constraints(ev: dict, cfg: AutoConfig, base_pp: float) -> list[float]:
    """Values <= 0 when satisfied: PM, GM (worst tuned axis), saturation, S1 p-p."""
    if "failed" in ev:
        return [1e3] * len(CONSTRAINT_NAMES)
    pms = [m.get("phase_margin_deg") for m in ev["margins"].values()]
    # A phase crossover above the sweep's coherent band counts with its bound (tune_sysid).
    gms = [m.get("gain_margin_db") if m.get("gain_margin_db") is not None
           else m.get("gain_margin_min_db") for m in ev["margins"].values()]
    pm = min((v if v is not None else -math.inf) for v in pms)
    gm = min((v if v is not None else -math.inf) for v in gms)
    sat = float(ev["S1"].get(SAT_KEY) or 0.0) + float(ev["S4"].get(SAT_KEY) or 0.0)
    big = 1e3   # a missing margin: clearly infeasible, still finite for the sampler
    return [min(cfg.pm_min - pm, big), min(cfg.gm_min - gm, big), sat,
            float(ev["S1"][SMOOTH_KEY]) - base_pp]


def objective(ev: dict) -> float:
    if "failed" in ev:
        return 1e3
    v = float(ev["S4"][track_key(ev["S4"])])
    return v if math.isfinite(v) else 1e3


def _suggest(trial, name: str, lo: float, hi: float, log: bool):
    """The trial's value for name: whole numbers for an integer parameter (INS_GYRO_FILTER
    is an INT16, as in ArduCopter; our FC refuses a fractional value, which ArduCopter
    would truncate)."""
    if P.BY_NAME[name].is_int:
        return trial.suggest_int(name, math.ceil(lo), math.floor(hi), log=log)
    return trial.suggest_float(name, lo, hi, log=log)


def search(pool, cfg: AutoConfig, work: Path, *, progress=True, out=print) -> dict:
    """Run the optuna study; returns {"trials": [...], "baseline": ev, "ranked": [...]}."""
    import optuna
    from tqdm import tqdm

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    base = dict(cfg.base_params)
    full = search_space(cfg.axes, cfg.input_tc)
    tied = cfg.tie_roll_pitch and {"roll", "pitch"} <= set(cfg.axes)
    # tied: sample the roll names only; each pitch name copies its roll twin
    twins = tied_twins(full) if tied else {}
    space = {n: r for n, r in full.items() if n not in twins.values()}
    defaults = P.defaults()
    start = {n: float(base.get(n, defaults[n])) for n in space}
    for n, (lo, hi, _log) in space.items():
        start[n] = min(max(start[n], lo), hi)
        if P.BY_NAME[n].is_int:
            start[n] = int(round(start[n]))
    # Constraints: Trial.set_constraint from optuna 5, the sampler's constraints_func before.
    new_api = hasattr(optuna.trial.Trial, "set_constraint")
    extra = {} if new_api else {"constraints_func": lambda t: t.user_attrs["constraints"]}
    sampler = optuna.samplers.TPESampler(
        seed=cfg.seed, multivariate=True, n_startup_trials=max(4, min(10, cfg.trials // 5)),
        **extra)
    study = optuna.create_study(direction="minimize", sampler=sampler)
    study.enqueue_trial(start)     # trial 0: the defaults (clipped into the space)
    bar = tqdm(total=cfg.trials, desc="tune auto", unit="trial", disable=not progress,
               dynamic_ncols=True)
    evals = []
    base_pp = None
    done = 0
    try:
        while done < cfg.trials:
            n = 1 if done == 0 else min(cfg.batch, cfg.trials - done)
            trials = [study.ask() for _ in range(n)]
            cands = [{k: _suggest(t, k, lo, hi, log) for k, (lo, hi, log) in space.items()}
                     for t in trials]
            for c in cands:
                c.update({twin: c[n] for n, twin in twins.items()})
            evs = evaluate(pool, [{**base, **c} for c in cands], cfg, work, f"t{done}_")
            if base_pp is None:
                if "failed" in evs[0]:
                    raise TuneError(f"the starting gains fail ({evs[0]['failed']}): start "
                                    f"from gains that fly (--param / --params)")
                base_pp = float(evs[0]["S1"][SMOOTH_KEY])
            for t, c, ev in zip(trials, cands, evs):
                cons = constraints(ev, cfg, base_pp)
                t.set_user_attr("constraints", cons)
                if new_api:
                    for cname, value in zip(CONSTRAINT_NAMES, cons):
                        t.set_constraint(cname, value)
                obj = objective(ev)
                study.tell(t, obj)
                evals.append({"number": t.number, "candidate": c, "objective": obj,
                              "constraints": cons, "feasible": all(v <= 0 for v in cons),
                              "eval": ev})
            done += n
            best = min((e["objective"] for e in evals if e["feasible"]), default=None)
            bar.set_postfix_str("best S4 RMS " + ("-" if best is None else f"{best:.3f} deg"))
            bar.update(n)
    finally:
        bar.close()
    ranked = sorted((e for e in evals if e["feasible"]), key=lambda e: e["objective"])
    return {"trials": evals, "baseline": evals[0], "ranked": ranked, "base_pp": base_pp}


def table1_runs(pool, params: dict, cfg: AutoConfig, work: Path, tag: str):
    """S1 and S4 over cfg.runs seeds -> (RunResults for table1.aggregate)."""
    from silbridge.tools.benchmark.campaign import RunResult

    specs = [_spec(sc, cfg.seed + i, params, work, tag) for sc in ("S1", "S4")
             for i in range(cfg.runs)]
    metrics = pool.map(auto_task, [("flight", s) for s in specs])
    failed = [m["failed"] for m in metrics if "failed" in m]
    if failed:
        raise TuneError(f"{tag}: {failed[0]}")
    return [RunResult(spec=s, metrics=m) for s, m in zip(specs, metrics)]


def means(table: dict) -> dict:
    """aggregate() table -> {scenario: {metric: mean}}."""
    return {sc: {k: v["mean"] for k, v in rows.items()} for sc, rows in table["scenarios"].items()}


def check(before: dict, after: dict, margins: dict, cfg: AutoConfig,
          compare: dict | None = None) -> dict:
    """The targets of the issue, each with its figures. compare: {label: Table 1 means,
    or None when that set crashed} that S4 tracking must beat as well (a set that crashed
    counts as beaten, and `beats` says so)."""
    tk = track_key(after["S4"])
    ok_m = all((m.get("phase_margin_deg") or -1) >= cfg.pm_min
               and (m.get("gain_margin_db") or m.get("gain_margin_min_db") or -1) >= cfg.gm_min
               for m in margins.values())
    res = {
        "track_metric": tk,
        "s4_track_better": after["S4"][tk] < before["S4"][tk],
        "s1_pp_not_higher": after["S1"][SMOOTH_KEY] <= before["S1"][SMOOTH_KEY],
        "no_saturation": (after["S1"].get(SAT_KEY) or 0) == 0 and (after["S4"].get(SAT_KEY) or 0) == 0,
        "margins_ok": ok_m,
    }
    if compare:
        res["beats"] = {lab: ("crashed" if m is None else bool(after["S4"][tk] < m["S4"][tk]))
                        for lab, m in compare.items()}
        res["s4_track_better_than_compare"] = all(v for v in res["beats"].values())
    res["met"] = all(v for k, v in res.items() if k not in ("track_metric", "beats"))
    return res


def run_auto(cfg: AutoConfig, out_dir: Path, *, pool, progress=True, out=print) -> dict:
    """The whole command: search, before/after check (and the compare sets), .parm and
    report files."""
    from silbridge.tools.benchmark.table1 import markdown
    from silbridge.tools.tune.tune_compare import comparison_table, score_set, summary
    from silbridge.tools.tune.tune_parm import write_parm
    from silbridge.tools.tune.tune_report import margins_table, write_index

    t0 = time.monotonic()
    out_dir.mkdir(parents=True, exist_ok=True)
    work = out_dir / "runs"
    work.mkdir(exist_ok=True)
    base = dict(cfg.base_params)
    found = search(pool, cfg, work, progress=progress, out=out)
    t_search = time.monotonic() - t0

    before_col = score_set(pool, base, cfg, work, "before")
    if before_col["failed"]:
        raise TuneError(f"the starting gains fail the check: {before_col['failed']}")
    before, margins_before = before_col["means"], before_col["margins"]
    compare_sets = {lab: {**base, **dict(vals)} for lab, vals in cfg.compare}
    compare_cols = {lab: score_set(pool, params, cfg, work, f"cmp{i}_")
                    for i, (lab, params) in enumerate(compare_sets.items())}
    compare_means = {lab: col["means"] for lab, col in compare_cols.items()}
    checked = []
    chosen = None
    for cand in found["ranked"][:CHECKS]:
        params = {**base, **cand["candidate"]}
        col = score_set(pool, params, cfg, work, "after")
        if col["failed"]:             # flew in the search, fails on another seed
            checked.append({"trial": cand["number"], "verdict": {"met": False,
                                                                  "note": col["failed"]}})
            continue
        verdict = check(before, col["means"], col["margins"], cfg, compare_means)
        checked.append({"trial": cand["number"], "verdict": verdict})
        chosen = (cand, params, col, verdict)
        if verdict["met"]:
            break
    if chosen is None:
        # No feasible trial at all: report the defaults as the result, and say so.
        chosen = (found["baseline"], base, before_col,
                  {**check(before, before, margins_before, cfg, compare_means),
                   "met": False, "note": "no trial met the constraints: the defaults"})
    cand, params, after_col, verdict = chosen
    after, margins = after_col["means"], after_col["margins"]
    tuned = {k: float(v) for k, v in cand["candidate"].items()}
    parm = write_parm(out_dir / "tuned.parm", tuned,
                      header=f"silbridge tune auto --axis {','.join(cfg.axes)}: trial "
                             f"{cand['number']} of {cfg.trials}, seed {cfg.seed}")
    wall = time.monotonic() - t0
    columns = {"defaults": before_col, "tuned": after_col, **compare_cols}
    col_params = {"defaults": base, "tuned": params, **compare_sets}
    comparison = comparison_table(columns, cfg.axes, col_params)
    tables = [
        (f"Comparison ({cfg.runs} seeds from {cfg.seed}, 120 s; margins from the check sweeps)",
         comparison),
        ("Table 1 before (defaults)", markdown(before_col["table"], paper=False, title="before")),
        ("Table 1 after (tuned)", markdown(after_col["table"], paper=False, title="after")),
        ("Margins before", margins_table(margins_before)),
        ("Margins after", margins_table(margins)),
    ] + [(f"Table 1: {lab}", markdown(col["table"], paper=False, title=lab))
         for lab, col in compare_cols.items() if col["table"] is not None]
    result = {"params": tuned, "margins": margins, "before": before, "after": after,
              "parm_file": str(parm), "margins_before": margins_before, "verdict": verdict}
    if compare_cols:
        result["compare"] = {lab: {**summary(col), "params": dict(dict(cfg.compare)[lab])}
                             for lab, col in compare_cols.items()}
    details = {**result,
               "checked": checked, "trials": cfg.trials, "feasible_trials": len(found["ranked"]),
               "search_wall_s": t_search, "wall_s": wall, "comparison_md": comparison,
               "history": [{k: e[k] for k in ("number", "objective", "constraints", "feasible")}
                           for e in found["trials"]]}
    write_index(out_dir, "silbridge tune auto", details, tables, [])
    return {"result": result, "details": details}
