"""FC -> simulator direction of the HIL transport: FAULT records <-> COMMAND_LONG.

Over shared memory a fault the FC switches (fc_sil/fault_inject.py) is a FAULT record in the
actuator ring beside the PWM. Over the MAVLink HIL links it travels as one COMMAND_LONG from
the FC to the simulator, in the user range the MAVLink spec leaves for such private uses:

  command  MAV_CMD_USER_1 (31010)      confirmation 0, no COMMAND_ACK expected
  param1   action: 1 on, 0 off         param2  catalog unit code (shm/fault_catalog.py)
  param3   catalog type code           param4  instance (0 all where the unit allows it)
  param5..param7  the type's first three parameter slots (fault_catalog.pack_params)

Every value is a small integer or a float32, so it arrives exactly. Three slots cover every
type of the catalog today (a vec3 is the widest); a type that needs more fails this module's
import, so a catalog change cannot silently truncate a fault on this link. The simulator
rebuilds the FAULT record (its wall_ns is the arrival time, seq its own count) and hands it to
its fault engine as the shared-memory bridge does.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.shm import fault_catalog as fc
from silbridge.shm.records import KIND_FAULT, Kind, record_struct

COMMAND = mav.MAV_CMD_USER_1
SLOTS = 3

_FAULT = record_struct(Kind.FAULT)      # the whole 64-byte FAULT slot (shm/records.py)


def _check_slots() -> None:
    for u in fc.UNITS:
        for t in u.types:
            if t.slots > SLOTS:
                raise AssertionError(f"hil_fault: {u.name}.{t.name} needs {t.slots} parameter "
                                     f"slots; the HIL encoding carries {SLOTS}: extend it")


_check_slots()


def encode(codec, rec: bytes, target_system: int, target_component: int) -> bytes:
    """One FAULT record (64 bytes) -> a COMMAND_LONG frame."""
    f = _FAULT.unpack_from(rec)
    action, unit, ftype, instance = f[5:9]
    slots = f[9:9 + SLOTS]
    return codec.command_long_encode(target_system, target_component, COMMAND, 0,
                                     action, unit, ftype, instance, *slots).pack(codec)


def decode(m, seq: int, sim_ns: int, now_ns: int) -> bytes | None:
    """A COMMAND_LONG from the FC -> a FAULT record, or None when it is not a sane one (the
    caller counts it): codes that are not small integers, NaN or infinite parameters."""
    head = (m.param1, m.param2, m.param3, m.param4)
    if not all(math.isfinite(x) and x == int(x) and 0 <= x <= 255 for x in head):
        return None
    slots = (m.param5, m.param6, m.param7)
    if not all(math.isfinite(x) for x in slots):
        return None
    return _FAULT.pack(KIND_FAULT, 0, seq & 0xFFFFFFFF, sim_ns, now_ns,
                       *(int(x) for x in head), *slots, *([0.0] * (9 - SLOTS)))
