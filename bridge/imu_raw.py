"""The chip's raw samples on request (`[imu_chip] log_raw`): the scenario's rule.

The sensor stage runs the IMU chip (its output data rate, its anti-alias filter) only
when the scenario turns the vibration on; without it the stage reads the rigid-body
signal once per physics step and there is no chip signal to log. So `log_raw = true`
with `vibration.enabled = false` is refused, naming the key, rather than giving a log
without the channel asked for. The C side: bridge/src/imu_raw.h; the log channel:
tools/logs/imu_raw_log.py. No imports: scenario.py loads it.
"""

from __future__ import annotations


def requested(sc) -> bool:
    """The scenario asks for /imu_raw (and check() has let it)."""
    return bool(sc.imu_chip.log_raw)


def check(sc, fail) -> None:
    """fail(key, problem) raises the ScenarioError when log_raw cannot be honoured."""
    if sc.imu_chip.log_raw and not sc.vibration.enabled:
        fail("imu_chip.log_raw", "raw chip samples exist only with the chip pipeline: set "
                                 "vibration.enabled = true, or log_raw = false")
