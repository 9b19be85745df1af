"""Stream rates that outlive a connection: ArduCopter's SRn_* parameters.

ArduCopter stores the rate of every REQUEST_DATA_STREAM in SRn_<group> of the serial port it
came in on (n) and starts that port's streams at the stored rates, at boot and for whoever
connects next. MAVProxy relies on it: it asks for its streams (REQUEST_DATA_STREAM ALL) once
at start-up, before it has seen the vehicle (so the request goes nowhere), and then only every
15 s; with the rates remembered, `status GLOBAL_POSITION_INT` right after a take-off shows the
current message, as against ArduCopter. We do the same per endpoint: endpoint n (the order of
the --gcs endpoints; every client of a TCP listener shares its listener's n) keeps SRn_*, for
n = 0..2, saved with the other parameters (--params FILE). Rates are stored clamped to the
parameters' 0..50 Hz.
"""

from __future__ import annotations

import logging

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.streams import STREAM_GROUPS, StreamSchedule

log = logging.getLogger(__name__)

SUFFIX = {
    mav.MAV_DATA_STREAM_RAW_SENSORS: "RAW_SENS",
    mav.MAV_DATA_STREAM_EXTENDED_STATUS: "EXT_STAT",
    mav.MAV_DATA_STREAM_RC_CHANNELS: "RC_CHAN",
    mav.MAV_DATA_STREAM_RAW_CONTROLLER: "RAW_CTRL",
    mav.MAV_DATA_STREAM_POSITION: "POSITION",
    mav.MAV_DATA_STREAM_EXTRA1: "EXTRA1",
    mav.MAV_DATA_STREAM_EXTRA2: "EXTRA2",
    mav.MAV_DATA_STREAM_EXTRA3: "EXTRA3",
}
ENDPOINTS = 3
MAX_HZ = 50


def _name(endpoint: int, stream_id: int) -> str | None:
    if not 0 <= endpoint < ENDPOINTS or stream_id not in SUFFIX:
        return None
    return f"SR{endpoint}_{SUFFIX[stream_id]}"


def apply_stored(params, endpoint: int, sched: StreamSchedule) -> None:
    """Start a new link's streams at the rates stored for its endpoint."""
    for stream_id in STREAM_GROUPS:
        name = _name(endpoint, stream_id)
        if name is None:
            continue
        try:
            hz = int(params.get(name)[0])
        except (KeyError, TypeError, ValueError):
            continue
        if hz > 0:
            sched.request_data_stream(stream_id, hz, True)


def remember(params, endpoint: int, stream_id: int, rate_hz: int, start: bool) -> list[str]:
    """Store a REQUEST_DATA_STREAM's rate; returns the names changed (for the .parm save)."""
    ids = list(SUFFIX) if stream_id == mav.MAV_DATA_STREAM_ALL else [stream_id]
    hz = min(MAX_HZ, max(0, int(rate_hz))) if start else 0
    if start and rate_hz <= 0:
        return []           # ArduCopter ignores a start with rate 0
    changed = []
    for sid in ids:
        name = _name(endpoint, sid)
        if name is None:
            continue
        try:
            if int(params.get(name)[0]) == hz:
                continue
            err = params.set(name, float(hz))
        except KeyError:
            continue
        if err:
            log.warning("cannot store %s=%d: %s", name, hz, err)
        else:
            changed.append(name)
    return changed
