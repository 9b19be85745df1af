"""The MAVLink HIL transport: open either end by transport name ('udp' or 'tcp').

HilBridgeEnd (hil_bridge_end.py) and HilFcEnd (hil_fc_end.py) present the Segment surface the
bridge and FC loops use, over MAVLink 2 HIL messages (hil_codec.py, hil_pwm.py); the mapping
of the lockstep words onto messages is in those files and in docs/hil_transport.md. The
simulator listens (PX4's convention: TCP 4560), the autopilot connects.
"""

from __future__ import annotations

from silbridge.mavlink.hil.hil_bridge_end import HilBridgeEnd
from silbridge.mavlink.hil.hil_channel import DEFAULT_PORT, parse_addr
from silbridge.mavlink.hil.hil_errors import HilConfigError
from silbridge.mavlink.hil.hil_fc_end import HilFcEnd
from silbridge.mavlink.hil.hil_serial import is_serial

TRANSPORTS = ("shm", "udp", "tcp")

__all__ = ["HilBridgeEnd", "HilFcEnd", "open_bridge_end", "open_fc_end", "TRANSPORTS",
           "DEFAULT_PORT", "parse_addr", "check_transport"]


def check_transport(name: str) -> str:
    if name not in TRANSPORTS:
        raise HilConfigError(f"--transport {name!r}: choose one of {', '.join(TRANSPORTS)}")
    return name


def open_bridge_end(transport: str, addr: str | None = None, *, origin=(0, 0, 0),
                    default_port: int = DEFAULT_PORT,
                    attach_timeout_s: float = 15.0) -> HilBridgeEnd:
    """Listen for the FC. addr 'HOST:PORT' (default 127.0.0.1:default_port; port 0 = any), or
    'serial:/dev/PORT:BAUD' for a serial line (either transport name)."""
    check_transport(transport)
    if is_serial(addr):
        return HilBridgeEnd(serial=addr, origin=origin, attach_timeout_s=attach_timeout_s)
    host, port = parse_addr(addr)
    if not addr:
        port = default_port
    return HilBridgeEnd(host, port, datagram=check_transport(transport) == "udp", origin=origin,
                        attach_timeout_s=attach_timeout_s)


def open_fc_end(transport: str, addr: str | None = None, *, connect_timeout_s: float = 10.0,
                stall_s: float = 3.0, pwm_min_us: int = 1000, on_bad_input=None) -> HilFcEnd:
    """Connect to the simulator at addr (default 127.0.0.1:4560), or open 'serial:PATH:BAUD'."""
    if is_serial(addr):
        check_transport(transport)
        return HilFcEnd(serial=addr, connect_timeout_s=connect_timeout_s, stall_s=stall_s,
                        pwm_min_us=pwm_min_us, on_bad_input=on_bad_input)
    host, port = parse_addr(addr)
    return HilFcEnd(host, port, datagram=check_transport(transport) == "udp",
                    connect_timeout_s=connect_timeout_s, stall_s=stall_s, pwm_min_us=pwm_min_us,
                    on_bad_input=on_bad_input)
