"""Motor faults: a motor's thrust loss, an ESC's desync, a damaged prop. Instance 1..4 is
the motor (ArduCopter quad X order), 0 all four.

All act through the motor's thrust scale (JSBSim fcs/mN-thrust-scale, which scales its
thrust and reaction torque), the path of the motor_bias disturbance: the scale written is
the disturbances' product times the faults' (Disturbances.set_fault_thrust_scale). So every
autopilot flying this physics meets the same motor, whatever its link.
- thrust_loss: times `remaining`.
- desync: dropouts start at random (a Poisson process of rate_hz, drawn from the named
  stream "fault:motor<m>:desync:<t_on_ns>", so a run is reproducible) and each cuts the
  motor (scale 0) for dropout_s; each motor of instance 0 desyncs on its own. Each start
  and end is an engine timer, so it ends a step batch like a switch.
- damaged_prop: times `remaining`, and the rotor's imbalance (the vibrating world's,
  bridge/src/vibration.c) times imbalance_scale; needs [vibration] unless that is 1.
"""

from __future__ import annotations

from silbridge.bridge.faults.engine import FaultError
from silbridge.bridge.scenario import draw_rng

MOTORS = 4


def _motors(instance: int) -> range:
    return range(MOTORS) if instance == 0 else range(instance - 1, instance)


class _Desync:
    """One motor's dropouts under one desync fault."""

    def __init__(self, applier, fault, motor: int, start_step: int):
        self.applier, self.motor = applier, motor
        self.rate_hz = fault.params["rate_hz"]
        self.dropout_steps = max(1, round(fault.params["dropout_s"] * 1e9 / applier.dt_ns))
        self.rng = draw_rng(applier.seed, f"fault:motor{motor + 1}:desync:{fault.t_on_ns}")
        self.live = True
        self.cut = False
        self._next_start(start_step)

    def _next_start(self, step: int) -> None:
        if self.rate_hz <= 0:
            return
        gap_s = float(self.rng.exponential(1.0 / self.rate_hz))
        self.applier.engine.wake_at(step + max(1, round(gap_s * 1e9 / self.applier.dt_ns)),
                                    self._wake)

    def _wake(self, step: int) -> None:
        if not self.live:
            return
        self.cut = not self.cut
        if self.cut:
            self.applier.engine.wake_at(step + self.dropout_steps, self._wake)
            self.applier.engine.on_event((step - 1) * self.applier.dt_ns,
                                         f"failure motor.desync: motor {self.motor + 1} cut "
                                         f"for {self.dropout_steps} steps")
        else:
            self._next_start(step)
        self.applier.write()


class MotorApplier:
    def __init__(self, engine, sim):
        self.engine, self.sim = engine, sim
        self.dt_ns, self.seed = sim.dt_ns, sim.scenario.seed
        self.vibration = bool(sim.scenario.vibration.enabled)
        self._desyncs: dict[tuple, list] = {}   # fault key -> its motors' _Desync

    def on(self, fault, sim_ns: int) -> None:
        if fault.type == "damaged_prop" and fault.params["imbalance_scale"] != 1.0 \
                and not self.vibration:
            raise FaultError("a damaged prop's vibration needs the vibrating world: set "
                             "[vibration] enabled = true, or imbalance_scale = 1")
        if fault.type == "desync":
            step = sim_ns // self.dt_ns + 1
            self._desyncs[fault.key] = [_Desync(self, fault, m, step)
                                        for m in _motors(fault.instance)]
        self.write()

    def off(self, fault, sim_ns: int) -> None:
        for d in self._desyncs.pop(fault.key, ()):
            d.live = False
        self.write()

    def write(self) -> None:
        scale = [1.0] * MOTORS
        imbalance = [1.0] * MOTORS
        for f in self.engine.active("motor"):
            for m in _motors(f.instance):
                if f.type in ("thrust_loss", "damaged_prop"):
                    scale[m] *= f.params["remaining"]
                if f.type == "damaged_prop":
                    imbalance[m] *= f.params["imbalance_scale"]
        for ds in self._desyncs.values():
            for d in ds:
                if d.cut:
                    scale[d.motor] = 0.0
        self.sim.dist.set_fault_thrust_scale(scale)
        if self.vibration:
            for m in range(MOTORS):
                self.sim.kernel.set_imbalance_scale(m, imbalance[m])
