"""The anchor: ArduCopter's own AUTOTUNE, flown on our physics, and its gains.

A fresh ArduCopter SITL (the real binary, `--model JSON`, as `bench --fc
ardupilot` runs it: tools/autopilots/ardupilot/sitl.py) takes off in GUIDED to the
scenario's altitude; then, as a pilot would, the driver centres the sticks
with RC_CHANNELS_OVERRIDE (throttle mid = hold altitude in AltHold-based
modes), switches to AUTOTUNE (mode 15, AUTOTUNE_AXES roll+pitch by default)
and waits for "AutoTune: Success". It then lowers the throttle stick so the
vehicle lands and disarms while still in AUTOTUNE, which is when ArduCopter
saves the tuned gains, and reads them back with PARAM_REQUEST_READ. The gains
are ArduCopter's units (same ATC_* names and normalisation as our FC), so they
go straight into our FC for Table 1 and the margins (tools/tune/tune_cmds.py).
"""

from __future__ import annotations

import math
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.autopilots.ardupilot.json_protocol import sitl_port
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.autopilots.ardupilot.server import JsonPhysicsServer
from silbridge.bridge.link_spin import spin_budget_us

from silbridge.tools.autopilots.ardupilot.driver import MavlinkDriver
from silbridge.tools.autopilots.ardupilot.sitl import (ARDUCOPTER, SitlError, sitl_defaults,
                                                       start_sitl, write_defaults)
from silbridge.tools.autopilots.common.log_sink import AttitudeTarget
from silbridge.tools.autopilots.common.run import AutopilotRun, scenario_factory
from silbridge.tools.tune.tune_defaults import AUTOTUNE_AGGR

COPTER_MODE_AUTOTUNE = 15
COPTER_MODE_ALT_HOLD = 2     # AUTOTUNE is entered from a mode that allows it (not GUIDED)
RC_MID, RC_LOW = 1500, 1000
GAIN_NAMES = tuple(f"ATC_RAT_{a}_{t}" for a in ("RLL", "PIT", "YAW")
                   for t in ("P", "I", "D", "FF", "FLTD", "FLTT")) + \
    ("ATC_ANG_RLL_P", "ATC_ANG_PIT_P", "ATC_ANG_YAW_P", "INS_GYRO_FILTER",
     "ATC_ACCEL_R_MAX", "ATC_ACCEL_P_MAX", "ATC_ACCEL_Y_MAX")
AXIS_BITS = {"roll": 1, "pitch": 2, "yaw": 4}     # AUTOTUNE_AXES
# ArduCopter 4.6's documented @Range where its AUTOTUNE writes past it (our FC takes
# AUTOTUNE's values: fc_params.def); a second .parm holds the gains cut to these.
DOCUMENTED_RANGE = {"ATC_ANG_RLL_P": (3.0, 12.0), "ATC_ANG_PIT_P": (3.0, 12.0),
                    "ATC_ANG_YAW_P": (3.0, 12.0), "ATC_ACCEL_R_MAX": (0.0, 180000.0),
                    "ATC_ACCEL_P_MAX": (0.0, 180000.0)}


class AutotuneDriver(MavlinkDriver):
    """GUIDED take-off (the parent's), then AUTOTUNE, land, disarm, read the gains."""

    def __init__(self, instance: int, *, takeoff_alt_m: float, sim_time_s):
        super().__init__(instance, takeoff_alt_m=takeoff_alt_m, sim_time_s=sim_time_s,
                         on_takeoff=lambda: None, target=AttitudeTarget())
        self.phase = "takeoff"
        self.gains: dict[str, float] = {}
        self.done = False
        self.tune_started_s = None
        self.tune_done_s = None
        self._next_rc = 0.0
        self._next_cmd = 0.0
        self.events: list[tuple[float, str]] = []   # (sim s, phase) for the report

    def _rc(self, throttle: int) -> None:
        with self._tx_lock:
            self.codec.rc_channels_override_send(self.sysid, 1, RC_MID, RC_MID, throttle, RC_MID,
                                                 0, 0, 0, 0)

    def _handle(self, m) -> None:
        super()._handle(m)
        kind = m.get_type()
        if kind == "STATUSTEXT":
            text = m.text.lower()
            if "autotune" in text and "success" in text and self.phase == "tuning":
                self.phase = "landing"
                self.tune_done_s = self.sim_time_s()
            elif text.startswith("autotune") and "failed" in text:
                self.error = f"ArduCopter AUTOTUNE failed: {m.text}"
        elif kind == "PARAM_VALUE" and self.phase == "reading" and m.param_id in GAIN_NAMES:
            self.gains[m.param_id] = float(m.param_value)
            if len(self.gains) == len(GAIN_NAMES):
                self.done = True

    def _loop(self) -> None:
        while not self._halt.is_set() and not self.done:
            if self.phase == "takeoff" and (not self.took_off
                                            or (self.rel_alt_m or 0.0) < 0.9 * self.takeoff_alt_m):
                self._takeoff_pass()
                continue
            self._pump()
            now = time.monotonic()
            t = self.sim_time_s()
            if self.phase in ("takeoff", "tuning") and now >= self._next_rc:
                self._rc(RC_MID)
                self._next_rc = now + 0.2
            if self.phase == "takeoff":
                if self.mode == COPTER_MODE_AUTOTUNE:
                    self.phase = "tuning"
                    self.tune_started_s = t
                    self.events.append((t, "autotune"))
                elif now >= self._next_cmd:
                    want = (COPTER_MODE_AUTOTUNE if self.mode == COPTER_MODE_ALT_HOLD
                            else COPTER_MODE_ALT_HOLD)
                    self._command(mav.MAV_CMD_DO_SET_MODE,
                                  mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, want)
                    self._next_cmd = now + 0.5
            elif self.phase == "landing":
                if now >= self._next_rc:
                    self._rc(RC_LOW)
                    self._next_rc = now + 0.2
                if not self.armed:
                    self.phase = "reading"
                    self.events.append((t, "disarmed"))
                elif (self.rel_alt_m or 99.0) < 0.3 and now >= self._next_cmd:
                    self._command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 0)
                    self._next_cmd = now + 1.0
            elif self.phase == "reading" and now >= self._next_cmd:
                for name in GAIN_NAMES:
                    if name not in self.gains:
                        with self._tx_lock:
                            self.codec.param_request_read_send(self.sysid, 1, name.encode(), -1)
                self._next_cmd = now + 1.0

    def _takeoff_pass(self) -> None:
        """GUIDED, arm, take off: what the parent's loop does, one pass at a time."""
        self._pump()
        if self.sysid is None:
            return
        if not getattr(self, "_streams", False):
            self._command(mav.MAV_CMD_SET_MESSAGE_INTERVAL,
                          mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 1e5)
            self._streams = True
        if self.took_off:
            return
        t = self.sim_time_s()
        if t < getattr(self, "_next_try", 0.0):
            return
        self._next_try = t + 2.0
        if self.mode != 4:              # GUIDED
            self._command(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4)
        elif not self.armed:
            self._command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        else:
            self._command(mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, 0, 0, self.takeoff_alt_m)


def run_autotune(binary: str, *, axes_mask: int = 3, aggr: float = AUTOTUNE_AGGR,
                 scenario: str = "S1",
                 seed: int = 1, speedup: float = 50.0, budget_sim_s: float = 1500.0,
                 keep_dir: bool = False) -> dict:
    """Fly ArduCopter's AUTOTUNE on our physics; returns its saved gains and timings."""
    sc, make_sim = scenario_factory(scenario, seed, None)
    run = AutopilotRun(ARDUCOPTER, "silbridge-autotune-", keep_dir=keep_dir)
    phys = ArduPilotPhysics(make_sim)
    defaults = sitl_defaults(phys.sim, phys.physics_hz,
                             {"AUTOTUNE_AXES": axes_mask, "AUTOTUNE_AGGR": aggr})
    path = f"{run.workdir}/silbridge-defaults.parm"
    write_defaults(path, defaults)
    driver = AutotuneDriver(run.instance, takeoff_alt_m=sc.takeoff_alt_m,
                            sim_time_s=lambda: phys.sim.sim_ns / 1e9)
    server = JsonPhysicsServer(phys, ("127.0.0.1", sitl_port(run.instance)))
    try:
        run.launch(start_sitl, binary, run.instance, run.workdir, speedup=speedup,
                   home=sc.home, defaults_path=path)
        driver.start()
        server.serve(budget_sim_s, stop=run.stop_when(lambda: driver.done, driver),
                     connect_timeout_s=60.0, spin_us=spin_budget_us(1))   # one run at a time
        if driver.error:
            raise SitlError(f"{driver.error}; ArduCopter said: {' | '.join(driver.statustext)}")
        if not driver.done:
            raise SitlError(f"AUTOTUNE did not finish within {budget_sim_s:g} s of sim time "
                            f"(phase {driver.phase}, mode {driver.mode}); ArduCopter said: "
                            f"{' | '.join(driver.statustext)}; log: {run.log_tail()}")
    finally:
        run.close(driver, server)
    return {"gains": driver.gains, "tune_sim_s": (driver.tune_done_s or 0) -
            (driver.tune_started_s or 0), "sim_s": phys.sim.sim_ns / 1e9,
            "wall_s": time.monotonic() - run.t0, "statustext": list(driver.statustext),
            "events": driver.events}


def for_our_fc(gains: dict, axes) -> tuple[dict, dict]:
    """ArduCopter's tuned values for the tuned axes, as our FC takes them: (applied,
    clipped) where clipped lists each value our declared range cut ({name: [theirs,
    ours]}; e.g. ATC_ANG_*_P, declared 0-12 here, which AUTOTUNE may push past 20)."""
    from silbridge.fc_sil import params as P
    from silbridge.tools.tune.tune_auto import search_space

    names = set(search_space(axes)) | {f"ATC_ACCEL_{a[0].upper()}_MAX" for a in axes}
    applied, clipped = {}, {}
    for name in sorted(names):
        if name not in gains:
            continue
        d = P.BY_NAME[name]
        v = min(max(gains[name], d.min), d.max)
        if v != gains[name]:
            clipped[name] = [gains[name], v]
        applied[name] = v
    return applied, clipped


def within_documented(applied: dict) -> dict:
    """AUTOTUNE's values cut to ArduCopter's documented ranges (DOCUMENTED_RANGE)."""
    return {n: min(max(v, DOCUMENTED_RANGE[n][0]), DOCUMENTED_RANGE[n][1])
            if n in DOCUMENTED_RANGE else v for n, v in applied.items()}
