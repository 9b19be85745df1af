"""Viewable channels of a run log: per-sample messages derived from the analysis batches.

The analysis channels (/imu, /gt_att, /fc/status, ...) carry batches of up to
1,024 rows per message: fast to write and read, useless to Foxglove's Plot
panel, which plots one value per message. Every time the writer emits a
batch (tools/logs/log_stream.py `ChannelStream`), the batch's rows come here and
become one message per sample, at most `viz_hz` per second (every row of slower
channels), so the values are the batch's values by construction:

  /viz/attitude  ground truth: roll_deg, pitch_deg, yaw_deg, body rates p/q/r_deg_s
  /viz/command   the scenario's setpoint: roll_deg, pitch_deg, yaw_deg, altitude_m
  /viz/fc        the FC: estimated and target attitude, filtered and target rates,
                 throttle_us
  /viz/motors    the PWM the FC published: m1_us .. m4_us
  /viz/rotor     the motor model's rotor speeds (/rotor): m1_rpm .. m4_rpm, m1_rad_s .. m4_rad_s
  /viz/vibration the IMU's spectrum 10 times a second: per gyro/accel axis the largest
                 peak's frequency and amplitude and the band RMS (tools/logs/viz_spectrum.py)
  /viz/tf        foxglove.FrameTransform world -> base_link (ground truth), at most
                 VIEW3D_HZ (as the next three)
  /viz/tf_fc     foxglove.FrameTransform world -> base_link_fc (the FC's estimate)
  /viz/tf_cmd    foxglove.FrameTransform world -> base_link_cmd (the FC's target)
  /viz/pose      foxglove.PoseInFrame of the vehicle in world (ground truth)
  /viz/scene     foxglove.SceneUpdate: vehicle, commanded attitude, force arrows
                 (tools/logs/viz_scene.py), at most SCENE_HZ

Frames: world is ENU, base_link FLU (tools/logs/viz_frames.py). The FC's frames
are placed at the true position (the FC estimates attitude, not position).
Cost: whole-batch numpy work (tools/logs/viz_codec.py) and one file write per
channel per batch, in uncompressed MCAP chunks of one channel each, so the
log reader skips them without parsing (tools/logs/log_reader.py). The same
messages can also go to a live view (tools/logs/live_view.py).
"""

from __future__ import annotations

import time

import numpy as np

from silbridge.tools.logs.mcap_layout import message_records
from silbridge.tools.logs.viz_codec import (FixedMessage, cdr_items, pb_doubles, pb_message,
                                            pb_string, pb_timestamp, ros2msg_text)
from silbridge.tools.logs.viz_frames import euler_from_quat, ned_to_enu, q_enu_flu, quat_from_euler
from silbridge.tools.logs import viz_spectrum
from silbridge.shm.records import NS_PER_S as _NS

VIZ_HZ_DEFAULT = 1000.0
VIEW3D_HZ = 100.0       # transforms and poses: smooth in the 3D panel, a tenth of the cost
SCENE_HZ = 10.0         # the scene only moves its force arrows

# Plot channels: topic -> (schema name, source channel, [(field, meaning), ...]).
PLOTS = {
    "/viz/attitude": ("silbridge_msgs/msg/VizAttitude", "/gt_att", [
        ("roll_deg", "true roll (ZYX Euler of FRD -> NED)"), ("pitch_deg", "true pitch"),
        ("yaw_deg", "true yaw"), ("p_deg_s", "true body rate about forward (FRD)"),
        ("q_deg_s", "true body rate about right"), ("r_deg_s", "true body rate about down")]),
    "/viz/command": ("silbridge_msgs/msg/VizCommand", "/setpoint", [
        ("roll_deg", "commanded roll (scenario setpoint)"), ("pitch_deg", "commanded pitch"),
        ("yaw_deg", "commanded yaw"), ("altitude_m", "commanded altitude above home")]),
    "/viz/fc": ("silbridge_msgs/msg/VizFc", "/fc/status", [
        ("roll_deg", "FC estimate"), ("pitch_deg", "FC estimate"), ("yaw_deg", "FC estimate"),
        ("target_roll_deg", "FC target (shaped command)"), ("target_pitch_deg", "FC target"),
        ("target_yaw_deg", "FC target"),
        ("p_deg_s", "rate loop input (filtered gyro, FRD)"), ("q_deg_s", "rate loop input"),
        ("r_deg_s", "rate loop input"), ("target_p_deg_s", "rate target"),
        ("target_q_deg_s", "rate target"), ("target_r_deg_s", "rate target"),
        ("throttle_us", "mixer throttle")]),
    "/viz/motors": ("silbridge_msgs/msg/VizMotors", "/pwm", [
        ("m1_us", "motor 1 PWM (front right)"), ("m2_us", "motor 2 PWM (rear left)"),
        ("m3_us", "motor 3 PWM (front left)"), ("m4_us", "motor 4 PWM (rear right)")]),
    "/viz/rotor": ("silbridge_msgs/msg/VizRotor", "/rotor", [
        *((f"m{i}_rpm", f"motor {i} rotor speed [rpm] (JSBSim fcs/m{i}-omega-rad_s)")
          for i in range(1, 5)),
        *((f"m{i}_rad_s", f"motor {i} rotor speed [rad/s]") for i in range(1, 5))]),
    viz_spectrum.VIBRATION_CHANNEL: viz_spectrum.PLOT,     # 10 Hz, tools/logs/viz_spectrum.py
}
TRANSFORMS = {"/viz/tf": "base_link", "/viz/tf_fc": "base_link_fc",
              "/viz/tf_cmd": "base_link_cmd"}
POSE_CHANNEL = "/viz/pose"
SCENE_CHANNEL = "/viz/scene"
CHANNELS = (*PLOTS, *TRANSFORMS, POSE_CHANNEL, SCENE_CHANNEL)
# The fields each source must have (an ArduCopter run's /fc/status has other ones: its
# batches then feed no viewable channel).
SOURCES = {
    "/gt_att": ("q_wxyz", "rates_frd_rad_s"),
    "/gt_nav": ("pos_ned_m",),
    "/setpoint": ("roll_rad", "pitch_rad", "yaw_rad", "altitude_m"),
    "/fc/status": ("q_est_wxyz", "euler_est_rad", "att_target_rad", "rate_frd_rad_s",
                   "rate_target_frd_rad_s", "throttle_us"),
    "/pwm": ("pwm_us",),
    "/rotor": ("omega_rad_s", "rpm"),
    viz_spectrum.SOURCE: viz_spectrum.SOURCE_FIELDS,
}

_XYZ = ["tx", "ty", "tz"]
_WXYZ = ["qx", "qy", "qz", "qw"]


def _transform_items(child: str) -> list:
    # foxglove.FrameTransform: timestamp 1, parent 2, child 3, translation 4, rotation 5.
    return (pb_timestamp(1) + pb_string(2, "world") + pb_string(3, child)
            + pb_doubles(4, _XYZ) + pb_doubles(5, _WXYZ))


def _pose_items() -> list:
    # foxglove.PoseInFrame: timestamp 1, frame_id 2, pose 3 (position 1, orientation 2).
    return (pb_timestamp(1) + pb_string(2, "world")
            + pb_message(3, pb_doubles(1, _XYZ) + pb_doubles(2, _WXYZ)))


def _deg(a):
    return np.degrees(np.asarray(a, dtype=np.float64))


def _plot_values(topic: str, rows: np.ndarray) -> dict:
    """The plot message's columns from a source batch (float64)."""
    if topic == "/viz/attitude":
        e, w = _deg(euler_from_quat(rows["q_wxyz"])), _deg(rows["rates_frd_rad_s"])
        return {"roll_deg": e[:, 0], "pitch_deg": e[:, 1], "yaw_deg": e[:, 2],
                "p_deg_s": w[:, 0], "q_deg_s": w[:, 1], "r_deg_s": w[:, 2]}
    if topic == "/viz/command":
        return {"roll_deg": _deg(rows["roll_rad"]), "pitch_deg": _deg(rows["pitch_rad"]),
                "yaw_deg": _deg(rows["yaw_rad"]), "altitude_m": rows["altitude_m"]}
    if topic == "/viz/fc":
        out = {}
        for prefix, col in (("", "euler_est_rad"), ("target_", "att_target_rad")):
            v = _deg(rows[col])
            for i, ax in enumerate(("roll", "pitch", "yaw")):
                out[f"{prefix}{ax}_deg"] = v[:, i]
        for prefix, col in (("", "rate_frd_rad_s"), ("target_", "rate_target_frd_rad_s")):
            v = _deg(rows[col])
            for i, ax in enumerate("pqr"):
                out[f"{prefix}{ax}_deg_s"] = v[:, i]
        out["throttle_us"] = rows["throttle_us"]
        return out
    if topic == "/viz/rotor":
        rpm, w = rows["rpm"], rows["omega_rad_s"]
        return {**{f"m{i + 1}_rpm": rpm[:, i] for i in range(4)},
                **{f"m{i + 1}_rad_s": w[:, i] for i in range(4)}}
    us = rows["pwm_us"]
    return {f"m{i + 1}_us": us[:, i] for i in range(4)}


class _Decimate:
    """Keeps the first sample of each 1/hz period of sim time (all of a slower channel)."""

    def __init__(self, hz: float):
        self.period = int(round(_NS / hz)) if hz > 0 else 0
        self.last = None

    def __call__(self, sim_ns: np.ndarray) -> np.ndarray:
        if self.period <= 1:
            return np.ones(len(sim_ns), dtype=bool)
        b = sim_ns // self.period
        keep = np.empty(len(b), dtype=bool)
        keep[0] = b[0] != self.last
        np.not_equal(b[1:], b[:-1], out=keep[1:])
        self.last = b[-1]
        return keep


class _Placed:
    """Attitude samples waiting for the true position at their time (from /gt_nav)."""

    def __init__(self):
        self.t = np.zeros(0, dtype=np.int64)
        self.q = np.zeros((0, 4))
        self.extra = np.zeros((0, 4))

    def add(self, t, q, extra=None):
        self.t = np.concatenate([self.t, t])
        self.q = np.concatenate([self.q, q])
        self.extra = np.concatenate([self.extra, q if extra is None else extra])

    def take(self, upto_ns: int | None):
        """Samples at or before upto_ns (all if None), removed from the queue."""
        n = len(self.t) if upto_ns is None else int(np.searchsorted(self.t, upto_ns, "right"))
        out = self.t[:n], self.q[:n], self.extra[:n]
        self.t, self.q, self.extra = self.t[n:], self.q[n:], self.extra[n:]
        return out


class VizChannels:
    """Turns emitted batches into viewable channels (see the module docstring).

    mcap: the log's McapFile / LibraryMcap (tools/logs/mcap_writer.py; None: live view only);
    live: a tools.live_view.LiveView or None; metadata: the run's start metadata
    (the scenario's forces for the arrows); viz_hz: messages per second of the
    per-sample channels, at most."""

    def __init__(self, mcap, metadata: dict, viz_hz: float = VIZ_HZ_DEFAULT, live=None):
        from foxglove.messages import FrameTransform, PoseInFrame

        from silbridge.tools.logs.viz_scene import Scene
        if viz_hz <= 0:
            raise ValueError("viz_hz must be > 0 (leave the viewable channels out instead)")
        self.viz_hz = viz_hz
        self._mcap, self._live = mcap, live
        self._ids, self._seq, self._live_ch = {}, {}, {}
        self._fixed = {}
        for topic, (schema_name, _src, fields) in PLOTS.items():
            self._fixed[topic] = FixedMessage(cdr_items([f for f, _ in fields]))
            self._register(topic, schema_name, "ros2msg",
                           ros2msg_text(f"silbridge {topic}: one sample", fields), "cdr")
        tf_schema, pose_schema = FrameTransform.get_schema(), PoseInFrame.get_schema()
        for topic, child in TRANSFORMS.items():
            self._fixed[topic] = FixedMessage(_transform_items(child))
            self._register(topic, tf_schema.name, tf_schema.encoding, tf_schema.data, "protobuf")
        self._fixed[POSE_CHANNEL] = FixedMessage(_pose_items())
        self._register(POSE_CHANNEL, pose_schema.name, pose_schema.encoding, pose_schema.data,
                       "protobuf")
        self._scene = Scene(metadata)
        s = self._scene.schema
        self._register(SCENE_CHANNEL, s.name, s.encoding, s.data, "protobuf")
        self._decimate = {src: _Decimate(viz_hz) for src in SOURCES if src != "/gt_nav"}
        self._vibration = viz_spectrum.VibrationView(viz_hz)   # 10 Hz at most
        self._decimate3d = {src: _Decimate(min(viz_hz, VIEW3D_HZ))
                            for src in ("/gt_att", "/fc/status")}
        self._scene_decimate = _Decimate(min(viz_hz, SCENE_HZ))
        self._nav_t = np.zeros(0, dtype=np.int64)
        self._nav_pos = np.zeros((0, 3))
        self._true = _Placed()      # /gt_att -> /viz/tf, /viz/pose
        self._fc = _Placed()        # /fc/status -> /viz/tf_fc, /viz/tf_cmd
        self._closed = False
        self.cpu_s = 0.0            # thread CPU time spent here: the cost, measured in place

    def _register(self, topic, schema_name, schema_encoding, schema_data, msg_encoding):
        if self._mcap is not None:
            sid = self._mcap.register_schema(schema_name, schema_encoding, bytes(schema_data))
            self._ids[topic] = self._mcap.register_channel(topic, msg_encoding, sid)
        if self._live is not None:
            self._live_ch[topic] = self._live.channel(topic, schema_name, schema_encoding,
                                                      bytes(schema_data), msg_encoding)
        self._seq[topic] = 0

    # -- the writer's hook ----------------------------------------------------
    def tap(self, source: str, dtype: np.dtype):
        """The function a source channel's batches go to, or None if none uses them."""
        need = SOURCES.get(source)
        if need is None or not set(need) <= set(dtype.names or ()):
            return None
        return lambda rows: self.batch(source, rows)

    def batch(self, source: str, rows: np.ndarray) -> None:
        if not len(rows) or self._closed:
            return
        t0 = time.thread_time()
        try:
            self._batch(source, rows)
        finally:
            self.cpu_s += time.thread_time() - t0

    def _batch(self, source: str, rows: np.ndarray) -> None:
        sim_ns = rows["sim_ns"]
        if source == viz_spectrum.SOURCE:
            out = self._vibration.batch(rows)
            if out is not None:
                self._write_fixed(viz_spectrum.VIBRATION_CHANNEL, *out)
            return
        if source == "/gt_nav":
            self._nav(sim_ns, rows["pos_ned_m"])
            return
        keep = self._decimate[source](sim_ns)
        if not keep.all():
            rows, sim_ns = rows[keep], sim_ns[keep]
            if not len(rows):       # every row in the period of one already sent
                return
        for topic, (_n, src, _f) in PLOTS.items():
            if src == source:
                self._write_fixed(topic, sim_ns, _plot_values(topic, rows))
        if source not in self._decimate3d:
            return
        keep = self._decimate3d[source](sim_ns)
        rows, sim_ns = rows[keep], sim_ns[keep]
        if not len(rows):
            return
        if source == "/gt_att":
            self._true.add(sim_ns, q_enu_flu(rows["q_wxyz"]))
        else:
            self._fc.add(sim_ns, q_enu_flu(rows["q_est_wxyz"]),
                         q_enu_flu(quat_from_euler(rows["att_target_rad"])))
        self._place(final=False)

    def _nav(self, sim_ns, pos_ned) -> None:
        self._nav_t = np.concatenate([self._nav_t, sim_ns])
        self._nav_pos = np.concatenate([self._nav_pos, np.asarray(pos_ned, dtype=np.float64)])
        keep = self._scene_decimate(sim_ns)
        if keep.any():
            t = sim_ns[keep]
            self._write_messages(SCENE_CHANNEL, t,
                                 self._scene.messages(t, np.asarray(pos_ned)[keep]))
        self._place(final=False)

    def _place(self, final: bool) -> None:
        """Emit the transforms of attitude samples whose true position is known."""
        if not len(self._nav_t) and not final:
            return
        upto = None if final else int(self._nav_t[-1])
        t, q, _ = self._true.take(upto)
        if len(t):
            pos = self._position(t)
            self._write_transform("/viz/tf", t, pos, q)
            self._write_fixed(POSE_CHANNEL, t, _pose_columns(pos, q))
        t, q_est, q_tgt = self._fc.take(upto)
        if len(t):
            pos = self._position(t)
            self._write_transform("/viz/tf_fc", t, pos, q_est)
            self._write_transform("/viz/tf_cmd", t, pos, q_tgt)
        # Keep the last position row at or before the oldest waiting sample.
        oldest = min([int(p.t[0]) for p in (self._true, self._fc) if len(p.t)],
                     default=int(self._nav_t[-1]) if len(self._nav_t) else 0)
        cut = max(int(np.searchsorted(self._nav_t, oldest, "right")) - 1, 0)
        self._nav_t, self._nav_pos = self._nav_t[cut:], self._nav_pos[cut:]

    def _position(self, t: np.ndarray) -> np.ndarray:
        """ENU position at each time: the latest /gt_nav row at or before it (held)."""
        if not len(self._nav_t):
            return np.zeros((len(t), 3))
        i = np.clip(np.searchsorted(self._nav_t, t, "right") - 1, 0, len(self._nav_t) - 1)
        return ned_to_enu(self._nav_pos[i])

    def _write_transform(self, topic, t, pos, q) -> None:
        self._write_fixed(topic, t, _pose_columns(pos, q))

    # -- output ----------------------------------------------------------------
    def _write_fixed(self, topic: str, sim_ns: np.ndarray, values: dict) -> None:
        fixed = self._fixed[topic]
        seq = self._seq[topic]
        recs = fixed.encode(self._ids.get(topic, 0), seq, sim_ns, values)
        self._seq[topic] = seq + len(recs)
        t0, t1 = max(int(sim_ns[0]), 0), max(int(sim_ns[-1]), 0)
        if self._mcap is not None:
            self._mcap.add_message_records(self._ids[topic], recs.tobytes(), len(recs), t0, t1)
        if self._live is not None:
            ch = self._live_ch[topic]
            for ns, data in zip(recs["log_time"].tolist(), fixed.data_of(recs)):
                ch.log(data.tobytes(), ns)

    def _write_messages(self, topic: str, sim_ns: np.ndarray, datas: list[bytes]) -> None:
        seq = self._seq[topic]
        self._seq[topic] = seq + len(datas)
        times = np.maximum(sim_ns, 0).tolist()
        if self._mcap is not None:
            cid = self._ids[topic]
            self._mcap.add_message_records(cid, message_records(cid, seq, times, datas),
                                           len(datas), times[0], times[-1])
        if self._live is not None:
            ch = self._live_ch[topic]
            for ns, d in zip(times, datas):
                ch.log(d, ns)

    def close(self) -> None:
        """Emit the samples still waiting for a position (held at the last one)."""
        if not self._closed:
            t0 = time.thread_time()
            self._place(final=True)
            self.cpu_s += time.thread_time() - t0
            self._closed = True


def _pose_columns(pos, q) -> dict:
    return {"tx": pos[:, 0], "ty": pos[:, 1], "tz": pos[:, 2],
            "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]}
