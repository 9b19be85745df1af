"""Pre-arm checks: the first failing check, worded as ArduCopter's STATUSTEXT ("PreArm: ...").

Run on every arm request (unless ARMING_CHECK is 0 or the arm is forced) and once a second
for SYS_STATUS's PREARM_CHECK health bit, which MAVSDK reads as "armable".

  sensors healthy : IMU, barometer and (COMPASS_USE) magnetometer streams fresh within
                    SB_FS_SENS_TO of sim time, and no samples refused lately (NaN/inf)
  AHRS converged  : the estimator has run for ESTIMATOR_SETTLE_S with its accelerometer
                    trust high (the vehicle is still and level enough to have a tilt)
  FFT             : with FFT_ENABLE, the in-flight FFT has learned its noise reference
  GPS             : modes that need a position have a 3D fix and a fused position estimate
  throttle low    : manual-throttle modes need the throttle stick down; ALT_HOLD-like modes
                    need it no higher than the centre dead zone (else it would climb at once)
  mode            : RTL, LAND, AUTO and BRAKE cannot be armed in (as ArduCopter by default)
  battery         : no battery failsafe active; at least BATT_ARM_VOLT and BATT_ARM_MAH left
  fence           : the geofence's own checks (fence.py), worded as AC_Fence's
"""

from __future__ import annotations

from silbridge.shm.records import Kind

# The estimator needs this much still data before its attitude is trusted (the figure the
# pre-MAVLink AutoFlight waited too: a pilot's pause before arming).
ESTIMATOR_SETTLE_S = 1.0
TRUST_CONVERGED = 0.5


def prearm_failure(v) -> str | None:
    """None when every check passes, else the STATUSTEXT of the first failure."""
    to_ns = int(v.cfg.sens_timeout_s * 1e9)
    seen = v.last_seen_ns
    if seen[Kind.IMU] < 0 or v.sim_ns - seen[Kind.IMU] > to_ns:
        return "PreArm: Gyros not healthy"
    if v.rejected_recently:
        return "PreArm: Accels inconsistent (samples refused)"
    if seen[Kind.BARO] < 0 or v.sim_ns - seen[Kind.BARO] > to_ns:
        return "PreArm: Baro not healthy"
    if v.cfg.compass_use and (seen[Kind.MAG] < 0 or v.sim_ns - seen[Kind.MAG] > to_ns):
        return "PreArm: Compass not healthy"
    if v.imu_run_s < ESTIMATOR_SETTLE_S or v.trust < TRUST_CONVERGED:
        return "PreArm: AHRS not converged"
    if v.core.fft_calibrating():     # AP_GyroFFT::pre_arm_check: no noise reference yet
        return "PreArm: FFT calibrating noise"
    if v.mode.requires_position and not v.position_ok():
        return "PreArm: Need 3D Fix"
    fence = v.fence.prearm_failure(v)
    if fence:
        return fence
    if not v.mode.armable:
        return f"Arm: Mode {v.mode.name} not armable"
    thr = v.pilot_throttle_stick()
    if v.mode.manual_throttle and thr > 0.05:
        return "Arm: Throttle too high"
    if not v.mode.manual_throttle and thr > 0.6:
        return "Arm: Throttle too high"
    if v.failsafe.batt_low or v.failsafe.batt_crit:
        return "PreArm: Battery low"
    arm_v, arm_mah = v.store.host("BATT_ARM_VOLT"), v.store.host("BATT_ARM_MAH")
    if arm_v > 0 and v.battery.voltage_v < arm_v:
        return f"PreArm: Battery 1 below minimum arming voltage {arm_v:.2f}V"
    if arm_mah > 0 and v.battery.remaining_mah < arm_mah:
        return f"PreArm: Battery 1 below minimum arming capacity {arm_mah:.0f}mAh"
    return None
