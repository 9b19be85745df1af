"""The transport comparison's long-lived children (tools/transport/transport_procs.py): one real FC child
serves several steps (shared memory and TCP, real bridge in this process), reports a failed
step and keeps serving, and a child that dies or stays silent is reported with its pid and
status within a bounded time instead of hanging the run. Also the retry rule and the
others'-CPU meter it uses."""

from __future__ import annotations

import os
import signal
import sys
import threading
import time

import pytest

from silbridge.tools.transport import transport_bench as tb
from silbridge.tools.transport.transport_load import OthersCpu, machine_busy_s, process_cpu_s
from silbridge.tools.transport.transport_procs import ChildLost, FcChild, JsonChild

STEP_S = 0.3


def test_one_fc_child_answers_two_steps_over_two_transports():
    with FcChild(fastcrc=True) as fc:
        a = tb.run_step("shm", 1000, STEP_S, fc, 1)
        b = tb.run_step("tcp", 2000, STEP_S, fc, 2)
        assert fc.alive()
    for r, hz in ((a, 1000), (b, 2000)):
        assert r["records_received"] > 0.8 * hz * STEP_S
        assert r["achieved_hz"]["pwm"] > 300.0
        assert r["latency_us"]["p50"] is not None
        assert r["others_cpu_cores"] >= 0.0
    assert a["fastcrc"] is False and b["fastcrc"] is True
    assert not fc.alive()          # close() asked it to quit


def test_a_failed_step_is_reported_and_the_child_keeps_serving():
    with FcChild(fastcrc=True) as fc:
        fc.start_step(1, "shm", f"tbench-missing-{os.getpid()}", attach_timeout_s=0.2)
        with pytest.raises(ChildLost, match="failed in step 1"):
            fc.step_result(1, timeout_s=20.0)
        r = tb.run_step("shm", 1000, STEP_S, fc, 2)
        assert r["records_received"] > 0


def test_a_dead_fc_child_is_reported_not_waited_for():
    with FcChild(fastcrc=True) as fc:
        os.kill(fc.pid, signal.SIGKILL)
        fc.proc.wait(timeout=5.0)
        t0 = time.monotonic()
        with pytest.raises(ChildLost, match=rf"pid {fc.pid}\) exited with status -9"):
            tb.run_step("shm", 1000, STEP_S, fc, 1)
        assert time.monotonic() - t0 < 5.0


def test_an_fc_child_dying_mid_step_ends_the_step_with_its_status():
    with FcChild(fastcrc=True) as fc:
        killer = threading.Timer(0.5, os.kill, (fc.pid, signal.SIGKILL))
        killer.start()
        t0 = time.monotonic()
        try:
            with pytest.raises(ChildLost, match=r"exited with status -9 while running step 1"):
                tb.run_step("shm", 1000, 30.0, fc, 1)
        finally:
            killer.cancel()
        assert time.monotonic() - t0 < 20.0    # ended by the death, not the step's 30 s


def test_a_silent_child_times_out_and_is_stopped():
    child = JsonChild([sys.executable, "-c", "import time; time.sleep(60)"], "a silent child")
    try:
        t0 = time.monotonic()
        with pytest.raises(ChildLost, match=r"did not answer within 0.3 s while starting"):
            child.read_msg(0.3, "starting")
        assert time.monotonic() - t0 < 2.0
        assert not child.alive()
    finally:
        child.close()


def _step(ok=False, imu=0.0, pwm=0.0, drop=0.0, others=0.0, hz=50_000):
    return {"ok": ok, "imu_hz_requested": hz, "achieved_hz": {"imu": imu, "pwm": pwm},
            "drop_ratio": drop, "others_cpu_cores": others}


def test_retry_only_narrow_misses_or_busy_machines():
    assert tb.retry_reason(_step(ok=True, imu=50_000, pwm=400)) is None
    assert tb.retry_reason(_step(imu=49_884, pwm=397.9)) == "narrow miss"      # measured, udp
    assert tb.retry_reason(_step(imu=47_410, pwm=377.3)) is None               # measured, tcp
    assert tb.retry_reason(_step(imu=49_900, pwm=399.0, drop=0.05)) is None    # many drops
    busy = tb.retry_reason(_step(imu=33_918, pwm=270.1, others=1.05))
    assert busy is not None and "1.05 cores" in busy


def test_others_cpu_sees_a_busy_process_that_is_not_ours():
    spin = JsonChild([sys.executable, "-c",
                      "import time\nt = time.monotonic() + 0.6\nwhile time.monotonic() < t: pass"],
                     "a spinning child")
    try:
        meter = OthersCpu([os.getpid()])
        meter.start()
        spin.proc.wait(timeout=10.0)
        assert meter.cores() > 0.3
    finally:
        spin.close()
    assert machine_busy_s() > 0.0
    assert process_cpu_s(os.getpid()) > 0.0
    assert process_cpu_s(spin.pid) == 0.0         # gone: counts nothing


def test_a_runner_whose_fc_child_died_exits_with_the_reason(capfd):
    cmd = [sys.executable, "-m", "silbridge.tools.transport.transport_child", "runner",
           "--steps", "1000,2000", "--seconds-per-rate", str(STEP_S)]
    with JsonChild(cmd, "the test runner") as runner:
        hello = runner.read_msg(60.0, "starting")
        assert hello["ready"] and hello["fc_pid"] != hello["pid"]
        os.kill(hello["fc_pid"], signal.SIGKILL)
        runner.send({"go": "shm"}, "being sent shm")
        with pytest.raises(ChildLost, match=r"exited with status 2 while measuring shm"):
            runner.read_msg(30.0, "measuring shm")
    err = capfd.readouterr().err
    assert f"transport shm: the FC child (pid {hello['fc_pid']}) exited with status -9" in err
