"""The FC's C poll with its log capture (Core.poll_io + Core.bind_log, fc_sil/ext) against
the Python poll with the plain per-cycle path (sink.fc_batch -> write_cycle): the same
flight must give the same log, /timing rows included (but their wall-clock values)."""

import numpy as np

import silbridge.tools.loop.run_log as run_log
from silbridge.tools.loop import flight
from silbridge.tools.logs.mcap_log import read_log


class _PlainSink:
    """RunLogSink without capture_fc: the FC loop falls back to fc_batch per cycle."""

    def __init__(self, inner):
        self.fc_batch = inner.fc_batch
        self.pwm_records = inner.pwm_records
        self.event = inner.event
        self.close = inner.close
        self.rotor = inner.rotor


def _fly(tmp_path, monkeypatch, plain: bool):
    path = str(tmp_path / f"{'plain' if plain else 'capture'}.mcap")
    real = run_log.RunLogSink
    captured = []

    def make(*a, **k):
        sink = real(*a, **k)
        if plain:
            return _PlainSink(sink)
        orig = sink.capture_fc
        sink.capture_fc = lambda core_c, **kw: captured.append(1) or orig(core_c, **kw)
        return sink

    monkeypatch.setattr(run_log, "RunLogSink", make)
    flight.fly_one_process(flight.FlightOptions(scenario="S4", duration_s=12.0, log_path=path),
                           out=lambda s: None)
    monkeypatch.setattr(run_log, "RunLogSink", real)
    assert bool(captured) != plain
    return read_log(path)


def test_c_capture_logs_what_the_per_cycle_path_logs(tmp_path, monkeypatch):
    a = _fly(tmp_path, monkeypatch, plain=False)
    b = _fly(tmp_path, monkeypatch, plain=True)
    assert a.read_error is None and b.read_error is None
    assert sorted(a.channels) == sorted(b.channels)
    assert "/fc/status" in a.channels and "/imu" in a.channels
    for name, rows in a.channels.items():
        other = b.channels[name]
        assert len(rows) == len(other) > 0, name
        # Wall-clock stamps differ from run to run; everything else is lockstep-exact.
        for f in rows.dtype.names:
            if "wall" not in f and "period" not in f:
                np.testing.assert_array_equal(rows[f], other[f], err_msg=f"{name}.{f}")
