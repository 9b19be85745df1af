"""Ctrl-C and SIGTERM for every long-running command: stop cleanly, then at once.

A terminal's Ctrl-C sends SIGINT to the whole foreground process group (the
`fly` parent, its `fc` child, a campaign's workers), and `kill`, systemd or
CI send SIGTERM. Python's default turns SIGINT into a KeyboardInterrupt raised
wherever the main thread happens to be (half-way through writing a log batch,
inside `proc.communicate` while the child is still closing its log...) and
ignores nothing for SIGTERM: the process just dies, leaving its segment.

`install()` (called once by the command line) replaces both with one handler:
- first signal, while a run loop polls (`with stop.polling():`): set
  `stop.requested`; the loop stops at its next step, finishes and indexes the
  log, prints the summary marked interrupted; the command exits 128 + signal
  (130 for SIGINT, 143 for SIGTERM);
- first signal while nothing polls (start-up, loading JSBSim): raise
  KeyboardInterrupt there, so `with` blocks unwind and remove what they made;
- second signal: run the registered emergency clean-ups (unlink segments,
  terminate children; each a few system calls) and leave with os._exit. The
  log is still readable: the writer puts every channel on disk at least
  every half second (tools/logs/mcap_log.py) and `silbridge analyze` reads an
  unfinished log.

The loops themselves (bridge/bridge_driver.py, fc_sil/fc_loop.py) only read a
`requested` attribute of whatever stop object they are given; they import
nothing from here.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopRequest:
    """Process-wide stop state; see the module docstring."""

    def __init__(self):
        self.requested = False
        self.signum = 0
        self.count = 0
        self._polling = 0
        self._cleanups: dict[int, object] = {}
        self._next = 0
        self._installed = False
        self._label = None

    @property
    def name(self) -> str | None:
        """"SIGINT" / "SIGTERM" once requested, else None."""
        if not self.requested:
            return None
        return self._label or signal.Signals(self.signum).name

    def exit_code(self, default: int = 0) -> int:
        """128 + signal number once a signal stopped the run (shell convention), else default."""
        return 128 + self.signum if self.requested else default

    @contextlib.contextmanager
    def polling(self):
        """Declare that a loop polls `requested` at every step (signals then only set it)."""
        self._polling += 1
        try:
            yield self
        finally:
            self._polling -= 1

    def on_emergency(self, fn) -> int:
        """Register fn() to run if a second signal forces an immediate exit; returns a token."""
        self._next += 1
        self._cleanups[self._next] = fn
        return self._next

    def forget(self, token: int) -> None:
        self._cleanups.pop(token, None)

    @contextlib.contextmanager
    def emergency(self, fn):
        """on_emergency(fn) for the duration of a with block."""
        token = self.on_emergency(fn)
        try:
            yield
        finally:
            self.forget(token)

    def request(self, signum: int) -> None:
        """What the signal handler does (also callable directly, e.g. by tests)."""
        self.count += 1
        if self.count >= 2:
            self._emergency_exit(signum)
        self.requested = True
        self.signum = signum
        if not self._polling:
            raise KeyboardInterrupt(f"stopped by {signal.Signals(signum).name}")

    def request_soft(self, label: str, signum: int = signal.SIGTERM) -> None:
        """A stop asked for by a parent process (not a user's signal): never counts towards
        the second-signal emergency exit, so a worker that got the terminal's Ctrl-C too
        still finishes its log."""
        if self.requested:
            return
        self.requested = True
        self.signum = signum
        self._label = label
        if not self._polling:
            raise KeyboardInterrupt(label)

    def _emergency_exit(self, signum: int) -> None:
        for fn in list(self._cleanups.values())[::-1]:
            try:
                fn()
            except BaseException:  # noqa: BLE001 - leaving anyway; clean up what we can
                pass
        try:
            os.write(2, f"silbridge: {signal.Signals(signum).name} again: exit now "
                        f"(the log stays readable; `silbridge clean` removes leftovers)\n"
                        .encode())
        finally:
            os._exit(128 + signum)

    def install(self) -> "StopRequest":
        """Take over SIGINT and SIGTERM (main thread only; idempotent)."""
        if self._installed or threading.current_thread() is not threading.main_thread():
            return self
        for s in STOP_SIGNALS:
            signal.signal(s, self._handler)
        self._installed = True
        return self

    def _handler(self, signum, _frame) -> None:
        self.request(signum)


# One per process: a signal is process-wide, and so is the answer to it.
STOP = StopRequest()


def install() -> StopRequest:
    return STOP.install()


# A parent asks its workers to stop with this signal (tools/benchmark/campaign.py, the transport
# runners): a soft stop, which a worker that got the terminal's Ctrl-C too ignores.
PARENT_STOP_SIGNAL = signal.SIGUSR1


def install_worker() -> StopRequest:
    """install(), plus PARENT_STOP_SIGNAL as a soft stop from the parent process."""
    STOP.install()
    if threading.current_thread() is threading.main_thread():
        signal.signal(PARENT_STOP_SIGNAL,
                      lambda *_: STOP.request_soft("campaign stopped"))
    return STOP


class NeverStop:
    """The stop object of a loop nobody can interrupt (library use, tests)."""

    requested = False
    name = None
