"""`silbridge fc --transport tcp` fed by another simulator (PX4's convention): no silbridge
configuration, one HIL_SENSOR per lockstep step; the FC answers each with one
HIL_ACTUATOR_CONTROLS whose time_usec is that step's time and whose LOCKSTEP flag is set."""

from __future__ import annotations

import numpy as np

from silbridge.mavlink.hil.hil_channel import HilListener, make_codec
from silbridge.mavlink.hil.hil_codec import UPD_ABS_PRESSURE, UPD_IMU, UPD_MAG, UPD_TEMPERATURE
from silbridge.mavlink.hil.hil_pwm import FLAG_LOCKSTEP
from silbridge.shm import lockstep as ls
from silbridge.tools.loop.flight import make_fc_loop
from silbridge.tools.loop.transport_wiring import fc_segment


def test_px4_style_simulator_gets_one_answer_per_sensor_step():
    listener = HilListener("127.0.0.1", 0, datagram=False)
    host, port = listener.addr
    codec = make_codec(1, 51)
    fc_end = fc_segment("tcp", "unused", hil_addr=f"{host}:{port}", wait_config=False)
    sim = listener.accept(codec, timeout_s=5.0)
    try:
        assert sim is not None
        fc = make_fc_loop(fc_end)
        answers = []
        for k in range(1, 41):
            t_us = 4000 * k                     # a 250 Hz simulator
            bits = UPD_IMU | UPD_MAG | UPD_ABS_PRESSURE | UPD_TEMPERATURE
            sim.send([codec.hil_sensor_encode(t_us, 0.0, 0.0, -9.81, 0.0, 0.0, 0.0, 0.2, 0.0,
                                              0.4, 1013.25, 0, 0, 20.0, bits, 0).pack(codec)])
            assert fc_end.sensors.wait(2.0)
            fc.poll()
            for _ in range(100):
                got = [m for m in sim.receive(0.02) if m.get_type() == "HIL_ACTUATOR_CONTROLS"]
                if got:
                    answers += got
                    break
        assert fc_end.words[ls.RUN_MODE] == ls.MODE_LOCKSTEP
        assert [m.time_usec for m in answers] == [4000 * k for k in range(1, 41)]
        assert all(m.flags & FLAG_LOCKSTEP for m in answers)
        motors = np.array([m.controls[:4] for m in answers])
        assert np.all((motors >= 0.0) & (motors <= 1.0))
    finally:
        fc_end.close()
        if sim is not None:
            sim.close()
        listener.close()
