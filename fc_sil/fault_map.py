"""MAV_CMD_INJECT_FAILURE's (FAILURE_UNIT, FAILURE_TYPE) onto the fault catalog: the one table.

PX4 users inject faults with MAV_CMD_INJECT_FAILURE (MAVSDK's Failure plugin): param1 a
FAILURE_UNIT, param2 a FAILURE_TYPE, param3 the instance (0 all). Our FC accepts it as PX4
1.15 does (SYS_FAILURE_EN must be 1) and turns each pair it can honour into a catalog fault
(shm/fault_catalog.py) with the catalog's default parameters, unless the row overrides one.
A pair not in this table is UNSUPPORTED, which is also what PX4 answers for the many pairs
its simulation does not implement. FAILURE_TYPE_OK clears every fault the FC switched on for
that unit and instance.

Meanings chosen where the MAVLink names are loose (the spec says only "wrong", "garbage"):
WRONG on a position or pressure sensor is a jump (glitch), on an inertial sensor a bias step;
GARBAGE on an inertial sensor is a noisy axis; MOTOR OFF is a total thrust loss of motor
`instance`; MOTOR INTERMITTENT an ESC desync; BATTERY OFF all remaining charge lost (PX4's
battery simulator empties the pack).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.shm import fault_catalog as fc

FAILURE_TYPE_OK = mav.FAILURE_TYPE_OK
MOTORS = 4      # quad X: motor instances 1..4


@dataclass(frozen=True)
class Mapping:
    unit: str                   # catalog unit name
    type: str                   # catalog type name
    params: dict = field(default_factory=dict)   # overrides of the catalog defaults


# (FAILURE_UNIT, FAILURE_TYPE) -> catalog fault
_U = _T = mav       # short names for the two enums' members, so each row stays on a line
TABLE: dict[tuple[int, int], Mapping] = {
    (_U.FAILURE_UNIT_SENSOR_GPS, _T.FAILURE_TYPE_OFF): Mapping("gnss", "off"),
    (_U.FAILURE_UNIT_SENSOR_GPS, _T.FAILURE_TYPE_WRONG): Mapping("gnss", "glitch"),
    (_U.FAILURE_UNIT_SENSOR_BARO, _T.FAILURE_TYPE_STUCK): Mapping("baro", "stuck"),
    (_U.FAILURE_UNIT_SENSOR_BARO, _T.FAILURE_TYPE_WRONG): Mapping("baro", "glitch"),
    (_U.FAILURE_UNIT_SENSOR_MAG, _T.FAILURE_TYPE_OFF): Mapping("mag", "off"),
    (_U.FAILURE_UNIT_SENSOR_GYRO, _T.FAILURE_TYPE_STUCK): Mapping("gyro", "stuck"),
    (_U.FAILURE_UNIT_SENSOR_GYRO, _T.FAILURE_TYPE_WRONG): Mapping("gyro", "bias"),
    (_U.FAILURE_UNIT_SENSOR_GYRO, _T.FAILURE_TYPE_GARBAGE): Mapping("gyro", "noisy"),
    (_U.FAILURE_UNIT_SENSOR_ACCEL, _T.FAILURE_TYPE_STUCK): Mapping("accel", "stuck"),
    (_U.FAILURE_UNIT_SENSOR_ACCEL, _T.FAILURE_TYPE_WRONG): Mapping("accel", "bias"),
    (_U.FAILURE_UNIT_SENSOR_ACCEL, _T.FAILURE_TYPE_GARBAGE): Mapping("accel", "noisy"),
    (_U.FAILURE_UNIT_SYSTEM_MOTOR, _T.FAILURE_TYPE_OFF): Mapping("motor", "thrust_loss",
                                                                 {"remaining": 0.0}),
    (_U.FAILURE_UNIT_SYSTEM_MOTOR, _T.FAILURE_TYPE_INTERMITTENT): Mapping("motor", "desync"),
    (_U.FAILURE_UNIT_SYSTEM_BATTERY, _T.FAILURE_TYPE_OFF): Mapping("battery", "capacity_loss",
                                                                   {"fraction": 1.0}),
    (_U.FAILURE_UNIT_SYSTEM_RC_SIGNAL, _T.FAILURE_TYPE_OFF): Mapping("rc", "lost"),
    (_U.FAILURE_UNIT_SYSTEM_MAVLINK_SIGNAL, _T.FAILURE_TYPE_OFF): Mapping("gcs", "lost"),
}

# FAILURE_UNIT -> catalog unit, for FAILURE_TYPE_OK (clear) and the instance check.
UNITS: dict[int, str] = {k[0]: m.unit for k, m in TABLE.items()}


@dataclass(frozen=True)
class Injection:
    """What one MAV_CMD_INJECT_FAILURE asks of the catalog."""

    unit: str
    type: str | None            # None: FAILURE_TYPE_OK, clear the unit's faults
    instance: int               # catalog instance (0 all where the unit has several)
    params: dict


def _instance(unit: str, instance: int) -> int | None:
    """The catalog instance of a MAVLink instance (0 all), None if we have no such one.

    As PX4 1.15: the GPS, barometer and battery simulations ignore the instance (the real
    PX4 accepts GPS OFF for instance 3 with one receiver), the compass, IMU and motor ones
    act on the instance asked for; we have one compass, one IMU and four motors."""
    if unit == "motor":
        return instance if 0 <= instance <= MOTORS else None
    if unit in ("gyro", "accel"):       # one IMU: 0 (all) and 1 are the same
        return instance if instance in (0, 1) else None
    if unit == "mag":
        return 1 if instance in (0, 1) else None
    return 1


def from_mavlink(failure_unit: int, failure_type: int, instance: int) -> Injection | str:
    """The Injection for a command's (param1, param2, param3), or why it is UNSUPPORTED."""
    unit = UNITS.get(failure_unit)
    if unit is None:
        name = mav.enums["FAILURE_UNIT"].get(failure_unit)
        return f"Failure injection: unit {name.name if name else failure_unit} not supported"
    inst = _instance(unit, instance)
    if inst is None:
        return f"Failure injection: {unit} has no instance {instance}"
    if failure_type == FAILURE_TYPE_OK:
        return Injection(unit, None, inst, {})
    m = TABLE.get((failure_unit, failure_type))
    if m is None:
        name = mav.enums["FAILURE_TYPE"].get(failure_type)
        return (f"Failure injection: {name.name if name else failure_type} "
                f"not supported for {unit}")
    ftype = fc.unit_named(m.unit).type_named(m.type)
    params = {p.name: m.params.get(p.name, p.default) for p in ftype.params}
    return Injection(m.unit, m.type, inst, params)


def _check_table() -> None:
    for m in TABLE.values():
        u = fc.unit_named(m.unit)
        if u is None or u.type_named(m.type) is None:
            raise AssertionError(f"fault_map: {m.unit}.{m.type} is not in the catalog")


_check_table()
