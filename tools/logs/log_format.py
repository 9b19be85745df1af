"""What a silbridge run log is made of, shared by its writer and its reader.

Names of the fixed channels and MCAP metadata records, the record-kind ->
channel map, the /timing row, the user-facing LogError, and the JSON
encoding used for metadata and events (numpy values allowed).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from silbridge.shm.records import Kind

LOG_FORMAT_VERSION = 1
META_RUN = "silbridge.run"
META_END = "silbridge.end"
CHANNEL_DTYPE_KEY = "silbridge.dtype"
EVENTS_CHANNEL = "/events"
RUN_CHANNEL = "/run/metadata"
STATUS_CHANNEL = "/fc/status"
TIMING_CHANNEL = "/timing"

# The channel each record kind goes to (names fixed by the logging contract).
KIND_CHANNELS = {
    Kind.IMU: "/imu", Kind.BARO: "/baro", Kind.MAG: "/mag", Kind.GNSS: "/gnss",
    Kind.GT_ATT: "/gt_att", Kind.GT_NAV: "/gt_nav", Kind.PWM: "/pwm",
    Kind.SETPOINT: "/setpoint", Kind.ESC: "/esc", Kind.BATTERY: "/battery",
}

# One row per FC cycle (per consumed IMU batch or per PWM tick), built by the loop.
# Sensor->FC latency = consume - imu_wall; end-to-end = pwm_wall - imu_wall.
TIMING_DTYPE = np.dtype([
    ("sim_ns", "<i8"),           # sim time of the newest IMU sample consumed [ns]
    ("imu_wall_ns", "<i8"),      # monotonic wall time that IMU sample was published [ns]
    ("consume_wall_ns", "<i8"),  # when the FC read it [ns]
    ("pwm_wall_ns", "<i8"),      # when the PWM computed from it was published; 0 if none [ns]
    ("loop_period_ns", "<i8"),   # wall time since the previous FC cycle [ns]
])


class LogError(Exception):
    """A log that cannot be written or read; the message says what to do."""

    user_facing = True


def _json_default(obj):
    """Make numpy values, paths and dataclasses JSON-serialisable."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON-serialisable")


def to_json(obj) -> str:
    return json.dumps(obj, default=_json_default, allow_nan=True)
