"""Ctrl-C, SIGTERM and SIGKILL on the long-running commands (issue 15).

Each test starts the real command line in a new session (a process group of its own, as a
terminal's foreground job) and signals it the way a terminal (os.killpg: every process of
the group) or `kill` (the parent only) does. Then: the exit status, the summary marked
interrupted, `silbridge analyze` on the log without --force, and no segment left in /dev/shm.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

SB = [sys.executable, "-m", "silbridge.tools"]


class Job:
    """One command in its own process group; output to files (no pipe can fill up)."""

    def __init__(self, args, tmp: Path, tag: str, *, cmd=None):
        self.out_path = tmp / f"{tag}.out"
        self.err_path = tmp / f"{tag}.err"
        self._out = open(self.out_path, "w")
        self._err = open(self.err_path, "w")
        self.proc = subprocess.Popen(cmd or SB + list(args), stdout=self._out,
                                     stderr=self._err, text=True, start_new_session=True)

    def text(self) -> str:
        return self.out_path.read_text() + self.err_path.read_text()

    def wait_for(self, needle: str, timeout_s: float = 90.0) -> None:
        end = time.monotonic() + timeout_s
        while needle not in self.text():
            assert self.proc.poll() is None, f"exited early:\n{self.text()[-3000:]}"
            assert time.monotonic() < end, f"no {needle!r} within {timeout_s} s:\n" \
                                           f"{self.text()[-3000:]}"
            time.sleep(0.05)

    def killpg(self, sig) -> None:
        os.killpg(self.proc.pid, sig)

    def finish(self, timeout_s: float = 60.0) -> int:
        try:
            rc = self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.killpg(signal.SIGKILL)
            self.proc.wait()
            raise AssertionError(f"still running {timeout_s} s after the signal:\n"
                                 f"{self.text()[-3000:]}")
        finally:
            self._out.close()
            self._err.close()
        return rc

    def summary(self) -> dict:
        lines = [ln for ln in self.out_path.read_text().splitlines() if ln.startswith("{")]
        assert lines, f"no JSON summary:\n{self.text()[-3000:]}"
        return json.loads(lines[-1])

    def cleanup(self) -> None:
        if self.proc.poll() is None:
            self.killpg(signal.SIGKILL)
            self.proc.wait()


def analyze(log: Path) -> dict:
    r = subprocess.run(SB + ["analyze", str(log), "--json"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, f"analyze refused {log}:\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}"
    return json.loads(r.stdout)


def segment_gone(instance: str) -> bool:
    return not os.path.exists(f"/dev/shm/silbridge-{instance}")


@pytest.fixture
def instance():
    return f"sig-{os.getpid()}-{uuid.uuid4().hex[:6]}"


@pytest.mark.parametrize("processes,sig,group", [
    (2, signal.SIGINT, True),     # Ctrl-C in a terminal: parent and FC child both get it
    (1, signal.SIGINT, True),
    (2, signal.SIGTERM, False),   # `kill PID` of the parent alone
])
def test_fly_stops_cleanly_on_a_signal(tmp_path, instance, processes, sig, group):
    log = tmp_path / "run.mcap"
    job = Job(["fly", "--realtime", "--no-mavlink", "--duration", "120", "--processes",
               str(processes), "--instance", instance, "--log", str(log), "--json"],
              tmp_path, "fly")
    try:
        job.wait_for("check drops")
        time.sleep(1.0)
        if group:
            job.killpg(sig)
        else:
            os.kill(job.proc.pid, sig)
        rc = job.finish()
    finally:
        job.cleanup()
    assert rc == 128 + sig, job.text()[-3000:]
    s = job.summary()
    assert s["interrupted"] == signal.Signals(sig).name
    assert 1.0 < s["sim_s"] < 60.0                   # stopped at once, not at the end
    report = analyze(log)
    assert report["ok"], report["problems"]
    assert any("interrupted" in n for n in report["integrity"]["notes"])
    assert report["integrity"]["unfinished"] is None  # closed and indexed, not cut
    assert report["integrity"]["channels"]["/imu"]["rows"] > 500
    assert segment_gone(instance)
    assert not os.path.exists(f"{log}.meta.json")


# Stands in for the user's shell: starts both programs in its process group, survives the
# Ctrl-C itself (as an interactive shell does) and reports each program's exit status.
_SHELL = """
import json, signal, subprocess, sys
bridge_cmd, fc_cmd, out = json.loads(sys.argv[1])
bridge = subprocess.Popen(bridge_cmd, stdout=open(out + ".bridge.out", "w"),
                          stderr=open(out + ".bridge.err", "w"))
fc = subprocess.Popen(fc_cmd, stdout=open(out + ".fc.out", "w"), stderr=open(out + ".fc.err", "w"))
signal.signal(signal.SIGINT, lambda *a: None)
print(json.dumps({"bridge": bridge.wait(), "fc": fc.wait()}), flush=True)
"""


def test_bridge_and_fc_programs_stop_on_ctrl_c(tmp_path, instance):
    """`silbridge bridge` and `silbridge fc` started from one shell: one Ctrl-C stops both."""
    log = tmp_path / "fc.mcap"
    out = str(tmp_path / "pair")
    cmds = [SB + ["bridge", "--realtime", "--duration", "120", "--instance", instance, "--json"],
            SB + ["fc", "--instance", instance, "--no-mavlink", "--json", "--log", str(log)],
            out]
    shell = Job([], tmp_path, "shell", cmd=[sys.executable, "-c", _SHELL, json.dumps(cmds)])
    bridge_err = Path(out + ".bridge.err")
    try:
        end = time.monotonic() + 90
        while not (bridge_err.exists() and "check drops" in bridge_err.read_text()):
            assert shell.proc.poll() is None and time.monotonic() < end, shell.text()
            time.sleep(0.05)
        time.sleep(0.5)
        shell.killpg(signal.SIGINT)
        assert shell.finish() == 0
    finally:
        shell.cleanup()
    rcs = json.loads(shell.out_path.read_text().strip().splitlines()[-1])
    assert rcs == {"bridge": 130, "fc": 130}, Path(out + ".bridge.err").read_text()[-2000:] + \
        Path(out + ".fc.err").read_text()[-2000:]
    bridge_sum = json.loads(Path(out + ".bridge.out").read_text().strip().splitlines()[-1])
    fc_sum = json.loads(Path(out + ".fc.out").read_text().strip().splitlines()[-1])
    assert bridge_sum["interrupted"] == "SIGINT"
    assert fc_sum["interrupted"] in ("SIGINT", "bridge")
    report = analyze(log)
    assert report["ok"], report["problems"]
    assert segment_gone(instance)


def test_bridge_sigterm_removes_its_segment(tmp_path, instance):
    """SIGTERM to a bridge still waiting for its FC: exit 143, segment gone."""
    bridge = Job(["bridge", "--duration", "60", "--instance", instance], tmp_path, "bridge")
    try:
        bridge.wait_for("segment")
        assert not segment_gone(instance)
        os.kill(bridge.proc.pid, signal.SIGTERM)
        rc = bridge.finish()
    finally:
        bridge.cleanup()
    assert rc == 143, bridge.text()[-3000:]
    assert "INTERRUPTED" in bridge.text()
    assert segment_gone(instance)


def test_second_ctrl_c_exits_at_once_with_a_readable_log(tmp_path, instance):
    """Two Ctrl-C in a row: the processes leave at once; the log is unfinished or closed,
    readable by analyze without --force; the segment is unlinked by the emergency path."""
    log = tmp_path / "run.mcap"
    job = Job(["fly", "--realtime", "--no-mavlink", "--duration", "120", "--instance",
               instance, "--log", str(log)], tmp_path, "fly")
    try:
        job.wait_for("check drops")
        time.sleep(1.5)
        job.killpg(signal.SIGINT)
        job.killpg(signal.SIGINT)
        rc = job.finish(timeout_s=30)
    finally:
        job.cleanup()
    assert rc == 130, job.text()[-3000:]
    report = analyze(log)
    assert report["integrity"]["channels"]["/imu"]["rows"] > 500
    assert segment_gone(instance)


@pytest.mark.parametrize("victim", ["fc", "bridge", "single"])
def test_sigkill_keeps_every_channel_to_the_last_second(tmp_path, victim):
    """SIGKILL of each process of a real-time logged run: every channel's rows reach the
    file to within ~1 s of the kill (bound generous: 2 s), analyze reads the log as is."""
    from silbridge.tools.logs.kill_check import run

    res = run(victim, 2.0, tmp_path)
    assert not res["missing_channels"], res
    for name, c in res["channels"].items():
        assert c["lag_s"] < 2.0 + c["period_s"], (name, c)
    assert res["analyze_exit"] == 0, res
    if victim == "fc":
        assert not res["segment_left"]   # the bridge survived and unlinked it


@pytest.mark.parametrize("jobs,sig,group", [(2, signal.SIGINT, True), (2, signal.SIGTERM, False),
                                            (1, signal.SIGINT, True)])
def test_bench_stops_cleanly_and_keeps_what_ran(tmp_path, jobs, sig, group):
    """`silbridge bench`: a signal stops the runs in flight at their next step (their logs
    closed, marked interrupted, analyze accepts them), starts no new run, exits 128+sig."""
    out = tmp_path / "bench"
    job = Job(["bench", "--scenarios", "S1", "--runs", "4", "--duration", "120", "--jobs",
               str(jobs), "--out", str(out), "--keep-logs", "all", "--no-report", "--json"],
              tmp_path, "bench")
    try:
        first = out / "logs" / "full" / "S1_run00.mcap"
        end = time.monotonic() + 120
        while not (first.exists() and first.stat().st_size > 300_000):
            assert job.proc.poll() is None and time.monotonic() < end, job.text()[-3000:]
            time.sleep(0.1)
        if group:
            job.killpg(sig)
        else:
            os.kill(job.proc.pid, sig)
        rc = job.finish(timeout_s=90)
    finally:
        job.cleanup()
    assert rc == 128 + sig, job.text()[-3000:]
    s = job.summary()
    assert s["interrupted"] == signal.Signals(sig).name
    assert s["runs_done"] < s["runs_planned"] == 4
    assert s["partial_logs"], s
    for log in s["partial_logs"]:
        report = analyze(Path(log))
        assert any("interrupted" in n for n in report["integrity"]["notes"]), report
    # The workers' segments (bench-<worker pid>-...) are gone: none carries this session's tag.
    from silbridge.shm.leftovers import list_segments, own_tag
    assert not [x.name for x in list_segments("bench-*") if x.tag == own_tag()]


def test_transport_stops_on_ctrl_c_without_leftovers(tmp_path):
    """`silbridge transport`: Ctrl-C while a transport is measured stops every child; the
    report says interrupted; exit 130; none of its segments stays (conftest checks too)."""
    job = Job(["transport", "--imu-max", "20000", "--seconds-per-rate", "2", "--json"], tmp_path,
              "tr")
    try:
        job.wait_for("IMU     1,000 Hz", timeout_s=120)
        job.killpg(signal.SIGINT)
        rc = job.finish(timeout_s=60)
    finally:
        job.cleanup()
    assert rc == 130, job.text()[-3000:]
    assert job.summary()["interrupted"] == "SIGINT"
    assert "again" not in job.text()      # no child took the stop for a second Ctrl-C
