"""Lockstep flights of the real MAVLink vehicle, scripted from the test (no GCS, no sockets).

The real parts: JSBSim physics and sensor models (bridge.Simulator), the shared-memory
segment, the C core and the Vehicle. A script function is called after every vehicle outer
step (50 Hz of sim time) with a ``Flight`` giving access to the vehicle and the truth; it
issues VehicleCommands exactly as the GCS server would (same thread, between batches).
"""

from __future__ import annotations

import math
import os

from silbridge.bridge.bridge_driver import prepare_segment, run_bridge
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.fc_loop import FcLoop
from silbridge.fc_sil.vehicle import Vehicle
from silbridge.shm import Segment
from silbridge.tools.loop.flight import FlightOptions, bridge_config, make_simulator

FT_M = 0.3048


class Flight:
    def __init__(self, sim, vehicle):
        self.sim = sim
        self.v = vehicle
        self.log: list[dict] = []
        self.stop_requested = False

    @property
    def t_s(self) -> float:
        return self.v.sim_ns / 1e9

    def truth_ne_m(self) -> tuple[float, float]:
        f = self.sim.fdm
        return ((f.h_lat.get_double_value() - f.home_lat_rad) * f.m_per_rad_lat,
                (f.h_lon.get_double_value() - f.home_lon_rad) * f.m_per_rad_lon)

    def truth_agl_m(self) -> float:
        f = self.sim.fdm
        return f.h_hagl.get_double_value() * FT_M - f.home_agl_m

    def truth_tilt_deg(self) -> float:
        f = self.sim.fdm
        phi, theta = f.h_phi.get_double_value(), f.h_theta.get_double_value()
        return math.degrees(math.acos(max(-1.0, min(1.0, math.cos(phi) * math.cos(theta)))))


class _Scripted:
    def __init__(self, flight, script, sample_every: int):
        self.flight = flight
        self.script = script
        self.sample_every = sample_every
        self.sink = None
        self._last = 0

    def after_batch(self, loop, recs, pwm, status):
        v = self.flight.v
        v.after_batch(loop, recs, pwm, status)
        if v.steps != self._last:
            self._last = v.steps
            f = self.flight
            if v.steps % self.sample_every == 0:
                f.log.append(dict(t=f.t_s, alt=v.alt_m, agl=f.truth_agl_m(), ne=f.truth_ne_m(),
                                  est_ne=tuple(v.est.pos_ne_m), mode=v.mode.name,
                                  armed=v.armed, airborne=v.airborne,
                                  tilt=f.truth_tilt_deg()))
            self.script(f)


def fly_scripted(script, *, duration_s: float, scenario: str = "S1", params: dict | None = None,
                 sample_every: int = 5, vehicle_kw: dict | None = None, core=None):
    """Run one lockstep flight; returns (Flight, bridge result)."""
    opts = FlightOptions(scenario=scenario, duration_s=duration_s, lockstep=True, processes=1)
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    name = f"vehtest-{os.getpid()}-{id(script) & 0xFFFF}"
    with Segment.create(name) as seg:
        prepare_segment(seg, sim, cfg)
        with Segment.attach(name) as fc_seg:
            core = core if core is not None else FlightCore()
            for k, val in (params or {}).items():
                core.set_param(k, val)
            vehicle = Vehicle(core, **(vehicle_kw or {}))
            flight = Flight(sim, vehicle)
            loop = FcLoop(core, fc_seg, supervisor=_Scripted(flight, script, sample_every))
            res = run_bridge(sim, seg, cfg, fc_poll=loop.poll, out=lambda s: None)
    return flight, res


class DroppingCore(FlightCore):
    """A FlightCore whose input loses one sensor stream from a given sim time (the records
    never reach the C core, as when a sensor driver dies). The FC loop steps through
    bind_batch's step, so the filter wraps that; and it refuses the C record router,
    which would hand the records to the core unfiltered."""

    def __init__(self, kind: int, after_s: float):
        super().__init__()
        self.kind, self.after_ns = int(kind), int(after_s * 1e9)

    def bind_batch(self, records, pwm_out, status_out):
        def step(n: int) -> int:
            recs = records[:n]
            keep = ~((recs["kind"] == self.kind) & (recs["sim_ns"] >= self.after_ns))
            pwm, _ = self.step_batch(recs if keep.all() else recs[keep], pwm_out, status_out)
            return len(pwm)
        return step

    def attach_router(self, *args, **kwargs):
        return None     # the filter runs in Python: the FC loop polls in Python
