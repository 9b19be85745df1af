"""Cut raw link bytes into MAVLink frames and classify each one.

pymavlink's own byte parser hides why a frame was dropped and, on a datagram link, carries a
truncated frame over into the next datagram (so one bad packet can spoil a good one). We split
frames ourselves and let the codec only decode complete frames:

* a datagram is parsed on its own: whatever is left incomplete at its end is one truncated
  (malformed) frame, and the next datagram starts clean;
* on a stream (TCP) the incomplete tail waits for more bytes;
* a run of bytes that starts no frame is one malformed item, and the scan resyncs on the next
  magic byte, so a valid frame after garbage in the same packet is still accepted.

Outcomes are counted per link (``RxCounters``) and a bad frame is never fatal.

A link may name messages it wants without pymavlink's message objects (`shortcut`): their
good frames are checked and unpacked by mavlink/v2_frames.py and built by the link's own
function (PX4's HIL_ACTUATOR_CONTROLS, once per lockstep step); any frame that path does not
vouch for goes through the codec as before, so it is counted the same way.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mav

MAGIC_V1 = 0xFE
MAGIC_V2 = 0xFD
HEADER_V1 = 6
HEADER_V2 = 10
CRC_LEN = 2
SIGNATURE_LEN = 13
MAX_FRAME_LEN = HEADER_V2 + 255 + CRC_LEN + SIGNATURE_LEN   # 280 bytes

_MAGIC_RE = re.compile(b"[\xfd\xfe]")
_KNOWN_IFLAGS = mav.MAVLINK_IFLAG_SIGNED


@dataclass(slots=True)
class RxCounters:
    rx_packets: int = 0       # datagrams or stream reads
    rx_bytes: int = 0
    rx_ok: int = 0
    rx_bad_crc: int = 0
    rx_malformed: int = 0     # garbage runs, truncated frames, bad flags, bad payloads
    rx_unknown: int = 0       # well-formed frame of a message id the dialect does not know

    def as_dict(self) -> dict[str, int]:
        return {k: getattr(self, k) for k in self.__slots__}


class FrameDecoder:
    """Owns one link's receive buffer; decodes with that link's codec."""

    def __init__(self, codec: mav.MAVLink, counters: RxCounters):
        self._codec = codec
        self._counters = counters
        self._buf = bytearray()
        self._shortcuts: dict = {}

    def shortcut(self, frames, build) -> None:
        """Decode frames.msg_id (a v2_frames.V2Frames) as build(wire values) instead."""
        self._shortcuts[frames.msg_id] = (frames, build)

    def feed(self, data: bytes, datagram: bool) -> list[mav.MAVLink_message]:
        """Decode all complete frames in data; return the good messages."""
        c = self._counters
        c.rx_packets += 1
        c.rx_bytes += len(data)
        if self._buf:
            self._buf += data
            buf = self._buf
        else:
            buf = data
        out: list[mav.MAVLink_message] = []
        n = len(buf)
        i = 0
        while i < n:
            b = buf[i]
            if b != MAGIC_V2 and b != MAGIC_V1:
                m = _MAGIC_RE.search(buf, i)
                i = n if m is None else m.start()
                c.rx_malformed += 1
                continue
            if b == MAGIC_V2:
                if n - i < 3:
                    break
                length = HEADER_V2 + buf[i + 1] + CRC_LEN
                if buf[i + 2] & mav.MAVLINK_IFLAG_SIGNED:
                    length += SIGNATURE_LEN
            else:
                if n - i < 2:
                    break
                length = HEADER_V1 + buf[i + 1] + CRC_LEN
            if n - i < length:
                break
            msg = self._decode(bytearray(buf[i:i + length]))
            if msg is not None:
                out.append(msg)
            i += length
        tail = buf[i:] if i < n else b""
        if datagram:
            if tail:
                c.rx_malformed += 1          # truncated frame at the end of a datagram
            self._buf = bytearray()
        else:
            self._buf = bytearray(tail)
        return out

    def _decode(self, frame: bytearray) -> mav.MAVLink_message | None:
        c = self._counters
        if frame[0] == MAGIC_V2:
            if frame[2] & ~_KNOWN_IFLAGS:
                c.rx_malformed += 1          # an incompatibility flag we cannot honour
                return None
            msg_id = frame[7] | (frame[8] << 8) | (frame[9] << 16)
            short = self._shortcuts.get(msg_id)
            if short is not None:
                values = short[0].check(frame)
                if values is not None:
                    c.rx_ok += 1
                    return short[1](values)
        else:
            msg_id = frame[5]
        if msg_id not in mav.mavlink_map:
            c.rx_unknown += 1
            return None
        try:
            msg = self._codec.decode(frame)
        except mav.MAVError as exc:
            if "CRC" in str(exc.message):
                c.rx_bad_crc += 1
            else:
                c.rx_malformed += 1
            return None
        except Exception:  # noqa: BLE001 - any decoder failure is a malformed frame, not a crash
            c.rx_malformed += 1
            return None
        c.rx_ok += 1
        return msg
