"""`silbridge analyze LOG --spectrum`: the IMU's vibration peaks and the rotor harmonics.

The options of the spectrum mode (declared here, added to `analyze` by cmd_analyze.py)
and its two outputs: a table per IMU channel, or with --json one object
(tools/logs/spectrum_summary.py gives its shape). The log passes the integrity check
first, as for the metrics.
"""

from __future__ import annotations

import argparse
import json

from silbridge.tools.logs.spectrum_log import SENSORS, SpectrumError, window_of
from silbridge.tools.logs.spectrum_peaks import MIN_HZ
from silbridge.tools.logs.spectrum_summary import vibration_summary

SEGMENT_S = 1.0     # Welch segment: 1 Hz bins, 4 s of hover give 7 averaged segments
PEAKS = 5           # per axis: the rotor's 1x, 2x, 3x and room for a resonance or alias


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("spectrum (--spectrum)")
    g.add_argument("--spectrum", action="store_true",
                   help="print the gyro and accelerometer spectra's peaks and the rotor "
                        "harmonics they sit at, instead of the metrics")
    g.add_argument("--spectrum-window", nargs=2, type=float, metavar=("A_S", "B_S"),
                   default=None,
                   help="window in s of sim time (default: the analysis window, cut to "
                        "the log)")
    g.add_argument("--segment-s", type=float, default=SEGMENT_S, metavar="S",
                   help="Welch segment length in s: the frequency resolution is its "
                        "inverse (default %(default)g)")
    g.add_argument("--sensor", choices=(*SENSORS, "both"), default="both",
                   help="which sensor (default %(default)s)")
    g.add_argument("--peaks", type=int, default=PEAKS, metavar="N",
                   help="peaks per axis, largest first (default %(default)d)")
    g.add_argument("--min-hz", type=float, default=MIN_HZ, metavar="HZ",
                   help="lowest frequency searched for peaks, in Hz (default %(default)g)")
    g.add_argument("--track", action="store_true",
                   help="also follow the rotor harmonics 1x, 2x, 3x segment by segment "
                        "through throttle changes (needs rotor speed in the log)")


def run(args: argparse.Namespace, log, analysis: tuple[float, float], integrity) -> int:
    """Print the spectrum summary of an already checked log."""
    window = window_of(log, tuple(args.spectrum_window) if args.spectrum_window else None,
                       analysis)
    if args.peaks < 1:
        raise SpectrumError(f"--peaks {args.peaks}: give at least 1")
    sensors = list(SENSORS) if args.sensor == "both" else [args.sensor]
    summary = vibration_summary(log, window, args.segment_s, sensors, args.peaks, args.min_hz,
                                track=args.track)
    if args.json:
        print(json.dumps({"log": args.log, "ok": integrity.ok, "problems": integrity.problems,
                          "spectrum": summary}))
        return 0
    _print_table(args.log, summary, integrity)
    return 0


def _rotor_line(s: dict) -> str:
    r = s["rotor"]
    if r is None:
        return f"  rotor: {s['rotor_note']}: peaks carry no harmonic"
    motors = ", ".join(f"{v:.1f}" for v in r["per_motor_hz"])
    return (f"  rotor: median {r['median_hz']:.2f} Hz ({r['median_hz'] * 60:.0f} rpm; motors "
            f"{motors} Hz; spread +-{r['spread_hz']:.2f} Hz) from {r['source']}; "
            + ", ".join(f"{k}x {v:.1f} Hz" for k, v in r["harmonics_hz"].items()))


def _print_table(path: str, s: dict, integrity) -> None:
    a, b = s["window_s"]
    print(f"{path}: spectrum {a:g}-{b:g} s, Welch, Hann, {s['segment_s']:g} s segments, "
          f"{s['overlap'] * 100:.0f} % overlap, peaks above {s['min_hz']:g} Hz"
          + ("" if integrity.ok else " (integrity FAILED, forced)"))
    if s["window_note"]:
        print(f"  note: {s['window_note']}")
    print(_rotor_line(s))
    for ch in s["channels"]:
        print(f"  {ch['channel']}: {ch['rate_hz']:.0f} Hz, resolution {ch['resolution_hz']:.3g} Hz"
              f" ({ch['segments']} segments of {ch['segment_n']})")
        print(f"    {'axis':<8} {'band RMS':>12}  peaks: freq [Hz] amplitude (harmonic)")
        for axis, v in ch["axes"].items():
            peaks = "  ".join(_peak_cell(p) for p in v["peaks"]) or "none above the floor"
            print(f"    {axis:<8} {v['band_rms']:>8.3g} {v['unit']:<5} {peaks}")
        if "track" in ch:
            _print_track(ch)


def _peak_cell(p: dict) -> str:
    """freq amp, then (kx) at a rotor harmonic or (alias of F) where the chip shows it."""
    label = (f" ({p['harmonic']}x)" if p["harmonic"] else
             f" (alias of {p['alias_of_hz']:.1f})" if p.get("alias_of_hz") else "")
    return f"{p['freq_hz']:.1f} {p['amp']:.3g}{label}"


def _print_track(ch: dict) -> None:
    t = ch["track"]
    lo, hi = t["rotor_hz_range"] or (float("nan"), float("nan"))
    print(f"    harmonics followed in {t['segments']} segments of {t['segment_s']:g} s "
          f"({t['resolution_hz']:.3g} Hz bins), rotor {lo:.1f}-{hi:.1f} Hz: "
          "found/segments, |peak - k f_rot| median and max [% of k f_rot]")
    for axis, v in ch["axes"].items():
        cells = []
        for r in v["track"]:
            dev = ("" if r["median_dev_pct"] is None else
                   f" {r['median_dev_pct']:.2f}/{r['max_dev_pct']:.2f} %")
            cells.append(f"{r['k']}x {r['found']}/{r['segments']}{dev}")
        print(f"    {axis:<8} " + "   ".join(cells))
