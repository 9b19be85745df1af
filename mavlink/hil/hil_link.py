"""What every HIL channel shares, whatever carries it (a socket, a serial line).

`HilLink` holds a channel's codec, frame decoder and counters, and its lost state: a lost
channel has `eof` set and says why in `error`, and from then on sends and receives nothing.
Its subclasses (mavlink/hil/hil_channel.py, mavlink/hil/hil_serial.py) open the line and
move the bytes.

Writing to a stream link (TCP, serial) is `write_all`. Lockstep needs every frame, so a
batch is never cut short: a partial write is continued, and while the kernel takes nothing
the writer waits in select() (asleep, not spinning) for the peer to read. A peer that takes
nothing for `timeout_s` is hung or gone, and so is one whose write fails: the channel is
marked lost (`lost(why)`, so its eof and error tell later callers) and HilPeerLost stops the
run. Each link words those two endings for its own user (a TCP peer, a board on a serial
line), in a `WriteTexts`.
"""

from __future__ import annotations

import select
import time
from dataclasses import dataclass

from silbridge.mavlink.framing import FrameDecoder, RxCounters
from silbridge.mavlink.hil.hil_errors import HilPeerLost
from silbridge.mavlink.v2_frames import V2Frames

_WAIT_S = 0.01    # one select() wait: short, so the deadline is checked often


@dataclass(frozen=True)
class WriteTexts:
    """What a link says when a write ends it; `why` / `error` / `timeout_s` are filled in."""
    failed: str       # the channel's error when a write fails: "{why}" is the OS's reason
    failed_hint: str  # the HilPeerLost message then: "{error}" is the text above
    stalled: str      # the channel's error when nothing was taken: "{timeout_s:g}"
    stalled_hint: str  # the HilPeerLost message then: "{error}" is the text above


def write_all(write, waitable, data: bytes, timeout_s: float, lost, texts: WriteTexts) -> None:
    """Write all of data with write(view) -> bytes taken, waiting on waitable when blocked."""
    view = memoryview(data)
    deadline = None
    while view:
        try:
            n = write(view)
            view = view[n:]
            continue
        except (BlockingIOError, InterruptedError):
            pass
        except OSError as exc:
            error = texts.failed.format(why=exc.strerror or exc)
            lost(error)
            raise HilPeerLost(texts.failed_hint.format(error=error)) from None
        now = time.monotonic()
        deadline = deadline or now + timeout_s
        if now > deadline:
            error = texts.stalled.format(timeout_s=timeout_s)
            lost(error)
            raise HilPeerLost(texts.stalled_hint.format(error=error))
        select.select([], [waitable], [], _WAIT_S)


class HilLink:
    """A HIL channel's state: codec, decoder, counters, and whether (and why) it is lost."""

    def __init__(self, codec, send_timeout_s: float):
        self.codec = codec
        self.rx = RxCounters()
        self._decoder = FrameDecoder(codec, self.rx)
        self.send_timeout_s = send_timeout_s
        self.eof = False
        self.error = ""
        self.tx_frames = 0
        self.tx_bytes = 0
        self.tx_dropped = 0

    def shortcut(self, msg_class, build) -> None:
        """Receive msg_class (a pymavlink dialect class) as build(wire values), without
        pymavlink's message objects (mavlink/framing.py: bad frames still go to the codec)."""
        self._decoder.shortcut(V2Frames(self.codec, msg_class), build)

    def _lost(self, why: str) -> None:
        self.eof = True
        self.error = why

    def _readable(self, waitable, timeout_s: float) -> bool:
        """Worth reading: not lost, and (when timeout_s > 0) bytes came within timeout_s."""
        if self.eof:
            return False
        if timeout_s > 0:
            r, _, _ = select.select([waitable], [], [], timeout_s)
            return bool(r)
        return True

    def _send_all(self, frames: list, write, waitable, texts: WriteTexts) -> None:
        """All frames, in one complete write (write_all), counted."""
        data = b"".join(frames)
        write_all(write, waitable, data, self.send_timeout_s, self._lost, texts)
        self.tx_frames += len(frames)
        self.tx_bytes += len(data)
