"""The logging sink a flight's loops call: loop hooks -> MCAP channels.

The loops know nothing of MCAP: they call `fc_batch`, `pwm_records` and
`event` on whatever sink they are given. Sensor records are logged as the FC
consumed them (wall stamps from the ring, so the log shows what the FC really
got, drops included); PWM as the bridge received them; FC status and per-cycle
timing from the FC side.
"""

from __future__ import annotations

from .mcap_log import TIMING_DTYPE, LogWriter

TIMING_CHANNEL = "/timing"


class RunLogSink:
    """Loop hooks -> one LogWriter. Cost per FC cycle ~1 us (one write_cycle call);
    measure the effect on a run by flying with and without --log."""

    def __init__(self, path, *, metadata: dict, fc_logs_pwm: bool = False):
        self.writer = LogWriter(path, metadata=metadata)
        self.writer.declare(TIMING_CHANNEL, TIMING_DTYPE)
        cycle = self.writer.write_cycle
        # With the FC in its own process the bridge's PWM never reaches this
        # writer: the FC then logs the PWM it published (fc_logs_pwm). The hook is
        # bound once here so a cycle costs one call and no branching.
        if fc_logs_pwm:
            self.fc_batch = lambda recs, pwm, status, timing: cycle(recs, status, timing, pwm)
        else:
            self.fc_batch = lambda recs, pwm, status, timing: cycle(recs, status, timing)

    # fc_batch(recs, pwm, status, timing): FC side, once per cycle; timing is the
    # /timing row (sim_ns, imu_wall_ns, consume_wall_ns, pwm_wall_ns, loop_period_ns).

    # -- bridge side ----------------------------------------------------------
    def pwm_records(self, pwm) -> None:
        self.writer.write_records(pwm)

    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        self.writer.event(sim_ns, kind, text, **fields)

    def close(self, **summary) -> None:
        self.writer.close(**summary)
