"""The physics-side battery (bridge/battery/): the pack model, its faults, its records and
their MAVLink HIL form, and the scenario keys that moved to [battery]."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.battery import BatteryFaults, Pack
from silbridge.bridge.battery.cell import ocv_v, r_temp_factor
from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.faults.engine import ActiveFault
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.mavlink.hil.hil_codec import SensorDecoder, SensorEncoder
from silbridge.shm.records import BATTERY_DTYPE, Kind

HOVER_W = 4 * 37.0        # four motors at hover (scenario_schema.py's ESC figures)


def _pack(**over):
    return Pack(load_scenario("S1", overrides={f"battery.{k}": v for k, v in over.items()}).battery,
                air_c=25.0)


def _fault(ftype, **params):
    return ActiveFault("battery", ftype, 1, params, 0)


def test_open_circuit_curve_is_the_cited_fit_and_not_linear():
    assert ocv_v(1.0) == pytest.approx(4.1029, abs=1e-4)
    assert ocv_v(0.0) == pytest.approx(2.654, abs=1e-3)
    mid = ocv_v(0.5)
    assert mid > 0.5 * (ocv_v(1.0) + ocv_v(0.0)) + 0.2     # flat middle, knee at the bottom
    soc = np.linspace(0, 1, 101)
    assert np.all(np.diff([ocv_v(s) for s in soc]) > 0)


def test_the_pack_sags_under_load_and_recovers():
    p = _pack()
    rest = p.voltage_v
    p.update(HOVER_W * 3, 0.1)                    # a climb: three times hover power
    loaded, i = p.voltage_v, p.current_a
    assert i > 20.0
    assert rest - loaded == pytest.approx(i * 0.025, rel=0.15)     # sag ~ I R of the 25 mOhm pack
    p.update(0.0, 0.1)
    assert p.voltage_v > loaded + 0.4
    assert rest - 0.005 < p.voltage_v < rest      # back to rest, less the charge drawn


def test_voltage_falls_with_the_charge_drawn():
    p = _pack()
    volts, mah = [], []
    for _ in range(6):
        for _ in range(600):                      # a minute at hover power
            p.update(HOVER_W, 0.1)
        volts.append(p.voltage_v)
        mah.append(p.consumed_mah)
    assert all(np.diff(volts) < 0) and all(np.diff(mah) > 0)
    # ~10.5 A for 6 min is ~1050 mAh of the 3300
    assert 900 < mah[-1] < 1200
    assert p.remaining == pytest.approx(1.0 - mah[-1] / 3300.0, abs=1e-6)


def test_a_weak_cell_lowers_the_pack_and_the_lowest_cell_and_sags_more():
    p = _pack()
    f = BatteryFaults(p)
    p.update(HOVER_W, 0.1)
    v0, low0 = p.voltage_v, p.lowest_cell_v
    f.on(_fault("weak_cell", cell_drop_v=0.3, r_scale=3.0), 0)
    p.update(HOVER_W, 0.1)
    assert p.voltage_v < v0 - 0.3
    assert p.lowest_cell_v < low0 - 0.3
    assert p.cell_v.index(p.lowest_cell_v) == 0
    others = p.cell_v[1]
    assert others - p.lowest_cell_v > 0.3 + 2 * p.current_a * p.r_cell_ohm * 0.9
    f.off(_fault("weak_cell", cell_drop_v=0.3, r_scale=3.0), 0)
    p.update(HOVER_W, 0.1)
    assert p.lowest_cell_v == pytest.approx(others, abs=0.005)


def test_capacity_loss_drops_remaining_at_once_and_keeps_consumed():
    p = _pack(initial_soc=0.9)
    p.update(HOVER_W, 0.1)
    rem, used, v = p.remaining, p.consumed_mah, p.voltage_v
    BatteryFaults(p).on(_fault("capacity_loss", fraction=0.5), 0)
    assert p.remaining == pytest.approx(rem * 0.5)
    assert p.consumed_mah == used
    p.update(HOVER_W, 0.1)
    assert p.voltage_v < v - 0.5                      # 45 % charge sits lower on the curve


def test_cold_raises_the_resistance_and_the_pack_warms_under_load():
    assert r_temp_factor(0.0, 35e3) == pytest.approx(3.64, abs=0.02)
    assert r_temp_factor(25.0, 35e3) == pytest.approx(1.0)
    cold, warm = _pack(temperature_c=0.0), _pack()
    cold.update(HOVER_W * 3, 0.1)
    warm.update(HOVER_W * 3, 0.1)
    assert warm.voltage_v - cold.voltage_v > 0.5
    t0 = warm.temp_c
    for _ in range(600):
        warm.update(HOVER_W * 3, 0.1)
    assert warm.temp_c > t0 + 1.0


def _fly(sc, steps):
    sim = Simulator(sc)
    pwm = [sim.hover_pwm_us + 20.0] * 4
    out = []
    for _ in range(steps):
        r = sim.step(pwm)
        out.append(r.copy())
    return sim, np.concatenate(out)


def test_the_simulator_publishes_the_pack_at_10_hz_quantised_as_battery_status_carries():
    sim, recs = _fly(load_scenario("S1"), 1000)
    b = recs[recs["kind"] == Kind.BATTERY].view(BATTERY_DTYPE)
    assert b["sim_ns"].tolist() == [100_000_000 * k for k in range(1, 11)]
    assert np.array_equal(b["seq"], np.arange(10))
    assert (b["cell_count"] == 4).all()
    assert b["current_a"][-1] > 5.0 and 14.0 < b["voltage_v"][-1] < 16.5
    assert b["voltage_v"][-1] == pytest.approx(sim.battery.voltage_v, abs=0.005)
    assert b["current_a"][-1] == pytest.approx(sim.battery.current_a, abs=0.006)
    for f, per in (("voltage_v", 1000), ("current_a", 100), ("consumed_mah", 1),
                   ("remaining", 100), ("temperature_c", 100), ("lowest_cell_v", 1000)):
        k = b[f].astype(np.float64) * per
        assert np.allclose(k, np.round(k), atol=1e-3), f


def test_esc_telemetry_reads_the_same_pack():
    sim, recs = _fly(load_scenario("S1", overrides={"esc.telemetry_hz": 10}), 1000)
    esc = recs[recs["kind"] == Kind.ESC]
    from silbridge.shm.records import ESC_DTYPE
    v_esc = esc.view(ESC_DTYPE)["voltage_v"][-1]
    assert v_esc == pytest.approx(sim.battery.voltage_v, abs=0.006)


def test_the_hil_link_rebuilds_battery_records_bit_for_bit():
    sc = load_scenario("S1", overrides={"battery.initial_soc": 0.4})
    sim = Simulator(sc)
    sim.faults.inject("battery", "weak_cell", 1, {}, True, 0)
    codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    enc, dec = SensorEncoder(codec), SensorDecoder()
    rx = mav.MAVLink(None)
    sent, got = [], []
    for _ in range(300):
        recs = sim.step([sim.hover_pwm_us] * 4).copy()
        sent.append(recs[recs["kind"] == Kind.BATTERY])
        frames = []
        enc.encode(recs, 0, frames)
        for fr in frames:
            for m in rx.parse_buffer(fr) or []:
                out = dec.feed(m, 0)
                if out:
                    r = np.frombuffer(out, dtype=sent[-1].dtype)
                    got.append(r[r["kind"] == Kind.BATTERY])
    a, b = np.concatenate(sent).view(BATTERY_DTYPE), np.concatenate(got).view(BATTERY_DTYPE)
    assert len(a) == 3
    for f in ("sim_ns", "seq", "voltage_v", "current_a", "consumed_mah", "remaining",
              "temperature_c", "lowest_cell_v", "cell_count"):
        assert np.array_equal(a[f], b[f]), f
    assert a["lowest_cell_v"][-1] < a["voltage_v"][-1] / 4 - 0.25      # the weak cell shows


@pytest.mark.parametrize("old,new", [("battery_mohm", "internal_mohm"),
                                     ("avionics_a", "avionics_a"),
                                     ("battery_cells", "cells"), ("battery_mah", "capacity_mah")])
def test_a_moved_esc_key_says_where_it_went(old, new):
    with pytest.raises(ScenarioError, match=rf"esc\.{old}: moved to battery\.{new}"):
        load_scenario("S1", overrides={f"esc.{old}": 1.0})


def test_battery_keys_load_with_their_defaults():
    b = load_scenario("S2").battery
    assert (b.cells, b.capacity_mah, b.internal_mohm, b.avionics_a, b.rate_hz) == (4, 3300.0,
                                                                                    25.0, 0.6, 10.0)
