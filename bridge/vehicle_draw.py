"""The vehicle's own imperfections, drawn once per run from the scenario seed.

A real quad is not the symmetric model in quadx.xml: its CG sits a few mm off the
frame's centre, its four motor and propeller sets differ by a few % in thrust and
torque coefficient, its motors stand a fraction of a degree off vertical, and its
flight controller is mounted a little crooked. With ``[vehicle] imperfect = true``
`draw_vehicle` draws each of these uniformly within the scenario's +- tolerances
(defaults and their derivations: bridge/scenario_schema.py, section [vehicle]); with
it off (the default) it returns the neutral draw, which changes nothing, so the
built-in scenarios keep their trace hashes.

Each quantity has its own named stream (``draw_rng(seed, "vehicle:cg")``, ...), so
changing one tolerance leaves the other draws as they were. Who applies what:
bridge/fdm.py the CG, the coefficients and the tilts (JSBSim properties); the
sensor stage the IMU rotation (`imu_rot`).

Frames: body FRD. Motor order 1..4 is ArduCopter quad X (front-right, back-left,
front-left, back-right).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from silbridge.bridge.scenario import draw_rng

_IDENTITY3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@dataclass(frozen=True)
class VehicleDraw:
    """One vehicle's imperfections (the neutral one: every field at its nominal value)."""

    imperfect: bool = False
    cg_offset_frd_m: tuple = (0.0, 0.0, 0.0)       # CG from the structural origin [m]
    kt_scale: tuple = (1.0, 1.0, 1.0, 1.0)          # thrust coefficient multipliers, motors 1..4
    kq_scale: tuple = (1.0, 1.0, 1.0, 1.0)          # torque coefficient multipliers
    tilt_frd_rad: tuple = ((0.0, 0.0),) * 4         # per motor: (about body x, about body y) [rad]
    thrust_dir_frd: tuple = ((0.0, 0.0, -1.0),) * 4  # per motor: unit thrust direction
    imu_rpy_rad: tuple = (0.0, 0.0, 0.0)            # IMU mounting roll, pitch, yaw (ZYX) [rad]
    imu_rot: tuple = _IDENTITY3                     # v_imu = imu_rot @ v_body

    @property
    def imu_identity(self) -> bool:
        """True when the IMU is mounted square (apply nothing: bit-identical records)."""
        return self.imu_rot == _IDENTITY3

    def to_dict(self) -> dict:
        """JSON-ready, for the run log's metadata and summaries."""
        return {"imperfect": self.imperfect, "cg_offset_frd_m": list(self.cg_offset_frd_m),
                "kt_scale": list(self.kt_scale), "kq_scale": list(self.kq_scale),
                "tilt_frd_deg": [[math.degrees(a) for a in t] for t in self.tilt_frd_rad],
                "imu_rpy_deg": [math.degrees(a) for a in self.imu_rpy_rad]}


NEUTRAL = VehicleDraw()


def draw_vehicle(scenario) -> VehicleDraw:
    """The scenario's vehicle: NEUTRAL unless [vehicle] imperfect = true."""
    v = scenario.vehicle
    if not v.imperfect:
        return NEUTRAL
    seed = scenario.seed

    def uniform(stream: str, shape, bound: float):
        # +-bound, uniform: a tolerance says where a part lies, not how it is distributed.
        return (bound * draw_rng(seed, "vehicle:" + stream).uniform(-1.0, 1.0, shape)).tolist()

    cx, cy, cz = uniform("cg", 3, 1.0)
    tilt_tol, imu_tol = math.radians(v.tilt_tol_deg), math.radians(v.imu_tilt_tol_deg)
    tilts = tuple(tuple(t) for t in uniform("tilt", (4, 2), tilt_tol))
    rpy = tuple(uniform("imu", 3, imu_tol))
    return VehicleDraw(
        imperfect=True,
        cg_offset_frd_m=(cx * v.cg_tol_xy_m, cy * v.cg_tol_xy_m, cz * v.cg_tol_z_m),
        kt_scale=tuple(1.0 + s for s in uniform("kt", 4, v.kt_tol)),
        kq_scale=tuple(1.0 + s for s in uniform("kq", 4, v.kq_tol)),
        tilt_frd_rad=tilts,
        thrust_dir_frd=tuple(thrust_direction(ax, ay) for ax, ay in tilts),
        imu_rpy_rad=rpy,
        imu_rot=imu_from_body(*rpy))


def thrust_direction(about_x_rad: float, about_y_rad: float) -> tuple:
    """The rotor's thrust direction in body FRD: up (0, 0, -1) turned about body x, then
    about body y. A positive turn about x leans the thrust to the right (+y), a positive
    turn about y leans it back (-x): the right-hand rule applied to the up vector."""
    sx, cx = math.sin(about_x_rad), math.cos(about_x_rad)
    sy, cy = math.sin(about_y_rad), math.cos(about_y_rad)
    return (-sy * cx, sx, -cy * cx)


def imu_from_body(roll: float, pitch: float, yaw: float) -> tuple:
    """R with v_imu = R v_body for a sensor frame turned by (roll, pitch, yaw), ZYX, from the
    body: the transpose of Rz(yaw) Ry(pitch) Rx(roll), which maps sensor axes to body axes."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cyw, syw = math.cos(yaw), math.sin(yaw)
    body_from_imu = ((cyw * cp, cyw * sp * sr - syw * cr, cyw * sp * cr + syw * sr),
                     (syw * cp, syw * sp * sr + cyw * cr, syw * sp * cr - cyw * sr),
                     (-sp, cp * sr, cp * cr))
    return tuple(tuple(body_from_imu[j][i] for j in range(3)) for i in range(3))
