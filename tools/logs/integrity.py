"""Integrity check of a run log (paper section 4.2, step 8), before any metric.

A log passes when, channel by channel:
- it was read whole: no cut (killed writer), no CRC failure, and every
  channel holds as many rows as the writer's closing summary says it wrote;
- sim time is monotonic: strictly increasing for sensor, ground-truth, PWM
  and status rows; non-decreasing for /timing (an FC cycle without a new IMU
  sample repeats the time) and /setpoint. Events are not checked: they come
  from both sides of the loop and are logged when drained, not in time order;
- record sequence numbers (the per-kind `seq` of the shm records) have no
  repeats or steps back, and the gaps they show lose at most `max_loss_pct`
  of the samples (paper: drop/overwrite ratio 0, or < 0.5 %);
- the row count matches the expected count, rate x run duration, from the
  start metadata ("config": imu_hz, physics_hz (ground truth), pwm_hz (PWM
  and status), baro_hz, mag_hz, gnss_hz, duration_s; or "rates_hz":
  {channel: Hz}), within `max_loss_pct` (and 2 samples of rounding); a
  channel with a configured rate must be present;
- the effective rate (rows over time span) is within `rate_tol_pct` of the
  configured rate (paper: +-5 %);
- no "check" event reported a failure (fields ok=False, or without an ok
  field, a text saying "fail"/"FAILED").

`inspect_log` returns the per-channel figures with the problems; `check_log`
only the problems, each one sentence naming the channel and what is wrong
([] = the log is fit for analysis).
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np

from silbridge.tools.logs.mcap_log import RunLog

# Start-metadata config keys giving each channel's nominal rate (first found wins).
RATE_KEYS = {
    "/imu": ("imu_hz",),
    "/baro": ("baro_hz",),
    "/mag": ("mag_hz",),
    "/gnss": ("gnss_hz",),
    "/gt_att": ("gt_hz", "physics_hz"),
    "/gt_nav": ("gt_hz", "physics_hz"),
    "/rotor": ("rotor_hz",),     # only a log that declares it (tools/logs/rotor_log.py)
    "/imu_raw": ("imu_raw_hz",),  # likewise (tools/logs/imu_raw_log.py)
    "/pwm": ("pwm_hz",),
    "/fc/status": ("pwm_hz",),
}
# Channels whose sim time may repeat (several rows for one instant).
# /setpoint: a scenario may script two setpoints for one step; /fc/target: an external FC's
# reports are stamped when read, and two may be read at one physics step.
# /fc/ftn2: one row per peak slot at the same time, as ArduCopter writes FTN2
NON_STRICT = {"/timing", "/setpoint", "/fc/target", "/fc/ftn2"}
_FAILED = re.compile(r"\bfail(ed|s|ure)?\b", re.IGNORECASE)
ROUNDING_SLACK = 2  # samples: first/last sample conventions differ by one at each end


@dataclasses.dataclass
class ChannelStats:
    channel: str
    rows: int
    first_s: float | None
    last_s: float | None
    rate_hz: float | None         # configured nominal rate
    effective_hz: float | None    # (rows - 1) / (last - first)
    expected: int | None          # rate x duration
    missing: int | None           # expected - rows, >= 0
    seq_lost: int                 # samples missing between sequence numbers
    seq_repeats: int              # sequence numbers repeated or stepping back
    time_backwards: int           # sim time steps back (or repeats on strict channels)
    max_gap_s: float | None
    loss_pct: float | None        # max(missing, seq_lost) / expected (or rows + lost) in %


@dataclasses.dataclass
class IntegrityReport:
    channels: dict[str, ChannelStats]
    problems: list[str]
    duration_s: float | None      # the run duration the counts are checked against
    notes: list[str] = dataclasses.field(default_factory=list)   # how the run ended early
    # An unfinished log (its writer was killed: no closing summary, cut at the end) is
    # checked over what it holds; this says what is missing at the end, per channel:
    # {"reason", "planned_s", "channels": {name: {"last_s", "missing_s"}}}. None otherwise.
    unfinished: dict | None = None

    @property
    def ok(self) -> bool:
        return not self.problems

    def as_dict(self) -> dict:
        return {"ok": self.ok, "problems": list(self.problems), "duration_s": self.duration_s,
                "notes": list(self.notes), "unfinished": self.unfinished,
                "channels": {k: dataclasses.asdict(v) for k, v in self.channels.items()}}


def _config(log: RunLog) -> dict:
    cfg = log.metadata.get("config")
    return cfg if isinstance(cfg, dict) else {}


def expected_duration_s(log: RunLog) -> float | None:
    for source in (_config(log), log.metadata.get("scenario") or {}, log.metadata):
        if isinstance(source, dict) and source.get("duration_s") is not None:
            return float(source["duration_s"])
    return None


def nominal_rates_hz(log: RunLog) -> dict[str, float]:
    """Configured rate per channel, from the start metadata."""
    cfg = _config(log)
    rates = {}
    for channel, keys in RATE_KEYS.items():
        for key in keys:
            if cfg.get(key):
                rates[channel] = float(cfg[key])
                break
    explicit = cfg.get("rates_hz") or log.metadata.get("rates_hz") or {}
    rates.update({ch: float(hz) for ch, hz in explicit.items() if hz})
    return rates


def _check_passed(event: dict) -> bool:
    """A check event passed unless its fields say ok=False or its text says it failed."""
    ok = (event.get("fields") or {}).get("ok")
    if ok is not None:
        return bool(ok)
    return _FAILED.search(event["text"]) is None


def _seq_figures(seq: np.ndarray) -> tuple[int, int]:
    """(lost, repeats) from a per-kind uint32 sequence that may wrap at 2**32."""
    if len(seq) < 2:
        return 0, 0
    step = (np.diff(seq.astype(np.int64)) % (1 << 32))
    back = (step == 0) | (step >= (1 << 31))
    lost = int(np.sum(step[~back] - 1))
    return lost, int(np.count_nonzero(back))


def _channel_stats(name: str, rows: np.ndarray, rate_hz: float | None,
                   duration_s: float | None) -> ChannelStats:
    n = len(rows)
    t_ns = rows["sim_ns"] if "sim_ns" in rows.dtype.names else np.zeros(0, np.int64)
    first = last = eff = gap = None
    backwards = 0
    if len(t_ns):
        first, last = t_ns[0] * 1e-9, t_ns[-1] * 1e-9
        d = np.diff(t_ns)
        backwards = int(np.count_nonzero(d < 0 if name in NON_STRICT else d <= 0))
        if len(d):
            gap = float(d.max()) * 1e-9
        if n >= 2 and last > first:
            eff = (n - 1) / (last - first)
    lost, repeats = _seq_figures(rows["seq"]) if "seq" in rows.dtype.names else (0, 0)
    expected = missing = None
    if rate_hz and duration_s:
        expected = int(math.floor(rate_hz * duration_s + 1e-6))
        missing = max(expected - n, 0)
    denom = expected if expected else n + lost
    worst = max(missing or 0, lost)
    loss = 100.0 * worst / denom if denom else None
    return ChannelStats(name, n, first, last, rate_hz, eff, expected, missing, lost, repeats,
                        backwards, gap, loss)


def unfinished_reason(log: RunLog) -> str | None:
    """Why a log whose writer never finished is incomplete, or None (whole, or damaged)."""
    if log.corrupt:
        return None        # damaged data is not an unfinished run: --force only
    if log.truncated:
        return f"the writer never finished (killed run?): {log.read_error}"
    if log.end is None:
        return "the writer never finished (no closing summary)"
    return None


@dataclasses.dataclass
class _RunSpan:
    """The sim time a log's counts are checked over, and what the log's ending says."""
    duration_s: float | None
    unfinished: str | None        # why the writer never finished, None if it did
    problems: list[str]
    notes: list[str]


def inspect_log(log: RunLog, *, max_loss_pct: float = 0.5,
                rate_tol_pct: float = 5.0) -> IntegrityReport:
    span = _run_span(log)
    problems, notes = span.problems, span.notes
    rates = nominal_rates_hz(log)
    stats: dict[str, ChannelStats] = {}
    for name in sorted(set(log.channels) | set(rates)):
        rows = log.channels.get(name)
        if rows is None or not len(rows):
            _no_rows(name, rates, span.duration_s, problems, notes)
            continue
        # Each channel is checked over the time it covers: up to its own last row in an
        # unfinished log (the writer flushes every channel at least every half second, so a
        # killed run loses at most that much of each), up to the stop in an interrupted one.
        duration = span.duration_s
        if span.unfinished is not None and "sim_ns" in rows.dtype.names:
            duration = int(rows["sim_ns"][-1]) * 1e-9
        st = stats[name] = _channel_stats(name, rows, rates.get(name), duration)
        problems += _channel_problems(st, duration, max_loss_pct, rate_tol_pct)
    problems += _writer_problems(log) + _failed_checks(log)
    return IntegrityReport(stats, problems, span.duration_s, notes,
                           _missing_at_end(span, stats))


def _run_span(log: RunLog) -> _RunSpan:
    span = _RunSpan(expected_duration_s(log), unfinished_reason(log), [], [])
    if span.unfinished is not None:
        span.notes.append(f"log unfinished: {span.unfinished}; metrics cover what it holds")
    elif log.read_error:
        span.problems.append(f"log is corrupt: {log.read_error}; its data ends at "
                             f"{log.duration_s():.3f} s")
    # A run that ended early on purpose (Ctrl-C: "interrupted") or because its other half
    # died ("aborted", e.g. the bridge was killed) is checked up to where it ended.
    end = log.end or {}
    early = ("interrupted by " + str(end["interrupted"])) if end.get("interrupted") else \
        ("aborted: " + str(end["aborted"])) if end.get("aborted") else None
    if early and end.get("end_sim_ns") is not None:
        stopped = int(end["end_sim_ns"]) * 1e-9
        span.notes.append(f"run {early} at {stopped:.3f} s of sim time"
                          + (f" (planned {span.duration_s:g} s)" if span.duration_s else ""))
        span.duration_s = stopped
    return span


def _no_rows(name: str, rates: dict[str, float], duration: float | None, problems: list[str],
             notes: list[str]) -> None:
    """A channel without rows: a problem only if its rate owed some over the run."""
    # A stream owes no rows over a span too short for more samples than the rounding
    # slack (as with rows below): a run stopped (Ctrl-C) just after it started, e.g.
    # a campaign's second worker, or GNSS whose first fix comes one period + latency in.
    due = None if duration is None or name not in rates else \
        int(math.floor(rates[name] * duration + 1e-6))
    owed = name in rates and (due is None or due > ROUNDING_SLACK)
    if owed:
        problems.append(f"{name}: no rows, but the run config sets {rates[name]:g} Hz")
    elif name in rates:
        notes.append(f"{name}: no rows (the run ended within its first samples)")


def _channel_problems(s: ChannelStats, span: float | None, max_loss_pct: float,
                      rate_tol_pct: float) -> list[str]:
    name, problems = s.channel, []
    if s.time_backwards:
        kind = "steps back" if name in NON_STRICT else "does not increase"
        problems.append(f"{name}: sim time {kind} {s.time_backwards} times "
                        "(timestamps must be monotonic)")
    if s.seq_repeats:
        problems.append(f"{name}: sequence number repeats or steps back "
                        f"{s.seq_repeats} times")
    if s.expected:
        slack = max(ROUNDING_SLACK, s.expected * max_loss_pct / 100.0)
        if s.missing and s.missing > slack:
            problems.append(f"{name}: {s.rows} of {s.expected} expected samples "
                            f"({s.missing} missing, {100.0 * s.missing / s.expected:.2f} %; "
                            f"{s.rate_hz:g} Hz for {span:g} s; data ends at "
                            f"{s.last_s:.3f} s)")
        elif s.rows - s.expected > slack:
            problems.append(f"{name}: {s.rows} samples, {s.rows - s.expected} more than "
                            f"the {s.expected} that {s.rate_hz:g} Hz for {span:g} s gives")
    seq_pct = 100.0 * s.seq_lost / (s.rows + s.seq_lost) if s.seq_lost else 0.0
    if seq_pct > max_loss_pct:
        problems.append(f"{name}: {s.seq_lost} samples lost between sequence numbers "
                        f"({seq_pct:.2f} % > {max_loss_pct:g} %)")
    if s.rate_hz and s.effective_hz and \
            abs(s.effective_hz - s.rate_hz) > s.rate_hz * rate_tol_pct / 100.0:
        problems.append(f"{name}: effective rate {s.effective_hz:.1f} Hz is off the "
                        f"configured {s.rate_hz:g} Hz by more than {rate_tol_pct:g} %")
    return problems


def _writer_problems(log: RunLog) -> list[str]:
    """What the writer's closing summary says went wrong, or does not match the file."""
    problems = []
    if log.end is not None:
        for kind, n in (log.end.get("unknown_records") or {}).items():
            problems.append(f"{n} records of unknown kind {kind} reached the writer "
                            "and were not logged")
    if log.end is not None and not log.read_error:
        for name, written in (log.end.get("rows") or {}).items():
            held = len(log.channels.get(name, ()))
            if held != written:
                problems.append(f"{name}: the writer wrote {written} rows, the log holds {held}")
    return problems


def _failed_checks(log: RunLog) -> list[str]:
    return [f"run check failed at {e['sim_ns'] * 1e-9:.3f} s: {e['text']}"
            for e in log.events if e["kind"] == "check" and not _check_passed(e)]


def _missing_at_end(span: _RunSpan, stats: dict[str, ChannelStats]) -> dict | None:
    """IntegrityReport.unfinished: per channel, how much is missing at the end."""
    if span.unfinished is None:
        return None
    duration = span.duration_s
    return {"reason": span.unfinished, "planned_s": duration, "channels": {
        name: {"last_s": st.last_s,
               # Only streams with a rate are due until the end (not /setpoint, /events).
               "missing_s": (max(duration - st.last_s, 0.0) if duration is not None
                             and st.last_s is not None and st.rate_hz else None)}
        for name, st in stats.items()}}


def check_log(log: RunLog, *, max_loss_pct: float = 0.5, rate_tol_pct: float = 5.0) -> list[str]:
    """Problems that make a log unfit for analysis, one sentence each ([] = ok)."""
    return inspect_log(log, max_loss_pct=max_loss_pct, rate_tol_pct=rate_tol_pct).problems
