"""HilFcEnd: the SIL FC's side of the HIL transport, with the Segment surface it uses.

fc_sil/fc_loop.py (FcLoop.poll, run_fc; the surface is fc_sil/fc_transport.py FcTransport) reads
sensors with sensors.pop_into / wait, publishes PWM with actuators.push_batch and answers
lockstep through set_word(FC_SIM_NS); c_capsule() is None, so it polls in Python. Here the same
calls speak MAVLink (see hil_bridge_end.py for the word <-> message mapping):

  connect      TCP to the simulator (retrying) or UDP to its address; then the hello:
               NAMED_VALUE_INT SB_PID = our pid and a HEARTBEAT (MAV_TYPE_QUADROTOR)
  words        RUN_MODE / PHYSICS_DT_NS / IMU_HZ from the bridge's configuration; a simulator
               that sends none (PX4-style) is taken as lockstep at its first HIL_SENSOR
  FC_SIM_NS    set_word sends HIL_ACTUATOR_CONTROLS acknowledging that step (hil_pwm.py)
  FC_STATE     set_word sends SB_FC; FC_STOP sends SB_FCSTOP
  STOP         SB_STOP from the bridge (the stream ending without it is a lost bridge:
               peer_alive() turns False and run_fc reports it)

Bad input (hil_codec: NaN, time going backwards; here: no message for stall_s while
connected) is reported with HilInputError after the FC's safe state: `on_bad_input(reason)`
(tools/loop/flight.py disarms the core there) and a last HIL_ACTUATOR_CONTROLS with every motor at
MOT_PWM_MIN and the armed flag clear.
"""

from __future__ import annotations

import time

import numpy as np

from silbridge.shm import lockstep as ls
from silbridge.shm.records import KIND_FAULT, RECORD_DTYPE, RECORD_SIZE

from silbridge.mavlink.hil.hil_channel import connect, make_codec, pid
from silbridge.mavlink.hil.hil_codec import DECODED_IDS, SensorDecoder
from silbridge.mavlink.hil.hil_errors import HilInputError, HilPeerLost
from silbridge.mavlink.hil import hil_fault
from silbridge.mavlink.hil.hil_bridge_end import BRIDGE_COMPID, BRIDGE_SYSID
from silbridge.mavlink.hil.hil_pwm import PwmEncoder

FC_SYSID = 1
FC_COMPID = 1
_BEAT_S = 0.5


class _Sensors:
    """The sensor 'ring' of a HilFcEnd: records decoded from HIL messages."""

    def __init__(self, end: "HilFcEnd"):
        self.end = end
        self.buf = bytearray()
        self.pos = 0
        self.read = 0

    def available(self) -> int:
        return (len(self.buf) - self.pos) // RECORD_SIZE

    def pop_into(self, out: np.ndarray) -> int:
        end = self.end
        end.flush_pwm()
        end.pump(0.0)
        n = min(self.available(), len(out))
        if n == 0:
            return 0
        stop = self.pos + n * RECORD_SIZE
        out[:n] = np.frombuffer(self.buf, dtype=RECORD_DTYPE, count=n, offset=self.pos)
        self.pos = stop
        if self.pos == len(self.buf):
            self.buf = bytearray()
            self.pos = 0
        elif self.pos > (1 << 20):
            del self.buf[:self.pos]
            self.pos = 0
        self.read += n
        return n

    def wait(self, timeout_s: float, **_spin) -> bool:
        """Sleep in select() until records arrive (spin/yield options of the ring: unused)."""
        end = self.end
        end.flush_pwm()
        deadline = time.monotonic() + timeout_s
        while not self.available():
            left = deadline - time.monotonic()
            if left <= 0 or end.channel.eof:
                break
            end.pump(min(left, 0.05))
        return self.available() > 0

    def stats(self) -> dict:
        d = self.end.decoder
        written = sum(d.seq)
        return {"written": written, "read": self.read, "overwritten": 0, "rejected": d.bad,
                "available": self.available()}


class _Actuators:
    """The actuator 'ring': PWM records wait here for the step's acknowledgement."""

    def __init__(self, end: "HilFcEnd"):
        self.end = end
        self.pending: list = []
        self.written = 0
        self.faults = False     # a FAULT batch waits (the supervisor pushes those alone)

    def push_batch(self, pwm: np.ndarray) -> int:
        raw = pwm.tobytes()
        n = len(raw) // RECORD_SIZE
        if n and int.from_bytes(raw[:2], "little") == KIND_FAULT:
            self.faults = True
        self.pending += [raw[i * RECORD_SIZE:(i + 1) * RECORD_SIZE] for i in range(n)]
        self.written += n
        return n

    def stats(self) -> dict:
        return {"written": self.written, "read": self.written - len(self.pending),
                "overwritten": 0, "rejected": self.end.channel.tx_dropped,
                "available": len(self.pending)}


class HilFcEnd:
    """See module docstring. Connects at construction; `wait_config` waits for the bridge."""

    is_owner = False

    def __init__(self, host: str = "127.0.0.1", port: int = 4560, *, datagram: bool = False,
                 connect_timeout_s: float = 10.0, stall_s: float = 3.0, pwm_min_us: int = 1000,
                 on_bad_input=None, serial: str | None = None):
        self.codec = make_codec(FC_SYSID, FC_COMPID)
        if serial:      # a serial line (hil_serial.py): the same messages, framed on it
            from silbridge.mavlink.hil.hil_serial import open_serial
            self.channel = open_serial(serial, self.codec)
            self.name = self.channel.name
        else:
            self.name = f"{'udp' if datagram else 'tcp'}://{host}:{port}"
            self.channel = connect(host, port, datagram, self.codec, connect_timeout_s)
        self.decoder = SensorDecoder()
        self.encoder = PwmEncoder(self.codec)
        self.words = [0] * 8
        self.sensors = _Sensors(self)
        self.actuators = _Actuators(self)
        self.stall_s = stall_s
        self.pwm_min_us = pwm_min_us
        self.on_bad_input = on_bad_input
        self.config_ready = False
        self.peer_pid = 0
        self.closed = False
        self.bad_input = ""
        self._origin = None
        self._last_rx = time.monotonic()
        self._last_beat = 0.0
        self._hello()

    def _hello(self) -> None:
        c = self.codec
        self.channel.send([c.named_value_int_encode(0, b"SB_PID", pid()).pack(c),
                           c.heartbeat_encode(2, 0, 0, 0, 3).pack(c)])
        self._last_beat = time.monotonic()

    def wait_config(self, timeout_s: float) -> None:
        """Wait for the bridge's configuration (or a PX4-style simulator's first sensors)."""
        deadline = time.monotonic() + timeout_s
        while not self.config_ready:
            if self.channel.eof:
                raise HilPeerLost(f"the simulator at {self.name} went away while starting "
                                  f"({self.channel.error})")
            if time.monotonic() > deadline:
                raise HilPeerLost(f"no configuration from a simulator at {self.name} within "
                                  f"{timeout_s:g} s: start `silbridge bridge --transport ...` "
                                  f"or check --link-addr")
            self.pump(0.05)

    # -- receive ----------------------------------------------------------------------------
    def pump(self, timeout_s: float = 0.0) -> int:
        try:
            msgs = self.channel.receive(timeout_s)
            now_ns = time.monotonic_ns()
            for m in msgs:
                self._on_message(m, now_ns)
        except HilInputError as exc:
            self.go_safe(str(exc))
            raise
        now = time.monotonic()
        if msgs:
            self._last_rx = now
        elif (self.stall_s and not self.channel.eof and not self.words[ls.STOP]
              and now - self._last_rx > self.stall_s):
            why = (f"the simulator's HIL stream stalled: nothing for "
                   f"{now - self._last_rx:.1f} s (limit {self.stall_s:g} s)")
            self.decoder.bad += 1
            self.go_safe(why)
            raise HilInputError(why + "; the FC went to its safe state and stops")
        if now - self._last_beat > _BEAT_S:
            self.beat()
        return len(msgs)

    def _on_message(self, m, now_ns: int) -> None:
        mid = m.get_msgId()
        if mid in DECODED_IDS:
            if not self.config_ready and mid == 107:
                self._foreign_simulator()
            data = self.decoder.feed(m, now_ns)
            if data:
                self.sensors.buf += data
        elif mid == 252:      # NAMED_VALUE_INT
            name, value = m.name, int(m.value)
            if name == "SB_MODE":
                self.words[ls.RUN_MODE] = value
            elif name == "SB_DT_NS":
                self.words[ls.PHYSICS_DT_NS] = value
            elif name == "SB_IMU_HZ":
                self.words[ls.IMU_HZ] = value
            elif name == "SB_STOP":
                self.words[ls.STOP] = value
            elif name == "SB_CFG" and not self.config_ready:
                self.config_ready = True
                self.decoder.silbridge_peer = True
                self.decoder.imu_hz = self.words[ls.IMU_HZ]
                self.decoder.origin = self._origin
                self.encoder.lockstep = self.words[ls.RUN_MODE] == ls.MODE_LOCKSTEP
        elif mid == 49:       # GPS_GLOBAL_ORIGIN
            self._origin = (m.latitude, m.longitude, m.altitude)

    def _foreign_simulator(self) -> None:
        """Sensors before any configuration: a PX4-style simulator (lockstep per HIL_SENSOR)."""
        self.config_ready = True
        self.decoder.silbridge_peer = False
        self.words[ls.RUN_MODE] = ls.MODE_LOCKSTEP
        self.encoder.lockstep = True
        self.encoder.one_per_step = True

    # -- send -------------------------------------------------------------------------------
    def flush_pwm(self, ack_ns: int | None = None) -> None:
        pending = self.actuators.pending
        if not pending and ack_ns is None:
            return
        frames: list = []
        # A FAULT record (fc_sil/fault_inject.py) goes as its own COMMAND_LONG (hil_fault.py),
        # before the step's PWM, as it sits before it in the shared-memory ring.
        if self.actuators.faults:
            self.actuators.faults = False
            frames += [hil_fault.encode(self.codec, r, BRIDGE_SYSID, BRIDGE_COMPID)
                       for r in pending if int.from_bytes(r[:2], "little") == KIND_FAULT]
            pending = [r for r in pending if int.from_bytes(r[:2], "little") != KIND_FAULT]
        self.encoder.encode(pending, ack_ns, frames)
        self.actuators.pending = []
        self.channel.send(frames)

    def go_safe(self, reason: str) -> None:
        """Safe state on bad input: the host disarms, the simulator gets MOT_PWM_MIN."""
        self.bad_input = reason
        if self.on_bad_input is not None:
            self.on_bad_input(reason)
        self.actuators.pending = []
        t_us = max(self.decoder.last_sensor_us, 0)
        try:
            self.channel.send([self.encoder.safe_frame(t_us, self.pwm_min_us)])
        except HilPeerLost:
            pass

    # -- the Segment surface ----------------------------------------------------------------
    def set_word(self, i: int, value: int) -> None:
        self.words[i] = int(value)
        c = self.codec
        if i == ls.FC_SIM_NS:
            self.flush_pwm(int(value))
        elif i == ls.FC_STATE:
            self.channel.send([c.named_value_int_encode(0, b"SB_FC", int(value)).pack(c)])
        elif i == ls.FC_STOP and value:
            self.channel.send([c.named_value_int_encode(0, b"SB_FCSTOP", 1).pack(c)])

    def c_capsule(self) -> None:
        return None     # records cross in Python (MAVLink): the FC loop polls in Python

    def word(self, i: int) -> int:
        if i == ls.STOP:
            self.pump(0.0)
        return self.words[i]

    def peer_alive(self) -> bool:
        return not self.channel.eof

    def peer_heartbeat(self) -> int:
        return self.channel.rx.rx_ok

    def beat(self) -> None:
        now = time.monotonic()
        if now - self._last_beat > _BEAT_S and not self.channel.eof:
            self._last_beat = now
            c = self.codec
            mode = self.encoder.last_mode
            # SB_PID again: over a serial line the hello may have gone out before the
            # bridge was reading.
            try:
                self.channel.send([c.heartbeat_encode(2, 0, mode, 0, 4).pack(c),
                                   c.named_value_int_encode(0, b"SB_PID", pid()).pack(c)])
            except HilPeerLost:
                pass

    def counters(self) -> dict:
        ch = self.channel
        out = ch.rx.as_dict()
        out.update(tx_frames=ch.tx_frames, tx_bytes=ch.tx_bytes, tx_dropped=ch.tx_dropped,
                   bad_input=self.decoder.bad)
        return out

    def close(self) -> None:
        self.channel.close()
        self.closed = True

    def __enter__(self) -> "HilFcEnd":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()
