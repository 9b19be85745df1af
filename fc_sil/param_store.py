"""CoreParamStore: the FC's parameter table as the MAVLink server sees it.

Every declared parameter (fc_params.def, C core and host side) in index order, with
ArduPilot typing (integers reported with their integer MAV_PARAM_TYPE). ``set`` is called on
the GCS thread while the control loop runs ``step_batch`` on the main thread, so a set is
never applied to the live core from the GCS thread. Instead:

* the value is validated at once against the declaration (range, integer, finite) AND against
  the C core's own cross-parameter rules, by applying it to a *shadow* C core that holds the
  same parameter values as the live one (so the verdict is exactly the live core's);
* the accepted value is echoed at once (``get`` reads the shadow and host table), as
  ArduPilot's PARAM_VALUE echo does;
* it is queued, and the vehicle thread applies the queue to the live core with ``apply()``
  at its next outer-loop step (within 20 ms of sim time), between two batches.

Host-side parameters live in this store (``host(name)``); the vehicle's outer loops read them
through a cached ``version`` counter so they re-read only after a change.
"""

from __future__ import annotations

import collections
import threading
from typing import Iterable, Sequence

from . import _core
from . import params as P
from .errors import ParamError


class CoreParamStore:
    """ParamStore (mavlink.vehicle_api) over a FlightCore; see module text."""

    def __init__(self, core):
        self._core = core
        self._lock = threading.Lock()
        self._shadow = _core.Core()
        self._host: dict[str, float] = {}
        for p in P.PARAMS:
            if p.host:
                self._host[p.name] = core.get_param(p.name)
        # Two passes: a value the core's cross-parameter rules refuse against a default
        # (MOT_PWM_MIN 1950 while MOT_PWM_MAX is still 2000) is accepted once its partner moved.
        for _ in range(2):
            for p in P.PARAMS:
                if not p.host:
                    self._shadow.set_param(p.index, core.get_param(p.name))
        self._names = tuple(p.name for p in P.PARAMS)
        self._queue: collections.deque[tuple[str, float]] = collections.deque()
        self.version = 0          # bumped on every accepted set (outer loops re-read then)
        self.sets_ok = 0
        self.sets_refused = 0

    # ---- ParamStore protocol (any thread) ------------------------------------------------

    def names(self) -> Sequence[str]:
        return self._names

    def get(self, name: str) -> tuple[float, int]:
        d = P.BY_NAME[name]      # KeyError for an unknown name, as the protocol wants
        with self._lock:
            if d.host:
                v = self._host[d.name]
            else:
                v = self._shadow.get_param(d.index)
        return (int(v) if d.is_int else float(v)), d.mav_type

    def set(self, name: str, value: float) -> str | None:
        """Validate, echo, queue for the vehicle thread; None or the reason for refusal."""
        try:
            d = P.lookup(name)
            v = d.validate(value)
        except ParamError as exc:
            self.sets_refused += 1
            return str(exc)
        with self._lock:
            if not d.host:
                old = self._shadow.get_param(d.index)
                code = self._shadow.set_param(d.index, v)
                if code != _core.FC_OK:
                    self._shadow.set_param(d.index, old)
                    self.sets_refused += 1
                    return (f"{d.name}={v:g} contradicts another parameter (MOT_PWM_MIN + 100 <= "
                            f"MOT_PWM_MAX, MOT_SPIN_ARM <= MOT_SPIN_MIN < MOT_SPIN_MAX, "
                            f"INS_HNTCH/HNTC2_FREQ > _BW / 2)")
                v = self._shadow.get_param(d.index)
            else:
                self._host[d.name] = v
            self._queue.append((d.name, v))
            self.version += 1
        self.sets_ok += 1
        return None

    # ---- vehicle thread --------------------------------------------------------------------

    def apply(self) -> int:
        """Apply queued sets to the live core (vehicle thread, between batches)."""
        if not self._queue:
            return 0
        with self._lock:
            items = list(self._queue)
            self._queue.clear()
        for name, v in items:
            self._core.set_param(name, v)
        return len(items)

    def host(self, name: str) -> float:
        """Current value of a parameter (host or core) as the outer loops read it."""
        return self.get(name)[0]

    def values(self, names: Iterable[str]) -> dict[str, float]:
        return {n: self.get(n)[0] for n in names}

    def set_param(self, name: str, value: float) -> float:
        """FlightCore.set_param's surface, for timed changes made on the vehicle thread (a
        scenario's [[fc_param]] and FC-side [[failure]] entries, param_schedule.py): the live
        core at once, as without a vehicle, and this store too, so the vehicle's host
        parameters and the GCS's view follow."""
        stored = self._core.set_param(name, value)
        self.set(name, stored)
        return stored

    def set_many(self, values: dict[str, float]) -> list[str]:
        """Set several (start-up overrides); returns the refusals as messages."""
        problems = []
        for name, v in values.items():
            err = self.set(name, v)
            if err:
                problems.append(f"{name}: {err}")
        return problems
