"""Generate docs/params.md from the one parameter declaration (fc_params.def).

    python -m silbridge.tools.gen_param_doc            # rewrite docs/params.md
    python -m silbridge.tools.gen_param_doc --check    # exit 1 if it is stale

tests/fc_sil/test_params.py runs the check, so the page cannot drift from the
declaration.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from silbridge.fc_sil.params import ABLATION_FEATURES, BY_NAME, DEF_PATH, FEATURES, PARAMS
from silbridge.tools.param_effects import effect, gcs_params

DOC_PATH = Path(__file__).resolve().parent.parent / "docs" / "params.md"


def _num(v: float, typ: str) -> str:
    return str(int(v)) if typ != "FLOAT" else f"{v:g}"


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def render() -> str:
    out = [
        "# silbridge flight-controller parameters",
        "",
        "Generated from `fc_sil/core/fc_params.def` by `tools/gen_param_doc.py`; do not edit "
        "by hand (`python -m silbridge.tools.gen_param_doc` rewrites it).",
        "",
        "ArduCopter 4.6 names and defaults where ArduCopter has the parameter; `SB_` names for "
        "the paper's own features. The index is the permanent slot (never renumbered). "
        "*Where*: `core` parameters live in the C core's struct (validated and effective at "
        "once, filters recomputed); `host` parameters are kept by the Python runtime. "
        "*Effect in SIL*: `acts` with the code that reads it, or `no effect in SIL` (accepted, "
        "range-checked, served over MAVLink and saved in `.parm` files, as ArduCopter keeps "
        "it; nothing in a simulator uses it: serial ports, sensor ids, LEDs, ...).",
        "",
        "Deliberate departures from ArduCopter defaults: `ATC_ANG_YAW_P` 0 (the paper's yaw "
        "rate damping; set > 0 for heading hold) and `MOT_SLEW_UP_TIME`/`MOT_SLEW_DN_TIME` "
        "0.05 s (ArduCopter 0 = off) so the paper's slew limit acts by default. The "
        "ground-station block (indices 1000-2999) has ArduCopter 4.6.0's types and firmware "
        "defaults, except the values ArduCopter SITL's copter.parm sets so QGroundControl's "
        "setup pages show as done (`FRAME_CLASS` 1, `RC1..8_MIN/MAX` 1000/2000, "
        "`INS_ACCOFFS_*` 0.001, `BATT_MONITOR` 4) and one simulated sensor of each kind "
        "(the second and third compass, IMU and barometer ids are 0).",
        "",
        "| Index | Name | Type | Default | Min | Max | Unit | Where | Effect in SIL | Description |",
        "|---:|---|---|---:|---:|---:|---|---|---|---|",
    ]
    for p in PARAMS:
        out.append(f"| {p.index} | `{p.name}` | {p.type} | {_num(p.default, p.type)} | "
                   f"{_num(p.min, p.type)} | {_num(p.max, p.type)} | {_cell(p.unit)} | "
                   f"{'host' if p.host else 'core'} | {effect(p)} | {_cell(p.text)} |")
    out += [
        "",
        "## Stabilisation features (ablation switches)",
        "",
        "`FlightCore.set_feature(name, on)` sets the enable parameter; the paper's ablation "
        "(`silbridge ablate`) flies the paper's controller with every marked feature on "
        "(`full`, whatever the default), then each marked one off alone, then all off, and "
        "the defaults. The ablation also decided the defaults (CHANGELOG.md, \"The flight "
        "controller\"): off "
        "are the features whose removal lost nothing measurable in S1..S4 and A1..A4, and "
        "the PT2x2 D filter, whose removal buys 5.2 us of S4 PWM p-p for 0.006 deg of S4 "
        "tracking (N = 20).",
        "",
        "| Feature | Parameter | Default | In the paper's ablation |",
        "|---|---|---|---|",
    ]
    for name, param in FEATURES.items():
        on = "on" if BY_NAME[param].default else "off"
        out.append(f"| `{name}` | `{param}` | {on} | "
                   f"{'yes' if name in ABLATION_FEATURES else 'no'} |")
    out += _gcs_section()
    out.append("")
    return "\n".join(out)


def _gcs_section() -> list[str]:
    """The parameters QGroundControl and MAVProxy read (docs/gcs_params.txt) and their fate."""
    gcs = gcs_params()
    read = [n for n, src in gcs.items() if any(s.startswith(("qgc:", "mavproxy:")) for s in src)]
    acts = sum(1 for n in gcs if n in BY_NAME and not effect(BY_NAME[n]).startswith("no"))
    out = ["", "## Parameters ground stations read", "",
           f"{len(read)} ArduCopter parameters are read by name by QGroundControl's ArduPilot "
           "setup pages (airframe, radio, flight modes, sensors, power, safety, tuning, camera) "
           "and plan managers, and by MAVProxy's modules (`docs/gcs_params.txt` names the files); "
           f"with RCn_DZ for the RC calibration the list has {len(gcs)}. "
           f"{sum(1 for n in gcs if n in BY_NAME)} are declared here, {acts} of them act in SIL.",
           "", "| Name | Effect in SIL | Read by |", "|---|---|---|"]
    for name, sources in gcs.items():
        fx = effect(BY_NAME[name]) if name in BY_NAME else "not declared"
        out.append(f"| `{name}` | {fx} | {', '.join(s.split('/')[-1] for s in sources)} |")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if docs/params.md is stale")
    ap.add_argument("--output", type=Path, default=DOC_PATH)
    args = ap.parse_args(argv)
    text = render()
    if args.check:
        current = args.output.read_text() if args.output.exists() else ""
        if current != text:
            print(f"{args.output} is out of date with {DEF_PATH}; run "
                  "`python -m silbridge.tools.gen_param_doc`", file=sys.stderr)
            return 1
        return 0
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
