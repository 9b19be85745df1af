"""Which of the FC's spectrum peaks are aliases: read against the chip's raw channel.

The FC samples the chip's register at its own rate, so a line above the FC's Nyquist
frequency that the chip's anti-alias filter lets through appears in `/imu` folded down
(1.2 kHz read at 1 kHz: at 200 Hz) and at its true frequency in the chip's `/imu_raw`
(tools/logs/imu_raw_log.py). With both channels in the summary, an FC peak that sits where
a raw peak above the FC's Nyquist folds to, on the same axis, is marked with that peak's
true frequency (`alias_of_hz`), so the table says where it came from.
"""

from __future__ import annotations

from silbridge.tools.logs.imu_raw_log import RAW_IMU_CHANNEL
from silbridge.tools.logs.spectrum_log import IMU_CHANNEL


def fold_hz(freq_hz: float, rate_hz: float) -> float:
    """Where sampling at rate_hz puts a tone of freq_hz: into 0 .. rate_hz / 2."""
    f = freq_hz % rate_hz
    return rate_hz - f if f > rate_hz / 2 else f


def mark_aliases(channels: list[dict]) -> None:
    """Give every peak of the FC's channel `alias_of_hz`: the true frequency of the raw
    channel's peak above the FC's Nyquist that folds onto it (within the coarser of the
    two resolutions), else None. Without both channels nothing changes."""
    by_name = {ch["channel"]: ch for ch in channels}
    fc, raw = by_name.get(IMU_CHANNEL), by_name.get(RAW_IMU_CHANNEL)
    if fc is None or raw is None:
        return
    rate, tol = fc["rate_hz"], max(fc["resolution_hz"], raw["resolution_hz"])
    for axis, v in fc["axes"].items():
        above = [p["freq_hz"] for p in raw["axes"].get(axis, {"peaks": []})["peaks"]
                 if p["freq_hz"] > rate / 2]
        for p in v["peaks"]:
            hits = [f for f in above if abs(fold_hz(f, rate) - p["freq_hz"]) <= tol]
            p["alias_of_hz"] = hits[0] if hits else None
