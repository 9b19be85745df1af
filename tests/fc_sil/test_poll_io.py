"""The FC loop's two polls: the C record router (Core.poll_io over the shared-memory
segment) against the Python poll the MAVLink HIL links use, over the same rings."""

import subprocess
import sys

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.fc_sil import STATUS_DTYPE
from silbridge.fc_sil.fc_loop import FcLoop
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import Segment
from silbridge.shm import lockstep as ls
from silbridge.shm.records import FLAG_STEP_END, PWM_DTYPE, RECORD_DTYPE


class _RecordsInPython:
    """The FC's segment as a link whose records cross in Python (as a HIL link's do):
    it offers the C record router nothing, so the loop polls in Python."""

    def __init__(self, seg):
        self.sensors, self.actuators = seg.sensors, seg.actuators
        self.set_word, self.word = seg.set_word, seg.word
        self.beat, self.peer_alive = seg.beat, seg.peer_alive

    def c_capsule(self):
        return None


class _CycleSink:
    """A sink without capture_fc: one fc_batch call per cycle, timing rows kept."""

    def __init__(self):
        self.rows = []

    def fc_batch(self, recs, pwm, status, timing):
        self.rows.append((int(recs["sim_ns"][-1]), bool(recs["flags"][-1] & FLAG_STEP_END),
                          len(pwm), len(status), timing))


def _fly(name, in_c: bool, steps=600):
    """Owner publishes simulator steps; the FC polls (C or Python); returns the PWM seen,
    the loop's summary and what a per-cycle sink got."""
    sim = Simulator(load_scenario("S1"))
    out = []
    sink = _CycleSink()
    with Segment.create(name) as seg, Segment.attach(name) as fc_seg:
        core = FlightCore()
        core.arm()
        loop = FcLoop(core, fc_seg if in_c else _RecordsInPython(fc_seg), sink=sink)
        assert loop.polls_in_c == in_c
        buf = np.zeros(64, RECORD_DTYPE)
        pwm = (1000.0,) * 4
        for _ in range(steps):
            seg.sensors.push_batch(sim.step(pwm))
            assert loop.poll() > 0
            assert seg.word(ls.FC_SIM_NS) == sim.sim_ns      # the step is acknowledged
            n = seg.actuators.pop_into(buf)
            if n:
                rec = buf[:n].view(PWM_DTYPE)
                out.append(rec[["sim_ns", "pwm_us", "armed"]].copy())
                pwm = tuple(float(v) for v in rec["pwm_us"][-1, :4])
        summary = loop.summary()
        assert loop.last_sim_ns == sim.sim_ns
        loop.close()
    return np.concatenate(out), summary, sink.rows


def test_c_poll_matches_the_python_poll():
    a, sa, rows_a = _fly("pollio-c", True)
    b, sb, rows_b = _fly("pollio-py", False)
    assert len(a) == 240                                    # 400 Hz over 0.6 s
    np.testing.assert_array_equal(a, b)
    for key in ("polls", "records", "pwm_published"):
        assert sa[key] == sb[key] > 0
    assert sa["latency_us"]["p50"] is not None and sa["jitter_us"]["p50"] is not None
    # The per-cycle sink sees the same cycles under both polls, and each /timing row
    # (sim, imu wall, consume, pwm wall, period) belongs to its cycle.
    assert [r[:4] for r in rows_a] == [r[:4] for r in rows_b]
    for rows in (rows_a, rows_b):
        assert len(rows) == sa["polls"]
        for sim_ns, _, k, _, (t_sim, imu_wall, consume, pwm_wall, period) in rows:
            assert t_sim == sim_ns and consume >= imu_wall > 0
            assert (pwm_wall >= consume) if k else (pwm_wall == 0)
        assert rows[0][4][4] == 0 and all(r[4][4] > 0 for r in rows[1:])


def test_attach_io_refuses_the_owner_side_and_a_closed_segment():
    core = FlightCore()
    buf = np.zeros(8, RECORD_DTYPE)
    core.bind_batch(buf, np.zeros(8, PWM_DTYPE), np.zeros(8, STATUS_DTYPE))
    rings = [np.zeros(8, np.int64) for _ in range(3)]
    with Segment.create("pollio-own") as seg:
        with pytest.raises(ValueError, match="peer"):
            core.attach_router(seg.c_capsule(), fc_sim_word=ls.FC_SIM_NS, latency_ns=rings[0],
                               period_ns=rings[1], e2e_ns=rings[2], words=np.zeros(16, np.int64))
        with Segment.attach("pollio-own") as fc_seg:
            loop = FcLoop(FlightCore(), fc_seg)
            assert loop.polls_in_c
        with pytest.raises(RuntimeError, match="closed"):
            loop.poll()


def _surface(protocol) -> list[str]:
    return [n for n in vars(protocol) if not n.startswith("_")]


def test_both_fc_links_present_the_fc_transport_surface():
    """The FC loop speaks only FcTransport: the segment and the MAVLink HIL end both have
    every method it names, on each side, and only the segment offers the C router."""
    from silbridge.fc_sil.fc_transport import ActuatorSink, FcTransport, SensorSource
    from silbridge.mavlink.hil import hil_fc_end
    from silbridge.shm import Ring
    sides = ((FcTransport, Segment, hil_fc_end.HilFcEnd),
             (SensorSource, Ring, hil_fc_end._Sensors),
             (ActuatorSink, Ring, hil_fc_end._Actuators))
    for protocol, shm_side, hil_side in sides:
        for name in _surface(protocol):         # methods (sensors/actuators: annotations)
            assert callable(getattr(shm_side, name)), (shm_side, name)
            assert callable(getattr(hil_side, name)), (hil_side, name)
    assert hil_fc_end.HilFcEnd.c_capsule(None) is None
    with Segment.create("pollio-surface"), Segment.attach("pollio-surface") as fc_seg:
        assert fc_seg.c_capsule() is not None
        assert fc_seg.sensors.wait(0.0, yield_s=1e-4) is False


# A fresh interpreter reports how much of each statistics store is resident (mincore) just
# after the loop is made: in the test process the allocator may hand back memory another test
# already touched and freed, resident whatever the loop does.
_RESIDENCY = r"""
import ctypes, mmap, os, sys
from silbridge.fc_sil.fc_loop import FcLoop
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import Segment

libc = ctypes.CDLL(None, use_errno=True)


def resident(arr):
    page = mmap.PAGESIZE
    start = arr.ctypes.data // page * page
    length = arr.ctypes.data + arr.nbytes - start
    vec = (ctypes.c_ubyte * ((length + page - 1) // page))()
    if libc.mincore(ctypes.c_void_p(start), ctypes.c_size_t(length), vec) != 0:
        raise OSError(ctypes.get_errno(), "mincore")
    return sum(b & 1 for b in vec) / len(vec)


name = f"sbt-touch-{os.getpid()}"
with Segment.create(name), Segment.attach(name) as fc_seg:
    loop = FcLoop(FlightCore(), fc_seg, bounded=sys.argv[1] == "1")
    print(*(resident(s.arr) for s in (loop.latency_ns, loop.period_ns, loop.e2e_ns)))
"""


@pytest.mark.parametrize("bounded", [False, True])
def test_the_statistics_stores_are_touched_up_front_only_for_open_ended_sessions(bounded):
    """A real-time session's three 8 MB stores are resident from the start (its RSS stays
    flat: the soak benchmark reads growth as a leak); a flight that ends by itself leaves
    them to be touched by the samples it takes, and keeps the same statistics."""
    out = subprocess.run([sys.executable, "-c", _RESIDENCY, str(int(bounded))], check=True,
                         capture_output=True, text=True).stdout
    shares = [float(x) for x in out.split()]
    assert len(shares) == 3
    if bounded:
        assert max(shares) < 0.25, shares
    else:
        assert min(shares) == 1.0, shares
    name = f"sbt-touch-{int(bounded)}"
    with Segment.create(name) as seg, Segment.attach(name) as fc_seg:
        loop = FcLoop(FlightCore(), fc_seg, bounded=bounded)
        sim = Simulator(load_scenario("S1"))
        for _ in range(50):
            seg.sensors.push_batch(sim.step((1000.0,) * 4))
            loop.poll()
        assert loop.latency_ns.n == 50 and len(loop.latency_ns.values()) == 50
