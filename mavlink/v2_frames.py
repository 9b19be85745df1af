"""MAVLink 2 frames of one message type, packed and checked without pymavlink's objects.

Why: pymavlink builds a message object, a header object and a CRC object for every frame it
packs or decodes (about 16 us for one HIL_SENSOR on the 2-core VM). A lockstep bridge packs
one to three frames and decodes one per 4 ms PX4 step, on the path PX4 waits for; these
functions do the same work with one struct call and one CRC call.

The bytes are exactly those of `msg.pack(codec)` (tests/mavlink/test_v2_frames.py checks it
over random values): a 10-byte v2 header (incompatibility and compatibility flags 0, the
codec's current `seq`, `srcSystem` and `srcComponent`: `pack` reads, never advances, the
sequence number, as pymavlink's does), the payload in wire order (fields sorted by size, the
dialect's own `unpacker` struct) with trailing zero bytes trimmed down to at least one byte,
then CRC-16/MCRF4XX over header-after-magic + payload + the message's CRC_EXTRA byte.
The field layout, id and CRC_EXTRA come from the dialect's message class, never retyped.

Signed links are not handled here (nothing in silbridge signs its HIL link): `pack` refuses a
codec that signs, and `check` leaves frames of a codec with a key to the codec.

Why production keeps both this and pymavlink, and which is which: pymavlink is the dialect
(every message class, whose layout, id and CRC_EXTRA this module reads rather than retypes)
and the codec of every other message and of every frame this path does not vouch for (bad
CRC, flags, signing: mavlink/framing.py hands those to it, so they are counted as before).
This module is only the per-step fast path of the HIL links: HIL_SENSOR, HIL_GPS and
HIL_STATE_QUATERNION packed by `SensorEncoder` (mavlink/hil/hil_codec.py: our HIL link's and
PX4's sensor frames), HIL_ACTUATOR_CONTROLS checked as it arrives from PX4
(`HilLink.shortcut`, mavlink/hil/hil_link.py). The package keeps no slow copy of this path:
its oracle is pymavlink's own `msg.pack(codec)` and `codec.decode`, in
tests/mavlink/test_v2_frames.py.
"""

from __future__ import annotations

import struct

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.framing import HEADER_V2, MAGIC_V2

_HEADER = struct.Struct("<BBBBBBBHB")   # magic, len, incompat, compat, seq, sys, comp, id
assert _HEADER.size == HEADER_V2
_CRC = struct.Struct("<H")
try:                                    # CRC-16/MCRF4XX (X.25 without the final xor)
    from fastcrc.crc16 import mcrf4xx as _mcrf4xx
except ImportError:
    # `silbridge transport` hides fastcrc on purpose (its *-nofastcrc variants measure
    # pymavlink's pure-Python CRC): then take pymavlink's own, as its encoder does.
    def _mcrf4xx(data: bytes) -> int:
        return mav.x25crc(data).crc


class V2Frames:
    """Pack and check frames of one message class (pymavlink dialect) for one codec."""

    def __init__(self, codec, msg_class):
        self.codec = codec
        self.msg_id = msg_class.id
        self.payload = msg_class.unpacker        # the wire layout: fields sorted by size
        self._extra = bytes((msg_class.crc_extra,))
        self._id_lo = msg_class.id & 0xFFFF
        self._id_hi = msg_class.id >> 16

    def pack(self, *wire_values) -> bytes:
        """One frame of wire_values (the payload's fields in wire order, arrays flattened)."""
        c = self.codec
        if c.signing.sign_outgoing:
            raise ValueError("mavlink/v2_frames.py packs unsigned frames only: turn signing "
                             "off on this link's codec")
        payload = self.payload.pack(*wire_values).rstrip(b"\0") or b"\0"
        body = _HEADER.pack(MAGIC_V2, len(payload), 0, 0, c.seq, c.srcSystem, c.srcComponent,
                            self._id_lo, self._id_hi) + payload
        return body + _CRC.pack(_mcrf4xx(body[1:] + self._extra))

    def check(self, frame) -> tuple | None:
        """A complete v2 frame of this message -> its wire values, or None when this path
        cannot vouch for it (bad CRC, flags set, a codec that checks signatures): the caller
        then hands the frame to the codec, which decodes or rejects it as before."""
        if frame[2] or self.codec.signing.secret_key is not None:
            return None
        end = len(frame) - 2
        if _mcrf4xx(bytes(frame[1:end]) + self._extra) != frame[end] | (frame[end + 1] << 8):
            return None
        payload = bytes(frame[HEADER_V2:end])
        size = self.payload.size
        if len(payload) != size:     # trimmed zeros come back; a longer payload is cut
            payload = (payload + bytes(size))[:size]
        return self.payload.unpack(payload)
