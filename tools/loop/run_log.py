"""The logging sink a flight's loops call: loop hooks -> MCAP channels.

The loops know nothing of MCAP: they call `fc_batch` (or, offered
`capture_fc`, a per-cycle tick while the FC's C core appends the records
itself), `pwm_records` and `event` on whatever sink they are given. Sensor
records are logged as the FC consumed them (wall stamps from the ring, so the
log shows what the FC really got, drops included); PWM with fc_logs_pwm (what
`fly` and `fc --log` use) as the FC computed them, wall-stamped then, otherwise
as the bridge received them; FC status and per-cycle timing from the FC side.
"""

from __future__ import annotations

from silbridge.bridge import imu_raw
from silbridge.tools.logs.imu_raw_log import ImuRawLog, rows_per_step
from silbridge.tools.logs.imu_raw_log import declare_rate as declare_raw_rate
from silbridge.tools.logs.mcap_log import TIMING_DTYPE, LogWriter
from silbridge.tools.logs.rotor_log import RotorLog, declare_rate

TIMING_CHANNEL = "/timing"


class RunLogSink:
    """Loop hooks -> one LogWriter. Over shared memory the FC's C poll appends the
    records itself (capture_fc); measure the cost with `python -m silbridge.tools.logs.log_bench`."""

    def __init__(self, path, *, metadata: dict, fc_logs_pwm: bool = False, live=None,
                 rotor_rad_s=None, **writer_kw):
        self.writer = LogWriter(path, metadata=metadata, live=live, **writer_kw)
        self.live = live            # a tools.live_view.LiveView, closed with the sink
        self._cycles = 0
        self.writer.declare(TIMING_CHANNEL, TIMING_DTYPE)
        # With the FC in its own process the bridge's PWM never reaches this
        # writer: the FC then logs the PWM it published (fc_logs_pwm).
        # The bridge's hook: None when the FC logs the PWM (the bridge then skips it).
        self.pwm_records = None if fc_logs_pwm else self.writer.write_records
        self._fc_logs_pwm = fc_logs_pwm
        self._unbind = None
        # The bridge's per-step hook rotor(sim_ns) writing /rotor when this process also
        # steps the physics (rotor_rad_s: Simulator.rotor_rad_s; tools/logs/rotor_log.py).
        self.rotor = None if rotor_rad_s is None else RotorLog(self.writer, rotor_rad_s)
        self.imu_raw = None     # attach_imu_raw(): the chip's samples ride on the rotor hook

    def attach_imu_raw(self, sim) -> None:
        """Log the chip's ODR samples (/imu_raw, tools/logs/imu_raw_log.py) after each step
        this process's simulator takes; needs the rotor hook (rotor_rad_s given)."""
        self.imu_raw = ImuRawLog(self.writer, sim.kernel, rows_per_step(sim), self.rotor)
        self.rotor = self.imu_raw

    def capture_fc(self, core_c, timing: bool = False):
        """Let the FC's C core append what it consumes straight into the log's queues
        (Core.bind_log). Returns the per-cycle hook tick(sim_ns, imu_wall_ns,
        consume_wall_ns, pwm_wall_ns, loop_period_ns) or, with timing=True (the C poll
        writes the /timing rows too), flush() to call every hundred or so cycles. The FC
        loop uses this instead of fc_batch when the sink offers it: no Python work per
        record."""
        from silbridge.fc_sil.status import STATUS_DTYPE
        from silbridge.tools.logs.ftn_log import bind_ftn
        writer = self.writer

        def bind():
            queues, stage, status, tm = writer.capture_targets(STATUS_DTYPE)
            core_c.bind_log(queues, stage=stage, status=status, log_pwm=self._fc_logs_pwm,
                            timing=tm if timing else None)
            # FTN1/FTN2 from the in-flight FFT (bind_log unbinds them): only with FFT_ENABLE
            bind_ftn(writer, core_c, core_c.get_param("FFT_ENABLE") != 0)
        bind()
        writer.set_capture_rebind(bind)
        self._unbind = lambda: core_c.bind_log(None)
        return writer.capture_flush if timing else writer.cycle_tick

    def fc_batch(self, recs, pwm, status, timing) -> None:
        """FC side, once per cycle, when the FC loop does not capture in C (capture_fc);
        timing is the /timing row (sim_ns, imu_wall_ns, consume_wall_ns, pwm_wall_ns,
        loop_period_ns)."""
        self.writer.write_cycle(recs, status, timing, pwm if self._fc_logs_pwm else None)
        if self.live is not None:   # a live view: cut partial batches now and then
            self._cycles += 1
            if self._cycles >= LogWriter.CAPTURE_CHECK_TICKS:
                self._cycles = 0
                self.writer.capture_flush()

    # -- bridge side ----------------------------------------------------------
    # pwm_records(pwm): the PWM records the bridge received (bound in __init__; None
    # with fc_logs_pwm: the FC logs the PWM it published, stamped when computed).

    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        self.writer.event(sim_ns, kind, text, **fields)

    def close(self, **summary) -> None:
        if self._unbind is not None:    # the core must not append to a closed log
            self._unbind()
            self._unbind = None
        if self.imu_raw is not None:    # nor the kernel write rows nobody takes
            self.imu_raw.close()
            self.imu_raw = None
        try:
            self.writer.close(**summary)
        finally:
            if self.live is not None:
                self.live.close()
                self.live = None


def open_run_sink(path, metadata: dict, *, viz_hz: float | None = None, live: str | None = None,
                  out=print, sim=None) -> RunLogSink:
    """The sink of `fly`/`fc`: the log at `path` (None: no file, a live view only), its
    viewable channels at viz_hz (None: the default), a live view on `live` (HOST:PORT,
    '' for the default address, None for none), announced through out()."""
    view = None
    if live is not None:
        from silbridge.tools.logs.live_view import LiveView, parse_address
        view = LiveView(*parse_address(live))
        out(f"live view: {view.url} (Foxglove: Open connection -> Foxglove WebSocket)")
    kw = {} if viz_hz is None else {"viz_hz": viz_hz}
    try:
        raw = sim is not None and imu_raw.requested(sim.scenario)
        if sim is not None:     # the physics runs here: log its rotor speeds per step
            kw["rotor_rad_s"] = sim.rotor_rad_s
            metadata = declare_rate(dict(metadata), 1e9 / sim.dt_ns)
            if raw:             # and, asked for, the chip's samples at its data rate
                metadata = declare_raw_rate(metadata, sim.scenario.imu_chip.odr_hz)
        sink = RunLogSink(path, metadata=metadata, fc_logs_pwm=True, live=view, **kw)
        if raw:
            sink.attach_imu_raw(sim)
        return sink
    except BaseException:
        if view is not None:
            view.close()
        raise
