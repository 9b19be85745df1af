"""The position controller (AC_PosControl's horizontal half) and LOITER's target generator
(AC_Loiter) on a point-mass vehicle that gets exactly the acceleration asked of it."""

from __future__ import annotations

import math

import pytest

from silbridge.fc_sil.nav_loiter import LoiterConfig, LoiterNav
from silbridge.fc_sil.nav_pos import G_M_S2, PosController, PosGains, lean_to_accel

DT = 0.02


def _fly(pc: PosController, steps: int, pos=(0.0, 0.0), vel=(0.0, 0.0), command=None):
    """Point mass: the lean's acceleration acts at once. command(pc) sets the targets."""
    trace = []
    for _ in range(steps):
        if command:
            command(pc)
        roll, pitch = pc.update(DT, pos, vel)
        a = lean_to_accel(roll, pitch, 0.0)
        pos = (pos[0] + vel[0] * DT + 0.5 * a[0] * DT * DT,
               pos[1] + vel[1] * DT + 0.5 * a[1] * DT * DT)
        vel = (vel[0] + a[0] * DT, vel[1] + a[1] * DT)
        trace.append((pos, vel, a, roll, pitch))
    return trace


def test_reset_then_hold_here_gives_no_glitch():
    pc = PosController()
    pc.reset((5.0, -3.0), (0.0, 0.0))
    tr = _fly(pc, 100, pos=(5.0, -3.0),
              command=lambda c: c.set_pos_vel_accel((5.0, -3.0), (0.0, 0.0), (0.0, 0.0)))
    assert max(abs(r) + abs(p) for *_, r, p in tr) < 1e-12


def test_lean_limit_holds_and_the_integrator_does_not_wind_up_against_it():
    g = PosGains(angle_max_rad=math.radians(10.0))
    pc = PosController(g)
    pc.reset((0.0, 0.0), (0.0, 0.0))
    # a velocity the vehicle cannot follow at 10 degrees: the output saturates
    tr = _fly(pc, 100, command=lambda c: c.set_pos_vel_accel(c.pos_target, (20.0, 0.0),
                                                            (0.0, 0.0)))
    a_lim = G_M_S2 * math.tan(math.radians(10.0))
    assert max(math.hypot(*a) for _, _, a, _, _ in tr) <= a_lim * (1 + 1e-9)
    assert max(abs(p) for *_, p in tr) <= math.radians(10.0) + 1e-12
    assert pc._integ[0] < 0.5, "integrator grew while the lean limit clipped"


def test_velocity_command_is_reached_and_the_hold_point_is_where_it_stopped():
    pc = PosController()
    pc.reset((0.0, 0.0), (0.0, 0.0))
    go = _fly(pc, 400, command=lambda c: c.input_vel_accel(DT, (4.0, 0.0), (0.0, 0.0), 10.0))
    assert go[-1][1][0] == pytest.approx(4.0, abs=0.05)
    pos, vel = go[-1][0], go[-1][1]
    stop = _fly(pc, 600, pos=pos, vel=vel,
                command=lambda c: c.input_vel_accel(DT, (0.0, 0.0), (0.0, 0.0), 10.0))
    end = stop[-1][0]
    assert math.hypot(*stop[-1][1]) < 0.01
    assert end[0] == pytest.approx(pc.pos_target[0], abs=0.05)
    # it stopped at WPNAV_ACCEL along a jerk-limited path: no backing up past 5 cm
    assert min(p[0] for p, *_ in stop) >= pos[0] - 1e-9
    assert max(p[0] for p, *_ in stop) - end[0] < 0.05


def test_loiter_full_stick_settles_at_loit_speed_and_centred_sticks_brake_and_hold():
    cfg = LoiterConfig()
    nav = LoiterNav(cfg)
    pc = PosController()
    pc.reset((0.0, 0.0), (0.0, 0.0))
    stick = {"pitch": -1.0}         # forward

    def command(c):
        pos, vel, acc = nav.update(DT, c.pos_target, 0.0, stick["pitch"], 0.0)
        c.set_pos_vel_accel(pos, vel, acc)

    go = _fly(pc, 1500, command=command)
    assert nav.desired_vel[0] == pytest.approx(cfg.speed_m_s, rel=0.02)
    assert go[-1][1][0] == pytest.approx(cfg.speed_m_s, rel=0.05)
    stick["pitch"] = 0.0
    pos, vel = go[-1][0], go[-1][1]
    stop = _fly(pc, 1500, pos=pos, vel=vel, command=command)
    assert math.hypot(*nav.desired_vel) < 1e-6
    held = stop[-1][0]
    assert math.hypot(*stop[-1][1]) < 0.05
    # braked: LOIT_BRK_DELAY of coasting under drag only, then braking up to LOIT_BRK_ACCEL
    decel = [-a[0] for _, v, a, _, _ in stop if v[0] > 1.0]
    assert max(decel) <= cfg.brake_accel_m_s2 + G_M_S2 * math.tan(cfg.angle_max_rad) + 0.5
    assert abs(stop[-300][0][0] - held[0]) < 0.05, "holds where it stopped"
