"""Vehicle: the ArduCopter-like flight logic around the C core, obeying a GCS over MAVLink.

The vehicle is the FcLoop's supervisor: ``after_batch`` runs on the FC's main thread after
every poll and returns at once (one compare) unless an outer-loop step is due; steps run at
``nav_hz`` (50 Hz) of SIMULATION time, so the vehicle flies identically in lockstep, in real
time and at ``--speed X``. One step:

  parameters queued by the GCS -> live core (param_store.py), config re-read if changed;
  GcsServer.service(): queued GCS requests run here, on this thread (the VehicleCommands
  methods below), so they never race the control loop;
  estimation: C core status (attitude, baro/accel altitude), position estimator (pos_est.py)
  fed by the raw accelerometer mean and each new GNSS fix; battery model (battery.py);
  failsafes (failsafe.py); the flight mode's outer loops (modes.py, mission_exec.py,
  nav_pos.py, nav_wp.py) -> the core's attitude / altitude / climb / throttle inputs;
  auto-disarm; a new VehicleSnapshot published to the server (snapshot.py).

Under MAVLink control the vehicle starts disarmed in STABILIZE on the ground and obeys the
GCS only: the core is told to skip the scenario's SETPOINT records.

Altitudes are metres up above home (the C core's altitude is relative to the arming point,
which is home); horizontal positions are metres NE about the estimator origin (first fix).
"""

from __future__ import annotations

import collections
import logging
import math
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.vehicle_api import CopterMode

from . import modes as M
from .battery import BatteryModel
from .failsafe import FailsafeMonitor
from .mission_exec import MissionExecutor
from .nav_config import NavConfig
from .nav_pos import PosController
from .nav_wp import WaypointNav, WpSpeeds
from .param_store import CoreParamStore
from .pilot import PilotInput
from .pos_est import PositionEstimator
from .prearm import prearm_failure
from .snapshot import build_snapshot

log = logging.getLogger(__name__)
_NS = 1_000_000_000
ACCEPTED, FAILED, DENIED = mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_FAILED, mav.MAV_RESULT_DENIED
TYPE_MASK_POS = 0x7
TYPE_MASK_VEL = 0x38
TYPE_MASK_YAW = 0x400
TYPE_MASK_YAW_RATE = 0x800
ATT_MASK_ATTITUDE = 0x80
# home altitude: GNSS altitude averaged while disarmed (one fix is +-3 m; this EMA settles it)
HOME_ALT_TC_S = 5.0


class Vehicle:
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
        self.pos_ctl = PosController(self.cfg.pos)
        self.wp = WaypointNav(self.cfg.wp)
        self.battery = BatteryModel(self.cfg.battery, self.cfg.pwm_min_us, self.cfg.pwm_max_us)
        self.failsafe = FailsafeMonitor()
        self.mission = MissionExecutor()
        self.pilot = PilotInput()
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
        self.vibe = [0.0, 0.0, 0.0]
        self._acc_lp = None
        self.accel_frd = (0.0, 0.0, -9.80665)
        self.guided_att = None
        self.mode: M.Mode = M.Stabilize()
        self.setpoints_ignored = 0
        self.custom_version = _git_hash()
        self._load_window = (time.monotonic_ns(), 0, 0)    # (wall start, step ns, permille)

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

    # ============================================================================================
    # the outer loop

    def step(self, sim_ns: int) -> None:
        w0 = time.perf_counter_ns()
        dt_s = self.nav_period_ns / _NS if self.steps == 0 else (sim_ns - self.sim_ns) / _NS
        dt_s = min(0.1, max(1e-4, dt_s))
        self.sim_ns = sim_ns
        self._next_ns = sim_ns - sim_ns % self.nav_period_ns + self.nav_period_ns
        self.steps += 1
        self.store.apply()
        if self.store.version != self._cfg_version:
            self._reconfigure()
        if self.server is not None:
            self.server.service()
        self._read_core()
        self._estimate(dt_s)
        self.battery.update(self.status["pwm_us"] if self.armed else (), dt_s)
        self.failsafe.check(self)
        self._radio_failsafe()
        self.landing = False
        self.yaw_rate_cmd = None if self.yaw_rate_cmd is None else self.yaw_rate_cmd
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
        self.battery.configure(self.cfg.battery, self.cfg.pwm_min_us, self.cfg.pwm_max_us)
        self.est.configure(self.cfg.pos_tc_s, self.cfg.vel_tc_s, self.cfg.gps_delay_s)

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
            self._vibration(acc, dt_s)
        self.est.predict(self.sim_ns, dt_s, self.q_wxyz, acc)
        if not self.airborne:
            self.est.hold_on_ground()
        fix = self.core.gnss()
        if fix is not None and fix["sim_ns"] != self.est.last_fix_sim_ns:
            self.gnss = fix
            self.est.fuse_gnss(fix)
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

    def _vibration(self, acc, dt_s: float) -> None:
        """ArduPilot's VIBE: RMS of the accel about its 5 Hz low-pass, per axis."""
        if self._acc_lp is None:
            self._acc_lp = list(acc)
        k = min(1.0, dt_s * 2.0 * math.pi * 5.0)
        kv = min(1.0, dt_s * 2.0 * math.pi * 2.0)
        for i in range(3):
            self._acc_lp[i] += k * (acc[i] - self._acc_lp[i])
            d = acc[i] - self._acc_lp[i]
            self.vibe[i] += kv * (d * d - self.vibe[i])

    def _set_home(self) -> None:
        self.home_ne = (self.est.pos_ne_m[0], self.est.pos_ne_m[1])
        self.home_lat_e7, self.home_lon_e7 = self.est.latlon_e7()
        if self._gnss_alt_filt is not None:
            self.home_alt_msl_m = self._gnss_alt_filt
        self.home_set = True

    def position_ok(self) -> bool:
        g = self.gnss
        return (self.est.valid and g is not None and g["fix_type"] >= 3
                and self.sim_ns - g["sim_ns"] <= self.cfg.gps_timeout_s * _NS)

    def gcs_silence_s(self) -> float | None:
        """Seconds since the last SYSID_MYGCS heartbeat; None without a server or GCS."""
        if self.server is None:
            return None
        s = self.server.seconds_since_gcs_heartbeat()
        return None if s == float("inf") else s

    # ============================================================================================
    # helpers the modes use

    def _wp_speeds(self, speed_m_s: float | None) -> WpSpeeds:
        sp = self.cfg.wp
        if speed_m_s:
            return WpSpeeds(speed_m_s, sp.up_m_s, sp.dn_m_s, sp.accel_m_s2, sp.radius_m)
        return sp

    def reset_vertical(self) -> None:
        self.alt_target_m = self.alt_m if self.airborne else min(self.alt_m, 0.0)
        self.alt_hold_m = self.alt_m if self.airborne else 0.0

    def reset_horizontal(self) -> None:
        self.pos_ctl.reset(self.est.vel_ne_m_s)

    def command_attitude(self, roll_rad: float, pitch_rad: float) -> None:
        self.cmd_roll, self.cmd_pitch = roll_rad, pitch_rad

    def command_throttle(self, throttle: float) -> None:
        self.core.set_throttle(min(1.0, max(0.0, throttle)))
        self.alt_target_m = self.alt_hold_m = self.alt_m

    def command_vertical(self, dt_s: float, goal_m: float) -> None:
        """Hold/approach an altitude, moving the target at WPNAV_SPEED_UP/_DN."""
        sp = self.cfg.wp
        if not self.airborne and goal_m <= 0.0:
            self.alt_target_m = goal_m
        else:
            err = goal_m - self.alt_target_m
            self.alt_target_m += max(-sp.dn_m_s * dt_s, min(sp.up_m_s * dt_s, err))
        self.core.set_altitude_target(self.alt_target_m)

    def command_climb(self, dt_s: float, climb_m_s: float) -> None:
        self.core.set_climb_rate(climb_m_s)
        self.alt_target_m = self.alt_hold_m = self.alt_m

    def land_descent(self, dt_s: float) -> bool:
        """LAND's vertical channel; True once touched down (the core's land detector)."""
        self.landing = True
        if self.armed and not self.airborne and self.spool != 2:
            return True
        fast = self.alt_m > self.cfg.land_alt_low_m
        speed = self.cfg.wp.dn_m_s if fast else self.cfg.land_speed_m_s
        self.core.set_climb_rate(-speed)
        self.alt_target_m = self.alt_hold_m = 0.0
        return False

    def hold_position(self, dt_s: float, target_ne, vel_ne, speed_m_s: float) -> None:
        if not self.airborne or not self.position_ok():
            self.pos_ctl.reset(self.est.vel_ne_m_s if self.airborne else (0.0, 0.0))
            self.command_attitude(0.0, 0.0)
            return
        roll, pitch = self.pos_ctl.update(dt_s, self.est.pos_ne_m, self.est.vel_ne_m_s,
                                          target_pos=target_ne, target_vel=vel_ne,
                                          speed_max_m_s=speed_m_s, yaw_rad=self.yaw_rad)
        self.command_attitude(roll, pitch)

    def start_track(self, dest_ne, alt_m: float, speed_m_s: float | None) -> None:
        self.wp.sp = self._wp_speeds(speed_m_s or self.speed_override_m_s)
        start_alt = self.alt_target_m if self.airborne else self.alt_m
        speed = math.hypot(*self.est.vel_ne_m_s) if self.airborne else 0.0
        self.wp.set_destination(self.est.pos_ne_m, start_alt, dest_ne, alt_m, speed)

    def fly_track(self, dt_s: float) -> bool:
        """Follow the active track; True when its destination is reached."""
        tp, tv, talt = self.wp.update(dt_s, self.est.pos_ne_m, self.alt_m)
        self.hold_position(dt_s, tp, tv, self.wp.sp.speed_m_s * 1.2)
        self.alt_target_m = talt
        self.alt_hold_m = self.wp.dest[2]
        self.core.set_altitude_target(talt)
        if not self.airborne and talt > 0.0:
            self.takeoff_in_progress = True
        return self.wp.reached(self.est.pos_ne_m, self.alt_m)

    def track_dest_ne(self):
        return self.wp.dest[0], self.wp.dest[1]

    def face_track(self, rtl: bool) -> None:
        b = self.wp.bearing_rad
        behave = self.cfg.wp_yaw_behavior
        if b is None or behave == 0 or (behave == 2 and rtl):
            return
        self.yaw_target_rad = b

    def hold_heading(self) -> None:
        self.yaw_rate_cmd = None

    # ---- pilot ----------------------------------------------------------------------------

    def _pilot_fresh(self) -> bool:
        return self.pilot.fresh(self.cfg.rc_fs_timeout_s)

    def pilot_sticks_rpy(self) -> tuple[float, float, float]:
        if not self._pilot_fresh():
            return 0.0, 0.0, 0.0
        return self.pilot.roll, self.pilot.pitch, self.pilot.yaw

    def pilot_throttle_stick(self) -> float:
        """0..1; 0 without fresh pilot input (throttle down)."""
        return self.pilot.throttle if self._pilot_fresh() else 0.0

    def pilot_attitude(self) -> None:
        r, p, y = self.pilot_sticks_rpy()
        a = self.cfg.angle_max_rad
        self.command_attitude(r * a, p * a)
        self.pilot_yaw(y)

    def pilot_yaw(self, yaw_in: float) -> None:
        if abs(yaw_in) > 0.05:
            self.yaw_rate_cmd = yaw_in * self.cfg.pilot_y_rate_rad_s
            self.yaw_target_rad = self.yaw_rad
        else:
            self.yaw_rate_cmd = None

    def pilot_throttle(self) -> float:
        """STABILIZE: stick centre = hover throttle (ArduCopter's throttle curve)."""
        z = self.pilot_throttle_stick()
        h = self.cfg.hover_throttle
        return z / 0.5 * h if z <= 0.5 else h + (z - 0.5) / 0.5 * (1.0 - h)

    def pilot_vertical(self, dt_s: float) -> None:
        """ALT_HOLD/LOITER: stick = climb rate outside a 10 % dead zone, centre = hold.
        Without pilot input the stick counts as centred (hold)."""
        z = self.pilot.throttle if self._pilot_fresh() else 0.5
        if z > 0.6:
            self.command_climb(dt_s, (z - 0.6) / 0.4 * self.cfg.pilot_speed_up_m_s)
        elif z < 0.4:
            self.command_climb(dt_s, (z - 0.4) / 0.4 * self.cfg.pilot_speed_dn_m_s)
        else:
            self.command_vertical(dt_s, self.alt_hold_m)

    def _radio_failsafe(self) -> None:
        age = self.pilot.age_s()
        if age is None or age <= self.cfg.rc_fs_timeout_s or getattr(self, "_rc_fs", False):
            if age is not None and age <= self.cfg.rc_fs_timeout_s:
                self._rc_fs = False
            return
        self._rc_fs = True
        if self.armed and self.airborne and self.mode.number in (
                CopterMode.STABILIZE, CopterMode.ALT_HOLD, CopterMode.LOITER):
            self.statustext(mav.MAV_SEVERITY_CRITICAL, "Radio Failsafe")
            target = CopterMode.RTL if self.home_set and self.position_ok() else CopterMode.LAND
            self.set_mode_internal(target, "radio failsafe")

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
        if text:
            self.statustext(mav.MAV_SEVERITY_INFO, text)
        self._event("disarmed")

    def disarm_landed(self, who: str) -> None:
        if self.armed:
            self._disarm(f"{who}: landed, disarming")

    def failsafe_disarm(self) -> None:
        self._disarm(None)

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
        self.mode = new
        self.yaw_rate_cmd = None
        self.guided_att = None
        self._event(f"mode {new.name}")
        return None

    def set_mode_internal(self, number: int, why: str) -> None:
        """A failsafe's mode change: LAND if the wanted mode refuses."""
        reason = self._change_mode(number)
        if reason and number != CopterMode.LAND:
            log.info("%s: %s refused (%s), landing", why, M.MODE_NAMES.get(number), reason)
            self._change_mode(CopterMode.LAND)

    # ============================================================================================
    # VehicleCommands (run on this thread by GcsServer.service(); tests may call them directly)

    def arm(self, force: bool):
        if self.armed:
            return ACCEPTED, None
        if not force and self.cfg.arming_check:
            reason = prearm_failure(self)
            if reason:
                return FAILED, reason
        if self.est.valid:
            self._set_home()
        self.reset_vertical()
        self.reset_horizontal()
        self.alt_target_m = self.alt_hold_m = 0.0
        self.yaw_target_rad = self.yaw_rad
        self.yaw_rate_cmd = None
        self.core.set_altitude_target(0.0)
        if self.mode.manual_throttle:
            self.core.set_throttle(0.0)
        self.core.set_attitude_target(0.0, 0.0, yaw_rad=self.yaw_rad)
        self.core.arm()
        self.armed = True
        self._landed_since_ns = self.sim_ns
        self._event("armed")
        return ACCEPTED, None

    def disarm(self, force: bool):
        if not self.armed:
            return ACCEPTED, None
        if self.airborne and not force:
            return DENIED, "Disarm: vehicle is flying (force to disarm in flight)"
        self._disarm(None)
        return ACCEPTED, None

    def set_mode(self, custom_mode: int):
        if custom_mode == self.mode.number:
            return ACCEPTED, None
        reason = self._change_mode(custom_mode)
        return (FAILED, reason) if reason else (ACCEPTED, None)

    def takeoff(self, alt_m: float):
        if not self.armed:
            return FAILED, "Takeoff: vehicle not armed"
        if self.mode.number != CopterMode.GUIDED:
            return FAILED, f"Takeoff: not supported in {self.mode.name}, use GUIDED"
        if self.airborne:
            return FAILED, "Takeoff: already flying"
        if not self.position_ok():
            return FAILED, "Takeoff: need a position estimate (GPS)"
        self.mode.start_takeoff(self, max(float(alt_m), self.cfg.takeoff_min_m))
        self._landed_since_ns = None
        return ACCEPTED, None

    def land(self):
        return self.set_mode(CopterMode.LAND)

    def rtl(self):
        return self.set_mode(CopterMode.RTL)

    def mission_start(self, first: int, last: int):
        if 0 < first < len(self.mission.items):
            self.mission.current = first
        if self.mode.number == CopterMode.AUTO:
            # MISSION_START in AUTO (MAVSDK sends it after the mode change): (re)start
            reason = self.mission.start(self, first if first > 0 else None)
        else:
            reason = self._change_mode(CopterMode.AUTO)
        return (FAILED, reason) if reason else (ACCEPTED, None)

    def reposition(self, lat_e7, lon_e7, alt_m, frame, speed_m_s, yaw_deg):
        if not self.armed or not self.airborne:
            return DENIED, "Reposition: take off first"
        if self.est.origin is None:
            return FAILED, "Reposition: no position estimate"
        if self.mode.number != CopterMode.GUIDED:
            reason = self._change_mode(CopterMode.GUIDED)
            if reason:
                return FAILED, reason
        ne = self.est.origin.to_ne(lat_e7, lon_e7)
        alt = alt_m if frame in (mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                 mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT) \
            else alt_m - self.home_alt_msl_m
        speed = speed_m_s if math.isfinite(speed_m_s) and speed_m_s > 0 else None
        self.mode.go_to(self, ne, alt, speed)
        if math.isfinite(yaw_deg):
            self.yaw_target_rad = math.radians(yaw_deg)
        else:
            self.face_track(rtl=False)
        return ACCEPTED, None

    def change_speed(self, speed_m_s: float, speed_type: int):
        if speed_m_s > 0:
            self.speed_override_m_s = float(speed_m_s)
            self.wp.sp = self._wp_speeds(self.speed_override_m_s)
        elif speed_m_s not in (-1.0, -2.0):
            return DENIED, "Change speed: speed must be > 0 (or -1 for no change)"
        return ACCEPTED, None

    def mission_set_current(self, seq: int):
        reason = self.mission.set_current(seq, self)
        return (DENIED, reason) if reason else (ACCEPTED, None)

    def mission_updated(self, items) -> None:
        self.mission.set_items(items, self)
        if self.mission_file:
            from silbridge.mavlink.errors import MissionFileError
            from silbridge.mavlink.wpl import save_wpl
            try:
                save_wpl(self.mission_file, items)
            except (MissionFileError, OSError) as exc:
                self.statustext(mav.MAV_SEVERITY_ERROR, f"Mission save failed: {exc}"[:150])

    def set_position_target(self, t) -> None:
        if self.mode.number != CopterMode.GUIDED or not self.armed or not self.airborne \
                or self.est.origin is None:
            self.setpoints_ignored += 1     # ArduCopter: take off first
            return
        mask = t.type_mask
        use_pos = (mask & TYPE_MASK_POS) != TYPE_MASK_POS
        use_vel = (mask & TYPE_MASK_VEL) != TYPE_MASK_VEL
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        vel = tuple(t.vel_ned_m_s)
        if t.is_global:
            ne = self.est.origin.to_ne(int(t.x), int(t.y))
            rel = t.frame in (mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                              mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                              mav.MAV_FRAME_GLOBAL_TERRAIN_ALT,
                              mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT)
            alt = t.z if rel else t.z - self.home_alt_msl_m
        elif t.frame == mav.MAV_FRAME_LOCAL_NED:
            ne = (t.x, t.y)
            alt = -t.z - (self.home_alt_msl_m - self.est.origin.alt_msl_m)
        else:
            dx, dy = t.x, t.y
            if t.frame in (mav.MAV_FRAME_BODY_NED, mav.MAV_FRAME_BODY_OFFSET_NED):
                dx, dy = dx * c - dy * s, dx * s + dy * c
                vel = (vel[0] * c - vel[1] * s, vel[0] * s + vel[1] * c, vel[2])
            ne = (self.est.pos_ne_m[0] + dx, self.est.pos_ne_m[1] + dy)
            alt = self.alt_m - t.z
        if not (mask & TYPE_MASK_YAW) and math.isfinite(t.yaw_rad):
            self.yaw_target_rad = t.yaw_rad
            self.yaw_rate_cmd = None
        if use_pos and all(map(math.isfinite, (*ne, alt))):
            self.mode.go_to(self, ne, alt)
            if mask & TYPE_MASK_YAW:
                self.face_track(rtl=False)
        elif use_vel and all(map(math.isfinite, vel)):
            self.mode.set_velocity(self, vel[:2], -vel[2])
        else:
            self.setpoints_ignored += 1

    def set_attitude_target(self, t) -> None:
        if self.mode.number != CopterMode.GUIDED or not self.armed or not self.airborne:
            self.setpoints_ignored += 1
            return
        if t.type_mask & ATT_MASK_ATTITUDE or not all(map(math.isfinite, t.q_wxyz)):
            self.setpoints_ignored += 1
            return
        w, x, y, z = t.q_wxyz
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        # ArduCopter (GUID_OPTIONS bit 3 clear): thrust 0.5 = hold, 0/1 = full descent/climb
        th = min(1.0, max(0.0, t.thrust)) if math.isfinite(t.thrust) else 0.5
        climb = (th - 0.5) * 2.0 * (self.cfg.wp.up_m_s if th >= 0.5 else self.cfg.wp.dn_m_s)
        self.mode.set_attitude(self, roll, pitch, yaw, climb)

    def manual_control(self, x, y, z, r, buttons) -> None:
        self.pilot.manual_control(x, y, z, r)

    def rc_override(self, channels_us) -> None:
        self.pilot.rc_override(channels_us)


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
