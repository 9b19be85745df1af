"""The /imu_raw channel: the IMU chip's own samples at its output data rate (ODR).

The FC reads the chip once per physics step (`/imu`); a line above the FC's Nyquist
frequency shows there only as its alias. A scenario with `[imu_chip] log_raw = true`
(and the vibration on: bridge/imu_raw.py) also logs what the chip's output register holds
at every ODR tick, after its anti-alias filter: the C stage computes them per physics step
from copies of its chip and vibration state (bridge/src/imu_raw.h), so the FC's samples do
not change by a bit, and this module moves them into the log.

/imu_raw rows (RAW_DTYPE, one per ODR tick, n = odr_hz / physics rate per step):
sim_ns (the tick), accel_frd_m_s2[3], gyro_frd_rad_s[3] in the IMU's axes (its mounting
misalignment applied, clipped to full scale; without the per-read bias and white noise
the FC's samples carry). Like every row channel (tools/logs/log_schema.py) a message
holds a batch of rows with a `t_s` per row, so Foxglove plots
`/imu_raw.rows[:].gyro_frd_rad_s[0]` against `/imu_raw.t_s[:]`. The rate is declared in
the start metadata as config.imu_raw_hz (integrity.py checks the channel against it).

Who writes them: the log's sink of a run whose physics steps in this process (`fly
--processes 1`, the campaign): the rows are taken right after each step or batch, where
the sink logs /rotor (ImuRawLog wraps that hook). A two-process flight's log carries no
/imu_raw (its FC process writes the log): use `--processes 1` to look at the chip.
"""

from __future__ import annotations

import numpy as np

from silbridge.bridge.bridge_loop import BATCH_MAX_STEPS

RAW_IMU_CHANNEL = "/imu_raw"
RAW_DTYPE = np.dtype([
    ("sim_ns", "<i8"),                   # the ODR tick [ns of sim time]
    ("accel_frd_m_s2", "<f4", (3,)),     # after the AAF, IMU axes
    ("gyro_frd_rad_s", "<f4", (3,)),
])
assert RAW_DTYPE.itemsize == 32          # bridge/src/imu_raw.h sb_imu_raw_row
RATE_KEY = "imu_raw_hz"                  # start metadata config key of the channel's rate
# Steps the buffer holds between two takes: a take follows every step or batch, and a
# batch is at most BATCH_MAX_STEPS steps; twice that is margin. (A logged flight's batches
# are shorter still, cut where the FC's log cuts its own, but the buffer must not rely on it.)
BUFFER_STEPS = 2 * BATCH_MAX_STEPS


def declare_rate(metadata: dict, odr_hz: float) -> dict:
    """The start metadata with /imu_raw's rate, for a log that carries the channel."""
    metadata.setdefault("config", {})[RATE_KEY] = float(odr_hz)
    return metadata


def rows_per_step(sim) -> int:
    """ODR ticks per physics step of the simulator's scenario."""
    return int(sim.scenario.imu_chip.odr_hz * sim.dt_ns // 1_000_000_000)


class ImuRawLog:
    """Wraps the sink's per-step /rotor hook: after each step (`hook(sim_ns)`), each batch
    (`hook.write_rows`) or row (`hook.write`) it also moves the chip's rows the kernel wrote
    into /imu_raw. close() takes the last rows, unbinds the kernel and reports a loss."""

    def __init__(self, writer, kernel, n_per_step: int, rotor_hook):
        writer.declare(RAW_IMU_CHANNEL, RAW_DTYPE)
        self._writer = writer
        self._kernel = kernel
        self._rotor = rotor_hook
        self._rows = np.zeros(BUFFER_STEPS * n_per_step, RAW_DTYPE)
        self.dropped = 0
        self._last_ns = 0
        kernel.bind_imu_raw(self._rows)

    def __call__(self, sim_ns: int) -> None:
        self._rotor(sim_ns)
        self.take()

    def write(self, sim_ns: int, omega) -> None:
        self._rotor.write(sim_ns, omega)
        self.take()

    def write_rows(self, sim_ns, omega_rows) -> None:
        """A batch's rotor rows (bridge_loop's call where a hook takes rows), then one take
        for the whole batch instead of one per step."""
        self._rotor.write_rows(sim_ns, omega_rows)
        self.take()

    def take(self) -> None:
        n, self.dropped = self._kernel.take_imu_raw()
        if n:
            self._writer.write(RAW_IMU_CHANNEL, self._rows[:n])
            self._last_ns = int(self._rows[n - 1]["sim_ns"])

    def close(self) -> None:
        """The rows of the last step, then no more: the kernel must not write into a buffer
        nobody takes. A loss (a take came too late) goes to the log as an event."""
        self.take()
        self._kernel.bind_imu_raw(None)
        if self.dropped:
            self._writer.event(self._last_ns, "imu_raw",
                               f"{self.dropped} chip samples dropped: the buffer filled "
                               "between two takes")
