"""Vehicle: the ArduCopter-like flight logic around the C core, obeying a GCS over MAVLink.

The vehicle is the FcLoop's supervisor: ``after_batch`` runs on the FC's main thread after
every poll and returns at once (one compare) unless an outer-loop step is due; steps run at
``nav_hz`` (50 Hz) of SIMULATION time, so the vehicle flies identically in lockstep, in real
time and at ``--speed X``. One step:

  parameters queued by the GCS -> live core (param_store.py), config re-read if changed;
  GcsServer.service(): queued GCS requests run here, on this thread (the VehicleCommands
  methods below), so they never race the control loop;
  estimation: C core status (attitude, baro/accel altitude), position estimator (pos_est.py)
  fed by the raw accelerometer mean and each new GNSS fix; the bridge's battery (battery.py);
  failsafes (failsafe.py); the flight mode's outer loops (modes.py, mission_exec.py,
  nav_pos.py, nav_wp.py) -> the core's attitude / altitude / climb / throttle inputs;
  auto-disarm; a new VehicleSnapshot published to the server (snapshot.py).

Under MAVLink control the vehicle starts disarmed in STABILIZE on the ground and obeys the
GCS only: the core is told to skip the scenario's SETPOINT records.

The class is split by concept: this file holds the loop and the state; vehicle_nav.py the
navigation outputs the modes use (NavHelpers), vehicle_commands.py the GCS requests
(GcsCommands); both are mixins of Vehicle.

Altitudes are metres up above home (the C core's altitude is relative to the arming point,
which is home); horizontal positions are metres NE about the estimator origin (first fix).
"""

from __future__ import annotations

import collections
import logging
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode

from . import modes as M
from .autodec import AutoDeclination
from .battery import BatteryMonitor
from .failsafe import FailsafeMonitor
from .fft_notice import FftNotices
from .gnss_gate import GateConfig
from .fault_inject import FaultInjector
from .fence import Geofence
from .mission_exec import MissionExecutor
from .nav_config import NavConfig
from .nav_pos import PosController
from .nav_wp import WaypointNav
from .param_store import CoreParamStore
from .pilot import PilotInput
from .pos_est import PositionEstimator
from .rally import RallyPoints
from .rc_input import ModeSwitch, RcConfig
from .snapshot import build_snapshot
from .vehicle_commands import GcsCommands
from .vehicle_nav import NavHelpers
from silbridge.shm.records import NS_PER_S as _NS

log = logging.getLogger(__name__)
# home altitude: GNSS altitude averaged while disarmed (one fix is +-3 m; this EMA settles it)
HOME_ALT_TC_S = 5.0


class Vehicle(NavHelpers, GcsCommands):
    """FcLoop supervisor and VehicleCommands implementation; see module text."""

    def __init__(self, core, store: CoreParamStore | None = None, *, nav_hz: float = 50.0,
                 sink=None, mission_file: str | None = None):
        self.core = core
        self.store = store or CoreParamStore(core)
        self.server = None
        self.sink = sink
        self.mission_file = mission_file
        core.set_scenario_setpoints(False)
        core.disarm()
        self.nav_period_ns = int(_NS / nav_hz)
        self._next_ns = 0
        self.sim_ns = 0
        self.steps = 0
        self.step_wall_ns = 0
        self.cfg = NavConfig.from_store(self.store.host)
        self._cfg_version = self.store.version
        self.est = PositionEstimator(self.cfg.pos_tc_s, self.cfg.vel_tc_s, self.cfg.gps_delay_s)
        self.est.gate.configure(GateConfig.from_params(self.store.host))
        self.autodec = AutoDeclination()    # COMPASS_AUTODEC at the estimator origin
        self.pos_ctl = PosController(self.cfg.pos)
        self.wp = WaypointNav(self.cfg.wp)
        self.battery = BatteryMonitor(self.cfg.battery)   # the bridge's pack (BATTERY records)
        self.failsafe = FailsafeMonitor()
        self.fft_notices = FftNotices()     # the FFT's STATUSTEXTs (fft_notice.py)
        self.mission = MissionExecutor()
        self.pilot = PilotInput()
        self.fence = Geofence()             # fence.py: FENCE_* and the uploaded fence
        self.rally = RallyPoints()          # rally.py: where RTL goes
        self.fence.configure(self.store.host)
        self.rally.configure(self.store.host)
        self.home_epoch = 0                 # +1 when home is announced (HOME_POSITION)
        self.pilot.configure(RcConfig.from_params(self.store.host))
        self.mode_switch = ModeSwitch()
        self.messages: collections.deque = collections.deque(maxlen=200)   # (sim_ns, sev, text)
        # state read by modes, failsafes and telemetry
        self.armed = False
        self.airborne = False
        self.spool = 0
        self.status = None
        self.alt_m = 0.0
        self.climb_m_s = 0.0
        self.euler_rad = (0.0, 0.0, 0.0)
        self.q_wxyz = (1.0, 0.0, 0.0, 0.0)
        self.trust = 0.0
        self.last_seen_ns = (-1,) * 16
        self.rejected_recently = False
        self._rejected_prev = 0
        self._rejected_at_ns = None
        self.first_imu_ns = None
        self.imu_run_s = 0.0
        self.gnss = None
        self.home_set = False
        self.home_ne = (0.0, 0.0)
        self.home_lat_e7 = self.home_lon_e7 = 0
        self.home_alt_msl_m = 0.0
        # The vertical channel's zero (alt_m = 0) is the arming point; its height above sea
        # level is the datum. Home is there too unless a GCS moved it (DO_SET_HOME), which
        # also locks it: then it neither follows the vehicle nor moves at arming.
        self.alt_datum_msl_m = 0.0
        self.home_locked = False
        self._gnss_alt_filt = None
        self.takeoff_in_progress = False
        self.landing = False
        self.alt_target_m = 0.0
        self.alt_hold_m = 0.0
        self.cmd_roll = self.cmd_pitch = 0.0
        self.yaw_target_rad = 0.0
        self.yaw_rate_cmd = None
        self.speed_override_m_s = None
        self._landed_since_ns = None
        self.accel_frd = (0.0, 0.0, -9.80665)
        self.guided_att = None
        self.mode: M.Mode = M.Stabilize()
        self.setpoints_ignored = 0
        self.custom_version = _git_hash()
        self._load_window = (time.monotonic_ns(), 0, 0)    # (wall start, step ns, permille)
        # Failure injection (fault_inject.py): MAV_CMD_INJECT_FAILURE, SIM_* parameters and a
        # scenario's FC-side [[failure]] entries; set on the command line, SIM_* act at once.
        self.faults = FaultInjector(self, self.statustext)
        self._sync_sim_faults()

    # ============================================================================================
    # wiring

    def attach_server(self, server) -> None:
        """Serve this vehicle on a GcsServer (built with this vehicle and self.store)."""
        self.server = server
        self._publish()

    def after_batch(self, loop, recs, pwm, status) -> None:
        t = loop.last_sim_ns
        if t < self._next_ns:
            return
        self.step(t)
        if self.faults.outbox:      # switched faults, to the bridge beside the PWM
            loop.push_records(self.faults.take_outbox())

    # ============================================================================================
    # the outer loop

    def step(self, sim_ns: int) -> None:
        w0 = time.perf_counter_ns()
        dt_s = self.nav_period_ns / _NS if self.steps == 0 else (sim_ns - self.sim_ns) / _NS
        dt_s = min(0.1, max(1e-4, dt_s))
        self.sim_ns = sim_ns
        self._next_ns = sim_ns - sim_ns % self.nav_period_ns + self.nav_period_ns
        self.steps += 1
        self.faults.tick(sim_ns)
        self.store.apply()
        if self.store.version != self._cfg_version:
            self._reconfigure()
        if self.server is not None:
            self.server.service()
        self._read_core()
        self._estimate(dt_s)
        self.follow_xy_reset()
        self.battery.read(self.core)
        self.failsafe.check(self)
        self.fft_notices.check(self)
        self.fence.check(self)
        self._read_mode_switch()
        self.landing = False
        if self.armed:
            self.mode.run(self, dt_s)
            self._apply_attitude()
            self._auto_disarm()
        else:
            self.cmd_roll = self.cmd_pitch = 0.0
        self._publish()
        self.step_wall_ns += time.perf_counter_ns() - w0

    def _reconfigure(self) -> None:
        self._cfg_version = self.store.version
        self.cfg = NavConfig.from_store(self.store.host)
        self.pos_ctl.g = self.cfg.pos
        self.wp.sp = self._wp_speeds(self.speed_override_m_s)
        self.battery.configure(self.cfg.battery)
        self.est.configure(self.cfg.pos_tc_s, self.cfg.vel_tc_s, self.cfg.gps_delay_s)
        self.est.gate.configure(GateConfig.from_params(self.store.host))
        self.fence.configure(self.store.host)
        self.rally.configure(self.store.host)
        self.pilot.configure(RcConfig.from_params(self.store.host))
        self._sync_sim_faults()

    # ---- failure injection: the FC-side links (fault_inject.py) ---------------------------------

    def _sync_sim_faults(self) -> None:
        g = self.gnss
        lat_deg = g["lat_e7"] * 1e-7 if g is not None else 0.0
        self.faults.sync_sim_params(self.store.host, lat_deg)

    def rc_link_lost(self, lost: bool) -> None:
        self.pilot.set_lost(lost)

    def gcs_link_lost(self, lost: bool) -> None:
        if self.server is not None:
            self.server.set_link_lost(lost)

    def _read_core(self) -> None:
        st = self.core.status()
        self.status = st
        self.airborne = bool(st["airborne"])
        self.spool = int(st["spool"])
        self.alt_m = float(st["alt_est_m"])
        self.climb_m_s = float(st["climb_est_m_s"])
        e = st["euler_est_rad"]
        self.euler_rad = (float(e[0]), float(e[1]), float(e[2]))
        q = st["q_est_wxyz"]
        self.q_wxyz = (float(q[0]), float(q[1]), float(q[2]), float(q[3]))
        self.trust = float(st["trust"])
        self.last_seen_ns = self.core.last_seen_ns()
        rej = int(st["rejected_count"])
        if rej != self._rejected_prev:
            self._rejected_prev = rej
            self._rejected_at_ns = self.sim_ns
        self.rejected_recently = (self._rejected_at_ns is not None
                                  and self.sim_ns - self._rejected_at_ns < _NS)
        imu_t = self.last_seen_ns[1]
        if imu_t >= 0:
            if self.first_imu_ns is None:
                self.first_imu_ns = imu_t
            self.imu_run_s = (imu_t - self.first_imu_ns) / _NS

    @property
    def yaw_rad(self) -> float:
        return self.euler_rad[2]

    def _estimate(self, dt_s: float) -> None:
        acc = self.core.take_accel_mean()
        if acc is not None:
            self.accel_frd = acc
        self.est.predict(self.sim_ns, dt_s, self.q_wxyz, acc)
        if not self.airborne:
            self.est.hold_on_ground()
        fix = self.core.gnss()
        if fix is not None and fix["sim_ns"] != self.est.last_fix_sim_ns:
            self.gnss = fix
            self.est.fuse_gnss(fix, -self.climb_m_s)
            o = self.est.origin
            if o is not None:     # COMPASS_AUTODEC: the value is set, not saved (ArduCopter)
                dec = self.autodec.due(self.store.host("COMPASS_AUTODEC"), o.lat_e7, o.lon_e7)
                if dec is not None:
                    self.store.set("COMPASS_DEC", dec)
            if fix["fix_type"] >= 3 and not self.armed:
                a = fix["alt_mm"] * 1e-3
                if self._gnss_alt_filt is None:
                    self._gnss_alt_filt = a
                else:
                    k = min(1.0, 0.1 / HOME_ALT_TC_S)
                    self._gnss_alt_filt += k * (a - self._gnss_alt_filt)
        if self.est.valid and not self.armed and self._gnss_alt_filt is not None:
            # ArduCopter: home follows the vehicle until arming, then stays
            self._set_home()

    def _set_home(self, announce: bool = False) -> None:
        """Home follows the vehicle while disarmed; like ArduCopter, a GCS is told (HOME_POSITION
        unasked) only when home is first set and when arming fixes it. A home a GCS set stays."""
        if self._gnss_alt_filt is not None:
            self.alt_datum_msl_m = self._gnss_alt_filt
        if self.home_locked:
            return
        if announce or not self.home_set:
            self.home_epoch += 1
        self.home_ne = (self.est.pos_ne_m[0], self.est.pos_ne_m[1])
        self.home_lat_e7, self.home_lon_e7 = self.est.latlon_e7()
        self.home_alt_msl_m = self.alt_datum_msl_m
        self.home_set = True

    def move_home(self, lat_e7: int, lon_e7: int, alt_msl_m: float) -> None:
        """A GCS's home (DO_SET_HOME): announced at once, kept until the next one."""
        self.home_ne = self.est.origin.to_ne(lat_e7, lon_e7)
        self.home_lat_e7, self.home_lon_e7 = int(lat_e7), int(lon_e7)
        self.home_alt_msl_m = float(alt_msl_m)
        self.home_set = self.home_locked = True
        self.home_epoch += 1

    @property
    def home_up_m(self) -> float:
        """Home's altitude in the vertical channel's frame (0 unless a GCS moved home)."""
        return self.home_alt_msl_m - self.alt_datum_msl_m if self.home_set else 0.0

    def alt_from_msl(self, alt_msl_m: float) -> float:
        return alt_msl_m - self.alt_datum_msl_m

    def alt_from_home(self, alt_rel_m: float) -> float:
        """An altitude above home (RTL_ALT, relative frames, the fence) in the vertical frame."""
        return alt_rel_m + self.home_up_m

    def position_ok(self) -> bool:
        """Copter::position_ok: an absolute position (the GNSS gate has not timed out,
        gnss_gate.py) and no EKF failsafe (ekf_check.py)."""
        return self.est.has_position(self.sim_ns) and not self.failsafe.ekf.failsafe

    @property
    def radio_failsafe_active(self) -> bool:
        return self.failsafe.radio.active

    # ---- outputs -------------------------------------------------------------------------

    def _apply_attitude(self) -> None:
        if self.yaw_rate_cmd is not None:
            self.core.set_attitude_target(self.cmd_roll, self.cmd_pitch,
                                          yaw_rate_rad_s=self.yaw_rate_cmd)
        else:
            self.core.set_attitude_target(self.cmd_roll, self.cmd_pitch,
                                          yaw_rad=self.yaw_target_rad)

    def _auto_disarm(self) -> None:
        delay = self.cfg.disarm_delay_s
        if delay <= 0 or self.airborne or self.spool == 2 or self.takeoff_in_progress \
                or (self.mode.manual_throttle and self.pilot_throttle_stick() > 0.05):
            self._landed_since_ns = None
            return
        if self._landed_since_ns is None:
            self._landed_since_ns = self.sim_ns
        elif self.sim_ns - self._landed_since_ns >= delay * _NS:
            self._disarm("Disarming motors (auto)")

    def _disarm(self, text: str | None) -> None:
        self.core.disarm()
        self.armed = False
        self.takeoff_in_progress = False
        self._landed_since_ns = None
        self.mission.on_disarm()
        if text:
            self.statustext(mav.MAV_SEVERITY_INFO, text)
        self._event("disarmed")

    def disarm_landed(self, who: str) -> None:
        if self.armed:
            self._disarm(f"{who}: landed, disarming")

    def failsafe_disarm(self) -> None:
        self._disarm(None)

    def fence_disarm(self) -> None:
        self._disarm("Disarming motors (fence breach)")

    def fence_set_mode(self, number: int) -> bool:
        """A fence action's mode change; True if the vehicle is now in that mode."""
        return self._change_mode(number) is None

    def mission_item_reached(self, seq: int) -> None:
        if self.server is not None:
            self.server.mission_item_reached(seq)
        self.statustext(mav.MAV_SEVERITY_INFO, f"Reached command #{seq}")

    def statustext(self, severity: int, text: str) -> None:
        self.messages.append((self.sim_ns, severity, text))
        if self.server is not None:
            self.server.send_statustext(severity, text)
        self._event(text)

    def _event(self, text: str) -> None:
        if self.sink is not None and hasattr(self.sink, "event"):
            self.sink.event(self.sim_ns, "vehicle", text)

    def _publish(self) -> None:
        if self.server is not None:
            self.server.publish(build_snapshot(self))

    def snapshot(self):
        return build_snapshot(self)

    def summary(self) -> dict:
        """End-of-run figures for `silbridge fc --json`."""
        out = {"mode": self.mode.name, "armed": self.armed, "outer_steps": self.steps,
               "outer_step_us_mean": (self.step_wall_ns / self.steps / 1e3) if self.steps
               else None, "setpoints_ignored": self.setpoints_ignored,
               "statustext": [t for _, _, t in list(self.messages)[-20:]]}
        if self.server is not None:
            c = self.server.counters()
            out["server"] = c
        return out

    def load_permille(self) -> int:
        """Share of wall time the outer loop used over the last second (SYS_STATUS load)."""
        start, used0, last = self._load_window
        now = time.monotonic_ns()
        if now - start >= _NS:
            last = int(1000 * (self.step_wall_ns - used0) / (now - start))
            self._load_window = (now, self.step_wall_ns, last)
        return last

    # ============================================================================================
    # modes

    def _change_mode(self, number: int) -> str | None:
        cls = M.MODES.get(number)
        if cls is None:
            return f"Flight mode change failed: unknown mode {number}"
        if cls.requires_position and not self.position_ok():
            return f"Flight mode change failed: {cls.name} requires position"
        new = cls()
        reason = new.enter(self)
        if reason:
            return reason
        if new.number != self.mode.number:
            self.mode.exit(self)
            # ArduCopter: any mode change during a breach is a manual recovery attempt
            self.fence.manual_recovery_start(self)
        self.mode = new
        self.yaw_rate_cmd = None
        self.guided_att = None
        self._event(f"mode {new.name}")
        return None

    def set_mode_internal(self, number: int, why: str) -> None:
        """A failsafe's mode change: LAND if the wanted mode refuses; a failsafe's LAND holds
        its altitude a few seconds first (ArduCopter's set_mode_land_with_pause)."""
        reason = self._change_mode(number)
        if reason and number != CopterMode.LAND:
            log.info("%s: %s refused (%s), landing", why, M.MODE_NAMES.get(number), reason)
            self._change_mode(CopterMode.LAND)
        if self.mode.number == CopterMode.LAND:
            self.mode.pause(self)    # set_mode_land_with_pause

def _git_hash() -> str:
    """AUTOPILOT_VERSION.flight_custom_version: the source's git hash (8 chars) if known."""
    import os
    import subprocess
    try:
        out = subprocess.run(["git", "rev-parse", "--short=8", "HEAD"], capture_output=True,
                             text=True, timeout=2.0,
                             cwd=os.path.dirname(os.path.abspath(__file__)))
    except (OSError, subprocess.SubprocessError):
        return "00000000"
    h = out.stdout.strip()
    return h[:8].ljust(8, "0") if out.returncode == 0 and h else "00000000"
