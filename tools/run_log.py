"""The logging sink a flight's loops call: loop hooks -> MCAP channels.

The loops know nothing of MCAP: they call `fc_batch`, `pwm_records` and
`event` on whatever sink they are given. Sensor records are logged as the FC
consumed them (wall stamps from the ring, so the log shows what the FC really
got, drops included); PWM as the bridge received them; FC status and per-cycle
timing from the FC side.
"""

from __future__ import annotations

import time

from .mcap_log import TIMING_DTYPE, LogWriter

TIMING_CHANNEL = "/timing"


class RunLogSink:
    def __init__(self, path, *, metadata: dict, fc_logs_pwm: bool = False):
        # With the FC in its own process the bridge's PWM never reaches this
        # writer: the FC then logs the PWM it published (fc_logs_pwm).
        self.fc_logs_pwm = fc_logs_pwm
        self.writer = LogWriter(path, metadata=metadata)
        self.writer.declare(TIMING_CHANNEL, TIMING_DTYPE)
        self._prev_consume = 0
        self.cost_ns = 0   # wall time spent inside the sink (for the <10 % budget)

    # -- FC side ------------------------------------------------------------
    def fc_batch(self, recs, pwm, status, consume_ns: int, pwm_wall_ns: int,
                 newest_sim_ns: int, newest_wall_ns: int) -> None:
        t0 = time.perf_counter_ns()
        period = consume_ns - self._prev_consume if self._prev_consume else 0
        self._prev_consume = consume_ns
        # One call per cycle: about half the cost of separate writes (tools/log_bench.py).
        self.writer.write_cycle(recs, status,
                                (newest_sim_ns, newest_wall_ns, consume_ns, pwm_wall_ns, period),
                                pwm if self.fc_logs_pwm else None)
        self.cost_ns += time.perf_counter_ns() - t0

    # -- bridge side ----------------------------------------------------------
    def pwm_records(self, pwm) -> None:
        t0 = time.perf_counter_ns()
        self.writer.write_records(pwm)
        self.cost_ns += time.perf_counter_ns() - t0

    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        self.writer.event(sim_ns, kind, text, **fields)

    def close(self, **summary) -> None:
        self.writer.close(**summary)
