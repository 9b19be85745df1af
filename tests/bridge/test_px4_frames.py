"""PX4's step frames (bridge/autopilots/px4/hil_messages.py) byte for byte against pymavlink's
encoders fed from the records' numpy fields, over a flight of the real Simulator: what PX4 receives did
not change when the frames stopped going through pymavlink's message objects."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.bridge.autopilots.px4 import hil_messages as px4_hil
from silbridge.mavlink.hil.hil_channel import make_codec
from silbridge.shm import record_structs
from silbridge.shm.records import DTYPES, RECORD_SIZE, Kind

_G0 = 9.80665
_M_PER_DEG = 6378137.0 * math.pi / 180.0


@pytest.mark.parametrize("kind, layout, fields", [
    (Kind.IMU, record_structs.IMU, ["accel_frd_m_s2", "gyro_frd_rad_s"]),
    (Kind.BARO, record_structs.BARO, ["pressure_pa", "temperature_c"]),
    (Kind.MAG, record_structs.MAG, ["field_frd_gauss"]),
    (Kind.GNSS, record_structs.GNSS, ["lat_e7", "lon_e7", "alt_mm", "vel_ned_m_s", "eph_cm",
                                      "epv_cm", "fix_type", "satellites"]),
    (Kind.GT_ATT, record_structs.GT_ATT,
     ["q_wxyz", "rates_frd_rad_s", "specific_force_frd_m_s2"]),
    (Kind.GT_NAV, record_structs.GT_NAV, ["pos_ned_m", "vel_ned_m_s"]),
])
def test_record_layouts_match_the_dtypes(kind, layout, fields):
    dt = DTYPES[kind]
    rng = np.random.default_rng(int(kind))
    rec = np.frombuffer(rng.integers(0, 256, RECORD_SIZE, dtype=np.uint8).tobytes(), dtype=dt)
    want = []
    for f in fields:
        want += np.atleast_1d(rec[f][0]).tolist()
    got = layout.unpack_from(rec.tobytes(), 0)
    assert len(got) == len(want)
    assert all((a != a and b != b) or a == b for a, b in zip(got, want))


class _Reference:
    """The frames as pymavlink's encoders build them from numpy record fields."""

    def __init__(self, codec, origin):
        self.c, self.origin = codec, origin
        self.temp_c = 20.0
        self.next_state_us = 0

    def step(self, recs: np.ndarray, step_us: int) -> list:
        c = self.c
        last = {int(k): recs[i:i + 1].view(DTYPES[Kind(int(k))])[0]
                for i, k in enumerate(recs["kind"])}
        imu = recs[recs["kind"] == Kind.IMU].view(DTYPES[Kind.IMU])
        sums = [0.0] * 6
        for row in np.concatenate([imu["accel_frd_m_s2"], imu["gyro_frd_rad_s"]], 1).tolist():
            for j, v in enumerate(row):
                sums[j] += v
        a = [s / len(imu) for s in sums]
        bits, m, hpa, alt = 0b111111, [0.0] * 3, 0.0, 0.0
        if Kind.MAG in last:
            m, bits = last[Kind.MAG]["field_frd_gauss"].tolist(), bits | px4_hil.FIELDS_MAG
        if Kind.BARO in last:
            pa = float(last[Kind.BARO]["pressure_pa"])
            hpa, alt = pa / 100.0, px4_hil.pressure_altitude_m(pa)
            self.temp_c = float(last[Kind.BARO]["temperature_c"])
            bits |= px4_hil.FIELDS_BARO
        out = []
        if Kind.GNSS in last:
            g = last[Kind.GNSS]
            cm = [max(-32767, min(32767, round(v * 100.0))) for v in g["vel_ned_m_s"].tolist()]
            out.append(c.hil_gps_encode(
                step_us, int(g["fix_type"]), int(g["lat_e7"]), int(g["lon_e7"]),
                int(g["alt_mm"]), int(g["eph_cm"]), int(g["epv_cm"]),
                min(65534, round(math.hypot(cm[0], cm[1]))), *cm,
                round(math.degrees(math.atan2(cm[1], cm[0])) * 100.0) % 36000,
                int(g["satellites"]), 0, 0).pack(c))
        out.append(c.hil_sensor_encode(step_us, *a, *m, hpa, 0.0, alt, self.temp_c, bits,
                                       0).pack(c))
        truth = []
        if step_us >= self.next_state_us:
            self.next_state_us = step_us + px4_hil.STATE_INTERVAL_US
            att, nav = last[Kind.GT_ATT], last[Kind.GT_NAV]
            pos, vel = nav["pos_ned_m"].tolist(), nav["vel_ned_m_s"].tolist()
            lat0, lon0, alt0 = self.origin
            coslat = max(1e-6, math.cos(math.radians(lat0 * 1e-7)))
            v_cm = [max(-32767, min(32767, round(v * 100.0))) for v in vel]
            acc = [max(-32767, min(32767, round(x / _G0 * 1000.0)))
                   for x in att["specific_force_frd_m_s2"].tolist()]
            speed = min(65535, round(math.sqrt(sum(v * v for v in v_cm))))
            truth.append(c.hil_state_quaternion_encode(
                step_us, att["q_wxyz"].tolist(), *att["rates_frd_rad_s"].tolist(),
                lat0 + round(pos[0] / _M_PER_DEG * 1e7),
                lon0 + round(pos[1] / (_M_PER_DEG * coslat) * 1e7),
                alt0 - round(pos[2] * 1000.0), *v_cm, speed, speed, *acc).pack(c))
        return out, truth


def test_px4_step_frames_are_pymavlinks_over_a_flight():
    sim = Simulator(load_scenario("S2", seed=3))
    codec = make_codec(1, 51)
    origin = (473977420, 85455940, 488000)
    enc = px4_hil.Px4SensorEncoder(codec, origin)
    ref = _Reference(make_codec(1, 51), origin)
    acc = px4_hil.StepAccumulator()
    rng = np.random.default_rng(5)
    seen = {"gps": 0, "baro": 0, "truth": 0}
    for k in range(1500):                    # 6 s: GNSS, baro, mag and truth all come
        pwm = [int(x) for x in rng.integers(1000, 2000, 4)] if k > 250 else [1000] * 4
        acc.reset()
        held = []
        for _ in range(4):
            recs = sim.step(pwm)
            acc.add(recs)
            held.append(recs.copy())
        step_us = sim.sim_ns // 1000
        frames, truth = [], []
        enc.encode(acc, step_us, frames)
        enc.encode_truth(acc, step_us, truth)
        want, want_truth = ref.step(np.concatenate(held), step_us)
        assert frames == want, k
        assert truth == want_truth, k
        seen["gps"] += len(frames) - 1
        seen["baro"] += bool(mav.MAVLink(None).decode(bytearray(frames[-1])).fields_updated
                             & px4_hil.FIELDS_BARO)
        seen["truth"] += len(truth)
    assert seen["gps"] >= 50 and seen["baro"] >= 500 and seen["truth"] == 750
