"""The FC's fault switchboard: the ways in on our FC, and what each switched fault becomes.

Two ways in reach it, both on the vehicle thread: MAV_CMD_INJECT_FAILURE (``inject_failure``,
mapped by fault_map.py, allowed by SYS_FAILURE_EN) and ArduPilot's SIM_* parameters
(``sync_sim_params`` after any parameter change, mapped by sim_faults.py); a third, a
scenario's [[failure]] entries for the FC-side units, arrives as timed ``switch`` calls
(fault_schedule.py). Each switch of a catalog fault goes one of two ways:

* rc and gcs are the FC's own links: ``links`` (the vehicle) makes them look lost as a real
  loss would (rc_link_lost / gcs_link_lost);
* every other unit belongs to the bridge's fault engine: a FAULT record (shm/records.py) goes
  into ``outbox``, which the vehicle hands to the FC loop's output beside the PWM.

A GCS loss injected over MAVLink cannot be cleared by the GCS that asked for it (it is no
longer heard), so it ends by itself after SB_FI_GCS_S of sim time; one from a scenario or from
a parameter set on the command line ends when its switch says so.
"""

from __future__ import annotations

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.shm import fault_catalog as fc
from silbridge.shm.records import Kind, empty

from . import fault_map, sim_faults

FC_SIDE = ("rc", "gcs")
ACCEPTED, DENIED, UNSUPPORTED = (mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_DENIED,
                                 mav.MAV_RESULT_UNSUPPORTED)


def fault_record(unit: str, ftype: str, instance: int, params: dict, on: bool,
                 sim_ns: int) -> np.ndarray:
    """One FAULT record (a 1-element array) for the bridge."""
    u = fc.unit_named(unit)
    t = u.type_named(ftype)
    rec = empty(Kind.FAULT, 1)
    rec["sim_ns"] = sim_ns
    rec["action"] = 1 if on else 0
    rec["unit"], rec["type"], rec["instance"] = u.code, t.code, instance
    rec["params"][0] = fc.pack_params(t, params)
    return rec


class FaultInjector:
    """See module text. ``links``: an object with rc_link_lost(bool) and gcs_link_lost(bool)."""

    def __init__(self, links, statustext=None):
        self.links = links
        self.statustext = statustext or (lambda severity, text: None)
        self.active: dict[tuple[str, str, int], dict] = {}   # (unit, type, instance) -> params
        self.outbox: list[np.ndarray] = []
        self._sim_wanted: dict = {}
        self._seq = 0
        self.gcs_ends_ns: int | None = None     # a MAVLink-injected GCS loss ends then
        self.sim_ns = 0
        self._gcs_next: bool | None = None

    # ---- the switch every way in uses ------------------------------------------------------

    def switch(self, unit: str, ftype: str, instance: int, params: dict, on: bool) -> None:
        key = (unit, ftype, instance)
        if on:
            self.active[key] = dict(params)
        elif self.active.pop(key, None) is None:
            return              # already off
        if unit == "rc":
            self.links.rc_link_lost(on)
        elif unit == "gcs":
            if not on:
                self.gcs_ends_ns = None
            # Applied at the next tick: the injecting command's ACK is queued by then, and the
            # server sends what is queued before it goes silent; the STATUSTEXT of the end
            # goes after the link is back.
            self._gcs_next = on
            if not on:
                return
        else:
            rec = fault_record(unit, ftype, instance, params, on, self.sim_ns)
            rec["seq"] = self._seq
            self._seq += 1
            self.outbox.append(rec)
        where = "" if instance == 1 else f" (instance {instance})"
        self.statustext(mav.MAV_SEVERITY_WARNING if on else mav.MAV_SEVERITY_INFO,
                        f"Failure {'injected' if on else 'cleared'}: {unit} {ftype}{where}")

    def take_outbox(self) -> np.ndarray | None:
        """The FAULT records waiting for the bridge (in order), or None."""
        if not self.outbox:
            return None
        recs = np.concatenate(self.outbox)
        self.outbox = []
        return recs

    def tick(self, sim_ns: int) -> None:
        """Each outer-loop step: the clock, and the end of a MAVLink-injected GCS loss."""
        self.sim_ns = sim_ns
        if self.gcs_ends_ns is not None and sim_ns >= self.gcs_ends_ns:
            for key in [k for k in self.active if k[0] == "gcs"]:
                self.switch(*key, {}, False)
        if self._gcs_next is not None:
            self.links.gcs_link_lost(self._gcs_next)
            if not self._gcs_next:
                self.statustext(mav.MAV_SEVERITY_INFO, "Failure cleared: gcs lost")
            self._gcs_next = None

    # ---- MAV_CMD_INJECT_FAILURE --------------------------------------------------------------

    def inject_failure(self, failure_unit: int, failure_type: int, instance: int,
                       enabled: bool, gcs_loss_s: float):
        """(MAV_RESULT, reason or None), as PX4 1.15 answers: DENIED unless SYS_FAILURE_EN."""
        if not enabled:
            return DENIED, "Failure injection disabled (set SYS_FAILURE_EN 1)"
        inj = fault_map.from_mavlink(failure_unit, failure_type, instance)
        if isinstance(inj, str):
            return UNSUPPORTED, inj
        if inj.type is None:        # FAILURE_TYPE_OK: clear what is on for that unit
            for key in [k for k in self.active
                        if k[0] == inj.unit and (inj.instance == 0 or k[2] == inj.instance)]:
                self.switch(*key, {}, False)
            return ACCEPTED, None
        if inj.unit == "gcs":
            self.gcs_ends_ns = self.sim_ns + int(gcs_loss_s * 1e9)
        self.switch(inj.unit, inj.type, inj.instance, inj.params, True)
        return ACCEPTED, None

    # ---- SIM_* parameters --------------------------------------------------------------------

    def sync_sim_params(self, get, lat_deg: float) -> None:
        """Switch what the SIM_* values now ask for against what they asked for before."""
        want = sim_faults.wanted(get, lat_deg)
        before = self._sim_wanted
        for key, params in before.items():
            if key not in want or want[key] != params:
                self.switch(*key, params, False)
        for key, params in want.items():
            if before.get(key) != params:
                self.switch(*key, params, True)
        self._sim_wanted = want
