"""Meaning of the segment's lockstep words, shared by the bridge and the FC.

The segment header holds nine uint64 words written with release and read with
acquire ordering (Segment.set_word / word / wait_word). Each word has exactly
one writer, so no read-modify-write is ever needed across processes.

Lockstep handshake, per physics step k (sim time t_k = k * dt_ns):
  bridge: publish every record of step k (last one flagged STEP_END),
          then BRIDGE_SIM_NS := t_k
  FC:     consume through the STEP_END record of step k, publish every PWM
          due by t_k, then FC_SIM_NS := t_k
  bridge: wait until FC_SIM_NS >= t_k, read the PWM, step physics to k+1.
Sim time (not a step counter) is the currency so the FC need not know dt.

The FC may promise more (FC_SYNC_NS, stored before FC_SIM_NS on the same line): with each
answer, the sim time of the next step whose answer the bridge must wait for, its next PWM
tick or its Python's next due poll. Every step before it the FC answers with no record, and
its Python does not act, so the bridge's batch (bridge/src/step_batch.c) publishes those
steps without waiting and the FC computes them while the bridge steps on: the same records,
PWM and trace, one hand-off where there were two or three. The bridge still waits at a step
carrying a record of HAND_ON_KINDS (the FC's Python follows that poll), at the last step of a
batch, and at least every 32 steps; a promise of 0 (an FC polling from Python, or after a
poll its Python follows) means every step.
"""

from silbridge.shm.records import Kind

BRIDGE_SIM_NS = 0   # writer: bridge. sim time of the last fully published step
FC_SIM_NS = 1       # writer: FC. sim time through which the FC consumed and answered
RUN_MODE = 2        # writer: bridge, before the FC attaches. see MODE_*
STOP = 3            # writer: bridge. nonzero (STOP_*) = run finished, FC should exit cleanly
FC_STATE = 4        # writer: FC. see FC_STATE_*
PHYSICS_DT_NS = 5   # writer: bridge, before the FC attaches
IMU_HZ = 6          # writer: bridge, before the FC attaches
FC_STOP = 7         # writer: FC. 1 = FC is leaving (error or finished); bridge stops
FC_SYNC_NS = 8      # writer: FC (its C poll). the next step the bridge must wait for (above)

# STOP values: 1 the run ended as planned; 2 a signal (Ctrl-C, SIGTERM) ended it early.
STOP_DONE = 1
STOP_INTERRUPTED = 2

MODE_REALTIME = 0
MODE_LOCKSTEP = 1

FC_STATE_NONE = 0
FC_STATE_READY = 1   # attached, core initialised, consuming
FC_STATE_DONE = 2    # left after STOP
FC_STATE_FAILED = 3  # left on an error (the FC prints why)

# The record kinds after whose poll the FC's Python runs (its supervisor sees the same polls
# in one and two processes: AutoFlight's declination waits for a GNSS fix): the steps of
# `fly --processes 1` that finish in Python (the bridge kernel's F_* flags). The FC's serve
# loop hands those polls to Python; the bridge waits for the FC's answer at a step carrying
# one, whatever FC_SYNC_NS says, so that poll ends there.
HAND_ON_KINDS = ((1 << Kind.GNSS) | (1 << Kind.SETPOINT) | (1 << Kind.ESC)
                 | (1 << Kind.BATTERY))
