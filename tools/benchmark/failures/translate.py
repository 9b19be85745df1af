"""How each fault of F1..F12 reaches each autopilot: the one translation table.

The bridge's fault engine (bridge/faults/) applies every fault to what the bridge sends:
the IMU samples, the motors' thrust, the battery pack, the SIL link, and the GNSS, baro
and compass records. Our FC (shared memory) and PX4 (MAVLink HIL: HIL_SENSOR, HIL_GPS)
read all of those, so the engine is their only route. ArduCopter's JSON interface takes
the IMU, the state and (where the bridge sends it) the battery from us, but its SITL builds
its own GPS, barometer and compass from the true state: for those, the same fault is set
through ArduCopter's own SIM_* parameters, at the fault's sim time, by the benchmark
(watch.py sends them from the physics step at which the engine switches the fault, so
both happen on the same step). The ground-station link loss is the client's own for
every autopilot: it stops sending for the fault's duration. The RC receiver is the
autopilot's own: our FC's scenario [[failure]] rc entry switches its SIM_RC_FAIL
(tools/loop/fc_param_events.py), ArduCopter gets SIM_RC_FAIL at the same step, and PX4 is
not flown on it (it flies the bench without RC, so there is no RC link to lose).

The battery: the bridge's pack (bridge/battery/) reaches our FC only. ArduCopter's JSON
reply carries no battery, so its SITL reads the constant SIM_BATT_VOLTAGE: it boots with
our pack's open-circuit voltage, and a battery fault sets it to the voltage our FC reads
just after the fault (the pack's terminal voltage under the ESCs' load of the moment),
held from then on (SITL's JSON battery draws no current, so it never sags or recovers).
PX4's simulator link takes no battery either: its SITL battery (battery_simulator) is
pinned near full (SIM_BAT_DRAIN 86400 s) and a capacity loss lowers SIM_BAT_MIN_PCT to the
pack's remaining charge just after the fault with SIM_BAT_DRAIN 1 s, so it gets there
within a second (PX4's documented way to change the SITL battery level in flight).
A value that depends on the physics' state is a function of the simulator, evaluated at
the fault's step.

ArduCopter 4.6's names and units below come from its parameter list (the real binary's
PARAM_VALUEs) and its libraries/SITL source (SIM_GPS.cpp, AP_Baro_SITL.cpp,
SIM_Aircraft.cpp): SIM_GPS_GLITCH_X/Y are added to the latitude/longitude in DEGREES
and _Z to the altitude in metres; SIM_BARO_GLITCH is metres added to the altitude;
SIM_MAG_MOT_X/Y/Z is mGauss per ampere of the battery current SITL reads, body frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from silbridge.tools.benchmark.nav.geo import radii_m

BRIDGE, CLIENT, SIM_PARAM, NONE = "bridge", "client", "SIM_* parameter", "not reachable"
FC_SIDE = "FC side"      # our FC's own link, switched by its SIM_* parameter at the step


@dataclass(frozen=True)
class Route:
    how: str                 # BRIDGE, CLIENT, SIM_PARAM, FC_SIDE or NONE
    text: str                # what the autopilot meets, for the report
    on: Callable[[dict, float], dict] | None = None   # (params, home lat) -> SIM_* values
    # (a value may be a function of the simulator, evaluated at the fault's step)
    off: dict | None = None                           # SIM_* values when the fault ends


def _glitch(p: dict, lat_deg: float) -> dict:
    """Our NED offset [m] as SIM_GPS_GLITCH_X/Y [deg] and _Z [m up] (WGS-84 radii at home,
    as the bridge's ground truth measures metres)."""
    r_lat, r_lon = radii_m(lat_deg)
    n, e, d = p["offset_m"]
    return {"SIM_GPS_GLITCH_X": math.degrees(n / r_lat),
            "SIM_GPS_GLITCH_Y": math.degrees(e / r_lon),
            "SIM_GPS_GLITCH_Z": 0.0 - d + 0.0}     # + 0.0: no -0 in the report


def pack_ocv_v(sim) -> float:
    """The physics pack's open-circuit voltage now [V]: the pack (bridge/src/battery.h) is its
    cells' summed open-circuit voltage E behind their summed resistance, V = E - I R, so two
    solutions under different loads, without advancing the pack, give E exactly."""
    b = sim.battery
    v0, i0 = b.solve(0.0)           # the avionics alone
    v1, i1 = b.solve(100.0)
    return v0 + i0 * (v0 - v1) / (i1 - i0)


def pack_loaded_v(sim) -> float:
    """The pack's terminal voltage now [V], its state after any fault switched this step,
    under the ESCs' power of its last report (bridge/battery solve)."""
    b = sim.battery
    esc_w = b.voltage_v * max(0.0, b.current_a - b.cfg.avionics_a)
    return round(b.solve(esc_w)[0], 3)


def _ap_battery(p: dict, _lat: float) -> dict:
    return {"SIM_BATT_VOLTAGE": pack_loaded_v}


def _px4_capacity(p: dict, _lat: float) -> dict:
    return {"SIM_BAT_MIN_PCT": lambda sim: round(100.0 * sim.battery.remaining, 2),
            "SIM_BAT_DRAIN": 1.0}


_ENGINE = Route(BRIDGE, "the bridge's fault engine, on the records the bridge sends")
_CLIENT = Route(CLIENT, "the benchmark client stops sending for the fault's duration")

# (unit, type) -> ArduCopter's route; anything not listed goes through the bridge.
ARDUCOPTER = {
    ("gnss", "off"): Route(SIM_PARAM, "SIM_GPS_DISABLE 1: 4.6 has no silent GPS; its "
                           "disabled GPS keeps sending without a fix",
                           lambda p, lat: {"SIM_GPS_DISABLE": 1}, {"SIM_GPS_DISABLE": 0}),
    ("gnss", "fix_lost"): Route(SIM_PARAM, "SIM_GPS_DISABLE 1 (messages without a fix)",
                                lambda p, lat: {"SIM_GPS_DISABLE": 1}, {"SIM_GPS_DISABLE": 0}),
    ("gnss", "sats_drop"): Route(SIM_PARAM, "SIM_GPS_NUMSATS = satellites, at once (no ramp)",
                                 lambda p, lat: {"SIM_GPS_NUMSATS": p["satellites"]},
                                 {"SIM_GPS_NUMSATS": 10}),
    ("gnss", "glitch"): Route(SIM_PARAM, "SIM_GPS_GLITCH_X/Y = offset in degrees of "
                              "latitude/longitude, _Z = -down in metres", _glitch,
                              {"SIM_GPS_GLITCH_X": 0.0, "SIM_GPS_GLITCH_Y": 0.0,
                               "SIM_GPS_GLITCH_Z": 0.0}),
    ("gnss", "drift"): Route(NONE, "4.6 has no horizontal GPS drift parameter "
                             "(SIM_GPS_DRIFTALT is a sine on the altitude)"),
    ("gnss", "vel_error"): Route(NONE, "4.6's SIM_GPS_VERR is a random error of that size, "
                                 "not a constant offset"),
    ("baro", "drift"): Route(SIM_PARAM, "SIM_BARO_DRIFT = rate [m/s] (integrated by SITL)",
                             lambda p, lat: {"SIM_BARO_DRIFT": p["rate_m_s"]},
                             {"SIM_BARO_DRIFT": 0.0}),
    ("baro", "stuck"): Route(SIM_PARAM, "SIM_BARO_FREEZE 1",
                             lambda p, lat: {"SIM_BARO_FREEZE": 1}, {"SIM_BARO_FREEZE": 0}),
    ("baro", "glitch"): Route(SIM_PARAM, "SIM_BARO_GLITCH = offset [m], added to the altitude",
                              lambda p, lat: {"SIM_BARO_GLITCH": p["offset_m"]},
                              {"SIM_BARO_GLITCH": 0.0}),
    ("mag", "off"): Route(SIM_PARAM, "SIM_MAG1_FAIL 1",
                          lambda p, lat: {"SIM_MAG1_FAIL": 1}, {"SIM_MAG1_FAIL": 0}),
    # SIM_MAG_MOT_X/Y/Z [mGauss/A, body frame] times the battery current SITL reads: its
    # JSON battery draws none, so the field it would add is 0.
    ("mag", "motor_interference"): Route(
        NONE, "SIM_MAG_MOT_X/Y/Z scales the battery current SITL reads, and its JSON "
        "battery draws none"),
    ("battery", "capacity_loss"): Route(
        SIM_PARAM, "SIM_BATT_VOLTAGE = our pack's voltage under load just after the loss",
        _ap_battery),
    ("battery", "weak_cell"): Route(
        SIM_PARAM, "SIM_BATT_VOLTAGE = our pack's voltage under load with the weak cell",
        _ap_battery, {"SIM_BATT_VOLTAGE": pack_loaded_v}),
    ("rc", "lost"): Route(SIM_PARAM, "SIM_RC_FAIL 1 (no RC pulses)",
                          lambda p, lat: {"SIM_RC_FAIL": 1}, {"SIM_RC_FAIL": 0}),
    ("gcs", "lost"): _CLIENT,
}
OURS = {("gcs", "lost"): _CLIENT,
        ("rc", "lost"): Route(FC_SIDE, "the scenario's rc entry sets our SIM_RC_FAIL 1 for its "
                              "duration: no pilot input reaches the FC (fc_sil/radio_failsafe.py)")}
PX4 = {
    ("battery", "capacity_loss"): Route(
        SIM_PARAM, "SIM_BAT_MIN_PCT = the pack's remaining charge after the loss, "
        "SIM_BAT_DRAIN 1 s", _px4_capacity),
    ("battery", "weak_cell"): Route(NONE, "PX4's SITL battery has no per-cell model"),
    ("rc", "lost"): Route(NONE, "PX4 flies the bench without RC "
                          "(COM_RC_IN_MODE 4, stick input off), so there is no RC link to lose; "
                          "an RC link of MANUAL_CONTROL (COM_RC_IN_MODE 1) would change its "
                          "setup for every plan"),
    ("gcs", "lost"): _CLIENT,
}
# SIM_* values each autopilot boots with, beside its failsafe settings (functions of the
# simulator as above): the battery it reads starts where our pack starts.
BOOT = {"ardupilot": {"SIM_BATT_VOLTAGE": pack_ocv_v}, "px4": {"SIM_BAT_DRAIN": 86400.0},
        "ours": {}}
TABLES = {"ours": OURS, "ardupilot": ARDUCOPTER, "px4": PX4}


def route(fc: str, unit: str, ftype: str) -> Route:
    return TABLES[fc].get((unit, ftype), _ENGINE)


def unreachable(fc: str, plan) -> list[str]:
    """Why some of the plan's faults cannot reach fc (empty: all of them reach it)."""
    return [f"{f['unit']}.{f['type']}: {r.text}" for f in plan.failures
            for r in [route(fc, f["unit"], f["type"])] if r.how == NONE]


def boot_params(fc: str, sim) -> dict:
    """The SIM_* values fc boots with, evaluated on the simulator."""
    return {k: (round(v(sim), 3) if callable(v) else v) for k, v in BOOT[fc].items()}


def sim_param_switches(fc: str, plan, home_lat_deg: float) -> list[tuple[float, dict]]:
    """fc's SIM_* switches of a plan: (sim time [s], {name: value or function of the
    simulator}) in time order."""
    out = []
    for f in plan.failures:
        r = route(fc, f["unit"], f["type"])
        if r.how != SIM_PARAM:
            continue
        params = {k: v for k, v in f.items() if k not in ("unit", "type", "instance", "at_s",
                                                          "duration_s")}
        from silbridge.bridge.faults.engine import resolve
        full = resolve(f["unit"], f["type"], int(f.get("instance", 1)), params)[2]
        out.append((float(f["at_s"]), r.on(full, home_lat_deg)))
        if "duration_s" in f and r.off is not None:
            out.append((float(f["at_s"] + f["duration_s"]), dict(r.off)))
    return sorted(out, key=lambda s: s[0])


def table_markdown() -> str:
    """The translation table for the report page, from the tables above."""
    from silbridge.shm.fault_catalog import UNITS
    lines = ["| fault | ours | ArduCopter 4.6 | PX4 v1.15 |", "|---|---|---|---|"]
    for u in UNITS:
        for t in u.types:
            cells = [route(fc, u.name, t.name) for fc in ("ours", "ardupilot", "px4")]
            lines.append(f"| {u.name}.{t.name} | "
                         + " | ".join(c.how if c.how == BRIDGE else f"{c.how}: {c.text}"
                                      for c in cells) + " |")
    return "\n".join(lines)
