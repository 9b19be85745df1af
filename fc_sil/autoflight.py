"""The FC's flight logic until MAVLink modes take over: arm, take off, hold.

The scenario (bridge side) sends SETPOINT records with the take-off altitude
and any scripted attitude; the core follows them by itself. What is left for
the host is the arming decision, made on sim time so it is deterministic:
the estimator gets `arm_after_s` of still, level data first: while disarmed it
runs fast gains to align and learn the gyro bias (~5 s, like a real FC's
ground calibration), and arming earlier leaves a bias that tilts the hover.
"""

from __future__ import annotations

import math

from .autodec import AutoDeclination
from silbridge.shm.records import NS_PER_S as _NS


class AutoFlight:
    def __init__(self, core, *, arm_after_s: float = 5.0, sink=None):
        self.core = core
        self.arm_at_ns = int(arm_after_s * _NS)
        self.sink = sink
        self.armed_at_ns = None
        self.autodec = AutoDeclination()
        self._dec_done = False       # the origin is the first 3D fix: looked up once

    def after_batch(self, loop, recs, pwm, status) -> None:
        if not self._dec_done:
            self._auto_declination()
        if self.armed_at_ns is None and loop.last_sim_ns >= self.arm_at_ns:
            self.core.arm()
            self.armed_at_ns = loop.last_sim_ns
            if self.sink is not None:
                self.sink.event(loop.last_sim_ns, "mode", "armed (auto take-off)")

    def next_due_ns(self) -> float:
        """When after_batch next acts (fc_loop.py batch_poll): the arming time. The declination
        waits for a GNSS fix, and a run's first fix comes in a step Python finishes (the
        bridge's Python releases it: bridge/gnss_kernel.py), which ends its batch."""
        return self.arm_at_ns if self.armed_at_ns is None else math.inf

    def _auto_declination(self) -> None:
        fix = self.core.gnss()
        if fix is None or fix["fix_type"] < 3:
            return
        self._dec_done = True
        dec = self.autodec.due(self.core.get_param("COMPASS_AUTODEC"),
                               fix["lat_e7"], fix["lon_e7"])
        if dec is not None:
            self.core.set_param("COMPASS_DEC", dec)
