"""How fast ArduCopter SITL runs on our physics, against the same binary on its own physics.

    python -m silbridge.tools.autopilots.ardupilot.speed [--sitl PATH] [--span 30] [--json]

Four runs of the same arducopter binary, one after the other, each with the
same defaults file (tools/autopilots/ardupilot/sitl.py sitl_defaults: SIM_RATE_HZ 1000,
so both physics give it the same number of frames per simulated second):

- reference: `--model quad --speedup 1000`, SITL's built-in physics;
- json_idle: `--model JSON` answered by our physics (ArduPilotPhysics on the
  UDP server), nothing logged, so the figure is the JSON path alone;
- json_floor: `--model JSON` answered at once with a vehicle at rest and no
  physics at all: what SITL's frame and the two UDP hops cost, the ceiling
  of any physics behind the JSON interface on this machine;
- bench: one `silbridge bench --fc ardupilot` run of S1 (boot, arming,
  take-off, `--flight` seconds of hover), logged as the benchmark logs it.

The first three idle on the ground, disarmed, from boot; the speed is the sim
time elapsed over wall time between sim time `--skip` and `--skip + --span`
(the boot's first seconds, parameter loading, are left out). The reference's
sim time is read from its MAVLink time_boot_ms, ours from the physics clock.
The bench figure is the run's own realtime_factor (boot to landing of the log).

The JSON runs also give a profile per servo packet (median and mean, us):
`ours` = packet arrival -> reply sent (decode, physics step, encode, and the
log in the bench run); `sitl` = reply sent -> next packet arrival (SITL's
frame plus both UDP hops and the wake-ups). Ratios: json_idle / reference and
bench / reference. Our server spins on the link as a lone campaign run does
(bridge/link_spin.py: when this process has two cores or more). Measure under the
shared lock: `flock /work/heavy.lock ...`.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import socket
import sys
import tempfile
import threading
import time

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.autopilots.ardupilot import json_protocol as apj
from silbridge.bridge.autopilots.ardupilot.json_protocol import sitl_port
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.autopilots.ardupilot.server import JsonPhysicsServer
from silbridge.bridge.link_spin import spin_budget_us
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator

from silbridge.tools.autopilots.common.run import AutopilotRun
from silbridge.tools.cli.aliases import add_deprecated_alias
from silbridge.tools.autopilots.ardupilot.sitl import (
    ARDUCOPTER,
    MAVLINK_TCP_BASE,
    PORT_STRIDE,
    SitlError,
    require_arducopter,
    sitl_defaults,
    start_sitl,
    write_defaults,
)
from silbridge.shm.records import NS_PER_S as _NS


class ClockReader(threading.Thread):
    """SITL's MAVLink TCP port, drained; remembers (wall, time_boot_ms) of each message."""

    def __init__(self, instance: int, timeout_s: float = 30.0):
        super().__init__(daemon=True)
        self.addr = ("127.0.0.1", MAVLINK_TCP_BASE + PORT_STRIDE * instance)
        self.timeout_s = timeout_s
        self.samples: list = []
        self.error: str | None = None
        self._halt = threading.Event()
        self.codec = mav.MAVLink(None)
        self.codec.robust_parsing = True

    def run(self) -> None:
        end = time.monotonic() + self.timeout_s
        sock = None
        while sock is None and not self._halt.is_set():
            try:
                sock = socket.create_connection(self.addr, timeout=0.5)
            except OSError:
                if time.monotonic() > end:
                    self.error = f"no MAVLink connection on port {self.addr[1]}"
                    return
                time.sleep(0.05)
        try:
            self.codec.file = _Out(sock)
            sock.settimeout(0.1)
            asked = 0.0
            while not self._halt.is_set():
                now = time.monotonic()
                if not self.samples and now - asked > 0.5:
                    # ATTITUDE at 20 Hz of sim time: a message with time_boot_ms whatever
                    # SRn_* say; asked again until it comes (SITL may not listen yet).
                    self.codec.command_long_send(1, 1, mav.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                                 mav.MAVLINK_MSG_ID_ATTITUDE, 50_000,
                                                 0, 0, 0, 0, 0)
                    asked = now
                try:
                    data = sock.recv(65536)
                except socket.timeout:
                    continue
                if not data:
                    return
                now = time.monotonic()
                for m in self.codec.parse_buffer(data) or []:
                    t = getattr(m, "time_boot_ms", None)
                    if t:
                        self.samples.append((now, t * 1e-3))
        finally:
            if sock is not None:
                sock.close()

    def sim_s(self) -> float:
        return self.samples[-1][1] if self.samples else 0.0

    def stop(self) -> None:
        self._halt.set()
        self.join(2.0)


class _Out:
    def __init__(self, sock):
        self.sock = sock

    def write(self, buf: bytes) -> None:
        self.sock.sendall(buf)


def _factor(samples, skip_s: float, span_s: float) -> float:
    """sim / wall from the first sample at or after skip_s to the first span_s of sim later."""
    t = [s for s in samples if s[1] >= skip_s]
    if not t:
        return float("nan")
    w0, s0 = t[0]
    end = [s for s in t if s[1] >= s0 + span_s]
    if not end:
        return float("nan")
    w1, s1 = end[0]
    return (s1 - s0) / max(w1 - w0, 1e-9)


def _run_with_defaults(sim, physics_hz: float) -> tuple[AutopilotRun, str]:
    """A fresh SITL run and its defaults file for our vehicle."""
    run = AutopilotRun(ARDUCOPTER, "silbridge-speed-")
    path = os.path.join(run.workdir, "silbridge-defaults.parm")
    write_defaults(path, sitl_defaults(sim, physics_hz))
    return run, path


def measure_reference(binary: str, *, skip_s: float, span_s: float) -> dict:
    sc = load_scenario("S1")
    sim = Simulator(sc)
    run, defaults = _run_with_defaults(sim, _NS / sim.dt_ns)
    reader = ClockReader(run.instance)
    try:
        run.launch(start_sitl, binary, run.instance, run.workdir, speedup=1000, home=sc.home,
                   defaults_path=defaults, model="quad")
        reader.start()
        deadline = time.monotonic() + 120.0
        while math.isnan(_factor(reader.samples, skip_s, span_s)) and \
                time.monotonic() < deadline:
            if run.exited() or reader.error:
                raise SitlError(f"reference SITL stopped: {reader.error or run.proc.returncode}")
            time.sleep(0.2)
    finally:
        run.close(reader)
    return {"realtime_factor": _factor(reader.samples, skip_s, span_s), "model": "quad",
            "speedup": 1000}


class _Profile:
    """The sink of a JSON run: no log, the per-packet timing and the clock kept."""

    def __init__(self, physics):
        self.physics = physics
        self.rows: list = []

    def step(self, recs, pwm, sim, rotor=None) -> None:
        pass

    def timing(self, applied_ns, rx, done, tx, period) -> None:
        self.rows.append((applied_ns, rx, done, tx, period))


def _profile(rows, skip_s: float, span_s: float) -> dict:
    a = np.array([r for r in rows if skip_s * _NS <= r[0] <= (skip_s + span_s) * _NS],
                 dtype=np.int64)
    if len(a) < 3:
        return {"realtime_factor": float("nan")}
    wall_s = (a[-1, 1] - a[0, 1]) / _NS
    ours = (a[:, 3] - a[:, 1]) / 1e3
    sitl = (a[1:, 1] - a[:-1, 3]) / 1e3
    step = (a[:, 2] - a[:, 1]) / 1e3
    return {"realtime_factor": (a[-1, 0] - a[0, 0]) / _NS / max(wall_s, 1e-9),
            "packets": int(len(a)),
            "ours_us": {"median": float(np.median(ours)), "mean": float(ours.mean())},
            "ours_step_us": {"median": float(np.median(step)), "mean": float(step.mean())},
            "sitl_us": {"median": float(np.median(sitl)), "mean": float(sitl.mean())}}


def _serve_json(binary: str, sc, phys, defaults_sim, physics_hz: float, duration_s: float,
                spin_us: float | None = None) -> None:
    """SITL at --speedup 1000 on phys over JSON for duration_s of sim time (its defaults
    from defaults_sim at physics_hz). spin_us None: a lone run's budget (bridge/link_spin.py)."""
    spin_us = spin_budget_us(1) if spin_us is None else spin_us
    run, defaults = _run_with_defaults(defaults_sim, physics_hz)
    reader = ClockReader(run.instance)
    server = None
    try:
        server = JsonPhysicsServer(phys, ("127.0.0.1", sitl_port(run.instance)))
        run.launch(start_sitl, binary, run.instance, run.workdir, speedup=1000, home=sc.home,
                   defaults_path=defaults)
        reader.start()
        server.serve(duration_s, connect_timeout_s=60.0, spin_us=spin_us,
                     stop=run.stop_when(lambda: False, reader))
    finally:
        run.close(reader, server)


def measure_json_idle(binary: str, *, skip_s: float, span_s: float,
                      spin_us: float | None = None) -> dict:
    sc = load_scenario("S1")
    phys = ArduPilotPhysics(lambda: Simulator(sc))
    prof = phys.sink = _Profile(phys)
    _serve_json(binary, sc, phys, phys.sim, phys.physics_hz, skip_s + span_s, spin_us)
    return _profile(prof.rows, skip_s, span_s) | {
        "model": "JSON", "speedup": 1000,
        "spin_us": spin_budget_us(1) if spin_us is None else spin_us}


class _Clock:
    sim_ns = 0
    crashed = False
    crash_reason = ""


class _NoPhysics:
    """The floor: answers each servo packet at once with a vehicle at rest, the clock
    advancing 1 ms per packet, no physics and no decoding. What SITL and the two UDP hops
    cost per frame on this machine, whatever the physics does."""

    def __init__(self):
        self.sim = _Clock()
        self.rows: list = []
        self._rx = 0

    def handle(self, data, src, rx_wall_ns: int) -> bytes:
        self.sim.sim_ns += 1_000_000
        self._rx = rx_wall_ns
        return apj.encode_values((self.sim.sim_ns / _NS, 0.0, 0.0, 0.0, 0.0, 0.0, -9.80665,
                                  0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,
                                  0.0, 0.0, 0.0))

    def sent(self, tx_wall_ns: int) -> None:
        self.rows.append((self.sim.sim_ns, self._rx, self._rx, tx_wall_ns, 0))

    def stats(self) -> dict:
        return {}


def measure_json_floor(binary: str, *, skip_s: float, span_s: float) -> dict:
    sc = load_scenario("S1")
    phys = _NoPhysics()
    _serve_json(binary, sc, phys, Simulator(sc), 1000.0, skip_s + span_s, spin_budget_us(1))
    return _profile(phys.rows, skip_s, span_s) | {"model": "JSON, no physics"}


def measure_bench(binary: str, *, flight_s: float) -> dict:
    from silbridge.tools.autopilots.ardupilot.flight import fly_ardupilot
    out = tempfile.mkdtemp(prefix="silbridge-speed-bench-")
    try:
        s = fly_ardupilot(scenario="S1", seed=1, duration_s=flight_s,
                          log_path=os.path.join(out, "s1.mcap"), binary=binary, speedup=1000,
                          spin_us=spin_budget_us(1))
    finally:
        shutil.rmtree(out, ignore_errors=True)
    return {"realtime_factor": s["sim_s_total"] / max(s["wall_total_s"], 1e-9),
            "sim_s": s["sim_s_total"], "wall_s": s["wall_total_s"], "scenario": "S1"}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m silbridge.tools.autopilots.ardupilot.speed",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--arducopter", default=None, metavar="PATH",
                   help="arducopter binary (default $SILBRIDGE_ARDUCOPTER, then PATH)")
    add_deprecated_alias(p, "--sitl", "--arducopter")
    p.add_argument("--skip", type=float, default=5.0, metavar="S",
                   help="sim seconds of boot left out (default %(default)g)")
    p.add_argument("--span", type=float, default=30.0, metavar="S",
                   help="sim seconds measured (default %(default)g)")
    p.add_argument("--flight", type=float, default=30.0, metavar="S",
                   help="flight seconds of the bench run; 0 skips it (default %(default)g)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    try:
        binary = require_arducopter(args.arducopter)
    except SitlError as e:
        print(f"{p.prog}: {e}", file=sys.stderr)
        return 2
    ref = measure_reference(binary, skip_s=args.skip, span_s=args.span)
    idle = measure_json_idle(binary, skip_s=args.skip, span_s=args.span)
    floor = measure_json_floor(binary, skip_s=args.skip, span_s=args.span)
    bench = measure_bench(binary, flight_s=args.flight) if args.flight > 0 else None
    r = ref["realtime_factor"]
    out = {"binary": binary, "skip_s": args.skip, "span_s": args.span, "reference": ref,
           "json_idle": idle, "ratio_json_idle": idle["realtime_factor"] / r,
           "json_floor": floor, "ratio_json_floor": floor["realtime_factor"] / r}
    if bench is not None:
        out.update(bench=bench, ratio_bench=bench["realtime_factor"] / r)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"ArduCopter SITL {binary}")
    print(f"  own physics (--model quad --speedup 1000): {r:7.1f}x real time")
    print(f"  our physics, JSON, idle:                   {idle['realtime_factor']:7.1f}x "
          f"real time  ratio {out['ratio_json_idle']:.2f}")
    if "ours_us" in idle:
        print(f"    per servo packet: ours {idle['ours_us']['median']:.1f} us "
              f"(step {idle['ours_step_us']['median']:.1f} us), SITL + link "
              f"{idle['sitl_us']['median']:.1f} us (medians)")
    print(f"  no physics at all (the JSON link's floor): {floor['realtime_factor']:7.1f}x "
          f"real time  ratio {out['ratio_json_floor']:.2f}")
    if bench is not None:
        print(f"  our physics, bench run S1 (logged):        {bench['realtime_factor']:7.1f}x "
              f"real time  ratio {out['ratio_bench']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
