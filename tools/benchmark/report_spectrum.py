"""The report's vibration figures of one run: spectrum and spectrogram of gyro and accel.

Spectrum: Welch's average over the analysis window (tools/logs/spectrum.py), amplitude per
body axis on a log scale, one panel per sensor, with the rotor harmonics 1x (imbalance),
2x (blade pass of a two-blade prop) and 3x marked at the median rotor frequency of the
window. Spectrogram: the whole log, the three axes' amplitudes combined (root sum of
squares), in dB, with k x the rotor frequency drawn over time, so a harmonic that follows
the throttle shows as a ridge under its line. Without rotor speed in the log, nothing is
marked and the title and caption say "no rotor speed in this log".
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from silbridge.tools.logs.spectrum import spectrogram
from silbridge.tools.logs.spectrum_log import (AXES, IMU_CHANNEL, NO_ROTOR, SENSORS,
                                               SpectrumError, channel_spectra, imu_channels,
                                               rotor_ref, rotor_series, sample_rate_hz,
                                               window_of)
from silbridge.tools.logs.spectrum_summary import HARMONICS_MARKED

SPECTRUM_SEGMENT_S = 1.0        # 1 Hz bins, as `analyze --spectrum`
SPECTROGRAM_SEGMENT_S = 0.25    # 4 Hz bins every 0.125 s: follows a throttle change
_LABEL = {1: "1x", 2: "2x blade pass", 3: "3x"}


def _rotor_track(log) -> tuple[np.ndarray, np.ndarray] | None:
    """(t_s, median rotor frequency of the motors [Hz]) over the log, None without."""
    series = rotor_series(log)
    if series is None:
        return None
    hz = np.median(series[1], axis=1)
    return series[0], np.where(hz > 1.0, hz, np.nan)        # no line while stopped


def _spectrum_figure(plt, log, channel, a_s, b_s, ref, path: Path, title: str) -> None:
    _rate, spectra = channel_spectra(log, channel, a_s, b_s, SPECTRUM_SEGMENT_S, list(SENSORS))
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    for ax, (sensor, (_col, unit)) in zip(axes, SENSORS.items()):
        sp = spectra[sensor]
        for i, name in enumerate(AXES):
            ax.semilogy(sp.freq_hz[1:], sp.amp[1:, i], lw=0.7, label=f"{sensor} {name}")
        if ref is not None:
            for k in HARMONICS_MARKED:
                ax.axvline(k * ref.median_hz, color="k", ls="--", lw=0.6, alpha=0.6)
                ax.text(k * ref.median_hz, 1.0, f" {_LABEL[k]}", transform=ax.get_xaxis_transform(),
                        va="top", fontsize=7)
        ax.set_ylabel(f"amplitude [{unit}]")
        ax.legend(loc="upper right", fontsize=7, ncol=3)
    axes[-1].set_xlabel("frequency [Hz]")
    axes[0].set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _spectrogram_figure(plt, log, track, path: Path, title: str) -> None:
    rows = log.channels[IMU_CHANNEL]
    rate = sample_rate_hz(rows["sim_ns"])
    if len(rows) < 2 * SPECTROGRAM_SEGMENT_S * rate:
        raise SpectrumError(f"{IMU_CHANNEL}: too short for a spectrogram")
    t0 = float(rows["sim_ns"][0]) * 1e-9
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    for ax, (sensor, (col, unit)) in zip(axes, SENSORS.items()):
        sg = spectrogram(rows[col], rate, int(round(SPECTROGRAM_SEGMENT_S * rate)), t0)
        combined = np.sqrt((sg.amp ** 2).sum(axis=2))           # (n_seg, n_bins)
        db = 20.0 * np.log10(np.maximum(combined, 1e-12))
        top = float(db.max())
        mesh = ax.pcolormesh(sg.t_s, sg.freq_hz, db.T, shading="nearest", cmap="viridis",
                             vmin=top - 60.0, vmax=top)
        fig.colorbar(mesh, ax=ax, label=f"dB re 1 {unit}")
        if track is not None:
            for k in HARMONICS_MARKED:
                ax.plot(track[0], k * track[1], color="w", ls="--", lw=0.6, alpha=0.8)
                ax.text(track[0][-1], k * track[1][-1], f"{_LABEL[k]} ", color="w",
                        ha="right", va="bottom", fontsize=7)
        ax.set_ylim(0, rate / 2)
        ax.set_ylabel(f"{sensor} [Hz]")
    axes[-1].set_xlabel("sim time [s]")
    axes[0].set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _spectrum_caption(name: str, who: str, ch: str, a_s: float, b_s: float, ref) -> str:
    head = (f"{name}, {who}: amplitude spectrum of gyro and accelerometer ({ch}, Welch, Hann, "
            f"{SPECTRUM_SEGMENT_S:g} s segments) over {a_s:g}-{b_s:g} s; ")
    if ref is None:
        return head + f"{NO_ROTOR}: no harmonic marked."
    return head + (f"dashed: the rotor harmonics 1x, 2x (blade pass), 3x at rotor "
                   f"{ref.median_hz:.1f} Hz (median of the motors over the window).")


def spectrum_plots(plt, log, name: str, out_dir: Path, analysis: tuple[float, float],
                   who: str) -> list[tuple[str, str]]:
    """[(file name, caption)] of the run's spectra (analysis window, cut to the log) and
    spectrogram (whole run). A log without IMU data, or too short for one segment, has no
    such figure: the report goes on without it."""
    files = []
    stem = name.replace(" ", "_")
    try:
        a_s, b_s, _note = window_of(log, None, analysis)
        ref = rotor_ref(log, a_s, b_s)
        rotor = f"rotor {ref.median_hz:.1f} Hz" if ref else NO_ROTOR
        for ch in imu_channels(log):
            fname = f"{stem}_spectrum{ch.replace('/', '_')}.png"
            _spectrum_figure(plt, log, ch, a_s, b_s, ref, out_dir / fname,
                             f"{name}: {ch} spectrum {a_s:g}-{b_s:g} s, {who}; {rotor}")
            files.append((fname, _spectrum_caption(name, who, ch, a_s, b_s, ref)))
        if IMU_CHANNEL not in imu_channels(log):
            return files
        track = _rotor_track(log)
        fname = f"{stem}_spectrogram.png"
        _spectrogram_figure(plt, log, track, out_dir / fname,
                            f"{name}: {IMU_CHANNEL} spectrogram, {who}"
                            + ("" if track is not None else f"; {NO_ROTOR}"))
        files.append((fname, f"{name}, {who}: spectrogram of gyro and accelerometer "
                      f"({IMU_CHANNEL}, {SPECTROGRAM_SEGMENT_S:g} s Hann segments, three axes "
                      "combined, dB); "
                      + ("dashed: 1x, 2x (blade pass) and 3x the rotor frequency over time."
                         if track is not None else f"{NO_ROTOR}: no harmonic marked.")))
    except SpectrumError:       # too short for a segment: the figures made so far stay
        pass
    return files
