"""The transport comparison's long-lived children and their line protocol (one JSON per line).

Spawning a fresh FC process per IMU step cost ~0.3 s of start-up around each 1 s measurement,
and each transport's runner another ~0.6 s before its first step. Now every child starts once,
all at the beginning (when nothing is being measured yet), and is driven over its stdin/stdout.

The FC child (one per runner, serves all its steps):

    child  -> runner   {"ready": true, "pid": P}                        once, after its imports
    runner -> child    {"step": K, "transport": T, "instance": N,
                        "hil_addr": A or null, "attach_timeout_s": S}  run step K
    child  -> runner   {"step": K, "result": {...}}                     the FC's measurements
                    or {"step": K, "error": "..."}                      failed; still serving
    runner -> child    {"quit": true}  (or end of stdin)                the child exits 0

The runner creates the segment (or listening HIL end) of step K, sends the step, then runs the
bridge; the child attaches, runs the real FC until the bridge says STOP and answers. Each step
gets a fresh FlightCore and segment, as a fresh process had; only the interpreter is reused.

A runner (one per CRC setting, spawned by the parent; it owns the bridge side):

    runner -> parent   {"ready": true, "pid": P, "fc_pid": Q}          once its FC child is up
    parent -> runner   {"go": "udp"}                                    measure one transport
    runner -> parent   {...the transport's summary...}                 or exits 2, says why
    parent -> runner   {"quit": true}  (or end of stdin)                it exits 0

Children keep the protocol on a private copy of their stdout and point fd 1 at stderr, so a
stray print (ours or a library's) cannot corrupt it. JsonChild, the parent's end, never waits
without a bound: a child that exits or stays silent raises ChildLost naming it, its pid, its
exit status and what it was doing.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import time


class ChildLost(Exception):
    """A child of the comparison exited, stopped answering or failed its work."""

    user_facing = True


# -- the child --------------------------------------------------------------------------------
def protocol_channel():
    """A private copy of this process's stdout for protocol lines; fd 1 (and sys.stdout) now
    lead to stderr, so nothing else printed can land between two protocol lines."""
    out_fd = os.dup(1)
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    return os.fdopen(out_fd, "w", buffering=1)


class ParentGone(Exception):
    """The protocol pipe is closed: whoever drove this child has exited."""


def send_line(proto, msg: dict) -> None:
    try:
        proto.write(json.dumps(msg) + "\n")
        proto.flush()
    except BrokenPipeError:
        raise ParentGone from None


def _requests(inp):
    """The parent's requests, one JSON object per line, until {"quit": true} or EOF."""
    for line in inp:
        line = line.strip()
        if not line:
            continue
        msg = json.loads(line)
        if msg.get("quit"):
            return
        yield msg


def serve_fc(inp=None, proto=None) -> int:
    """The FC child's main loop (`python -m silbridge.tools.transport.transport_child fc`)."""
    proto = protocol_channel() if proto is None else proto
    inp = sys.stdin if inp is None else inp
    try:
        return _serve_fc(inp, proto)
    except ParentGone:              # the runner is gone (its own error says why): just leave
        return 1


def _serve_fc(inp, proto) -> int:
    # Import the FC's modules before saying ready: no step pays for them.
    from silbridge.fc_sil import fc_loop  # noqa: F401
    from silbridge.mavlink.hil import hil_transport  # noqa: F401

    from silbridge.tools.loop import flight  # noqa: F401
    from silbridge.tools.transport.transport_bench import fc_child

    send_line(proto, {"ready": True, "pid": os.getpid()})
    for msg in _requests(inp):
        k = msg.get("step")
        try:
            result = fc_child(msg["transport"], msg["instance"], msg.get("hil_addr"),
                              attach_timeout_s=float(msg.get("attach_timeout_s", 15.0)))
        except Exception as e:            # reported to the runner, which decides; keep serving
            send_line(proto, {"step": k, "error": f"{type(e).__name__}: {e}"})
            continue
        send_line(proto, {"step": k, "result": result})
    return 0


def serve_runner(steps: list[int], duration_s: float, fastcrc: bool, inp=None,
                 proto=None) -> int:
    """A runner's main loop (`python -m silbridge.tools.transport.transport_child runner`)."""
    proto = protocol_channel() if proto is None else proto
    inp = sys.stdin if inp is None else inp
    try:
        return _serve_runner(steps, duration_s, fastcrc, inp, proto)
    except ParentGone:              # the parent is gone (its own error says why): just leave
        return 1


def _serve_runner(steps: list[int], duration_s: float, fastcrc: bool, inp, proto) -> int:
    with FcChild(fastcrc, wait=False) as fc:       # it starts while this process imports
        # Everything a step needs is imported before saying ready: no measurement pays for it.
        import silbridge.bridge.bridge_driver  # noqa: F401
        import silbridge.mavlink.hil.hil_transport  # noqa: F401

        from silbridge.tools.loop import flight  # noqa: F401
        from silbridge.tools.transport import transport_bench as tb

        fc.wait_ready()
        send_line(proto, {"ready": True, "pid": os.getpid(), "fc_pid": fc.pid})
        for msg in _requests(inp):
            variant = msg["go"]
            if tb.VARIANTS[variant][1] != fastcrc:
                raise ChildLost(f"transport {variant} sent to the runner with fastcrc={fastcrc}")
            try:
                summary = tb.run_variant(variant, steps, duration_s, fc)
            except Exception as e:
                if not getattr(e, "user_facing", False):
                    raise
                print(f"transport {variant}: {e}", file=sys.stderr, flush=True)
                return 2
            send_line(proto, summary)
    return 0


# -- the parent's end ------------------------------------------------------------------------
class JsonChild:
    """A child process that speaks JSON lines on its stdin/stdout. Every wait is bounded, and a
    child that exits or stays silent raises ChildLost naming it (`role`), its pid, its exit
    status and what it was doing."""

    def __init__(self, cmd: list[str], role: str):
        self.role = role
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self.pid = self.proc.pid
        self._fd = self.proc.stdout.fileno()
        self._buf = b""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def alive(self) -> bool:
        return self.proc.poll() is None

    def has_message(self) -> bool:
        """A line (or end of output) is waiting to be read; does not block."""
        return b"\n" in self._buf or self._readable(0.0)

    def send(self, msg: dict, what: str) -> None:
        try:
            self.proc.stdin.write((json.dumps(msg) + "\n").encode())
            self.proc.stdin.flush()
        except (BrokenPipeError, OSError, ValueError):
            raise self._lost(what) from None

    def read_msg(self, timeout_s: float, what: str) -> dict:
        t_end = time.monotonic() + timeout_s
        while b"\n" not in self._buf:
            left = t_end - time.monotonic()
            if left <= 0:
                self.proc.kill()
                self.proc.wait()
                raise ChildLost(f"{self.role} (pid {self.pid}) did not answer within "
                                f"{timeout_s:g} s while {what}; it was stopped. See its "
                                f"messages above")
            if not self._readable(min(left, 0.5)):
                continue
            chunk = os.read(self._fd, 65536)
            if not chunk:
                raise self._lost(what)
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        try:
            return json.loads(line)
        except ValueError:
            raise ChildLost(f"{self.role} (pid {self.pid}) wrote {line[:80]!r} on its "
                            f"protocol channel while {what}") from None

    def close(self, timeout_s: float = 5.0) -> None:
        """Ask the child to quit (end of its stdin), then make sure it is gone."""
        if self.proc.poll() is None:
            try:
                self.proc.stdin.write(b'{"quit": true}\n')
                self.proc.stdin.flush()
            except (BrokenPipeError, OSError, ValueError):
                pass
        for f in (self.proc.stdin, self.proc.stdout):
            try:
                f.close()
            except OSError:
                pass
        try:
            self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()

    def _readable(self, timeout_s: float) -> bool:
        r, _, _ = select.select([self._fd], [], [], timeout_s)
        return bool(r)

    def _lost(self, what: str) -> ChildLost:
        try:
            rc = self.proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            rc = None
        status = "closed its output" if rc is None else f"exited with status {rc}"
        return ChildLost(f"{self.role} (pid {self.pid}) {status} while {what}; see its "
                         f"messages above")


class FcChild(JsonChild):
    """A running FC child, ready when constructed: start_step(), then step_result()."""

    def __init__(self, fastcrc: bool = True, *, start_timeout_s: float = 60.0,
                 wait: bool = True):
        """wait=False returns at once (start other work, then wait_ready())."""
        cmd = [sys.executable, "-m", "silbridge.tools.transport.transport_child", "fc"]
        if not fastcrc:
            cmd.append("--no-fastcrc")
        super().__init__(cmd, "the FC child")
        self.steps_started = 0
        if wait:
            self.wait_ready(start_timeout_s)

    def wait_ready(self, timeout_s: float = 60.0) -> None:
        try:
            hello = self.read_msg(timeout_s, "starting")
            if not hello.get("ready"):
                raise ChildLost(f"the FC child (pid {self.pid}) sent {hello!r} instead of "
                                f"its ready line")
        except BaseException:
            self.close()
            raise

    def busy(self) -> bool:
        """True while the child runs a step: alive and no answer yet. The bridge's peer check,
        so a step the child gave up on (attach failed) ends at once instead of timing out."""
        return self.alive() and not self.has_message()

    def start_step(self, k: int, transport: str, instance: str, hil_addr: str | None = None,
                   attach_timeout_s: float = 15.0) -> None:
        self.steps_started += 1
        self.send({"step": k, "transport": transport, "instance": instance,
                   "hil_addr": hil_addr, "attach_timeout_s": attach_timeout_s},
                  f"being sent step {k}")

    def step_result(self, k: int, timeout_s: float) -> dict:
        """The child's answer to step k; ChildLost if it failed, died or stayed silent."""
        msg = self.read_msg(timeout_s, f"running step {k}")
        if msg.get("step") != k:
            raise ChildLost(f"the FC child (pid {self.pid}) answered {msg.get('step')!r} to "
                            f"step {k}; the protocol is out of step, rerun")
        if "error" in msg:
            raise ChildLost(f"the FC child failed in step {k}: {msg['error']}")
        return msg["result"]
