"""`silbridge fly --live`: the viewable channels served over Foxglove's WebSocket protocol.

A real flight (`fly --realtime --live 127.0.0.1:0`, JSBSim + SIL FC in real time) and a
real WebSocket client (the `websockets` package): the client reads serverInfo and the
channel advertisements, subscribes to every channel, receives binary message frames while
the vehicle flies and decodes each channel's messages with the ROS 2 and protobuf decoders
of the mcap packages, from the schemas the server advertised.

Subprotocol: foxglove-sdk serves the protocol under its current name, foxglove.sdk.v1;
the messages are those of foxglove.websocket.v1 (Foxglove renamed it, the Foxglove app
and Lichtblick offer both names). The client offers both and must get foxglove.sdk.v1.
"""

from __future__ import annotations

import asyncio
import base64
import json
import re
import struct
import subprocess
import sys
import threading
import time

import pytest
from mcap.records import Schema
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoders
from mcap_ros2.decoder import DecoderFactory as Ros2Decoders

from silbridge.tools.logs.viz_log import CHANNELS

websockets = pytest.importorskip("websockets")

SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]

def _decoder(channel: dict):
    data = channel["schema"].encode()
    if channel["schemaEncoding"] == "protobuf":
        data = base64.b64decode(channel["schema"])
        factory = ProtobufDecoders()
    else:
        factory = Ros2Decoders()
    schema = Schema(id=channel["id"], name=channel["schemaName"],
                    encoding=channel["schemaEncoding"], data=data)
    return factory.decoder_for(channel["encoding"], schema)


async def _listen(url: str, seconds: float) -> tuple[str, dict, dict]:
    """(subprotocol, advertised channels by topic, topic -> [(timestamp, decoded)])."""
    got: dict[str, list] = {}
    async with websockets.connect(url, subprotocols=SUBPROTOCOLS, max_size=None) as ws:
        info = json.loads(await asyncio.wait_for(ws.recv(), 10))
        assert info["op"] == "serverInfo"
        channels, by_sub = {}, {}
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                frame = await asyncio.wait_for(ws.recv(), max(0.1, end - time.monotonic()))
            except asyncio.TimeoutError:
                break
            if isinstance(frame, str):
                msg = json.loads(frame)
                if msg["op"] == "advertise":
                    subs = []
                    for ch in msg["channels"]:
                        channels[ch["topic"]] = ch
                        sub = len(by_sub) + 1
                        by_sub[sub] = (ch["topic"], _decoder(ch))
                        subs.append({"id": sub, "channelId": ch["id"]})
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                continue
            op, sub, stamp_ns = struct.unpack_from("<BIQ", frame)
            assert op == 0x01, f"unexpected binary opcode {op}"
            topic, decode = by_sub[sub]
            got.setdefault(topic, []).append((stamp_ns, decode(bytes(frame[13:]))))
        return ws.subprotocol, channels, got


def _fly_and_listen(scenario) -> tuple[int, str, tuple | None]:
    cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--processes", "1", "--realtime",
           "--no-mavlink", "--scenario", str(scenario), "--duration", "6", "--live", "127.0.0.1:0",
           "--instance", f"live-{time.monotonic_ns()}"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    heard = None
    try:
        url = None
        for line in proc.stdout:
            lines.append(line)
            m = re.search(r"live view: (ws://127\.0\.0\.1:\d+)", line)
            if m:
                url = m.group(1)
                break
        if url:
            pump = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
            pump.start()
            heard = asyncio.run(_listen(url, 5.0))
            proc.wait(timeout=60)
            pump.join(timeout=5)
        else:
            proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return proc.returncode, "".join(lines), heard


@pytest.mark.slow
def test_fly_live_serves_every_viewable_channel(tmp_path, pitch_push_scenario):
    # A command change and a push during the few seconds the client listens.
    scenario = pitch_push_scenario(
        tmp_path, "live", "pitch step at 2 s, push north from 2.5 to 3.5 s (on the ground)",
        seed=9, duration_s=6.0, step_s=2.0)
    # A loaded machine's rate shortfall no longer stops the run (it is reported instead).
    rc, output, heard = _fly_and_listen(scenario)
    assert rc == 0 and heard is not None, output[-3000:]
    proto, channels, got = heard
    assert proto == "foxglove.sdk.v1"
    assert set(channels) == set(CHANNELS)
    for topic in CHANNELS:
        assert got.get(topic), f"no {topic} message arrived"
        stamps = [t for t, _ in got[topic]]
        assert stamps == sorted(stamps), topic
    # Decoded values, stamped with sim time on the wire and in the message.
    for stamp, m in got["/viz/attitude"]:
        assert m.stamp.sec * 10**9 + m.stamp.nanosec == stamp
        assert -180.0 <= m.yaw_deg <= 180.0
    assert any(abs(m.pitch_deg - 10.0) < 1e-4 for _, m in got["/viz/command"])
    assert all(1000 <= m.m1_us <= 2000 for _, m in got["/viz/motors"])
    assert {m.child_frame_id for _, m in got["/viz/tf"]} == {"base_link"}
    assert {m.child_frame_id for _, m in got["/viz/tf_cmd"]} == {"base_link_cmd"}
    assert {m.frame_id for _, m in got["/viz/pose"]} == {"world"}
    arrows = [len({e.id: e for e in m.entities}["disturbance_world"].arrows)
              for _, m in got["/viz/scene"]]
    assert 1 in arrows, "the push never showed as an arrow"
    assert all(-90.0 <= m.roll_deg <= 90.0 for _, m in got["/viz/fc"])
