"""Fly scenario S1 twice, with the default gains and with a changed roll-rate D gain,
and print the paper's metrics side by side.

    python examples/fly_and_compare.py                   # the scenario's 120 s
    python examples/fly_and_compare.py --duration 30     # quicker; shorter windows

Each flight is deterministic (lockstep, same seed): run it again and the numbers
are the same, so any difference between the columns is the gain's doing.
"""

import argparse

import silbridge

CHANGE = {"ATC_RAT_RLL_D": 0.004}        # its default: `silbridge params show ATC_RAT_RLL_D`

ROWS = [                                  # (metric key, label)
    ("att_rms_deg", "attitude error RMS [deg]"),
    ("att_p95_deg", "attitude error P95 [deg]"),
    ("att_rms_roll_deg", "roll error RMS [deg]"),
    ("pwm_pp_us", "PWM peak-to-peak [us]"),
    ("sat_pct", "saturation [%]"),
    ("cr_us", "roll mixer input cr [us]"),
]


def main() -> None:
    parser = argparse.ArgumentParser(description="fly S1 with default and changed gains")
    parser.add_argument("--duration", type=float, default=None,
                        help="simulated seconds per flight (default: the scenario's)")
    args = parser.parse_args()

    base = silbridge.fly(scenario="S1", duration_s=args.duration)
    changed = silbridge.fly(scenario="S1", duration_s=args.duration, params=CHANGE)

    label = ", ".join(f"{k}={v:g}" for k, v in CHANGE.items())
    print(f"silbridge {silbridge.__version__}: S1, {base.sim_s:g} s simulated per flight")
    print(f"{'metric':<28}{'defaults':>12}{label:>24}")
    for key, name in ROWS:
        print(f"{name:<28}{base.metrics[key]:>12.4f}{changed.metrics[key]:>24.4f}")
    if base.metrics["window_note"]:
        print(f"note: {base.metrics['window_note']}")


if __name__ == "__main__":
    main()
