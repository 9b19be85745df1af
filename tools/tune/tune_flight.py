"""One captured lockstep flight for the tuning tools: a hover (or any scenario)
with the FC's SYSTEMID sweep started at a chosen sim time, and per physics step
the sweep, the rate-loop signals and the ground truth, as numpy columns.

Why not the MCAP log: the log holds one FC status row per PWM tick (400 Hz) and
no sweep sample, while identification wants every rate-loop step (1 kHz with the
default IMU) with the injected signal itself as the instrument. The flight is
`silbridge fly --processes 1` (bridge and FC interleaved in this process, same
ring, same C poll); only the supervisor is wrapped so that after each step it
reads the core (FlightCore.sysid_sample) and the simulator's true state.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from silbridge.tools.loop.flight import FlightOptions, bridge_config, make_fc_loop, make_simulator
from silbridge.tools.loop.transport_wiring import bridge_segment, fc_segment, guard_fc, in_process_poll
from silbridge.shm.records import NS_PER_S as _NS

# Column names of FlightCapture.data, in FlightCore.sysid_sample order, then truth.
SAMPLE_COLUMNS = (
    "sim_ns", "active", "axis", "t_s", "sample", "freq_hz", "runs",
    "rate_target_x", "rate_target_y", "rate_target_z",
    "rate_x", "rate_y", "rate_z",
    "pid_out_x", "pid_out_y", "pid_out_z",
    "mixer_x", "mixer_y", "mixer_z",
)
TRUTH_COLUMNS = ("gt_p", "gt_q", "gt_r", "gt_roll", "gt_pitch", "gt_yaw",
                 "target_roll", "target_pitch", "cmd_roll", "cmd_pitch", "cmd_yaw",
                 "pwm_max", "pwm_min")
COLUMNS = SAMPLE_COLUMNS + TRUTH_COLUMNS


@dataclass
class CaptureSpec:
    """What to fly and record. params: FC parameter overrides (SID_* included)."""
    scenario: str = "S1"
    seed: int = 1
    duration_s: float = 40.0
    params: dict = field(default_factory=dict)
    sweep_at_s: float | None = 15.0     # None: no sweep
    capture_from_s: float = 14.0
    imu_hz: float | None = None
    label: str = ""


class _Capture:
    """The supervisor wrapper: the inner AutoFlight first, then start and record."""

    def __init__(self, inner, core, sim, spec: CaptureSpec):
        self.inner = inner
        self.core = core
        self.sim = sim
        self.sweep_ns = None if spec.sweep_at_s is None else int(spec.sweep_at_s * _NS)
        self.from_ns = int(spec.capture_from_s * _NS)
        self.rows: list[tuple] = []
        self.sink = None
        self._target = (0.0, 0.0)
        self._pwm = (0, 0)
        fdm = sim.fdm
        self._h = [h.get_double_value for h in (fdm.h_p, fdm.h_q, fdm.h_r,
                                                fdm.h_phi, fdm.h_theta, fdm.h_psi)]
        self._inputs = core.inputs

    def after_batch(self, loop, recs, pwm, status) -> None:
        self.inner.after_batch(loop, recs, pwm, status)
        t = loop.last_sim_ns
        if self.sweep_ns is not None and t >= self.sweep_ns:
            self.sweep_ns = None
            self.core.sysid_start()
        if len(status):
            row = status[-1]
            self._target = (float(row["att_target_rad"][0]), float(row["att_target_rad"][1]))
            p = row["pwm_us"]
            self._pwm = (int(p.max()), int(p.min()))
        if t < self.from_ns:
            return
        inp = self._inputs()
        h = self._h
        self.rows.append(self.core.sysid_sample()
                         + (h[0](), h[1](), h[2](), h[3](), h[4](), h[5]())
                         + self._target + (inp["roll_target_rad"], inp["pitch_target_rad"],
                            inp["yaw_target_rad"])
                         + self._pwm)


@dataclass
class FlightCapture:
    spec: CaptureSpec
    data: dict            # column name -> numpy array (COLUMNS)
    crashed: bool
    dt_s: float           # physics step [s]

    def window(self, mask) -> dict:
        return {k: v[mask] for k, v in self.data.items()}


def fly_captured(spec: CaptureSpec) -> FlightCapture:
    """Fly spec in this process (lockstep, shared memory) and return the columns."""
    opts = FlightOptions(scenario=spec.scenario, duration_s=spec.duration_s, lockstep=True,
                         processes=1, imu_hz=spec.imu_hz, seed=spec.seed,
                         instance=f"tune-{os.getpid()}-{id(spec) & 0xFFFF:x}",
                         params=dict(spec.params))
    from silbridge.bridge.bridge_driver import prepare_segment, run_bridge

    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    with bridge_segment("shm", opts.instance, sim, default_port=0) as seg:
        prepare_segment(seg, sim, cfg)
        with fc_segment("shm", opts.instance, wait_config=False) as fc_seg:
            fc = make_fc_loop(fc_seg, params=opts.params, bounded=True)
            guard_fc(fc)
            cap = _Capture(fc.supervisor, fc.core, sim, spec)
            fc.supervisor = cap
            try:
                res = run_bridge(sim, seg, cfg, out=lambda s: None,
                                 fc_poll=in_process_poll(fc, fc_seg, seg, sim, True))
            finally:
                fc.close()
    arr = np.array(cap.rows, dtype=np.float64).reshape(-1, len(COLUMNS))
    data = {name: arr[:, i] for i, name in enumerate(COLUMNS)}
    data["t"] = data["sim_ns"] * 1e-9
    return FlightCapture(spec=spec, data=data, crashed=bool(res.crashed),
                         dt_s=sim.dt_ns / _NS)
