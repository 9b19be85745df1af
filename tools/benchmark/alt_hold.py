"""Altitude hold of flights, from their run logs: RMS of true altitude about the commanded one.

    python -m silbridge.tools.benchmark.alt_hold bench-out/logs/px4/*.mcap [--from 30] [--json]

Table 1 scores attitude; a hover benchmark also asks how well the altitude was held. For
every log: the true altitude (-down of /gt_nav) from `--from` seconds of log time to its
end (default 30 s: after the paper's warm-up and transient windows), against the scenario's
take-off altitude (the altitude S1..S4 command): RMS, mean and largest error, in metres.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from silbridge.tools.logs.mcap_log import read_log


def alt_hold(path: str, from_s: float = 30.0) -> dict:
    log = read_log(path)
    nav = log.channels["/gt_nav"]
    sel = nav["sim_ns"] >= int(from_s * 1e9)
    if not sel.any():
        raise SystemExit(f"alt_hold: {path} ends before {from_s:g} s; give a smaller --from")
    alt = -nav["pos_ned_m"][sel][:, 2]
    cmd = float(log.metadata["scenario"]["takeoff_alt_m"])
    err = alt - cmd
    return {"log": path, "fc": log.metadata.get("config", {}).get("fc", "ours"),
            "scenario": log.metadata["scenario"].get("name"), "cmd_alt_m": cmd,
            "from_s": from_s, "alt_rms_m": float(np.sqrt(np.mean(err ** 2))),
            "alt_mean_m": float(alt.mean()), "alt_max_err_m": float(np.abs(err).max())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m silbridge.tools.benchmark.alt_hold",
                                 description=__doc__.split("\n")[0])
    ap.add_argument("logs", nargs="+")
    ap.add_argument("--from", dest="from_s", type=float, default=30.0, metavar="S")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    rows = [alt_hold(p, args.from_s) for p in args.logs]
    if args.json:
        print(json.dumps(rows))
    else:
        for r in rows:
            print(f"{r['scenario']} {r['fc']}: altitude RMS {r['alt_rms_m']:.3f} m about "
                  f"{r['cmd_alt_m']:g} m (mean {r['alt_mean_m']:.2f} m, max error "
                  f"{r['alt_max_err_m']:.2f} m) from {r['from_s']:g} s  [{r['log']}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
