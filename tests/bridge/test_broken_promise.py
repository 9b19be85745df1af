"""An FC that breaks its promise (FC_SYNC_NS, shm/lockstep.py) stops the run with a clear
error: the bridge published the steps it promised to answer with nothing without waiting,
so a PWM for one of them reached the motors late. Real JSBSim, real shared memory, the
bridge's C batch; the FC is a thread that answers every step with a PWM record while it
promises nothing due for ever."""

import threading

import numpy as np
import pytest

from silbridge.bridge.bridge_driver import BridgeRunConfig, prepare_segment
from silbridge.bridge.bridge_loop import BridgeLoop
from silbridge.bridge.errors import LockstepBroken
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm import Segment
from silbridge.shm import lockstep as ls
from silbridge.shm.records import RECORD_DTYPE, Kind


def _lying_fc(seg, done: threading.Event) -> None:
    buf = np.zeros(256, RECORD_DTYPE)
    pwm = np.zeros(1, RECORD_DTYPE)
    pwm["kind"] = Kind.PWM
    while not done.is_set():
        n = seg.sensors.pop_into(buf)
        if not n:
            seg.sensors.wait(0.01)
            continue
        # A PWM for every step it took (the bridge wakes it only before it waits, so one
        # wake-up can bring several steps), each stamped with its step's time.
        for sim_ns in np.unique(buf["sim_ns"][:n]).tolist():
            pwm["sim_ns"] = sim_ns
            seg.actuators.push_batch(pwm)
        seg.set_word(ls.FC_SYNC_NS, 1 << 62)     # "nothing from me for ever"
        seg.set_word(ls.FC_SIM_NS, int(buf["sim_ns"][n - 1]))


def test_a_pwm_for_a_promised_step_stops_the_run(request):
    name = f"promise-{request.node.name[:20]}"
    sim = Simulator(load_scenario("S1"))
    with Segment.create(name) as seg, Segment.attach(name) as fc_seg:
        prepare_segment(seg, sim, BridgeRunConfig(duration_s=1.0))
        loop = BridgeLoop(sim, seg, settle_s=0.5)
        assert loop.bind_fc_process()
        done = threading.Event()
        fc = threading.Thread(target=_lying_fc, args=(fc_seg, done), daemon=True)
        fc.start()
        try:
            loop.run_batch(1)           # no promise held yet: the step is waited for
            assert loop.stats.steps_overlapped == 0
            with pytest.raises(LockstepBroken, match="promised to answer with none"):
                for _ in range(20):
                    loop.run_batch(16)
        finally:
            done.set()
            fc.join(5)
