"""The bridge program's loop: physics -> sensor ring, actuator ring -> motors.

`BridgeLoop` owns one physics step at a time (publish_step / collect_pwm) so
the same code serves every way of driving it (bridge/bridge_driver.py): lockstep
or real time, with the FC in another process or interleaved in this one
(`fly --processes 1`). It never imports the FC: they meet only through the
shared-memory segment.

Lockstep follows shm/lockstep.py: publish step k, wait for FC_SIM_NS >= t_k,
take the PWM, step again. Real time paces steps to the wall clock and never
waits for the FC; late PWM simply holds the previous command (zero-order hold),
as an ESC does.
"""

from __future__ import annotations

import hashlib
import math
import time
from dataclasses import dataclass

import numpy as np

from silbridge.shm import lockstep as ls
from silbridge.shm.records import PWM_DTYPE, RECORD_DTYPE, Kind, word_index

from .errors import PeerLost

_NS = 1_000_000_000

# Where collect_pwm reads a PWM slot, in the word sizes of its views (shm/records.py).
_SLOT_BYTES = RECORD_DTYPE.itemsize
_SLOT_U16 = _SLOT_BYTES // 2
_SLOT_I64 = _SLOT_BYTES // 8
_PWM_US_U16 = word_index(Kind.PWM, "pwm_us", 2)
_ARMED_BYTE = word_index(Kind.PWM, "armed", 1)
_SIM_NS_I64 = word_index(Kind.PWM, "sim_ns", 8)
_WALL_NS_I64 = word_index(Kind.PWM, "wall_ns", 8)


@dataclass
class LoopStats:
    """The PWM the bridge received: counts and first/last stamps, for the rates."""

    pwm_received: int = 0
    pwm_first_sim_ns: int = -1
    pwm_last_sim_ns: int = -1
    pwm_first_wall_ns: int = -1
    pwm_last_wall_ns: int = -1


class BridgeLoop:
    """One physics step at a time; see module docstring."""

    # Sample truth for the summary errors every this many physics steps.
    ERROR_SAMPLE_STEPS = 10

    def __init__(self, sim, segment, *, sink=None, settle_s: float = 10.0, trace: bool = True):
        self.sim = sim
        self.seg = segment
        self.sink = sink
        self.pwm_us = (1000.0, 1000.0, 1000.0, 1000.0)   # a tuple: cheapest to unpack per step
        self.armed = False
        self.stats = LoopStats()
        self._hash = hashlib.blake2b(digest_size=16)
        self._trace = trace
        self._pwm_buf = np.zeros(4096, dtype=RECORD_DTYPE)
        # Column views made once: per-step scalar reads then cost ~100 ns, not a view each.
        view = self._pwm_buf.view(PWM_DTYPE)
        self._pwm_view = view
        self._col_us = view["pwm_us"]
        self._col_armed = view["armed"]
        self._col_sim = view["sim_ns"]
        self._col_wall = view["wall_ns"]
        self.settle_ns = int(settle_s * _NS)
        # Running sums, not lists: a real-time session runs for hours and the lists grew
        # by 100 samples a second (the soak benchmark's memory check found it).
        self._n_err = 0
        self._att_err_sq = 0.0
        self._alt_err_sq = 0.0
        # Bound methods looked up once: `seg.sensors.push_batch` is three lookups a step.
        self._step = sim.step
        self._push = segment.sensors.push_batch
        self._pop_pwm = segment.actuators.pop_into
        self._set_word = segment.set_word
        self._word = segment.word
        self._hash_update = self._hash.update
        # A sink may log the PWM elsewhere (the FC's side) and set pwm_records to None.
        self._log_pwm = getattr(sink, "pwm_records", None) if sink is not None else None
        raw = memoryview(self._pwm_buf.view(np.uint8))
        self._pwm_raw = raw
        self._pwm_u16 = raw.cast("H")
        self._pwm_i64 = raw.cast("q")

    # -- one step ---------------------------------------------------------
    def publish_step(self) -> np.ndarray:
        """Advance physics one step with the held PWM; publish its records."""
        sim = self.sim
        recs = self._step(self.pwm_us)
        if self._trace:
            self._hash_update(recs)
        # A refused push (non-overwriting ring, full) is counted by the ring as
        # rejected and reported by the start-up checks and the summary.
        self._push(recs)
        sim_ns = sim.sim_ns
        self._set_word(ls.BRIDGE_SIM_NS, sim_ns)
        events = sim.events
        if events:
            if self.sink is not None:
                for ev_ns, text in events:
                    self.sink.event(ev_ns, "disturbance", text)
            events.clear()
        if sim.step_index % self.ERROR_SAMPLE_STEPS == 0 and sim_ns >= self.settle_ns:
            self._sample_errors()
        return recs

    def collect_pwm(self) -> int:
        """Drain the actuator ring; hold the newest command. Returns records read."""
        n = self._pop_pwm(self._pwm_buf)
        if n == 0:
            return 0
        last = n - 1
        # Header and payload fields through memoryviews: Python ints, no numpy scalars.
        u16, i64 = self._pwm_u16, self._pwm_i64
        b = last * _SLOT_U16 + _PWM_US_U16       # pwm_us[0..3]: the four motors
        self.pwm_us = (u16[b], u16[b + 1], u16[b + 2], u16[b + 3])
        self.armed = bool(self._pwm_raw[last * _SLOT_BYTES + _ARMED_BYTE])
        st = self.stats
        if st.pwm_first_sim_ns < 0:
            st.pwm_first_sim_ns = i64[_SIM_NS_I64]
            st.pwm_first_wall_ns = i64[_WALL_NS_I64]
        last_row = last * _SLOT_I64
        st.pwm_last_sim_ns = i64[last_row + _SIM_NS_I64]
        st.pwm_last_wall_ns = i64[last_row + _WALL_NS_I64]
        st.pwm_received += n
        if self._log_pwm is not None:
            self._log_pwm(self._pwm_view[:n])
        # Hash without wall-clock stamps: only what lockstep makes deterministic.
        if self._trace:
            for i in range(n):
                i64[i * _SLOT_I64 + _WALL_NS_I64] = 0
            self._hash_update(self._pwm_raw[:n * _SLOT_BYTES])
        return n

    def fc_caught_up(self) -> bool:
        return self._word(ls.FC_SIM_NS) >= self.sim.sim_ns

    # -- summary helpers ----------------------------------------------------
    def _sample_errors(self) -> None:
        roll, pitch, alt = self.sim.roll_pitch_alt()
        cmd = self.sim.command
        er = roll - cmd["roll_rad"]
        ep = pitch - cmd["pitch_rad"]
        self._n_err += 1
        self._att_err_sq += er * er + ep * ep
        self._alt_err_sq += (alt - cmd["alt_m"]) ** 2

    def attitude_rms_deg(self) -> float | None:
        if not self._n_err:
            return None
        return math.degrees(math.sqrt(self._att_err_sq / self._n_err))

    def altitude_rms_m(self) -> float | None:
        if not self._n_err:
            return None
        return math.sqrt(self._alt_err_sq / self._n_err)

    def trace_hash(self) -> str:
        return self._hash.hexdigest() if self._trace else ""


class PeerWatch:
    """Detects a dead or stalled FC within ~100 ms while the bridge waits."""

    def __init__(self, segment, *, extra_check=None, stall_s: float = 5.0):
        self.seg = segment
        self.extra_check = extra_check
        self.stall_ns = int(stall_s * _NS)
        self._last_beat = None
        self._last_change = time.monotonic_ns()

    def check(self) -> None:
        if self.seg.word(ls.FC_STOP):
            raise PeerLost("the FC left the run (see its messages above); the bridge stops too")
        if self.extra_check is not None and not self.extra_check():
            raise PeerLost("the FC process exited; the bridge stops. Check the FC's output for why")
        if not self.seg.peer_alive():
            raise PeerLost("the FC process is gone (pid no longer exists); restart `silbridge fc`")
        beat = self.seg.peer_heartbeat()
        now = time.monotonic_ns()
        if beat != self._last_beat:
            self._last_beat = beat
            self._last_change = now
        elif now - self._last_change > self.stall_ns:
            raise PeerLost(f"the FC stopped beating for {(now - self._last_change) / 1e9:.1f} s "
                           "(hung or stopped?); the bridge stops")

