"""The physics-side battery (bridge/battery/, run by the step kernel: bridge/src/battery.c):
the pack model's behaviour on its Python reference (battery_reference.py, beside this file),
the C pack against that reference bit for bit, its faults through the kernel, its records
and their MAVLink HIL form, and the scenario keys that moved to [battery]."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from battery_reference import Pack, apply_fault, esc_power_w, ocv_v, r_temp_factor

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
    p.update(HOVER_W, 0.1)
    v0, low0 = p.voltage_v, p.lowest_cell_v
    apply_fault(p, _fault("weak_cell", cell_drop_v=0.3, r_scale=3.0), True)
    p.update(HOVER_W, 0.1)
    assert p.voltage_v < v0 - 0.3
    assert p.lowest_cell_v < low0 - 0.3
    assert p.cell_v.index(p.lowest_cell_v) == 0
    others = p.cell_v[1]
    assert others - p.lowest_cell_v > 0.3 + 2 * p.current_a * p.r_cell_ohm * 0.9
    apply_fault(p, _fault("weak_cell", cell_drop_v=0.3, r_scale=3.0), False)
    p.update(HOVER_W, 0.1)
    assert p.lowest_cell_v == pytest.approx(others, abs=0.005)


def test_capacity_loss_drops_remaining_at_once_and_keeps_consumed():
    p = _pack(initial_soc=0.9)
    p.update(HOVER_W, 0.1)
    rem, used, v = p.remaining, p.consumed_mah, p.voltage_v
    apply_fault(p, _fault("capacity_loss", fraction=0.5), True)
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


def test_the_c_pack_solves_as_the_reference_and_switches_its_faults_through_the_kernel():
    sc = load_scenario("S1", overrides={"battery.initial_soc": 0.6, "battery.temperature_c": 5.0})
    sim = Simulator(sc)
    ref = Pack(sc.battery, air_c=sim._ambient_c)
    kernel = sim.kernel
    for w in (0.0, 37.0, HOVER_W, HOVER_W * 3, 5000.0, 1e6):       # 1e6 W: a collapsed pack
        assert kernel.battery_solve(w) == ref.solve(w)[:2], w
    sim.faults.inject("battery", "weak_cell", 1, {"cell_drop_v": 0.3, "r_scale": 3.0}, True, 0)
    apply_fault(ref, _fault("weak_cell", cell_drop_v=0.3, r_scale=3.0), True)
    assert kernel.battery_solve(HOVER_W) == ref.solve(HOVER_W)[:2]
    assert kernel.battery_solve(HOVER_W)[0] < sim.battery.voltage_v - 0.3
    sim.faults.inject("battery", "capacity_loss", 1, {"fraction": 0.25}, True, 0)
    apply_fault(ref, _fault("capacity_loss", fraction=0.25), True)
    assert sim.battery.remaining == ref.remaining == pytest.approx(0.45)
    sim.faults.inject("battery", "weak_cell", 1, {"cell_drop_v": 0.3, "r_scale": 3.0}, False, 0)
    apply_fault(ref, _fault("weak_cell", cell_drop_v=0.3, r_scale=3.0), False)
    assert kernel.battery_solve(HOVER_W) == ref.solve(HOVER_W)[:2]
    for _ in range(50):                       # spinning: the motors load the pack
        sim.step([sim.hover_pwm_us] * 4)
    omega = (900.0, 950.0, -1.0, 1000.0)      # a negative speed counts as stopped
    nodes = [sim.fdm.fdm.get_property_manager().get_node(f"fcs/m{i}-torque-lbsft")
             for i in range(1, 5)]
    now = [n.get_double_value() for n in nodes]
    assert min(now) > 0.0
    assert sim.battery.load.power_w(omega) == esc_power_w(omega, now, sim.battery.load.ke,
                                                          sim.battery.load.r_ohm)


def test_the_c_pack_matches_the_reference_to_the_last_bit_over_charge_heat_and_load():
    """300 packs drawn over charge, temperature, load and fault state: the kernel's solve and
    one report's update (write_battery) give the reference's doubles exactly."""
    from battery_reference import KernelPack
    sim = Simulator(load_scenario("S1"))
    for _ in range(100):                      # at 0.1 s: a freshly configured pack is due
        sim.step([sim.hover_pwm_us] * 4)
    kernel, load = sim.kernel, sim.battery.load
    rng = np.random.default_rng(25)
    for _ in range(300):
        soc, temp_c, air_c, w, drop = rng.uniform((0, -20, -10, 0, 0), (1, 60, 40, 3000, 0.5))
        torque = [(lambda q=float(q): q) for q in rng.uniform(-0.01, 0.06, 4)]
        cfg = dict(cells=int(rng.integers(1, 15)), capacity_mah=float(rng.uniform(500, 9000)),
                   internal_mohm=float(rng.uniform(5, 80)), avionics_a=0.6,
                   initial_soc=float(soc), temperature_c=float(temp_c), air_c=float(air_c),
                   activation_kj_mol=35.0, heat_capacity_j_k=320.0, thermal_k_per_w=1.8,
                   rate_hz=10.0, ke_v_s_rad=load.ke, winding_ohm=load.r_ohm)
        kernel.configure_battery(torque=torque, **cfg)
        ref = KernelPack(torque, **cfg)
        kernel.set_battery_cell(0, float(drop), 1.0 + 3.0 * float(drop))
        ref.set_cell(0, float(drop), 1.0 + 3.0 * float(drop))
        assert kernel.battery_solve(float(w)) == ref.solve(float(w))
        assert kernel.write_battery(0) == 1
        ref.report(bytearray(64), 0, sim.sim_ns, sim.rotor_rad_s())
        assert kernel.battery_state() == ref.state()


def test_the_kernel_reports_the_pack_bit_for_bit_as_the_reference_with_faults():
    """Both of the kernel's paths: the stage writes a report on a step without Python (GNSS
    at 5 Hz leaves every other 100 ms step to C); write_battery on a GNSS epoch's step."""
    from battery_reference import KernelPack
    sc = load_scenario("S1", overrides={"gnss.rate_hz": 5.0, "battery.initial_soc": 0.5})
    sim = Simulator(sc)
    load = sim.battery.load
    pm = sim.fdm.fdm.get_property_manager()
    torque = [pm.get_node(f"fcs/m{i}-torque-lbsft").get_double_value for i in range(1, 5)]
    b = sc.battery
    ref = KernelPack(torque, b.cells, b.capacity_mah, b.internal_mohm, b.avionics_a,
                     b.initial_soc, sim._ambient_c, sim._ambient_c, b.activation_kj_mol,
                     b.heat_capacity_j_k, b.thermal_k_per_w, b.rate_hz, load.ke, load.r_ohm)
    faults = {250: ("weak_cell", {"cell_drop_v": 0.2, "r_scale": 2.5}),
              420: ("capacity_loss", {"fraction": 0.3})}
    buf, got, want = bytearray(64), [], []
    for k in range(1, 701):
        if k in faults:
            ftype, params = faults[k]
            sim.faults.inject("battery", ftype, 1, params, True, sim.sim_ns)
            apply_fault(ref.pack, _fault(ftype, **params), True)
        recs = sim.step([sim.hover_pwm_us + 30.0 * (k % 3)] * 4)
        got += [r.tobytes() for r in recs[recs["kind"] == Kind.BATTERY]]
        if ref.due(sim.sim_ns):
            ref.report(buf, 0, sim.sim_ns, sim.rotor_rad_s())
            rec = np.frombuffer(buf, dtype=recs.dtype).copy()
            rec["flags"] = recs[-1]["flags"] if recs[-1]["kind"] == Kind.BATTERY else 0
            want.append(rec.tobytes())
    assert len(got) == 7 and got == want
    # the doubles behind the quantised records, to the last bit: voltage, current, charge
    # drawn, remaining, temperature, lowest cell, reports, next report
    assert sim.kernel.battery_state() == ref.state()


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
