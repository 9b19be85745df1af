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
        # With the FC in its own process the bridge's PWM never reaches this
        # writer: the FC then logs the PWM it published (fc_logs_pwm). The hook is
        # the writer's own method, so a cycle costs one call.
        self.fc_batch = self.writer.cycle_hook(fc_logs_pwm)
        self.pwm_records = self.writer.write_records

    # fc_batch(recs, pwm, status, timing): FC side, once per cycle; timing is the
    # /timing row (sim_ns, imu_wall_ns, consume_wall_ns, pwm_wall_ns, loop_period_ns).

    # -- bridge side ----------------------------------------------------------
    # pwm_records(pwm): the PWM records the bridge received (bound in __init__).

    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        self.writer.event(sim_ns, kind, text, **fields)

    def close(self, **summary) -> None:
        self.writer.close(**summary)
