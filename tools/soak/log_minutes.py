"""Per-minute figures from the run's MCAP log once it is closed: late steps, IMU and PWM rates.

The vehicle counts late steps only in its end summary. Its log's /timing channel holds,
for every IMU sample the FC consumed, the sim time, the wall time it was published and the
wall time of the PWM computed from it (0 if none). The bridge paces to absolute deadlines
t0 + sim_ns / speed, so a sample published more than one physics step after its deadline
is a late step (bridge/pacing.py); t0 is the earliest publish-minus-sim offset (the most
punctual sample).
"""

from __future__ import annotations

import numpy as np

from silbridge.tools.logs.mcap_log import TIMING_CHANNEL, read_log


def minutes_from_timing(imu_wall_ns: np.ndarray, sim_ns: np.ndarray, pwm_wall_ns: np.ndarray,
                        period_ns: float, speed: float = 1.0,
                        minute_s: float = 60.0) -> list[dict]:
    """One dict per whole wall interval of minute_s from the first sample (a minute unless
    a short run asks for finer bins): {"t_s" (its start), "late_steps",
    "late_steps_per_min", "imu_hz" (IMU samples the FC consumed), "pwm_hz" (PWM it
    published)}. Pure: the unit tests feed it synthetic
    timings."""
    if len(sim_ns) == 0:
        return []
    wall = imu_wall_ns.astype(np.int64)
    offset = wall - (sim_ns.astype(np.float64) / speed).astype(np.int64)
    late = (offset - offset.min()) > period_ns / speed
    rel_s = (wall - wall[0]) / 1e9
    n = int(rel_s[-1] // minute_s)
    if n == 0:
        return []
    idx = (rel_s // minute_s).astype(np.int64)

    def per_minute(mask):
        return np.bincount(idx[mask], minlength=n + 1)[:n]
    lates, imus = per_minute(late), per_minute(np.ones(len(idx), bool))
    pwms = per_minute(pwm_wall_ns != 0)
    return [{"t_s": i * minute_s, "late_steps": int(lates[i]),
             "late_steps_per_min": float(lates[i]) * 60.0 / minute_s,
             "imu_hz": float(imus[i]) / minute_s, "pwm_hz": float(pwms[i]) / minute_s}
            for i in range(n)]


def minutes_from_log(path: str, speed: float = 1.0, minute_s: float = 60.0) -> list[dict]:
    """minutes_from_timing over a closed log; the physics step is the log's own."""
    log = read_log(path, channels=[TIMING_CHANNEL])
    rows = log.channels.get(TIMING_CHANNEL)
    if rows is None:
        return []
    physics_hz = float(log.metadata["config"]["physics_hz"])
    return minutes_from_timing(rows["imu_wall_ns"], rows["sim_ns"], rows["pwm_wall_ns"],
                               1e9 / physics_hz, speed, minute_s)
