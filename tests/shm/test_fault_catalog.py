"""The fault catalog (shm/fault_catalog.py): codes are unique and permanent, every type's
parameters fit a record, and pack/unpack round-trip what the FC forwards to the bridge."""

import pytest

from silbridge.shm import fault_catalog as fc

# Codes are a wire contract between FC and bridge: renumbering one breaks saved logs and a
# running peer of another version. This table is the catalog at the time it was published.
PUBLISHED = {
    "gnss": (1, ["off", "fix_lost", "sats_drop", "glitch", "drift", "vel_error"]),
    "baro": (2, ["drift", "stuck", "glitch"]),
    "mag": (3, ["off", "motor_interference"]),
    "gyro": (4, ["stuck", "bias", "clip", "noisy"]),
    "accel": (5, ["stuck", "bias", "clip", "noisy"]),
    "motor": (6, ["thrust_loss", "desync", "damaged_prop"]),
    "battery": (7, ["weak_cell", "capacity_loss"]),
    "link": (8, ["latency", "drop"]),
    "rc": (9, ["lost"]),
    "gcs": (10, ["lost"]),
}


def test_published_codes_never_move():
    for name, (code, types) in PUBLISHED.items():
        unit = fc.unit_named(name)
        assert unit is not None and unit.code == code
        assert fc.unit_coded(code) is unit
        for i, t in enumerate(types, start=1):
            assert unit.type_named(t).code == i
            assert unit.type_coded(i).name == t


@pytest.mark.parametrize("unit", fc.UNITS, ids=lambda u: u.name)
def test_every_type_fits_a_record_and_round_trips(unit):
    for t in unit.types:
        assert t.slots <= fc.MAX_PARAM_SLOTS
        given = {}
        for k, p in enumerate(t.params):
            if p.kind == "vec3":
                given[p.name] = (1.5 + k, -2.0, 0.25)
            elif p.kind == "int":
                given[p.name] = 2
            else:
                given[p.name] = 0.5 + k
        slots = fc.pack_params(t, given)
        assert len(slots) == fc.MAX_PARAM_SLOTS
        assert fc.unpack_params(t, slots) == given


def test_missing_parameters_take_their_defaults():
    glitch = fc.unit_named("gnss").type_named("glitch")
    assert fc.unpack_params(glitch, fc.pack_params(glitch, {})) == {"offset_m": (20.0, 0.0, 0.0)}


def test_unknown_names_are_none():
    assert fc.unit_named("lidar") is None
    assert fc.unit_named("gnss").type_named("spoof") is None
