"""mavlink/v2_frames.py against pymavlink: the same bytes out, the same values and counts in."""

from __future__ import annotations

import random

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.framing import FrameDecoder, RxCounters
from silbridge.mavlink.v2_frames import V2Frames

MESSAGES = (mav.MAVLink_hil_sensor_message, mav.MAVLink_hil_gps_message,
            mav.MAVLink_hil_state_quaternion_message, mav.MAVLink_hil_actuator_controls_message)
_INT_RANGE = {"B": (0, 255), "H": (0, 65535), "h": (-32768, 32767), "I": (0, 2**32 - 1),
              "i": (-2**31, 2**31 - 1), "Q": (0, 2**64 - 1)}


def _wire_codes(cls) -> list[str]:
    """One struct code per wire value (arrays flattened), from the dialect's unpacker."""
    codes, count = [], ""
    for ch in cls.unpacker.format.lstrip("<"):
        if ch.isdigit():
            count += ch
            continue
        codes += [ch] * int(count or 1)
        count = ""
    return codes


def _random_wire(cls, rng: random.Random) -> tuple:
    """Random wire values; about a third are zero, so trailing-zero trimming is exercised
    (down to an all-zero payload)."""
    out = []
    zero_all = rng.random() < 0.05
    for code in _wire_codes(cls):
        if zero_all or rng.random() < 0.33:
            out.append(0.0 if code in "fd" else 0)
        elif code in "fd":
            out.append(rng.choice([rng.uniform(-1e5, 1e5), rng.gauss(0, 1), float("nan"),
                                   float("inf"), -0.0, 1e-40]))
        else:
            lo, hi = _INT_RANGE[code]
            out.append(rng.randint(lo, hi))
    return tuple(out)


def _message(cls, wire: tuple):
    """The pymavlink message of wire values (its constructor takes declaration order)."""
    t = list(wire)
    args = []
    for name in cls.fieldnames:
        j = cls.ordered_fieldnames.index(name)          # array_lengths are in wire order
        start = sum(cls.array_lengths[k] or 1 for k in range(j))
        n = cls.array_lengths[j]
        args.append(t[start:start + n] if n else t[start])
    return cls(*args)


def _same(a: tuple, b: tuple) -> bool:
    return all((x != x and y != y) or x == y for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize("cls", MESSAGES, ids=lambda c: c.msgname)
def test_pack_gives_pymavlinks_bytes_and_leaves_the_sequence_alone(cls):
    rng = random.Random(cls.id)
    for k in range(1500):
        codec = mav.MAVLink(None, srcSystem=rng.randint(0, 255), srcComponent=rng.randint(0, 255))
        codec.seq = rng.randint(0, 255)
        seq = codec.seq
        wire = _random_wire(cls, rng)
        ours = V2Frames(codec, cls).pack(*wire)
        assert ours == _message(cls, wire).pack(codec), (k, wire)
        assert codec.seq == seq       # msg.pack(codec) reads the sequence, never advances it


def test_an_all_zero_payload_keeps_one_byte():
    codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    cls = mav.MAVLink_hil_actuator_controls_message
    wire = (0, 0) + (0.0,) * 16 + (0,)
    frame = V2Frames(codec, cls).pack(*wire)
    assert frame[1] == 1 and frame == _message(cls, wire).pack(codec)


@pytest.mark.parametrize("cls", MESSAGES, ids=lambda c: c.msgname)
def test_check_gives_the_values_pymavlink_decodes(cls):
    rng = random.Random(1000 + cls.id)
    codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    frames = V2Frames(codec, cls)
    for _ in range(500):
        wire = _random_wire(cls, rng)
        frame = _message(cls, wire).pack(codec)
        got = frames.check(bytearray(frame))
        assert got is not None and _same(got, cls.unpacker.unpack(cls.unpacker.pack(*wire)))
        bad = bytearray(frame)
        bad[-1] ^= 0x40
        assert frames.check(bad) is None


def _stream(rng: random.Random) -> tuple[bytes, int]:
    """PX4-like traffic with damage: good replies, bad CRCs, garbage, a foreign message."""
    px4 = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    out, good = [], 0
    for k in range(400):
        m = px4.hil_actuator_controls_encode(k * 4000, [rng.random() for _ in range(16)],
                                             rng.choice([0, 128]), 1)
        f = bytearray(m.pack(px4))
        r = rng.random()
        if r < 0.1:
            f[12] ^= 0x01                            # payload bit flip: bad CRC
        elif r < 0.15:
            f = bytearray(b"\x00\x13garbage") + f    # garbage before a good frame
            good += 1
        elif r < 0.2:
            f[2] = 0x02                              # an incompatibility flag we cannot honour
        elif r < 0.25:
            f = bytearray(px4.heartbeat_encode(6, 8, 0, 0, 0).pack(px4))
            good += 1
        else:
            good += 1
        out.append(bytes(f))
    return b"".join(out), good


def test_a_shortcut_decoder_counts_and_decodes_as_the_codec_does():
    data, good = _stream(random.Random(7))
    cls = mav.MAVLink_hil_actuator_controls_message
    plain = FrameDecoder(mav.MAVLink(None), RxCounters())
    fast_rx = RxCounters()
    fast = FrameDecoder(mav.MAVLink(None), fast_rx)
    fast.shortcut(V2Frames(mav.MAVLink(None), cls), lambda v: ("wire", v))
    rng = random.Random(3)
    a, b = [], []
    i = 0
    while i < len(data):                 # the same stream cut at the same random points
        n = rng.randint(1, 300)
        a += plain.feed(data[i:i + n], False)
        b += fast.feed(data[i:i + n], False)
        i += n
    assert len(a) == len(b) == good
    assert fast_rx == plain._counters
    assert fast_rx.rx_bad_crc > 0 and fast_rx.rx_malformed > 0
    for m, got in zip(a, b, strict=True):
        if m.get_msgId() != cls.id:
            assert got.get_msgId() == m.get_msgId()
            continue
        tag, v = got
        assert v == (m.time_usec, m.flags, *m.controls, m.mode)


def test_signing_is_refused_not_faked():
    codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    codec.signing.secret_key = bytes(32)
    codec.signing.sign_outgoing = True
    cls = mav.MAVLink_hil_sensor_message
    with pytest.raises(ValueError, match="signing"):
        V2Frames(codec, cls).pack(*([0] + [0.0] * 13 + [0, 0]))
    frame = V2Frames(mav.MAVLink(None), cls).pack(*([0] + [1.0] * 13 + [7, 0]))
    assert V2Frames(codec, cls).check(bytearray(frame)) is None    # the codec decides


def test_without_fastcrc_the_crc_is_pymavlinks_pure_python_one(monkeypatch):
    # `silbridge transport --transports udp-nofastcrc` hides fastcrc from its runner.
    import importlib
    import sys

    from silbridge.mavlink import v2_frames
    monkeypatch.setitem(sys.modules, "fastcrc", None)
    monkeypatch.setitem(sys.modules, "fastcrc.crc16", None)
    try:
        slow = importlib.reload(v2_frames)
        assert slow._mcrf4xx(b"123456789") == 0x6F91        # CRC-16/MCRF4XX check value
        codec = mav.MAVLink(None, srcSystem=3, srcComponent=4)
        wire = (123, 2) + tuple(float(i) for i in range(16)) + (128,)
        cls = mav.MAVLink_hil_actuator_controls_message
        assert slow.V2Frames(codec, cls).pack(*wire) == _message(cls, wire).pack(codec)
    finally:
        monkeypatch.undo()
        importlib.reload(v2_frames)
