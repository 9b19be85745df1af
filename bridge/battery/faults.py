"""The battery unit's fault applier (shm/fault_catalog.py unit "battery"), registered with
the fault engine: ``sim.faults.register("battery", applier)``.

- weak_cell: cell 1 of the pack loses cell_drop_v of open-circuit voltage and its internal
  resistance is multiplied by r_scale; off restores both.
- capacity_loss: fraction of the remaining charge of every cell vanishes at once (a cell
  gives out: the series pack has only what its weakest cell has). Charge that is gone does
  not come back: off ends the fault but restores nothing.
The pack's next report (10 Hz) shows the change.
"""

from __future__ import annotations

WEAK_CELL = 0     # the weak cell's index: the pack's first cell


class BatteryFaults:
    def __init__(self, pack):
        self.pack = pack

    def on(self, fault, sim_ns: int) -> None:
        p = fault.params
        if fault.type == "weak_cell":
            self.pack.offset_v[WEAK_CELL] = float(p["cell_drop_v"])
            self.pack.r_scale[WEAK_CELL] = float(p["r_scale"])
        elif fault.type == "capacity_loss":
            self.pack.lose_charge(float(p["fraction"]))

    def off(self, fault, sim_ns: int) -> None:
        if fault.type == "weak_cell":
            self.pack.offset_v[WEAK_CELL] = 0.0
            self.pack.r_scale[WEAK_CELL] = 1.0
