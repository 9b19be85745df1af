"""ESC telemetry on the bridge side: off by default, at its declared rate when asked, values from
the motor model, bad rates refused, and bit-exact through the HIL link's ESC_TELEMETRY_1_TO_4.

Real JSBSim (bridge.Simulator); the HIL round trip uses the real encoder and decoder.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.mavlink.hil.hil_codec import SensorDecoder, SensorEncoder
from silbridge.shm.records import ESC_DTYPE, Kind

HOVERISH_PWM = [1560] * 4


def _fly(sc, steps: int, pwm=HOVERISH_PWM) -> np.ndarray:
    sim = Simulator(sc)
    out = [sim.step(pwm).copy() for _ in range(steps)]
    return sim, np.concatenate(out)


def _esc(recs) -> np.ndarray:
    return recs[recs["kind"] == int(Kind.ESC)].view(ESC_DTYPE)


def test_no_esc_records_unless_the_scenario_asks():
    sim, recs = _fly(load_scenario("S1"), 300)
    assert not (recs["kind"] == int(Kind.ESC)).any()
    assert "esc" not in sim.published_counts()


def test_reports_at_the_declared_rate_one_record_per_motor():
    sc = load_scenario("S1", overrides={"esc.telemetry_hz": 40})
    sim, recs = _fly(sc, 1500)                        # 1.5 s at 1 kHz physics
    esc = _esc(recs)
    epochs = np.unique(esc["sim_ns"])
    assert np.array_equal(epochs, np.arange(1, 61) * 25_000_000)       # every 25 ms, none lost
    assert np.array_equal(esc["seq"], np.arange(len(esc)))
    assert esc["motor"].tolist() == [0, 1, 2, 3] * 60
    assert (esc["motor_count"] == 4).all()
    assert sim.published_counts()["esc"] == 240
    # Each step's ESC records come last, the last one closes the step.
    assert esc["flags"][3::4].all() and not esc["flags"][0::4].any()


def test_values_come_from_the_motor_model():
    sc = load_scenario("S1", overrides={"esc.telemetry_hz": 50})
    sim, recs = _fly(sc, 3000)
    last = _esc(recs)[-4:]
    omega = sim.truth()["rotor_rad_s"]
    for m in range(4):
        assert abs(last["rpm"][m] - omega[m] * 60 / (2 * math.pi)) <= 0.5 + 1e-3
    # Winding power of the DC-motor equivalent over the pack voltage (esc_telemetry.py).
    kv_rad = 920 * 2 * math.pi / 60
    q = 2.3495e-7 * omega[0] ** 2
    i_m = q * kv_rad
    p = (omega[0] / kv_rad + i_m * 0.134) * i_m
    assert last["current_a"][0] == pytest.approx(p / last["voltage_v"][0], abs=0.011)
    # A 4S pack under load: below its 16.8 V open circuit, above its 3.3 V/cell floor.
    assert 13.2 < last["voltage_v"][0] < 16.8
    # Quantised as the ESC reports: 0.01 V, 0.01 A, whole rpm, degC and mAh.
    for f, step in (("voltage_v", 0.01), ("current_a", 0.01), ("rpm", 1.0),
                    ("temperature_c", 1.0), ("consumption_mah", 1.0)):
        k = last[f].astype(np.float64) / step
        assert np.allclose(k, np.round(k), atol=1e-3), f
    assert (_esc(recs)["consumption_mah"][-4:] > 0).all()


@pytest.mark.parametrize("rate", [0, -5])
def test_a_rate_of_zero_or_below_is_refused_naming_the_key(rate):
    with pytest.raises(ScenarioError, match=r"esc\.telemetry_hz"):
        load_scenario("S1", overrides={"esc.telemetry_hz": rate})


def test_a_rate_above_the_physics_rate_is_refused_naming_the_key():
    sc = load_scenario("S1", overrides={"esc.telemetry_hz": 2000})
    with pytest.raises(ScenarioError, match=r"esc\.telemetry_hz"):
        Simulator(sc)


def test_esc_records_cross_the_hil_link_bit_for_bit():
    sc = load_scenario("S1", overrides={"esc.telemetry_hz": 100})
    sim, recs = _fly(sc, 400)
    codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    enc = SensorEncoder(codec)
    frames: list = []
    enc.encode(recs, 0, frames)
    dec = SensorDecoder()
    dec.imu_hz = sim.imu_hz
    rx = mav.MAVLink(None)
    got = b"".join(dec.feed(m, 0) for m in rx.parse_buffer(b"".join(frames)) or [])
    back = np.frombuffer(got, recs.dtype)
    sent, rebuilt = _esc(recs), _esc(back)
    assert len(rebuilt) == len(sent) == 160
    for f in ("seq", "sim_ns", "motor", "motor_count", "rpm", "voltage_v", "current_a",
              "temperature_c", "consumption_mah", "flags"):
        assert np.array_equal(sent[f], rebuilt[f]), f
