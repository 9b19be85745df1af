"""HilBridgeEnd: the bridge's side of the HIL transport, with the Segment surface it uses.

The bridge loop (bridge/bridge_loop.py, bridge_driver.py) talks to a Segment: sensors.push_batch,
actuators.pop_into, the lockstep words, peer liveness. This class offers the same surface over
MAVLink 2 HIL messages, so lockstep, real time, the start-up checks, the trace hash and the
logs are the same code whatever the transport. The lockstep words map onto the protocol:

  RUN_MODE, PHYSICS_DT_NS, IMU_HZ  sent to the FC at first contact and with every heartbeat:
                 NAMED_VALUE_INT SB_MODE / SB_DT_NS / SB_IMU_HZ, GPS_GLOBAL_ORIGIN (NED zero),
                 then SB_CFG = 1 (complete)
  BRIDGE_SIM_NS  implicit: time_usec of the step's messages
  STOP           NAMED_VALUE_INT SB_STOP = 1, then the stream ends (TCP: close)
  FC_SIM_NS      time_usec * 1000 of the newest HIL_ACTUATOR_CONTROLS acknowledging a step
  FC_STATE       NAMED_VALUE_INT SB_FC from our FC (1 ready, 2 done, 3 failed); another
                 autopilot is READY at its first HEARTBEAT or HIL_ACTUATOR_CONTROLS
  FC_STOP        NAMED_VALUE_INT SB_FCSTOP = 1 from the FC
  peer_alive     the socket is open (TCP: no EOF/reset; UDP: no ICMP refusal)
  peer_heartbeat messages received from the FC (the bridge's stall watch uses it)
  peer_pid       NAMED_VALUE_INT SB_PID from our FC (0 for another autopilot)
"""

from __future__ import annotations

import collections
import time

import numpy as np

from silbridge.shm import lockstep as ls
from silbridge.shm.records import RECORD_DTYPE, RECORD_SIZE

from silbridge.mavlink.hil.hil_channel import HilListener, make_codec
from silbridge.mavlink.hil.hil_codec import SensorEncoder
from silbridge.mavlink.hil.hil_errors import HilPeerLost
from silbridge.mavlink.hil import hil_fault
from silbridge.mavlink.hil.hil_pwm import PwmDecoder

BRIDGE_SYSID = 1
BRIDGE_COMPID = 51          # a simulator component id, away from the autopilot's 1
_BEAT_S = 0.5
_NAMES = {ls.RUN_MODE: b"SB_MODE", ls.PHYSICS_DT_NS: b"SB_DT_NS", ls.IMU_HZ: b"SB_IMU_HZ"}


class _Sensors:
    """The sensor 'ring' of a HilBridgeEnd: records out as HIL messages."""

    def __init__(self, end: "HilBridgeEnd"):
        self.end = end
        self.written = 0
        self.read = 0
        self.rejected = 0
        self._pending = collections.deque()     # (step sim_ns, written total)

    def push_batch(self, recs: np.ndarray) -> int:
        end = self.end
        ch = end.require_peer()
        frames: list = []
        end.encoder.encode(recs, time.monotonic_ns(), frames)
        self.rejected += ch.send(frames)      # UDP refusals only; counted per frame
        n = len(recs)
        self.written += n
        self._pending.append((int(recs["sim_ns"][-1]), self.written))
        return n

    def acked(self, sim_ns: int) -> None:
        p = self._pending
        while p and p[0][0] <= sim_ns:
            self.read = p.popleft()[1]

    def stats(self) -> dict:
        return {"written": self.written, "read": self.read, "overwritten": 0,
                "rejected": self.rejected, "available": self.written - self.read}


class _Actuators:
    """The actuator 'ring': PWM records rebuilt from HIL_ACTUATOR_CONTROLS."""

    def __init__(self, end: "HilBridgeEnd"):
        self.end = end
        self.queue: collections.deque = collections.deque()
        self.received = 0
        self.read = 0

    def pop_into(self, buf: np.ndarray) -> int:
        self.end.pump(0.0)
        q = self.queue
        n = min(len(q), len(buf))
        if n == 0:
            return 0
        data = b"".join(q.popleft() for _ in range(n))
        buf[:n] = np.frombuffer(data, dtype=RECORD_DTYPE)
        self.read += n
        return n

    def stats(self) -> dict:
        lost = self.end.pwm_decoder.lost
        return {"written": self.received + lost, "read": self.read, "overwritten": lost,
                "rejected": 0, "available": len(self.queue)}


class HilBridgeEnd:
    """See module docstring. `HilBridgeEnd(host, port, datagram)` listens at once."""

    is_owner = True

    def __init__(self, host: str = "127.0.0.1", port: int = 4560, *, datagram: bool = False,
                 origin=(0, 0, 0), attach_timeout_s: float = 15.0, serial: str | None = None):
        self.codec = make_codec(BRIDGE_SYSID, BRIDGE_COMPID)
        if serial:      # a serial line (hil_serial.py): contact at the FC's first message
            from silbridge.mavlink.hil.hil_serial import open_serial
            self.listener = None
            self.channel = open_serial(serial, make_codec(BRIDGE_SYSID, BRIDGE_COMPID))
            self.name = self.channel.name
            self.addr = serial
        else:
            self.name = f"{'udp' if datagram else 'tcp'}://{host}:{port}"
            self.listener = HilListener(host, port, datagram)
            self.addr = self.listener.addr
            self.channel = None
        self.encoder = SensorEncoder(self.codec, origin)
        self.pwm_decoder = PwmDecoder()
        self.attach_timeout_s = attach_timeout_s
        self.words = [0] * 8
        self.sensors = _Sensors(self)
        self.actuators = _Actuators(self)
        self.peer_pid = 0
        self.closed = False
        self._silbridge_fc = False
        self._rx_msgs = 0
        self._last_beat = 0.0
        self._contact = False
        self.faults_received = 0
        self.faults_malformed = 0       # COMMAND_LONGs of hil_fault.py that were not sane

    # -- the peer ---------------------------------------------------------------------------
    def set_origin(self, lat_e7: int, lon_e7: int, alt_mm: int) -> None:
        self.encoder.origin = (int(lat_e7), int(lon_e7), int(alt_mm))

    def require_peer(self):
        """The channel to the FC, waiting for it up to the attach timeout."""
        deadline = time.monotonic() + self.attach_timeout_s
        while not self._contact:
            self.pump(0.02)
            if self.channel is not None and self.channel.eof:
                raise HilPeerLost(f"the FC disconnected ({self.channel.error})")
            if time.monotonic() > deadline:
                raise HilPeerLost(f"no FC {'spoke on' if self.listener is None else 'connected to'} {self.name} within "
                                  f"{self.attach_timeout_s:g} s: start `silbridge fc --transport "
                                  f"{'udp' if self.listener.datagram else 'tcp'}`")
        return self.channel

    def pump(self, timeout_s: float = 0.0) -> int:
        """Accept the FC, read what it sent, keep heartbeats going. Returns messages read."""
        if self.channel is None:
            self.channel = self.listener.accept(self.codec, timeout_s)
            if self.channel is None:
                return 0
            if not self.channel.datagram:
                self._first_contact()
            timeout_s = 0.0
        msgs = self.channel.receive(timeout_s)
        now_ns = time.monotonic_ns()
        for m in msgs:
            self._on_message(m, now_ns)
        self._rx_msgs += len(msgs)
        now = time.monotonic()
        if self._contact and now - self._last_beat > _BEAT_S:
            self._last_beat = now
            self._send_heartbeat()
        return len(msgs)

    def _first_contact(self) -> None:
        self._contact = True
        self._send_config()

    def _send_config(self) -> None:
        c = self.codec
        # MAV_TYPE_GENERIC, MAV_AUTOPILOT_INVALID: a simulator, not a vehicle
        frames = [c.heartbeat_encode(0, 8, 0, 0, 4).pack(c)]
        for word, name in _NAMES.items():
            frames.append(c.named_value_int_encode(0, name, int(self.words[word])).pack(c))
        lat, lon, alt = self.encoder.origin
        frames.append(c.gps_global_origin_encode(lat, lon, alt, 0).pack(c))
        frames.append(c.named_value_int_encode(0, b"SB_CFG", 1).pack(c))
        self.channel.send(frames)

    def _send_heartbeat(self) -> None:
        if self.channel is not None and not self.channel.eof:
            self._send_config()

    def _on_message(self, m, now_ns: int) -> None:
        if not self._contact:       # UDP: the FC's first datagram tells us where it is
            self._first_contact()
        mid = m.get_msgId()
        if mid == 93:          # HIL_ACTUATOR_CONTROLS
            rec, ack = self.pwm_decoder.decode(m, now_ns)
            if rec:
                self.actuators.queue.append(rec)
                self.actuators.received += 1
            if ack > self.words[ls.FC_SIM_NS]:
                self.words[ls.FC_SIM_NS] = ack
                self.sensors.acked(ack)
            if not self._silbridge_fc and self.words[ls.FC_STATE] == ls.FC_STATE_NONE:
                self.words[ls.FC_STATE] = ls.FC_STATE_READY
        elif mid == 252:       # NAMED_VALUE_INT
            name, value = m.name, int(m.value)
            if name == "SB_PID":
                self._silbridge_fc = True
                self.peer_pid = value
            elif name == "SB_FC":
                self.words[ls.FC_STATE] = value
            elif name == "SB_FCSTOP":
                self.words[ls.FC_STOP] = value
        elif mid == 76 and m.command == hil_fault.COMMAND:     # COMMAND_LONG: a FAULT
            rec = hil_fault.decode(m, self.faults_received, self.words[ls.FC_SIM_NS], now_ns)
            if rec is None:
                self.faults_malformed += 1
            else:
                self.actuators.queue.append(rec)    # beside the PWM, as in the shm ring
                self.faults_received += 1
        elif mid == 0:         # HEARTBEAT
            if not self._silbridge_fc and self.words[ls.FC_STATE] == ls.FC_STATE_NONE:
                self.words[ls.FC_STATE] = ls.FC_STATE_READY

    # -- the Segment surface ----------------------------------------------------------------
    def set_word(self, i: int, value: int) -> None:
        self.words[i] = int(value)
        if i == ls.STOP and value and self.channel is not None and not self.channel.eof:
            c = self.codec
            frame = c.named_value_int_encode(0, b"SB_STOP", int(value)).pack(c)
            try:
                self.channel.send([frame, frame, frame])   # UDP: thrice, a lost one is no hang
            except HilPeerLost:
                pass

    def word(self, i: int) -> int:
        if i in (ls.FC_SIM_NS, ls.FC_STATE, ls.FC_STOP):
            self.pump(0.0)
        return self.words[i]

    def c_capsule(self) -> None:
        """No segment for C code: records cross in Python (the bridge steps per step)."""
        return None

    def wait_word(self, i: int, at_least: int, timeout_s: float, **_spin) -> bool:
        deadline = time.monotonic() + timeout_s
        while True:
            if self.words[i] >= at_least:
                return True
            left = deadline - time.monotonic()
            if left <= 0:
                self.pump(0.0)
                return self.words[i] >= at_least
            if self.channel is not None and self.channel.eof:
                time.sleep(min(left, 0.005))
                return self.words[i] >= at_least
            self.pump(min(left, 0.05))

    def peer_alive(self) -> bool:
        return self.channel is None or not self.channel.eof

    def peer_heartbeat(self) -> int:
        return self._rx_msgs

    def beat(self) -> None:
        self.pump(0.0)

    def counters(self) -> dict:
        ch = self.channel
        out = {"messages_sent": self.encoder.messages, "pwm_lost": self.pwm_decoder.lost,
               "faults_received": self.faults_received, "faults_malformed": self.faults_malformed}
        if ch is not None:
            out.update(ch.rx.as_dict())
            out.update(tx_frames=ch.tx_frames, tx_bytes=ch.tx_bytes, tx_dropped=ch.tx_dropped)
        return out

    def close(self) -> None:
        if self.channel is not None:
            self.channel.close()
        if self.listener is not None:
            self.listener.close()
        self.closed = True

    def unlink(self) -> None:
        pass

    def __enter__(self) -> "HilBridgeEnd":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


assert RECORD_SIZE == RECORD_DTYPE.itemsize
