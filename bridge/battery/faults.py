"""The battery unit's fault applier (shm/fault_catalog.py unit "battery"), registered with
the fault engine: ``sim.faults.register("battery", applier)``. It switches the kernel's
pack (bridge/src/battery.h), so the step's next report (10 Hz) shows the change.

- weak_cell: cell 1 of the pack loses cell_drop_v of open-circuit voltage and its internal
  resistance is multiplied by r_scale; off restores both.
- capacity_loss: fraction of the remaining charge of every cell vanishes at once (a cell
  gives out: the series pack has only what its weakest cell has). Charge that is gone does
  not come back: off ends the fault but restores nothing.
"""

from __future__ import annotations

WEAK_CELL = 0     # the weak cell's index: the pack's first cell


class BatteryFaults:
    """battery: bridge/battery Battery (its kernel is bound before the first step)."""

    def __init__(self, battery):
        self.battery = battery

    def on(self, fault, sim_ns: int) -> None:
        p = fault.params
        kernel = self.battery.kernel
        if fault.type == "weak_cell":
            kernel.set_battery_cell(WEAK_CELL, float(p["cell_drop_v"]), float(p["r_scale"]))
        elif fault.type == "capacity_loss":
            kernel.battery_lose_charge(float(p["fraction"]))

    def off(self, fault, sim_ns: int) -> None:
        if fault.type == "weak_cell":
            self.battery.kernel.set_battery_cell(WEAK_CELL, 0.0, 1.0)
