"""COMPASS_AUTODEC (fc_sil/autodec.py) through the real FlightCore and the MAVLink vehicle.

A vehicle stands still and level, facing true north, at Canberra (declination 12.7 deg, large
enough that a zero COMPASS_DEC is plain to see). The magnetometer reads the WMM field there;
GNSS gives a 3D fix from 1 s. With COMPASS_AUTODEC = 1 (the default, as ArduCopter's) the
vehicle sets COMPASS_DEC at the first fix and the heading estimate turns onto true north at
once; with 0 the user's COMPASS_DEC stays, and so does the heading error it implies.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.vehicle import Vehicle
from silbridge.magfield import field_at
from silbridge.shm import records as R

G = 9.80665
LAT, LON = -35.363261, 149.16523
WMM2025_DEC_DEG = 12.67    # pygeomag 1.1.0, WMM_2025.COF, sea level, 2026.0 (test_magfield.py)
FIRST_FIX_S = 1.0


def standing_still(t_end_s: float) -> np.ndarray:
    """IMU 1 kHz, magnetometer 100 Hz, GNSS 10 Hz from FIRST_FIX_S: level, yaw 0."""
    t_ns = np.arange(1, int(t_end_s * 1000) + 1, dtype=np.int64) * 1_000_000
    imu = R.empty(R.Kind.IMU, len(t_ns))
    imu["sim_ns"], imu["seq"] = t_ns, np.arange(len(t_ns))
    imu["accel_frd_m_s2"] = (0.0, 0.0, -G)
    mag_t = t_ns[9::10]
    mag = R.empty(R.Kind.MAG, len(mag_t))
    mag["sim_ns"], mag["seq"] = mag_t, np.arange(len(mag_t))
    mag["field_frd_gauss"] = field_at(LAT, LON).ned_gauss      # level, facing north: FRD = NED
    fix_t = t_ns[(t_ns >= FIRST_FIX_S * 1e9) & (t_ns % 100_000_000 == 0)]
    gnss = R.empty(R.Kind.GNSS, len(fix_t))
    gnss["sim_ns"], gnss["seq"] = fix_t, np.arange(len(fix_t))
    gnss["lat_e7"], gnss["lon_e7"], gnss["alt_mm"] = round(LAT * 1e7), round(LON * 1e7), 580_000
    gnss["fix_type"], gnss["satellites"] = 3, 14
    recs = np.concatenate([R.as_generic(imu), R.as_generic(mag), R.as_generic(gnss)])
    return recs[np.lexsort((recs["kind"] != int(R.Kind.IMU), recs["sim_ns"]))]


def stand(params: dict, t_end_s: float = 3.0):
    """Run the vehicle over the records in 20 ms steps; (vehicle, {time s: yaw deg})."""
    core = FlightCore(params)
    vehicle = Vehicle(core)
    recs = standing_still(t_end_s)
    yaw_deg = {}
    edges = np.searchsorted(recs["sim_ns"], np.arange(0, t_end_s + 0.01, 0.02) * 1e9)
    for a, b in zip(edges[:-1], edges[1:]):
        if a == b:
            continue
        core.step_batch(recs[a:b])
        t = int(recs["sim_ns"][b - 1])
        vehicle.step(t)
        yaw_deg[round(t * 1e-9, 2)] = math.degrees(vehicle.yaw_rad)
    return vehicle, yaw_deg


def test_autodec_sets_compass_dec_at_the_first_fix_and_the_heading_turns_to_true_north():
    vehicle, yaw = stand({})
    dec = vehicle.core.get_param("COMPASS_DEC")
    assert math.degrees(dec) == pytest.approx(WMM2025_DEC_DEG, abs=0.25)
    assert vehicle.store.get("COMPASS_DEC")[0] == pytest.approx(dec)    # what a GCS reads
    # Before the fix the heading is magnetic (declination 0): 12.7 deg west of true.
    assert yaw[0.9] == pytest.approx(-WMM2025_DEC_DEG, abs=1.0)
    # Turned at the fix, not learned over a minute through the heading loop.
    assert abs(yaw[1.5]) < 0.5 and abs(yaw[3.0]) < 0.5


def test_autodec_0_keeps_the_users_declination():
    user_dec = 0.05
    vehicle, yaw = stand({"COMPASS_AUTODEC": 0, "COMPASS_DEC": user_dec})
    assert vehicle.core.get_param("COMPASS_DEC") == pytest.approx(user_dec)
    assert vehicle.est.valid                        # the fix was there and fused
    assert yaw[3.0] == pytest.approx(math.degrees(user_dec) - WMM2025_DEC_DEG, abs=1.0)


def _yaw_error_deg(log_path, start_s: float) -> float:
    """Mean estimated minus true heading after start_s, from a flight's MCAP log."""
    import silbridge
    log = silbridge.read_log(log_path)
    st, gt = log.channels["/fc/status"], log.channels["/gt_att"]
    w, x, y, z = gt["q_wxyz"].astype(float).T
    true = np.unwrap(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    t = st["imu_sim_ns"]
    err = st["euler_est_rad"][:, 2] - np.interp(t, gt["sim_ns"], true)
    err = (err + np.pi) % (2 * np.pi) - np.pi
    return math.degrees(float(np.mean(err[t >= start_s * 1e9])))


def test_a_flight_holds_its_heading_estimate_on_true_north(tmp_path):
    """`silbridge fly` S1 (Zurich, declination 3.5 deg): after take-off and settling the
    estimated heading is the true one within 1 deg; with COMPASS_AUTODEC 0 (COMPASS_DEC 0)
    it is off by about the declination, as before this parameter existed."""
    import silbridge
    logs = {}
    for autodec in (1, 0):
        logs[autodec] = tmp_path / f"autodec{autodec}.mcap"
        silbridge.fly(scenario="S1", duration_s=20.0, processes=1, log_path=str(logs[autodec]),
                      params={"COMPASS_AUTODEC": autodec}, metrics=False)
    assert abs(_yaw_error_deg(logs[1], start_s=8.0)) < 1.0
    assert _yaw_error_deg(logs[0], start_s=8.0) < -3.0
