"""FAULT records over MAVLink HIL (mavlink/hil/hil_fault.py): one COMMAND_LONG each, rebuilt
bit for bit on the simulator's side; a command that is not a sane fault is refused."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.fc_sil.fault_inject import fault_record
from silbridge.mavlink.hil import hil_fault
from silbridge.mavlink.hil.hil_channel import make_codec
from silbridge.shm import fault_catalog as cat
from silbridge.shm.records import FAULT_DTYPE


def _roundtrip(rec: np.ndarray):
    fc, sim = make_codec(1, 1), make_codec(1, 51)
    frame = hil_fault.encode(fc, rec.tobytes(), 1, 51)
    (m,) = sim.parse_buffer(frame)
    assert m.get_type() == "COMMAND_LONG" and m.command == mav.MAV_CMD_USER_1
    out = hil_fault.decode(m, seq=int(rec["seq"][0]), sim_ns=int(rec["sim_ns"][0]),
                           now_ns=int(rec["wall_ns"][0]))
    return m, out


@pytest.mark.parametrize("unit, ftype", [(u.name, t.name) for u in cat.UNITS for t in u.types])
def test_every_catalog_fault_crosses_exactly(unit, ftype):
    rng = np.random.default_rng(len(unit) * 31 + len(ftype))
    t = cat.unit_named(unit).type_named(ftype)
    params = {p.name: (tuple(rng.normal(size=3)) if p.slots == 3 else
                       int(rng.integers(0, 9)) if p.kind == "int" else float(rng.random()))
              for p in t.params}
    rec = fault_record(unit, ftype, 3 if unit == "motor" else 1, params, True, 123_000_000)
    rec["seq"], rec["wall_ns"] = 7, 99
    _, out = _roundtrip(rec)
    assert out == rec.tobytes()


def test_a_command_that_is_not_a_sane_fault_is_refused():
    rec = fault_record("gnss", "glitch", 1, {"offset_m": (1.0, 2.0, 3.0)}, False, 0)
    m, _ = _roundtrip(rec)
    for field, bad in (("param2", 2.5), ("param3", -1.0), ("param1", 300.0),
                       ("param4", math.nan), ("param5", math.inf), ("param7", math.nan)):
        good = getattr(m, field)
        setattr(m, field, bad)
        assert hil_fault.decode(m, 0, 0, 0) is None, field
        setattr(m, field, good)
    assert np.frombuffer(hil_fault.decode(m, 0, 0, 0), FAULT_DTYPE)["action"][0] == 0
