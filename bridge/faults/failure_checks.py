"""Scenario rules of [[failure]] that need more than its own keys (the schema, built from
shm/fault_catalog.py, checks the rest). scenario.py calls `check` with its fail(key,
problem), which raises the ScenarioError naming the key. No imports: scenario.py loads it.
"""

from __future__ import annotations


def check(sc, fail) -> None:
    for i, f in enumerate(sc.failures):
        where = f"failure[{i}]"
        if f.at_s >= sc.duration_s:
            fail(f"{where}.at_s", f"{f.at_s:g} s is not before the end of the run "
                                  f"({sc.duration_s:g} s)")
        if f.unit in ("gyro", "accel") and sc.imu.rate_hz != sc.physics.rate_hz:
            fail(f"{where}.unit", f"{f.unit} failures act on the one-per-step IMU sample: set "
                                  f"imu.rate_hz = physics.rate_hz ({sc.physics.rate_hz})")
        if (f.unit == "motor" and f.type == "damaged_prop" and f.imbalance_scale != 1.0
                and not sc.vibration.enabled):
            fail(f"{where}.imbalance_scale",
                 f"a damaged prop's vibration ({f.imbalance_scale:g} x the imbalance) needs the "
                 f"vibrating world: set [vibration] enabled = true, or imbalance_scale = 1 for "
                 f"the thrust loss alone")
