"""The fault catalog: every fault silbridge can inject, declared once.

A fault is (unit, type, instance, parameters). Three ways in reach the same catalog:
a scenario's ``[[failure]]`` entries (bridge/scenario_schema.py builds their keys from the
tables below), MAV_CMD_INJECT_FAILURE and ArduPilot's SIM_* parameters on our FC (the FC
maps them onto this catalog and forwards the fault to the bridge). The bridge's fault
engine applies each fault where it belongs (sensor stage, GNSS model, motors, battery,
SIL link), so every autopilot on the same physics meets the same fault.

This module lives beside the records because it is a contract between the two processes:
the FC's forwarded fault is a record whose unit, type and parameter slots are numbered
here, and neither bridge/ nor fc_sil/ imports the other.

Numbering is permanent: a unit's or type's code never changes and a retired one keeps its
number. Parameters of a type fill the record's float slots in the order listed (a vec3
takes three slots), at most ``MAX_PARAM_SLOTS``.
"""

from __future__ import annotations

from dataclasses import dataclass

MAX_PARAM_SLOTS = 9


@dataclass(frozen=True)
class FaultParam:
    """One parameter of a fault type: kind is float, int or vec3 (the scenario schema's)."""

    name: str
    kind: str
    default: object
    unit: str = ""
    text: str = ""
    min: float | None = None
    max: float | None = None

    @property
    def slots(self) -> int:
        return 3 if self.kind == "vec3" else 1


@dataclass(frozen=True)
class FaultType:
    code: int
    name: str
    text: str
    params: tuple = ()

    @property
    def slots(self) -> int:
        return sum(p.slots for p in self.params)


@dataclass(frozen=True)
class FaultUnit:
    code: int
    name: str
    text: str
    instance_text: str
    types: tuple
    instances: tuple = (1,)   # the instance numbers the unit accepts (0: all, where listed)

    def type_named(self, name: str) -> FaultType | None:
        return next((t for t in self.types if t.name == name), None)

    def type_coded(self, code: int) -> FaultType | None:
        return next((t for t in self.types if t.code == code), None)


P = FaultParam
T = FaultType

_AXIS = P("axis", "int", 0, "", "0 every axis, 1 x (forward), 2 y (right), 3 z (down)", 0, 3)


def _inertial(unit: str, clip_default: float, noise_default: float, bias_default: tuple):
    return (
        T(1, "stuck", f"the {unit} repeats its last sample on the chosen axes", (_AXIS,)),
        T(2, "bias", f"a constant offset added to the {unit} (a bias step)",
          (P("bias", "vec3", bias_default, _SI[unit], "offset, body FRD"),)),
        T(3, "clip", f"the {unit} saturates at +-limit on every axis (a range set too low)",
          (P("limit", "float", clip_default, _SI[unit], "saturation level", 0.0),)),
        T(4, "noisy", f"extra white noise on the {unit}'s chosen axes (a failing chip)",
          (_AXIS, P("sigma", "float", noise_default, _SI[unit], "one-sigma per sample", 0.0))),
    )


_SI = {"gyro": "rad/s", "accel": "m/s^2"}

UNITS = (
    FaultUnit(1, "gnss", "the GNSS receiver", "receiver (1)", (
        T(1, "off", "the receiver goes silent: no fixes at all"),
        T(2, "fix_lost", "fixes keep coming without a position (fix type 1, no satellites used)"),
        T(3, "sats_drop", "satellites drop to a count over a ramp; accuracy degrades as the count falls",
          (P("satellites", "int", 5, "", "satellites at the end of the ramp", 0, 40),
           P("ramp_s", "float", 5.0, "s", "time to fall to that count", 0.0))),
        T(4, "glitch", "the reported position jumps by an offset (multipath, a spoofing step)",
          (P("offset_m", "vec3", (20.0, 0.0, 0.0), "m", "jump, north east down"),)),
        T(5, "drift", "the reported position walks away at a constant rate",
          (P("rate_m_s", "vec3", (0.5, 0.0, 0.0), "m/s", "drift rate, north east down"),)),
        T(6, "vel_error", "the reported velocity is off by a constant vector",
          (P("error_m_s", "vec3", (1.0, 0.0, 0.0), "m/s", "velocity error, north east down"),)),
    )),
    FaultUnit(2, "baro", "the barometer", "barometer (1)", (
        T(1, "drift", "the pressure altitude walks away at a constant rate",
          (P("rate_m_s", "float", 0.2, "m/s", "altitude drift rate (positive: reads higher)"),)),
        T(2, "stuck", "the barometer repeats its last reading"),
        T(3, "glitch", "the pressure altitude jumps by an offset",
          (P("offset_m", "float", 10.0, "m", "altitude jump (positive: reads higher)"),)),
    )),
    FaultUnit(3, "mag", "the magnetometer", "magnetometer (1)", (
        T(1, "off", "the magnetometer goes silent"),
        T(2, "motor_interference", "a field proportional to the battery current adds to the reading "
          "(power wires near the compass)",
          (P("gauss_per_a", "vec3", (0.005, 0.005, 0.01), "gauss/A",
             "field per ampere of battery current, body FRD"),)),
    )),
    FaultUnit(4, "gyro", "the gyroscope", "IMU (0 all, 1)",
              _inertial("gyro", 2.0, 0.05, (0.05, 0.0, 0.0)), (0, 1)),
    FaultUnit(5, "accel", "the accelerometer", "IMU (0 all, 1)",
              _inertial("accel", 15.0, 1.0, (0.0, 0.0, 0.5)), (0, 1)),
    FaultUnit(6, "motor", "a motor, its ESC or its propeller", "motor 1..4 (0 all)", (
        T(1, "thrust_loss", "the motor's thrust (and reaction torque) falls to a fraction",
          (P("remaining", "float", 0.0, "", "thrust left, 0 = total loss, 1 = none lost", 0.0, 1.0),)),
        T(2, "desync", "the ESC loses sync at random moments and the motor cuts out briefly",
          (P("rate_hz", "float", 2.0, "Hz", "mean dropouts per second", 0.0),
           P("dropout_s", "float", 0.05, "s", "length of one dropout", 0.0))),
        T(3, "damaged_prop", "a chipped propeller: thrust loss and a stronger once-per-rev vibration",
          (P("remaining", "float", 0.85, "", "thrust left", 0.0, 1.0),
           P("imbalance_scale", "float", 5.0, "", "times the rotor's vibration amplitude "
             "(needs [vibration]; 1 = thrust loss only)", 0.0))),
    ), (0, 1, 2, 3, 4)),
    FaultUnit(7, "battery", "the battery (physics side)", "battery (1)", (
        T(1, "weak_cell", "one cell sits lower and sags more than the others",
          (P("cell_drop_v", "float", 0.3, "V", "open-circuit voltage lost by the weak cell", 0.0),
           P("r_scale", "float", 3.0, "", "times that cell's internal resistance", 1.0))),
        T(2, "capacity_loss", "part of the remaining charge vanishes at once (a cell gives out)",
          (P("fraction", "float", 0.5, "", "fraction of the remaining charge lost", 0.0, 1.0),)),
    )),
    FaultUnit(8, "link", "the SIL link between bridge and FC (shared memory or MAVLink HIL)",
              "direction: 0 both, 1 sensors (bridge to FC), 2 motor outputs (FC to bridge)", (
        T(1, "latency", "records arrive late, with an optional uniform jitter",
          (P("delay_s", "float", 0.01, "s", "added delay", 0.0),
           P("jitter_s", "float", 0.0, "s", "uniform extra delay 0..jitter", 0.0))),
        T(2, "drop", "records are lost at random",
          (P("probability", "float", 0.1, "", "chance each record is dropped", 0.0, 1.0),)),
    ), (0, 1, 2)),
    FaultUnit(9, "rc", "the RC receiver link", "receiver (1)", (
        T(1, "lost", "no RC input reaches the FC"),
    )),
    FaultUnit(10, "gcs", "the ground-station link", "link (1)", (
        T(1, "lost", "nothing from the ground station reaches the FC, nothing from the FC reaches it"),
    )),
)


def unit_named(name: str) -> FaultUnit | None:
    return next((u for u in UNITS if u.name == name), None)


def unit_coded(code: int) -> FaultUnit | None:
    return next((u for u in UNITS if u.code == code), None)


def pack_params(ftype: FaultType, values: dict) -> list[float]:
    """The record's float slots of a fault: each parameter in catalog order (its default
    when missing), a vec3 as three floats, unused slots 0."""
    slots: list[float] = []
    for p in ftype.params:
        v = values.get(p.name, p.default)
        slots.extend(float(x) for x in v) if p.slots == 3 else slots.append(float(v))
    return slots + [0.0] * (MAX_PARAM_SLOTS - len(slots))


def unpack_params(ftype: FaultType, slots) -> dict:
    """The inverse of pack_params: {name: value} (vec3 as a tuple, int as int)."""
    out, i = {}, 0
    for p in ftype.params:
        if p.slots == 3:
            out[p.name] = tuple(float(x) for x in slots[i:i + 3])
        else:
            out[p.name] = int(round(slots[i])) if p.kind == "int" else float(slots[i])
        i += p.slots
    return out


def _check_catalog() -> None:
    codes = [u.code for u in UNITS]
    if len(set(codes)) != len(codes):
        raise AssertionError("fault catalog: duplicate unit code")
    for u in UNITS:
        if len({t.code for t in u.types}) != len(u.types):
            raise AssertionError(f"fault catalog: duplicate type code in {u.name}")
        for t in u.types:
            if t.slots > MAX_PARAM_SLOTS:
                raise AssertionError(f"fault catalog: {u.name}.{t.name} needs too many slots")


_check_catalog()
