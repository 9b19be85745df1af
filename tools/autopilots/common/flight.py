"""What a bench flight of a foreign autopilot wires alike, whichever autopilot flies.

A bench flight (ardupilot/flight.py fly_ardupilot, px4/flight.py fly_px4) has four threads of
work meeting on the physics: the autopilot's MAVLink driver (its own thread) reports the
take-off and the autopilot's attitude target; the physics thread steps, forwards the
scenario's setpoints and writes the run log. `BenchWiring` connects them the same way for
every autopilot: the driver's reports go to an AttitudeTarget and the log's /fc/target feed,
its take-off to `BenchStepHooks`, which hands it to the forwarder and the log on the physics
thread. Each flight adds only its own parts: the physics end and its server, the driver,
the forwarder and the autopilot's process.
"""

from __future__ import annotations

from silbridge.tools.autopilots.common.log_sink import AttitudeTarget, AutopilotLogSink
from silbridge.tools.logs.fc_target import TargetFeed
from silbridge.shm.records import NS_PER_S as _NS


class BenchStepHooks:
    """The physics' sink during a bench run: the take-off hand-over, then per step forward the
    setpoints and log.

    The MAVLink thread only records what happened (`takeoff_sent`: the physics time a
    MAV_CMD_NAV_TAKEOFF was written; `takeoff_accepted`: its ACK arrived); the physics
    thread acts on it at its next step, so the log and the forwarder are touched by one
    thread only, and both take the accepted command's send time as their time 0.
    """

    def __init__(self, forwarder, log: AutopilotLogSink):
        self.forwarder = forwarder
        self.log = log
        self.timing = log.timing
        self._sent_ns: int | None = None     # written by the MAVLink thread
        self._accepted = False               # written by the MAVLink thread
        self._pending_ns: int | None = None

    def takeoff_sent(self, sim_ns: int) -> None:
        self._sent_ns = int(sim_ns)

    def takeoff_accepted(self) -> None:
        self._accepted = True

    def step(self, recs, pwm, sim, rotor=None) -> None:
        log = self.log
        if log.t0_ns is None:
            sent = self._sent_ns
            if sent is not None and sent != self._pending_ns:
                self._pending_ns = sent
                log.pending_from(sent)
            if self._accepted and self._pending_ns is not None:
                self.forwarder.start_at(self._pending_ns)
                log.start_at(self._pending_ns)
        # Before the log writes the step, so its status row holds the command just sent.
        self.forwarder.step(int(pwm["sim_ns"][0]))
        log.step(recs, pwm, sim, rotor)


class BenchWiring:
    """The driver's reports, the forwarder and the run log of one bench flight, on `phys`
    (a physics end: bridge/autopilots/*/physics.py)."""

    def __init__(self, phys):
        self.phys = phys
        self.target = AttitudeTarget()
        self.feed = TargetFeed()
        self.forwarder = None
        self.sink: AutopilotLogSink | None = None
        self.hooks: BenchStepHooks | None = None

    def driver_reports(self) -> dict:
        """The driver's keyword arguments: the physics clock, and where its reports go."""
        phys = self.phys
        return {"sim_time_s": lambda: phys.sim.sim_ns / _NS, "sim_ns": lambda: phys.sim.sim_ns,
                "target": self.target, "target_feed": self.feed,
                "on_takeoff": lambda: self.hooks.takeoff_accepted(),
                "on_takeoff_sent": lambda: self.hooks.takeoff_sent(phys.sim.sim_ns)}

    def log(self, log_path: str, *, forwarder, duration_s: float,
            metadata: dict) -> AutopilotLogSink:
        """The run log, from the take-off on, and the physics' sink that feeds it."""
        self.forwarder = forwarder
        self.sink = AutopilotLogSink(log_path, target=self.target, duration_s=duration_s,
                                     command=forwarder, target_feed=self.feed,
                                     metadata=metadata)
        self.hooks = self.phys.sink = BenchStepHooks(forwarder, self.sink)
        return self.sink

    def close_log(self, fc: str, **summary) -> None:
        """Close the log (if it was opened) with the flight's summary and the forwarder's."""
        if self.sink is not None:
            self.sink.close(fc=fc, takeoff_physics_ns=self.sink.t0_ns, **summary,
                            **self.forwarder.summary())
