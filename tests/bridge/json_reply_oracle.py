"""The ArduPilot JSON reply in readable Python: the oracle of the C `_step.json_reply`.

The hot path (bridge/autopilots/ardupilot/physics.py) sends what bridge/src/step_json.c
writes; this reads the same step records with struct (shm/record_structs.py), averages the
IMU samples, converts the quaternion and %-formats the line with the protocol's own
`encode_values`, so test_json_reply.py can hold the two to the same bytes.
"""

from __future__ import annotations

from silbridge.bridge.autopilots.ardupilot import json_protocol as apj
from silbridge.bridge.frames import euler_from_quat
from silbridge.shm.record_structs import GT_ATT as _GT_ATT
from silbridge.shm.record_structs import GT_NAV as _GT_NAV
from silbridge.shm.record_structs import IMU as _IMU
from silbridge.shm.record_structs import KIND as _KIND
from silbridge.shm.records import KIND_GT_ATT as _GT_ATT_KIND
from silbridge.shm.records import KIND_GT_NAV as _GT_NAV_KIND
from silbridge.shm.records import KIND_IMU as _IMU_KIND
from silbridge.shm.records import RECORD_SIZE

_NS = 1_000_000_000


def reply_line(raw: bytes, sim_ns: int) -> bytes:
    """The reply line of a step's record bytes (IMU*, GT_ATT, GT_NAV)."""
    # Contract order: the step's IMU samples first, then GT_ATT, then GT_NAV.
    n = off = 0
    a0 = a1 = a2 = g0 = g1 = g2 = 0.0
    while _KIND.unpack_from(raw, off)[0] == _IMU_KIND:
        x0, x1, x2, y0, y1, y2 = _IMU.unpack_from(raw, off)
        a0 += x0
        a1 += x1
        a2 += x2
        g0 += y0
        g1 += y1
        g2 += y2
        n += 1
        off += RECORD_SIZE
    if _KIND.unpack_from(raw, off)[0] != _GT_ATT_KIND or \
            _KIND.unpack_from(raw, off + RECORD_SIZE)[0] != _GT_NAV_KIND:
        raise RuntimeError("Simulator.step records out of contract order (IMU*, GT_ATT, "
                           "GT_NAV): bridge/simulator.py and this reader disagree")
    att = _GT_ATT.unpack_from(raw, off)
    nav = _GT_NAV.unpack_from(raw, off + RECORD_SIZE)
    if n:
        k = 1.0 / n
        imu = (g0 * k, g1 * k, g2 * k, a0 * k, a1 * k, a2 * k)
    else:   # an IMU slower than the physics: truth this step (its sample comes later)
        imu = (*att[4:7], *att[7:10])
    return apj.encode_values((sim_ns / _NS, *imu, *nav[0:3], *euler_from_quat(*att[0:4]),
                              *att[0:4], *nav[3:6]))
