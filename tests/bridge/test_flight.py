"""A truth-fed stand-in controller flies the scripted profile: the model is flyable,
the mixer signs match the motor order, and S4's tilts are reachable with altitude held.

The controller reads only the records the simulator publishes (GT_ATT, GT_NAV,
SETPOINT), as the real FC reads its ring, and mixes like ArduCopter's quad X
(roll, pitch, yaw factors per motor)."""

import math

import numpy as np

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

from bridge_test_helpers import of_kind

# ArduCopter quad X: motor 1 FR CCW, 2 BL CCW, 3 FL CW, 4 BR CW.
MIX = np.array([[-1.0, +1.0, +1.0], [+1.0, -1.0, +1.0], [+1.0, +1.0, -1.0], [-1.0, -1.0, -1.0]])


def euler_from_quat(q):
    w, x, y, z = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


def fly(sc, seconds):
    sim = Simulator(sc)
    sp = {"roll": 0.0, "pitch": 0.0, "yaw": 0.0, "alt": 0.0}
    pwm = [1000.0] * 4
    log = []
    for _ in range(int(seconds * 1000)):
        recs = sim.step(pwm)
        for s in of_kind(recs, Kind.SETPOINT):
            sp = {"roll": float(s["roll_rad"]), "pitch": float(s["pitch_rad"]),
                  "yaw": float(s["yaw_rad"]), "alt": float(s["altitude_m"])}
        att = of_kind(recs, Kind.GT_ATT)[0]
        nav = of_kind(recs, Kind.GT_NAV)[0]
        roll, pitch, yaw = euler_from_quat(att["q_wxyz"].astype(float))
        p, q, r = att["rates_frd_rad_s"].astype(float)
        alt, vz_up = -float(nav["pos_ned_m"][2]), -float(nav["vel_ned_m_s"][2])
        # Attitude P -> rate P (units: PWM us per rad/s error).
        yaw_err = (sp["yaw"] - yaw + math.pi) % (2 * math.pi) - math.pi
        u_roll = 40.0 * (6.0 * (sp["roll"] - roll) - p)
        u_pitch = 40.0 * (6.0 * (sp["pitch"] - pitch) - q)
        u_yaw = 150.0 * (2.0 * yaw_err - r)
        tilt = max(0.5, math.cos(roll) * math.cos(pitch))
        thr = (sim.hover_pwm_us - 1000.0 + 60.0 * (sp["alt"] - alt) - 80.0 * vz_up) / tilt
        out = 1000.0 + thr + MIX @ np.array([u_roll, u_pitch, u_yaw])
        pwm = np.clip(out, 1000.0, 2000.0).tolist()
        log.append((sim.sim_ns * 1e-9, roll, pitch, sp["roll"], sp["pitch"], alt))
    return sim, np.array(log)


def test_truth_controller_flies_the_s4_tilts():
    sc = load_scenario("S4", seed=3, overrides={
        "setpoint[0].start_s": 4.0, "setpoint[0].repeat": 1,
        "setpoint[1].start_s": 9.0, "setpoint[1].repeat": 1})
    sim, log = fly(sc, 14.0)
    assert not sim.crashed, sim.crash_reason
    t, roll, pitch, sp_roll, sp_pitch, alt = log.T
    hover = t > 3.0
    assert abs(alt[(t > 3.0) & (t < 4.0)].mean() - 10.0) < 0.5          # took off to 10 m
    a_roll = max(sc.setpoints[0].amplitude_deg[:1])
    a_pitch = max(sc.setpoints[1].amplitude_deg[:1])
    assert 20.0 <= a_roll <= 35.0 and 20.0 <= a_pitch <= 35.0
    assert math.degrees(roll.max()) > a_roll - 3.0                      # reaches +A and -A
    assert math.degrees(roll.min()) < -a_roll + 3.0
    assert math.degrees(pitch.max()) > a_pitch - 3.0
    assert math.degrees(pitch.min()) < -a_pitch + 3.0
    assert np.abs(alt[hover] - 10.0).max() < 2.5                        # altitude held
    assert abs(roll[-1]) < 0.05 and abs(pitch[-1]) < 0.05               # back to level
