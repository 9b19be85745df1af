"""The floor of every lockstep figure: how fast bare JSBSim `run()` steps our quadx model at the
physics rate of scenario S1 (1 kHz), on one core, with nothing of ours around it.

The model is loaded the way the bridge loads it (bridge/simulator.py builds bridge/fdm.py's
Fdm from the scenario: same model, home, integrators), placed 20 m up and spun to the
open-loop hover PWM through the simulator's own steps, so the timed steps are the airborne
case a hover run spends its time in (no ground contact). Then only `FGFDMExec.run()` is timed,
in blocks, by the wall clock, as a run's real-time factor is: the figure is sim seconds per
wall second, comparable with `realtime_factor` of a bench run. The median block is reported
(a loaded machine shows in it, as it shows in the campaign measured beside it), and the best.

    python -m silbridge.tools.docs.jsbsim_speed [--steps 5000] [--blocks 7]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

AIRBORNE_AGL_M = 20.0     # high enough that a few seconds of open-loop hover never touch down
SPIN_UP_STEPS = 200       # motors reach hover speed, the integrator switches to the air one


def measure(steps: int = 5000, blocks: int = 7, scenario: str = "S1") -> dict:
    """Bare `run()` speed: {'realtime_factor', 'best_realtime_factor', 'us_per_step', ...}."""
    from silbridge.bridge.scenario import load_scenario
    from silbridge.bridge.simulator import Simulator

    sc = load_scenario(scenario, overrides={"home.initial_agl_m": AIRBORNE_AGL_M})
    sim = Simulator(sc)
    hover = [sim.hover_pwm_us] * 4
    for _ in range(SPIN_UP_STEPS):
        sim.step(hover)
    run = sim.fdm.fdm.run
    per_step_s = []
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(steps):
            run()
        per_step_s.append((time.perf_counter() - t0) / steps)
    median, best = statistics.median(per_step_s), min(per_step_s)
    return {"realtime_factor": sim.dt_s / median, "best_realtime_factor": sim.dt_s / best,
            "us_per_step": median * 1e6, "physics_hz": sim.physics_hz, "model":
            sc.physics.model, "steps": steps, "blocks": blocks, "scenario": scenario}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m silbridge.tools.docs.jsbsim_speed",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=int, default=5000, help="steps per timed block "
                   "(default %(default)s)")
    p.add_argument("--blocks", type=int, default=7, help="timed blocks (default %(default)s)")
    args = p.parse_args(argv)
    print(json.dumps(measure(args.steps, args.blocks)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
