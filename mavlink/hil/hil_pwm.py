"""FC -> simulator direction of the HIL transport: PWM records <-> HIL_ACTUATOR_CONTROLS.

One HIL_ACTUATOR_CONTROLS per physics step in lockstep, time_usec = that step's time (the FC's
acknowledgement: the bridge's FC_SIM_NS word), carrying the newest motor outputs:
  controls[0..3]  motors 1..4 normalised 0..1 over 1000..2000 us (exact for whole us)
  mode            MAV_MODE_FLAG_HIL_ENABLED, | SAFETY_ARMED while armed
  flags           bit 0 HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP in lockstep runs;
                  bit 32 FLAG_SB_EXT: controls[8..15] hold the PWM record's bookkeeping
A PWM record that is not merged into a step's acknowledgement goes in its own message
(time_usec = its PWM tick). controls[4..7] stay 0. With FLAG_SB_EXT (silbridge's FC only),
channels a quad never drives carry exact small integers so the bridge rebuilds the FC's record
bit for bit (the trace hash covers it):
  controls[8]  bit 0: carries a PWM record; bit 1: acknowledges the step time_usec
  [9], [10]    record seq, low / high 16 bits      [11], [12] fc_step_seq, low / high 16 bits
  [13]         step time - PWM tick (ns, 0..2^24)  [14] imu_sim_ns - PWM tick (ns, 0..2^24)
  [15]         channel_count
From another autopilot (no FLAG_SB_EXT, e.g. PX4 SITL in HIL mode) every message is both a PWM
record at time_usec and the acknowledgement of time_usec; the bridge numbers the records.
Fed by another simulator, our FC sends exactly one message per sensor step (the newest PWM on
the acknowledgement; older ticks of the same step are superseded and counted).
"""

from __future__ import annotations

from silbridge.shm.records import KIND_PWM, Kind, record_struct

FLAG_LOCKSTEP = 1
FLAG_SB_EXT = 1 << 32
MODE_HIL_ENABLED = 32
MODE_SAFETY_ARMED = 128
HAS_PWM = 1
IS_ACK = 2
MOTORS = 4
_SPAN_NS = 1 << 24

_PWM = record_struct(Kind.PWM)       # the whole 64-byte PWM slot (shm/records.py)
_SIM_NS = record_struct(Kind.PWM, ["sim_ns"])    # a PWM record's tick


def _norm(pwm_us: int) -> float:
    return (pwm_us - 1000) / 1000.0


def _pwm_us(c: float) -> int:
    return max(0, min(65535, round(1000.0 + 1000.0 * c)))


class PwmEncoder:
    """FC side: PWM records and step acknowledgements -> HIL_ACTUATOR_CONTROLS frames."""

    def __init__(self, codec):
        self.codec = codec
        self.lockstep = True
        self.last_controls = [0.0] * 16
        self.last_mode = MODE_HIL_ENABLED
        self.next_seq = 0
        self.one_per_step = False     # PX4-style simulator: only the newest PWM, on the ack
        self.superseded = 0

    def _frame(self, time_us: int, rec, ack_ns: int | None) -> bytes:
        controls = [0.0] * 16
        kind_bits = 0
        if rec is not None:
            (_, _, seq, sim_ns, _, p0, p1, p2, p3, _, _, _, _, count, armed, _, step_seq,
             imu_ns) = _PWM.unpack_from(rec)
            kind_bits |= HAS_PWM
            self.next_seq = (seq + 1) & 0xFFFFFFFF
            controls[0:4] = [_norm(p0), _norm(p1), _norm(p2), _norm(p3)]
            base = ack_ns if ack_ns is not None else sim_ns
            d_step = base - sim_ns
            d_imu = imu_ns - sim_ns
            controls[9:16] = [seq & 0xFFFF, seq >> 16, step_seq & 0xFFFF, step_seq >> 16,
                              d_step if 0 <= d_step < _SPAN_NS else 0,
                              d_imu if 0 <= d_imu < _SPAN_NS else -1, count]
            self.last_controls[0:4] = controls[0:4]
            self.last_mode = MODE_HIL_ENABLED | (MODE_SAFETY_ARMED if armed else 0)
        else:
            controls[0:4] = self.last_controls[0:4]
        if ack_ns is not None:
            kind_bits |= IS_ACK
        controls[8] = kind_bits
        flags = FLAG_SB_EXT | (FLAG_LOCKSTEP if self.lockstep else 0)
        return self.codec.hil_actuator_controls_encode(time_us, controls, self.last_mode,
                                                       flags).pack(self.codec)

    def encode(self, pending: list, ack_ns: int | None, out: list) -> int:
        """PWM records (64-byte bytes each) and an optional step acknowledgement -> frames.

        The newest record rides on the acknowledgement when its tick is within 16 ms of the
        step; the others go alone. Returns the number of frames."""
        n = 0
        merge = None
        if self.one_per_step and ack_ns is not None and len(pending) > 1:
            self.superseded += len(pending) - 1     # another simulator wants one per step
            pending = pending[-1:]
        if ack_ns is not None and pending:
            tick = _SIM_NS.unpack_from(pending[-1])[0]
            if 0 <= ack_ns - tick < _SPAN_NS:
                merge = pending[-1]
                pending = pending[:-1]
        for rec in pending:
            tick = _SIM_NS.unpack_from(rec)[0]
            out.append(self._frame(tick // 1000, rec, None))
            n += 1
        if ack_ns is not None:
            out.append(self._frame(ack_ns // 1000, merge, ack_ns))
            n += 1
        return n

    def safe_frame(self, time_us: int, pwm_min_us: int) -> bytes:
        """Motors at MOT_PWM_MIN, disarmed: the FC's last word on bad input."""
        controls = [0.0] * 16
        controls[0:4] = [_norm(pwm_min_us)] * MOTORS
        seq = self.next_seq
        controls[8:16] = [HAS_PWM, seq & 0xFFFF, seq >> 16, 0, 0, 0, 0, MOTORS]
        self.next_seq = (seq + 1) & 0xFFFFFFFF
        self.last_controls[0:4] = controls[0:4]
        self.last_mode = MODE_HIL_ENABLED
        return self.codec.hil_actuator_controls_encode(time_us, controls, MODE_HIL_ENABLED,
                                                       FLAG_SB_EXT).pack(self.codec)


class PwmDecoder:
    """Bridge side: HIL_ACTUATOR_CONTROLS -> (PWM record bytes or b"", acknowledged sim ns or -1).

    The record's wall_ns is the arrival time (HIL_ACTUATOR_CONTROLS carries no wall clock)."""

    def __init__(self):
        self.seq = 0
        self.lost = 0

    def decode(self, m, now_ns: int = 0) -> tuple[bytes, int]:
        """now_ns: arrival time, the record's wall_ns (the bridge measures PWM rate on it)."""
        t_ns = m.time_usec * 1000
        c = m.controls
        armed = 1 if m.mode & MODE_SAFETY_ARMED else 0
        pwm = [_pwm_us(c[i]) for i in range(MOTORS)]
        if not m.flags & FLAG_SB_EXT:
            rec = _PWM.pack(KIND_PWM, 0, self.seq & 0xFFFFFFFF, t_ns, now_ns, *pwm, 0, 0, 0, 0,
                            MOTORS, armed, 0, 0, t_ns)
            self.seq += 1
            return rec, t_ns
        bits = int(c[8])
        ack = t_ns if bits & IS_ACK else -1
        if not bits & HAS_PWM:
            return b"", ack
        seq = int(c[9]) | (int(c[10]) << 16)
        if seq != (self.seq & 0xFFFFFFFF):
            self.lost += (seq - self.seq) & 0xFFFFFFFF    # a gap: PWM records lost on the way
        self.seq = seq + 1
        step_seq = int(c[11]) | (int(c[12]) << 16)
        tick = t_ns - int(c[13])
        imu_ns = tick + int(c[14]) if c[14] >= 0 else tick
        count = int(c[15])
        pwm += [0] * 4
        rec = _PWM.pack(KIND_PWM, 0, seq, tick, now_ns, *pwm, count, armed, 0, step_seq,
                        imu_ns)
        return rec, ack
