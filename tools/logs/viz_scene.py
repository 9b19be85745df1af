"""The 3D scene of a log: the vehicle, its commanded attitude and the disturbance forces.

foxglove.SceneUpdate messages (built with the foxglove-sdk classes, so the
bytes are the SDK's own protobuf encoding) for Foxglove's 3D panel:
- "vehicle": the F450-class quad X of jsbsim_models/quadx (450 mm motor to
  motor, 10-inch rotors, ArduCopter motor order) as primitives in frame
  base_link, so /viz/tf moves it; front arms red, rear arms grey.
- "command": the same frame, translucent green, in base_link_cmd (/viz/tf_cmd:
  the FC's target attitude at the vehicle's position), so the commanded
  attitude is drawn over the true one and their difference is visible.
- "disturbance": one arrow per scripted external force that is on (the
  scenario's [[disturbance]] type "force", bridge/disturbances.py), in world
  for NED forces and base_link for FRD ones, 0.1 m per m/s^2 of acceleration
  it imposes (1 g: ~1 m).
The vehicle entities never change, so they are encoded once, and so are the
force entities without arrows; a message prepends its timestamp to each (a
protobuf message concatenated with another is their merge, and the stamp is
three varints written here) and builds with the SDK only the arrows that are
on at that instant.
"""

from __future__ import annotations

import math

import numpy as np

from silbridge.tools.logs.viz_codec import pb_tag, varint
from silbridge.tools.logs.viz_frames import frd_to_flu, ned_to_enu, quat_x_to
from silbridge.shm.records import NS_PER_S

ARM_M = 0.225            # motor to centre (450 mm diagonal)
ROTOR_D_M = 0.254        # 10-inch propeller
ARROW_M_PER_M_S2 = 0.1
G0 = 9.80665
# ArduCopter quad X: motor 1 front right, 2 rear left, 3 front left, 4 rear right (FRD x, y).
_MOTORS_FRD = [(1, 1), (-1, -1), (1, -1), (-1, 1)]


def _fg():
    import foxglove.messages as fg
    return fg


def _quad_entity(fg, entity_id: str, frame: str, alpha: float, body_rgb, front_rgb, rear_rgb):
    def color(rgb):
        return fg.Color(r=rgb[0], g=rgb[1], b=rgb[2], a=alpha)

    def pose(x=0.0, y=0.0, z=0.0, yaw=0.0):
        return fg.Pose(position=fg.Vector3(x=x, y=y, z=z),
                       orientation=fg.Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                 w=math.cos(yaw / 2)))
    cubes = [fg.CubePrimitive(pose=pose(), size=fg.Vector3(x=0.14, y=0.10, z=0.05),
                              color=color(body_rgb))]
    cylinders = []
    r = ARM_M / math.sqrt(2.0)
    for fx, fy in _MOTORS_FRD:
        # FLU: y = -FRD y. An arm is a thin box from the centre to the motor.
        x, y = fx * r, -fy * r
        cubes.append(fg.CubePrimitive(
            pose=pose(x / 2, y / 2, 0.0, math.atan2(y, x)),
            size=fg.Vector3(x=ARM_M, y=0.02, z=0.02),
            color=color(front_rgb if fx > 0 else rear_rgb)))
        cylinders.append(fg.CylinderPrimitive(
            pose=pose(x, y, 0.04), size=fg.Vector3(x=ROTOR_D_M, y=ROTOR_D_M, z=0.01),
            bottom_scale=1.0, top_scale=1.0, color=color((0.2, 0.4, 0.9))))
    return fg.SceneEntity(frame_id=frame, id=entity_id, frame_locked=True, cubes=cubes,
                          cylinders=cylinders)


def _length_delimited(field: int, data: bytes) -> bytes:
    return pb_tag(field, 2) + varint(len(data)) + data


def _stamp(ns: int) -> bytes:
    """A SceneEntity holding only its timestamp (field 1, google.protobuf.Timestamp:
    seconds 1, nanos 2; zeros left out as proto3 encoders do)."""
    sec, nsec = divmod(ns, NS_PER_S)
    ts = (pb_tag(1, 0) + varint(sec) if sec else b"") + (pb_tag(2, 0) + varint(nsec)
                                                          if nsec else b"")
    return _length_delimited(1, ts)


class Scene:
    """SceneUpdate messages at chosen sample times (see the module docstring)."""

    def __init__(self, metadata: dict):
        fg = _fg()
        self.fg = fg
        self.schema = fg.SceneUpdate.get_schema()
        self._vehicle = _quad_entity(fg, "vehicle", "base_link", 1.0, (0.25, 0.25, 0.25),
                                     (0.85, 0.1, 0.1), (0.55, 0.55, 0.55)).encode()
        self._command = _quad_entity(fg, "command", "base_link_cmd", 0.35, (0.1, 0.8, 0.2),
                                     (0.1, 0.8, 0.2), (0.1, 0.8, 0.2)).encode()
        self._forces = _force_scripts(metadata)
        self._no_arrows = {frame: fg.SceneEntity(frame_id=frame, id=f"disturbance_{frame}",
                                                 frame_locked=True).encode()
                           for frame in ("world", "base_link")}

    def messages(self, sim_ns: np.ndarray, pos_ned: np.ndarray) -> list[bytes]:
        """One SceneUpdate per sample: the vehicle's position pos_ned (n, 3) places the
        world-frame force arrows."""
        fg = self.fg
        t_s = sim_ns * 1e-9
        arrows = {"world": _arrows(self._forces, "ned", t_s), "base_link":
                  _arrows(self._forces, "frd", t_s)}
        pos_enu = ned_to_enu(pos_ned)
        out = []
        for i, ns in enumerate(sim_ns.tolist()):
            stamp = _stamp(max(ns, 0))
            prims = []
            for frame, (vec, quat, length) in arrows.items():
                origin = pos_enu[i] if frame == "world" else (0.0, 0.0, 0.0)
                for k in range(vec.shape[1]):
                    if length[i, k] <= 0:
                        continue
                    q = quat[i, k]
                    prims.append((frame, fg.ArrowPrimitive(
                        pose=fg.Pose(position=fg.Vector3(x=origin[0], y=origin[1], z=origin[2]),
                                     orientation=fg.Quaternion(w=q[0], x=q[1], y=q[2], z=q[3])),
                        shaft_length=max(length[i, k] - 0.1, 0.01), shaft_diameter=0.03,
                        head_length=0.1, head_diameter=0.07,
                        color=fg.Color(r=1.0, g=0.55, b=0.0, a=1.0))))
            entities = [stamp + self._vehicle, stamp + self._command]
            for frame in ("world", "base_link"):
                mine = [p for f, p in prims if f == frame]
                entities.append(stamp + (fg.SceneEntity(
                    frame_id=frame, id=f"disturbance_{frame}", frame_locked=True,
                    arrows=mine).encode() if mine else self._no_arrows[frame]))
            out.append(b"".join(_length_delimited(2, e) for e in entities))
        return out


def _force_scripts(metadata: dict) -> list[dict]:
    """The scenario's force disturbances: frame, axis, amplitude, frequency, on/off times
    (switched at the first physics step starting at or after the scripted time)."""
    sc = metadata.get("scenario") or {}
    physics_hz = float((metadata.get("config") or {}).get("physics_hz") or 1000.0)
    dt = 1.0 / physics_hz
    out = []
    for d in sc.get("disturbances") or []:
        if d.get("type") != "force":
            continue
        axis = np.asarray(d.get("axis", (1.0, 0.0, 0.0)), dtype=np.float64)
        start = math.ceil(float(d.get("start_s", 0.0)) / dt - 1e-9) * dt
        stop = d.get("stop_s")
        out.append({"frame": d.get("frame", "ned"), "axis": axis,
                    "accel": G0 * float(d.get("amplitude_g", 0.0)),
                    "omega": 2.0 * math.pi * float(d.get("frequency_hz", 0.0)),
                    "phase": math.radians(float(d.get("phase_deg", 0.0))),
                    "on": start,
                    "off": math.inf if stop is None else
                    math.ceil(float(stop) / dt - 1e-9) * dt})
    return out


def _arrows(forces: list[dict], frame: str, t_s: np.ndarray):
    """(vectors (n, k, 3), arrow rotations (n, k, 4), lengths (n, k)) of the k forces in
    `frame` at times t_s, in the frame's Foxglove axes (ENU or FLU); length 0 when off."""
    sel = [f for f in forces if f["frame"] == frame]
    n = len(t_s)
    vec = np.zeros((n, len(sel), 3))
    quat = np.zeros((n, len(sel), 4))
    length = np.zeros((n, len(sel)))
    convert = ned_to_enu if frame == "ned" else frd_to_flu
    for k, f in enumerate(sel):
        on = (t_s >= f["on"]) & (t_s < f["off"])
        a = f["accel"] * (np.sin(f["omega"] * (t_s - f["on"]) + f["phase"])
                          if f["omega"] > 0 else np.ones(n))
        v = convert(np.outer(np.where(on, a, 0.0), f["axis"]))
        vec[:, k] = v
        quat[:, k] = quat_x_to(v)
        length[:, k] = np.linalg.norm(v, axis=1) * ARROW_M_PER_M_S2
    return vec, quat, length
