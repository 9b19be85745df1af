"""MAVFTP (FILE_TRANSFER_PROTOCOL) answered with NAKs, so clients fall back at once.

MAVProxy and QGC first try to fetch parameters as the file `@PARAM/param.pck`. We serve no
files: opening or listing anything is refused with FileNotFound, session operations with
InvalidSession, and session resets are acknowledged. A client then uses PARAM_REQUEST_LIST
immediately instead of waiting for its FTP timeout. The FTP capability bit is therefore not
advertised in AUTOPILOT_VERSION.

Payload layout (MAVLink FTP, little endian): seq u16, session u8, opcode u8, size u8,
req_opcode u8, burst_complete u8, padding u8, offset u32, data[239].
"""

from __future__ import annotations

import struct

from pymavlink.dialects.v20 import ardupilotmega as mav

HEADER = struct.Struct("<HBBBBBBI")
PAYLOAD_LEN = 251

OP_NONE, OP_TERMINATE, OP_RESET = 0, 1, 2
OP_ACK, OP_NAK = 128, 129
SESSION_OPS = frozenset({5, 7, 12, 15})              # read, write, truncate, burst read
ERR_FAIL, ERR_INVALID_SESSION, ERR_UNKNOWN_COMMAND, ERR_FILE_NOT_FOUND = 1, 4, 7, 10
PATH_OPS = frozenset({3, 4, 6, 8, 9, 10, 11, 13, 14})  # list, open, create, remove, ..., crc


def reply_payload(request: bytes | list[int]) -> bytes | None:
    """The reply payload for one request payload, or None if it is not a request."""
    req = bytes(request[:PAYLOAD_LEN]).ljust(PAYLOAD_LEN, b"\0")
    seq, session, opcode, _size, _req_op, _burst, _pad, _offset = HEADER.unpack_from(req)
    if opcode in (OP_ACK, OP_NAK):
        return None
    if opcode in (OP_TERMINATE, OP_RESET):
        out_op, data = OP_ACK, b""
    elif opcode in PATH_OPS:
        out_op, data = OP_NAK, bytes([ERR_FILE_NOT_FOUND])
    elif opcode in SESSION_OPS:
        out_op, data = OP_NAK, bytes([ERR_INVALID_SESSION])
    else:
        out_op, data = OP_NAK, bytes([ERR_UNKNOWN_COMMAND])
    head = HEADER.pack((seq + 1) & 0xFFFF, session, out_op, len(data), opcode, 0, 0, 0)
    return (head + data).ljust(PAYLOAD_LEN, b"\0")


def reply_message(msg, sysid: int, compid: int):
    """FILE_TRANSFER_PROTOCOL reply for a request addressed to us, else None."""
    if msg.target_system not in (0, sysid) or msg.target_component not in (0, compid):
        return None
    payload = reply_payload(msg.payload)
    if payload is None:
        return None
    return mav.MAVLink_file_transfer_protocol_message(0, msg.get_srcSystem(),
                                                      msg.get_srcComponent(), list(payload))
