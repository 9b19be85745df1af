"""Which segment a flight uses: shared memory, or the MAVLink HIL transport over UDP / TCP.

tools/loop/flight.py and the `bridge` / `fc` commands ask here for "the bridge's segment" and
"the FC's segment"; with --transport udp|tcp they get the HIL ends (silbridge.mavlink), which
present the same surface, so the loops, checks, hashes and logs stay one code path.
"""

from __future__ import annotations

import math

from silbridge.shm import Segment
from silbridge.shm import lockstep as ls


def hil_origin(sim) -> tuple[int, int, int]:
    """NED zero of the run as (lat degE7, lon degE7, alt mm) for HIL_STATE_QUATERNION."""
    fdm = sim.fdm
    return (round(math.degrees(fdm.home_lat_rad) * 1e7), round(math.degrees(fdm.home_lon_rad) * 1e7),
            round((fdm.ground_alt_m + fdm.home_agl_m) * 1000.0))


HIL_PORT = 4560     # the simulator's listening port (PX4's convention; instance N: + N)


def bridge_segment(transport: str, name: str, sim, *, hil_addr: str | None = None,
                   default_port: int = HIL_PORT):
    """The bridge's segment (a context manager): Segment.create or a listening HilBridgeEnd."""
    if transport == "shm":
        return Segment.create(name)
    from silbridge.mavlink.hil.hil_transport import open_bridge_end
    return open_bridge_end(transport, hil_addr, origin=hil_origin(sim), default_port=default_port)


def bridge_address(seg) -> str:
    if isinstance(seg.addr, str):       # serial:/dev/...:BAUD
        return seg.addr
    host, port = seg.addr[0], seg.addr[1]
    return f"{host}:{port}"


def fc_segment(transport: str, name: str, *, hil_addr: str | None = None,
               timeout_s: float = 10.0, wait_config: bool = True):
    """The FC's segment: Segment.attach, or a HilFcEnd connected to the simulator."""
    if transport == "shm":
        return Segment.attach(name, timeout_s=timeout_s)
    from silbridge.mavlink.hil.hil_transport import open_fc_end
    end = open_fc_end(transport, hil_addr, connect_timeout_s=timeout_s)
    if wait_config:
        try:
            end.wait_config(timeout_s)
        except BaseException:
            end.close()
            raise
    return end


def guard_fc(loop) -> None:
    """On bad HIL input the FC's safe state: disarm the core; motors to MOT_PWM_MIN."""
    seg = loop.seg
    if not hasattr(seg, "on_bad_input"):
        return
    seg.pwm_min_us = int(round(loop.core.get_param("MOT_PWM_MIN")))

    def safe(reason: str) -> None:
        loop.core.disarm()
    seg.on_bad_input = safe


def fc_cli_args(transport: str, seg) -> list[str]:
    """`silbridge fc` options that reach this bridge."""
    if transport == "shm":
        return []
    return ["--transport", transport, "--link-addr", bridge_address(seg)]


def in_process_poll(fc, fc_seg, seg, sim, lockstep: bool):
    """fc_poll for `fly --processes 1`. Over HIL the step's frames cross a socket, so in
    lockstep wait for them (and for the answer) instead of racing the kernel."""
    if fc.polls_in_c or not lockstep:       # shared memory: the records are there at once
        return fc.poll

    def poll() -> None:
        fc_seg.sensors.wait(5.0)
        fc.poll()
        seg.wait_word(ls.FC_SIM_NS, sim.sim_ns, 5.0)
    return poll
