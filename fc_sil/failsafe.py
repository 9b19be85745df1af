"""Failsafes: what the vehicle does when a link, a sensor or the battery lets it down.

Checked at the outer-loop rate; each failsafe latches (one action, one STATUSTEXT) and clears
when its cause is gone, as ArduCopter's do. Actions are requests to the vehicle
(``set_mode_internal``, ``failsafe_disarm``); the vehicle decides what a mode change means
when it is on the ground (nothing: a landed vehicle only stays landed).

* GCS: a HEARTBEAT from SYSID_MYGCS was seen and then none for FS_GCS_TIMEOUT of sim time
  while armed and flying -> RTL (FS_GCS_ENABLE 1) or LAND (5). Sim time as ArduCopter SITL,
  whose millis() is its simulated clock: a lockstep run at --speed 10 meets the failsafe at
  the same sim time as at --speed 1, and a ground station heartbeating at 1 Hz of wall time
  is silent for `speed` sim seconds between beats (docs/reference/failsafes.md). FS_OPTIONS
  may let the flight go on (fs_options.py; by default a pilot-flown mode goes on).
* radio: radio_failsafe.py (pilot input lost or throttle below FS_THR_VALUE -> FS_THR_ENABLE).
* sensors (sim time, SB_FS_SENS_TO): IMU stream lost -> motors to a safe state (disarm: the
  FC cannot stabilise without rates, and spinning motors under no control are the danger);
  barometer lost while flying -> LAND. GNSS loss is the EKF failsafe's, as in ArduCopter.
* estimator and flight checks as ArduCopter 4.6 (docs/reference/failsafes.md), each in its
  module: the innovation test ratios (innov_ratios.py), GPS glitch messages (gps_glitch.py),
  EKF failsafe (ekf_check.py), vibration (vibe_check.py), crash (crash_check.py), thrust
  loss (thrust_loss.py), yaw imbalance (yaw_imbalance.py).
* battery (the bridge's pack, battery.py): voltage below BATT_LOW_VOLT (BATT_CRT_VOLT) for BATT_LOW_TIMER, or remaining
  capacity below BATT_LOW_MAH (BATT_CRT_MAH) -> BATT_FS_LOW_ACT (BATT_FS_CRT_ACT):
  0 warn only, 1 LAND, 2 RTL (LAND when RTL is impossible).
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode
from silbridge.shm.records import NS_PER_S, Kind

from .crash_check import CrashCheck
from .fs_options import continuing
from .ekf_check import EkfCheck
from .gps_glitch import GpsGlitchCheck
from .innov_ratios import InnovationRatios
from .radio_failsafe import RadioFailsafe
from .thrust_loss import ThrustLossCheck
from .vibe_check import VibrationCheck
from .yaw_imbalance import YawImbalanceCheck

CRIT = mav.MAV_SEVERITY_CRITICAL


class GcsSilence:
    """Sim seconds since the last SYSID_MYGCS heartbeat (None: none heard yet). The server
    thread counts the heartbeats; one counts from the vehicle step that first sees it, as
    ArduCopter stamps last_heartbeat_ms when its main loop reads the message."""

    def __init__(self):
        self._heard = 0
        self._at_ns: int | None = None

    def update(self, heard: int, sim_ns: int) -> float | None:
        if heard != self._heard:
            self._heard, self._at_ns = heard, sim_ns
        return None if self._at_ns is None else max(0, sim_ns - self._at_ns) / NS_PER_S


class FailsafeMonitor:
    def __init__(self):
        self.gcs = False
        self.gcs_silence = GcsSilence()
        self.radio = RadioFailsafe()
        self.imu = False
        self.baro = False
        self.ratios = InnovationRatios()
        self.glitch = GpsGlitchCheck()
        self.ekf = EkfCheck()
        self.vibe = VibrationCheck()
        self.crash = CrashCheck()
        self.thrust = ThrustLossCheck()
        self.yaw = YawImbalanceCheck()
        self.batt_low = False
        self.batt_crit = False
        self._low_since_ns = None
        self._crit_since_ns = None

    @property
    def active(self) -> bool:
        return (self.gcs or self.imu or self.baro or self.ekf.failsafe or self.batt_low
                or self.batt_crit)

    def check(self, v) -> None:
        self._check_sensors(v)
        self._check_estimator(v)
        self._check_battery(v)
        self.check_links(v)

    # ---- sensors ----------------------------------------------------------------------------

    def _check_sensors(self, v) -> None:
        to_ns = int(v.cfg.sens_timeout_s * 1e9)
        seen = v.last_seen_ns
        imu_lost = seen[Kind.IMU] < 0 or v.sim_ns - seen[Kind.IMU] > to_ns
        if imu_lost and not self.imu and v.armed:
            self.imu = True
            v.statustext(CRIT, "Failsafe: IMU data lost, motors stopped")
            v.failsafe_disarm()
        elif not imu_lost:
            self.imu = False
        baro_lost = seen[Kind.BARO] < 0 or v.sim_ns - seen[Kind.BARO] > to_ns
        if baro_lost and not self.baro and v.armed and v.airborne:
            self.baro = True
            v.statustext(CRIT, "Failsafe: Baro data lost, landing")
            v.set_mode_internal(CopterMode.LAND, "baro failsafe")
        elif not baro_lost:
            self.baro = False

    # ---- estimator, crash, thrust loss, vibration (ArduCopter 4.6) -------------------------

    def _check_estimator(self, v) -> None:
        self.ratios.update(v)
        self.glitch.check(v, self.ratios)
        self.ekf.check(v, self.ratios)
        self.vibe.check(v, self.ekf)
        self.thrust.check(v)
        self.yaw.check(v, self.thrust.boost)
        self.crash.check(v)

    # ---- GCS and radio -----------------------------------------------------------------------

    def check_links(self, v) -> None:
        """The link failsafes alone (check() runs them with the others)."""
        self._check_gcs(v)
        self.radio.check(v)

    def _check_gcs(self, v) -> None:
        action = v.cfg.fs_gcs_enable
        heard = v.server.gcs_heartbeats if v.server is not None else 0
        silent_s = self.gcs_silence.update(heard, v.sim_ns)
        if silent_s is None or action == 0:
            self.gcs = False
            return
        lost = silent_s > v.cfg.fs_gcs_timeout_s
        if not lost:
            if self.gcs:
                v.statustext(mav.MAV_SEVERITY_INFO, "GCS Failsafe Cleared")
            self.gcs = False
            return
        if self.gcs or not (v.armed and v.airborne):
            return
        self.gcs = True
        going_on = continuing("GCS", v.mode.number, int(v.store.host("FS_OPTIONS")))
        v.statustext(CRIT, "GCS Failsafe" + (f" - {going_on}" if going_on else ""))
        if not going_on:
            self._act(v, 2 if action == 1 else 1, "GCS failsafe")

    # ---- battery ----------------------------------------------------------------------------

    def _check_battery(self, v) -> None:
        cfg, b = v.cfg, v.battery
        if not b.valid:         # no report from the bridge's pack yet
            return
        low = self._level(v, cfg.batt_low_volt, cfg.batt_low_mah, "_low_since_ns")
        crit = self._level(v, cfg.batt_crt_volt, cfg.batt_crt_mah, "_crit_since_ns")
        if crit and not self.batt_crit:
            self.batt_crit = True
            v.statustext(CRIT, f"Battery 1 is critical {b.voltage_v:.2f}V used "
                               f"{b.consumed_mah:.0f} mAh")
            if v.armed and v.airborne:
                self._act(v, cfg.batt_fs_crt_act, "battery critical")
        if low and not self.batt_low:
            self.batt_low = True
            v.statustext(CRIT, f"Battery 1 is low {b.voltage_v:.2f}V used "
                               f"{b.consumed_mah:.0f} mAh")
            if v.armed and v.airborne and not self.batt_crit:
                self._act(v, cfg.batt_fs_low_act, "battery low")

    def _level(self, v, volt: float, mah: float, since_attr: str) -> bool:
        b = v.battery
        hit_mah = mah > 0 and b.cfg.capacity_mah > 0 and b.remaining_mah < mah
        if volt > 0 and b.voltage_v < volt:
            since = getattr(self, since_attr)
            if since is None:
                setattr(self, since_attr, v.sim_ns)
                since = v.sim_ns
            hit_v = v.sim_ns - since >= int(v.cfg.batt_low_timer_s * 1e9)
        else:
            setattr(self, since_attr, None)
            hit_v = False
        return hit_mah or hit_v

    @staticmethod
    def _act(v, action: int, why: str) -> None:
        """1 LAND, 2 RTL (LAND when RTL is impossible); 0 warn only."""
        if action == 2 and v.home_set and v.position_ok():
            if v.mode.number not in (CopterMode.RTL, CopterMode.LAND):
                v.set_mode_internal(CopterMode.RTL, why)
        elif action in (1, 2):
            if v.mode.number != CopterMode.LAND:
                v.set_mode_internal(CopterMode.LAND, why)
