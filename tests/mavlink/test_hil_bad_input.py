"""Bad HIL input and lost peers: a stream that stalls, goes back in time or carries NaN is
reported and the FC goes to its safe state (core disarmed, motors to MOT_PWM_MIN); a peer
that disconnects is detected and reported on either side. Real sockets, real FC core."""

from __future__ import annotations

import time

import numpy as np
import pytest

from silbridge.bridge.bridge_loop import PeerWatch
from silbridge.bridge.errors import PeerLost
from silbridge.fc_sil.fc_loop import FcLost, run_fc
from silbridge.mavlink.hil.hil_codec import UPD_IMU
from silbridge.mavlink.hil.hil_errors import HilInputError, HilPeerLost
from silbridge.mavlink.hil.hil_transport import open_bridge_end
from silbridge.shm import lockstep as ls
from silbridge.shm.records import PWM_DTYPE, RECORD_DTYPE
from silbridge.tools.loop.flight import FlightOptions, bridge_config, make_fc_loop, make_simulator
from silbridge.tools.loop.transport_wiring import bridge_address, fc_segment, guard_fc


class Rig:
    """A bridge end fed by the real simulator, and a real FC loop on a HIL FC end."""

    def __init__(self, transport: str = "tcp"):
        opts = FlightOptions(scenario="S1", duration_s=2.0, seed=5)
        self.sc, self.sim = make_simulator(opts)
        self.bridge = open_bridge_end(transport, None, default_port=0)
        cfg = bridge_config(opts, self.sc)
        from silbridge.bridge.bridge_driver import prepare_segment
        prepare_segment(self.bridge, self.sim, cfg)
        self.fc_end = fc_segment(transport, "unused", hil_addr=bridge_address(self.bridge),
                                 wait_config=False)
        self.fc = make_fc_loop(self.fc_end)
        guard_fc(self.fc)
        self.pwm = np.full(4, 1000.0)
        self.buf = np.zeros(64, dtype=RECORD_DTYPE)

    def step(self, n: int = 1) -> None:
        for _ in range(n):
            recs = self.sim.step(self.pwm)
            self.bridge.sensors.push_batch(recs)
            assert self.fc_end.sensors.wait(2.0)
            self.fc.poll()
            assert self.bridge.wait_word(ls.FC_SIM_NS, self.sim.sim_ns, 2.0)
            self.bridge.actuators.pop_into(self.buf)

    def send_raw(self, frame: bytes) -> None:
        self.bridge.channel.send([frame])

    def last_pwm(self):
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline:
            n = self.bridge.actuators.pop_into(self.buf)
            if n:
                return self.buf[:n].view(PWM_DTYPE)[-1]
            time.sleep(0.005)
        raise AssertionError("no PWM record reached the bridge")

    def close(self) -> None:
        self.fc_end.close()
        self.bridge.close()


@pytest.fixture
def rig():
    r = Rig()
    r.step(30)
    r.fc.core.arm()
    r.step(5)
    assert r.fc.core.armed
    yield r
    r.close()


def _sensor(rig, t_us: int, accel=(0.0, 0.0, -9.8)) -> bytes:
    c = rig.bridge.codec
    return c.hil_sensor_encode(t_us, *accel, 0.0, 0.0, 0.0, 0, 0, 0, 0, 0, 0, 20.0, UPD_IMU,
                               0).pack(c)


def _assert_safe(rig) -> None:
    assert not rig.fc.core.armed
    last = rig.last_pwm()
    pwm_min = int(round(rig.fc.core.get_param("MOT_PWM_MIN")))
    assert list(last["pwm_us"][:4]) == [pwm_min] * 4
    assert last["armed"] == 0


def test_nan_is_reported_and_fc_goes_safe(rig):
    rig.send_raw(_sensor(rig, rig.sim.sim_ns // 1000 + 1000, accel=(float("nan"), 0.0, -9.8)))
    with pytest.raises(HilInputError, match="NaN"):
        rig.fc_end.sensors.wait(2.0)
        rig.fc.poll()
    _assert_safe(rig)


def test_time_going_back_is_reported_and_fc_goes_safe(rig):
    rig.send_raw(_sensor(rig, rig.sim.sim_ns // 1000 - 20_000))
    with pytest.raises(HilInputError, match="back"):
        rig.fc_end.sensors.wait(2.0)
        rig.fc.poll()
    _assert_safe(rig)


def test_stalled_stream_is_reported_and_fc_goes_safe(rig):
    rig.fc_end.stall_s = 0.3
    with pytest.raises(HilInputError, match="stalled"):
        rig.fc_end.sensors.wait(2.0)
    _assert_safe(rig)


@pytest.mark.parametrize("transport", ["tcp", "udp"])
def test_fc_disconnect_is_detected_by_the_bridge(transport):
    # TCP: the socket closes; UDP has no connection: the FC's messages stop (stall watch).
    r = Rig(transport)
    try:
        r.step(3)
        watch = PeerWatch(r.bridge, stall_s=0.3)
        watch.check()
        r.fc_end.close()
        with pytest.raises(PeerLost, match="gone|stopped beating"):
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline:
                r.bridge.pump(0.05)
                watch.check()
    finally:
        r.close()


def test_bridge_disconnect_is_detected_by_the_fc():
    r = Rig("tcp")
    try:
        r.step(3)
        r.bridge.close()
        with pytest.raises((FcLost, HilPeerLost), match="gone|disconnected"):
            run_fc(r.fc, wait_slice_s=0.02, out=lambda s: None)
        assert r.fc_end.words[ls.FC_STATE] == ls.FC_STATE_FAILED
    finally:
        r.close()
