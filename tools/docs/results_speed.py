"""The speed section of docs/results.md: the campaign's real-time factors beside the two
references measured in the same command, and the ratios between them.

References:
- bare JSBSim `run()` on our quadx at 1 kHz (tools/docs/jsbsim_speed.py): the physics alone,
  the ceiling of any loop built on it;
- ArduCopter SITL on its own built-in physics (`--model quad --speedup 1000`, measured by
  tools/autopilots/ardupilot/speed.py's `measure_reference`), when a binary is at hand: what
  the autopilot itself reaches with no external simulator, the ceiling of ArduCopter on ours.

A campaign run's figure is its own `realtime_factor` (sim seconds over the run's wall
seconds, one process pair per run), averaged over the runs of each controller; the campaign's
overall figure divides all simulated seconds by its wall time, so it includes running
`--jobs` runs side by side and everything between runs.
"""

from __future__ import annotations

# ArduCopter's reference window: sim seconds of boot skipped, then sim seconds measured
# (tools/autopilots/ardupilot/speed.py's defaults: parameter loading happens in the first seconds).
ARDUCOPTER_SKIP_S = 5.0
ARDUCOPTER_SPAN_S = 30.0


def measure_arducopter(binary: str) -> dict:
    from silbridge.tools.autopilots.ardupilot.speed import measure_reference
    ref = measure_reference(binary, skip_s=ARDUCOPTER_SKIP_S, span_s=ARDUCOPTER_SPAN_S)
    return ref | {"binary": binary, "skip_s": ARDUCOPTER_SKIP_S, "span_s": ARDUCOPTER_SPAN_S}


def per_controller_speed(table: dict) -> dict[str, dict]:
    """{'ours': {'realtime_factor': mean over all its runs, 'n': runs}, 'ArduCopter': ...}
    from Table 1's groups ('S1' is ours, 'S1 ArduCopter' is ArduCopter's)."""
    sums: dict[str, list[float]] = {}
    for key, metrics in table["scenarios"].items():
        stat = metrics.get("realtime_factor") or {}
        if stat.get("mean") is None or not stat.get("n"):
            continue
        fc = key.partition(" ")[2] or "ours"
        acc = sums.setdefault(fc, [0.0, 0])
        acc[0] += stat["mean"] * stat["n"]
        acc[1] += stat["n"]
    return {fc: {"realtime_factor": s / n, "n": n} for fc, (s, n) in sums.items() if n}


def campaign_speed(table: dict) -> float | None:
    wall, sim = table.get("wall_s"), table.get("sim_s_total")
    return sim / wall if wall and sim else None


def speed_rows(table: dict, jsbsim: dict, arducopter: dict | None) -> list[dict]:
    """Rows of the speed table: label, x real time, ratio to bare JSBSim, ratio to ArduCopter's
    own physics (None without that reference)."""
    j = jsbsim["realtime_factor"]
    a = arducopter["realtime_factor"] if arducopter else None
    rows = [{"label": f"bare JSBSim `run()`, {jsbsim['model']} at "
                      f"{jsbsim['physics_hz'] / 1000:g} kHz, one core", "x": j}]
    if arducopter:
        rows.append({"label": "ArduCopter SITL on its own physics (`--model quad --speedup "
                              "1000`, idle on the ground)", "x": a})
    for fc, s in per_controller_speed(table).items():
        who = "our FC" if fc == "ours" else f"{fc} on our physics"
        rows.append({"label": f"a campaign run, {who} (mean of {s['n']} runs)",
                     "x": s["realtime_factor"]})
    overall = campaign_speed(table)
    if overall is not None:
        rows.append({"label": "the whole campaign (all simulated seconds / its wall time; "
                              "runs side by side on the cores)",
                     "x": overall})
    for r in rows:
        r["of_jsbsim"] = r["x"] / j
        r["of_arducopter"] = r["x"] / a if a else None
    return rows
