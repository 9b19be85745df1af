"""Viewable channels of a run log (tools/logs/viz_log.py): what Foxglove plots and draws.

A real closed-loop flight (JSBSim + SIL FC, lockstep) writes its log; the mcap
package with the ROS 2 and protobuf decoders reads the /viz channels back: one
message per sample, time increasing sample by sample, values equal to the
batches the analysis reads, transforms placing the vehicle where ground truth
has it. The layout file names only channels and fields a log holds.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoders
from mcap_ros2.decoder import DecoderFactory as Ros2Decoders

from silbridge.tools.logs.foxglove_layout import layout, layout_paths, layout_topics
from silbridge.tools.logs.integrity import check_log
from silbridge.tools.logs.log_synth import synthetic_run, write_run
from silbridge.tools.logs.mcap_log import LogWriter, read_log
from silbridge.tools.logs.viz_frames import euler_from_quat, ned_to_enu, q_enu_flu, quat_from_euler
from silbridge.tools.logs.viz_log import CHANNELS, PLOTS
from silbridge.tools.logs.viz_scene import Scene

REPO = Path(__file__).resolve().parents[2]


def decoded(path, topics=None) -> dict[str, list]:
    """topic -> [(log_time, decoded message)] of the file, in file order."""
    out: dict[str, list] = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[Ros2Decoders(), ProtobufDecoders()],
                             validate_crcs=True)
        for _schema, ch, msg, dec in reader.iter_decoded_messages(topics=topics):
            out.setdefault(ch.topic, []).append((msg.log_time, dec))
    return out


@pytest.fixture(scope="module")
def flight(tmp_path_factory, pitch_push_scenario):
    from silbridge.tools.loop.flight import FlightOptions, fly_one_process
    tmp = tmp_path_factory.mktemp("viz")
    # Take-off (the scripted one arms at 5 s), a pitch step and a push north, in 12 s.
    scenario = pitch_push_scenario(
        tmp, "viz", "take-off at 5 s, a 10 deg pitch step at 10 s, "
        "a 0.2 g push north from 10.5 to 11.5 s", seed=7, duration_s=12.0, step_s=10.0)
    path = tmp / "flight.mcap"
    s = fly_one_process(FlightOptions(scenario=str(scenario), processes=1,
                                      log_path=str(path)), out=lambda line: None)
    assert not s["crashed"]
    return path, read_log(path), decoded(path, list(CHANNELS))


def _times(msgs) -> np.ndarray:
    return np.array([t for t, _ in msgs], dtype=np.int64)


def test_every_viewable_channel_is_in_a_flight_log(flight):
    _path, log, viz = flight
    assert set(viz) == set(CHANNELS)
    # Per sample, time increasing sample by sample.
    for topic in CHANNELS:
        t = _times(viz[topic])
        assert len(t) > (3 if topic == "/viz/command" else 10), topic   # setpoints: on change
        assert np.all(np.diff(t) > 0), f"{topic}: log times not increasing"
    # 1 kHz ground truth: every sample; 3D channels at 100 Hz; the scene at 10 Hz.
    assert len(viz["/viz/attitude"]) == len(log.channels["/gt_att"])
    assert len(viz["/viz/motors"]) == len(log.channels["/pwm"])
    assert len(viz["/viz/fc"]) == len(log.channels["/fc/status"])
    assert len(viz["/viz/command"]) == len(log.channels["/setpoint"])
    assert abs(len(viz["/viz/tf"]) - 100 * log.duration_s()) <= 2
    assert abs(len(viz["/viz/scene"]) - 10 * log.duration_s()) <= 2
    # The push north from 10.5 to 11.5 s is an arrow in the scene then, and only then.
    for t, m in viz["/viz/scene"]:
        ents = {e.id: e for e in m.entities}
        assert {"vehicle", "command", "disturbance_world", "disturbance_base_link"} <= set(ents)
        on = 10.5e9 <= t < 11.5e9
        assert len(ents["disturbance_world"].arrows) == (1 if on else 0), t
    # The summary's statistics count them (chunks included).
    with open(_path, "rb") as f:
        stats = make_reader(f).get_summary()
    counts = stats.statistics.channel_message_counts
    for cid, ch in stats.channels.items():
        if ch.topic in viz:
            assert counts[cid] == len(viz[ch.topic]), ch.topic
    assert stats.statistics.chunk_count > 0
    # The analysis reads the same log whole and sound.
    assert log.read_error is None
    assert check_log(log) == []


def test_plot_values_equal_the_batches(flight):
    _path, log, viz = flight
    gt, st, pwm, sp = (log.channels[c] for c in ("/gt_att", "/fc/status", "/pwm", "/setpoint"))
    att = viz["/viz/attitude"]
    np.testing.assert_array_equal(_times(att), gt["sim_ns"])
    euler = np.degrees(euler_from_quat(gt["q_wxyz"]))
    rates = np.degrees(gt["rates_frd_rad_s"].astype(np.float64))
    for j, axis in enumerate(("roll", "pitch", "yaw")):
        np.testing.assert_array_equal([getattr(m, f"{axis}_deg") for _, m in att], euler[:, j])
    for j, axis in enumerate("pqr"):
        np.testing.assert_array_equal([getattr(m, f"{axis}_deg_s") for _, m in att], rates[:, j])
    stamp = [m.stamp.sec * 10**9 + m.stamp.nanosec for _, m in att]
    np.testing.assert_array_equal(stamp, gt["sim_ns"])

    fc = viz["/viz/fc"]
    np.testing.assert_array_equal(_times(fc), st["sim_ns"])
    np.testing.assert_array_equal([m.target_roll_deg for _, m in fc],
                                  np.degrees(st["att_target_rad"][:, 0].astype(np.float64)))
    np.testing.assert_array_equal([m.target_q_deg_s for _, m in fc],
                                  np.degrees(st["rate_target_frd_rad_s"][:, 1].astype(np.float64)))
    np.testing.assert_array_equal([m.throttle_us for _, m in fc], st["throttle_us"])

    motors = viz["/viz/motors"]
    np.testing.assert_array_equal(_times(motors), pwm["sim_ns"])
    for i in range(4):
        np.testing.assert_array_equal([getattr(m, f"m{i + 1}_us") for _, m in motors],
                                      pwm["pwm_us"][:, i])
    cmd = viz["/viz/command"]
    np.testing.assert_array_equal([m.altitude_m for _, m in cmd], sp["altitude_m"])
    np.testing.assert_array_equal([m.pitch_deg for _, m in cmd],
                                  np.degrees(sp["pitch_rad"].astype(np.float64)))
    # The pitch step shows in the command plot, and the vehicle follows it.
    assert max(m.pitch_deg for _, m in cmd) == pytest.approx(10.0, abs=1e-4)
    assert max(m.pitch_deg for _, m in att) > 5.0


def test_transforms_place_the_vehicle_where_ground_truth_has_it(flight):
    _path, log, viz = flight
    gt, nav, st = log.channels["/gt_att"], log.channels["/gt_nav"], log.channels["/fc/status"]
    tf = viz["/viz/tf"]
    t = _times(tf)
    i = np.searchsorted(gt["sim_ns"], t)
    np.testing.assert_array_equal(gt["sim_ns"][i], t)
    j = np.searchsorted(nav["sim_ns"], t, "right") - 1
    pos = ned_to_enu(nav["pos_ned_m"][j])
    q = q_enu_flu(gt["q_wxyz"][i])
    got_pos = np.array([[m.translation.x, m.translation.y, m.translation.z] for _, m in tf])
    got_q = np.array([[m.rotation.w, m.rotation.x, m.rotation.y, m.rotation.z] for _, m in tf])
    np.testing.assert_allclose(got_pos, pos, atol=1e-9)
    np.testing.assert_allclose(got_q, q, atol=1e-12)
    assert {(m.parent_frame_id, m.child_frame_id) for _, m in tf} == {("world", "base_link")}
    assert got_pos[-1, 2] > 5.0         # hovering at 10 m: z is up in world
    pose = viz["/viz/pose"]
    assert [m.pose.position.z for _, m in pose] == list(got_pos[:, 2])
    assert {m.frame_id for _, m in pose} == {"world"}
    # The FC's frames: its estimate and its target attitude, at the true position.
    k = np.searchsorted(st["sim_ns"], _times(viz["/viz/tf_cmd"]))
    want = q_enu_flu(quat_from_euler(st["att_target_rad"][k]))
    got = np.array([[m.rotation.w, m.rotation.x, m.rotation.y, m.rotation.z]
                    for _, m in viz["/viz/tf_cmd"]])
    np.testing.assert_allclose(got, want, atol=1e-12)
    assert {m.child_frame_id for _, m in viz["/viz/tf_fc"]} == {"base_link_fc"}


def test_frames_follow_ros_conventions():
    """Level, nose north: base_link x (forward) is world +y (north), z is up; yawed 90 deg
    (nose east): forward is world +x."""
    def forward_and_up(q_ned_frd):
        q = q_enu_flu(np.array([q_ned_frd]))[0]
        w, x, y, z = q
        r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        return r @ [1, 0, 0], r @ [0, 0, 1]
    fwd, up = forward_and_up([1.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(fwd, [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(up, [0, 0, 1], atol=1e-12)
    fwd, up = forward_and_up(quat_from_euler(np.array([[0.0, 0.0, math.pi / 2]]))[0])
    np.testing.assert_allclose(fwd, [1, 0, 0], atol=1e-12)
    # Roll right (positive roll): the right wing goes down, so body "left" (FLU y) points up.
    q = quat_from_euler(np.array([[0.3, 0.0, 0.0]]))
    np.testing.assert_allclose(np.degrees(euler_from_quat(q))[0], [math.degrees(0.3), 0, 0],
                               atol=1e-9)


def test_viz_hz_thins_the_channels_and_the_analysis_reads_the_same(tmp_path):
    run = synthetic_run(4.0, seed=5)
    paths = {}
    for hz in (0, 100, 1000):
        paths[hz] = tmp_path / f"viz{hz}.mcap"
        with LogWriter(paths[hz], metadata=run.metadata, viz_hz=hz) as w:
            write_run(run, w)
    bare, thin, full = (read_log(paths[hz]) for hz in (0, 100, 1000))
    for name, rows in bare.channels.items():
        np.testing.assert_array_equal(thin.channels[name], rows)
        np.testing.assert_array_equal(full.channels[name], rows)
    assert not decoded(paths[0], ["/viz/attitude"])
    n_thin = len(decoded(paths[100], ["/viz/attitude"])["/viz/attitude"])
    n_full = len(decoded(paths[1000], ["/viz/attitude"])["/viz/attitude"])
    assert n_full == len(run.channels["/gt_att"])
    assert abs(n_thin - n_full / 10) <= 2


def test_compressed_logs_carry_them_too(tmp_path):
    run = synthetic_run(2.0, seed=2)
    path = tmp_path / "lz4.mcap"
    with LogWriter(path, metadata=run.metadata, compression="lz4") as w:
        write_run(run, w)
    viz = decoded(path, ["/viz/motors"])["/viz/motors"]
    np.testing.assert_array_equal([m.m3_us for _, m in viz], run.channels["/pwm"]["pwm_us"][:, 2])
    assert read_log(path).read_error is None


def test_scene_draws_the_vehicle_and_the_forces_while_they_are_on():
    from foxglove.messages import SceneUpdate  # noqa: F401 - the SDK the schema comes from
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    meta = {"config": {"physics_hz": 1000.0},
            "scenario": {"disturbances": [
                {"type": "force", "frame": "ned", "axis": [1.0, 0.0, 0.0], "amplitude_g": 0.5,
                 "frequency_hz": 0.0, "phase_deg": 0.0, "start_s": 1.0, "stop_s": 2.0},
                {"type": "gyro_bias", "start_s": 0.0}]}}
    scene = Scene(meta)
    fds = descriptor_pb2.FileDescriptorSet.FromString(scene.schema.data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    cls = message_factory.GetMessageClass(pool.FindMessageTypeByName("foxglove.SceneUpdate"))
    t = np.array([500_000_000, 1_500_000_000, 2_500_000_000])
    msgs = [cls.FromString(b) for b in scene.messages(t, np.array([[3.0, 4.0, -10.0]] * 3))]
    ids = [{e.id: e for e in m.entities} for m in msgs]
    for ents in ids:
        assert len(ents["vehicle"].cylinders) == 4 and len(ents["vehicle"].cubes) == 5
        assert ents["vehicle"].frame_id == "base_link"
        assert ents["command"].frame_id == "base_link_cmd"
    assert [len(e["disturbance_world"].arrows) for e in ids] == [0, 1, 0]
    arrow = ids[1]["disturbance_world"].arrows[0]
    # 0.5 g north at the vehicle (ENU: north is +y; NED (3, 4, -10) is ENU (4, 3, 10)).
    assert (arrow.pose.position.x, arrow.pose.position.y, arrow.pose.position.z) == (4, 3, 10)
    o = arrow.pose.orientation
    assert abs(o.w - math.sqrt(0.5)) < 1e-9 and abs(o.z - math.sqrt(0.5)) < 1e-9
    assert abs(arrow.shaft_length + arrow.head_length - 0.5 * 9.80665 * 0.1) < 1e-9
    assert ids[1]["vehicle"].timestamp.seconds == 1 and \
        ids[1]["vehicle"].timestamp.nanos == 500_000_000


def test_layout_file_is_generated_and_names_only_channels_that_exist(flight):
    path, _log, _viz = flight
    committed = json.loads((REPO / "docs" / "foxglove_layout.json").read_text())
    assert committed == layout(), \
        "docs/foxglove_layout.json is stale: python -m silbridge.tools.logs.foxglove_layout > it"
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    topics = {c.topic: c for c in summary.channels.values()}
    for topic in layout_topics(committed):
        assert topic in topics, f"the layout names {topic}, which no log holds"
    for p in layout_paths(committed):
        topic, field = p.split(".", 1)
        fields = [f for f, _ in PLOTS[topic][2]]
        assert field in fields, f"{p}: no field {field} in {topic}"
        schema = summary.schemas[topics[topic].schema_id].data.decode()
        assert f"float64 {field} " in schema
    assert {"3D!vehicle", "Plot!roll", "Plot!motors", "Plot!rates"} <= set(committed["configById"])


def test_a_low_viz_hz_skips_whole_batches(tmp_path):
    """At 0.5 Hz most 100-row batches hold no new period: nothing to send, nothing fails."""
    run = synthetic_run(4.0, seed=6)
    path = tmp_path / "slow.mcap"
    with LogWriter(path, metadata=run.metadata, viz_hz=0.5, batch_rows=100) as w:
        write_run(run, w)
    att = decoded(path, ["/viz/attitude"])["/viz/attitude"]
    t = run.channels["/gt_att"]["sim_ns"]
    first_of_period = t[np.unique(t // 2_000_000_000, return_index=True)[1]]
    assert [m for m, _ in att] == first_of_period.tolist()
    assert len(att) >= 2
