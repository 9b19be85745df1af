"""tools/loop/stop_signals.py on its own: a polled stop, an unpolled stop, the second signal."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

from silbridge.tools.loop.stop_signals import StopRequest


def test_a_polling_loop_gets_a_flag_not_an_exception():
    stop = StopRequest()
    with stop.polling():
        stop.request(signal.SIGTERM)
    assert stop.requested and stop.name == "SIGTERM" and stop.exit_code() == 143


def test_without_a_polling_loop_the_signal_unwinds_the_stack():
    stop = StopRequest()
    with pytest.raises(KeyboardInterrupt):
        stop.request(signal.SIGINT)
    assert stop.exit_code() == 130


def test_a_soft_stop_from_a_parent_never_counts_as_a_second_signal():
    stop = StopRequest()
    with stop.polling():
        stop.request(signal.SIGINT)          # the terminal's Ctrl-C
        stop.request_soft("campaign stopped")  # then the parent's forwarded stop
    assert stop.count == 1 and stop.name == "SIGINT"


_SECOND = """
import signal, sys
from silbridge.tools.loop.stop_signals import StopRequest
stop = StopRequest()
stop.on_emergency(lambda: print("cleanup ran", flush=True))
with stop.polling():
    stop.request(signal.SIGINT)
    print("first: flag", stop.requested, flush=True)
    stop.request(signal.SIGINT)
    print("not reached", flush=True)
"""


def test_the_second_signal_runs_the_cleanups_and_exits_at_once():
    p = subprocess.run([sys.executable, "-c", _SECOND], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 130
    assert p.stdout.splitlines() == ["first: flag True", "cleanup ran"]
    assert "SIGINT again: exit now" in p.stderr


def test_a_campaign_run_whose_start_up_the_stop_broke_counts_as_never_begun(monkeypatch, tmp_path):
    """Native code (JSBSim's model loader) can turn the stop's KeyboardInterrupt into a
    SystemError: with the stop requested that is a run that never began, not a failure;
    without one the error stands."""
    from silbridge.tools.benchmark import campaign
    from silbridge.tools.loop import stop_signals

    spec = campaign.make_specs(["S1"], 1, 1.0, tmp_path)[0]

    def broken(_spec):
        raise SystemError("load_model returned a result with an exception set")

    monkeypatch.setattr(campaign, "_fly_and_score", broken)
    stop = StopRequest()
    monkeypatch.setattr(stop_signals, "STOP", stop)
    with pytest.raises(SystemError):
        campaign.run_one(spec)
    with stop.polling():
        stop.request(signal.SIGINT)
    assert campaign.run_one(spec).summary == {"interrupted": "SIGINT", "skipped": True}
