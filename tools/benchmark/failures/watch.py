"""What the failure benchmark adds to the nav suite's MAVLink client: a timeline of what the
autopilot said and did (mode, armed, alert texts, battery voltage, on the sim clock), the
ground-station silence of a GCS-loss fault, and the SIM_* switches ArduCopter gets at the
physics step of its fault (translate.py).

The GCS loss is the client's own, the same for every autopilot: from the fault's at_s to
its end nothing leaves the client (no heartbeat, no command) and the flight script sends
nothing. What the autopilot sends meanwhile is still written down, as a telemetry log on a
ground station that lost its uplink would be: the autopilot cannot tell, and the timeline
needs it to time the detection.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.benchmark.nav.client import NavClient
from silbridge.shm.records import NS_PER_S as _NS

ALERT_SEVERITY = mav.MAV_SEVERITY_WARNING     # texts at this severity or worse are alerts
HEARTBEAT_SIM_S = 1.0                         # the client's GCS heartbeat period [sim s]


@dataclass
class Timeline:
    """Everything on the sim clock [s]: modes (mode as the autopilot sends it, armed),
    alerts (severity <= WARNING), battery voltage reports, SIM_* values ArduCopter echoed."""
    modes: list = field(default_factory=list)      # (t_s, custom_mode, armed)
    texts: list = field(default_factory=list)      # (t_s, severity, text), every one
    volts: list = field(default_factory=list)      # (t_s, volts)
    params: list = field(default_factory=list)     # (t_s, name, value) from PARAM_VALUE


class FailureClient(NavClient):
    """NavClient plus the timeline, the mute windows of a GCS loss and a lock, so the
    physics thread may send SIM_* parameters on the same link."""

    def __init__(self, link, home_lat_deg: float, home_lon_deg: float, clock=None, stop=None,
                 mute=()):
        super().__init__(link, home_lat_deg, home_lon_deg, clock=clock, stop=stop)
        self.timeline = Timeline()
        self.mute = tuple(mute)                    # (on_s, off_s) of client-made faults
        self.dropped = 0                           # writes not sent while muted
        self._lock = threading.RLock()
        self._last_mode = None
        self._next_hb_sim = 0.0

    def pump(self, wall_s: float = 0.02) -> None:
        """NavClient's pump, plus a GCS heartbeat every HEARTBEAT_SIM_S of sim time: the
        autopilots time their GCS failsafe on their own (sim) clock, and nav's wall-paced
        heartbeat comes only every 5 s of sim time at --speed 10, as late as their timeout."""
        if self.sysid is not None and self.clock() >= self._next_hb_sim:
            self.codec.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            self._next_hb_sim = self.clock() + HEARTBEAT_SIM_S
        super().pump(wall_s)

    def muted(self) -> bool:
        t = self.clock()
        return any(a <= t < b for a, b in self.mute)

    def write(self, buf: bytes) -> None:
        if self.muted():
            self.dropped += 1
            return
        with self._lock:
            super().write(buf)

    def send_params(self, values: dict) -> None:
        """PARAM_SET each value (ArduPilot reads the value by the parameter's own type)."""
        with self._lock:
            for name, value in values.items():
                self.codec.param_set_send(self.sysid or 1, 1, name.encode(), float(value),
                                          mav.MAV_PARAM_TYPE_REAL32)

    def _take(self, m) -> None:
        super()._take(m)
        kind = m.get_type()
        t = self.clock()
        tl = self.timeline
        if kind == "HEARTBEAT" and m.autopilot != mav.MAV_AUTOPILOT_INVALID \
                and m.get_srcComponent() == 1:
            now = (self.mode, self.armed)
            if now != self._last_mode:
                self._last_mode = now
                tl.modes.append((t, self.mode, self.armed))
        elif kind == "STATUSTEXT":
            tl.texts.append((t, m.severity, m.text.strip()))
        elif kind == "SYS_STATUS" and m.voltage_battery not in (0, 65535):
            tl.volts.append((t, m.voltage_battery * 1e-3))
        elif kind == "PARAM_VALUE" and m.param_id.startswith("SIM_"):
            tl.params.append((t, m.param_id, m.param_value))


class SimParamSwitcher:
    """A physics sink around the ground-truth log: after the first physics step that ends
    past each switch time it sends that switch's SIM_* values through the client (none yet: it
    waits for the client). switches: [(t_s, {name: value})] in time order; a value may be
    a function of the simulator, evaluated at that step (after the engine's switch)."""

    def __init__(self, sink, switches):
        self.sink = sink
        self.switches = list(switches)
        self.client: FailureClient | None = None
        self.sent: list = []                      # (t_s, values) as sent

    def step(self, recs, pwm, sim, rotor=None) -> None:
        self.sink.step(recs, pwm, sim, rotor)
        if self.switches and self.client is not None:
            t = sim.sim_ns / _NS
            # Strictly after: the engine switches a fault before the first step that starts
            # at or after its time, so this step (ending after it) already has it.
            while self.switches and t > self.switches[0][0]:
                _, values = self.switches.pop(0)
                values = {k: (v(sim) if callable(v) else v) for k, v in values.items()}
                self.client.send_params(values)
                self.sent.append((t, values))

    def timing(self, *row) -> None:
        self.sink.timing(*row)

    def close(self, **summary) -> None:
        self.sink.close(**summary)


def first_after(rows, t0: float, t1: float = math.inf):
    """The first row whose time (row[0]) lies in [t0, t1), or None."""
    return next((r for r in rows if t0 <= r[0] < t1), None)
