"""The rows of the in-flight FFT's FTN1/FTN2 log messages (fc_sil/ext/core_fft.c appends
them in C; the log channels are tools/logs/ftn_log.py). One description, read by both."""

from __future__ import annotations

import numpy as np

FTN1_CHANNEL = "/fc/ftn1"
FTN2_CHANNEL = "/fc/ftn2"
FTN1_DTYPE = np.dtype([
    ("sim_ns", "<i8"),              # IMU time of the row [ns] (TimeUS)
    ("pk_avg_hz", "<f4"),           # PkAvg: energy-weighted roll/pitch noise frequency [Hz]
    ("bw_avg_hz", "<f4"),           # BwAvg: its -FFT_ATT_REF dB bandwidth [Hz]
    ("snr_db", "<f4", (3,)),        # SnX, SnY, SnZ [dB]
    ("fit_pct", "<f4", (3,)),       # FtX, FtY, FtZ: harmonic fit [%] (100: none)
    ("cycle_us", "<u4"),            # Tc: sim time of the latest frame [us]
    ("health", "u1"),               # FH: healthy peaks
    ("pad", "u1", (3,)),
])
FTN2_DTYPE = np.dtype([
    ("sim_ns", "<i8"),              # IMU time of the row [ns] (TimeUS)
    ("pk_hz", "<f4", (3,)),         # PkX, PkY, PkZ: the slot's tracked frequency [Hz]
    ("bw_hz", "<f4", (3,)),         # BwX, BwY, BwZ [Hz]
    ("energy", "<f4", (3,)),        # EnX, EnY, EnZ: peak power x width x 5/6 [counts^2 Hz]
    ("id", "u1"),                   # Id: 0 centre (strongest), 1 lower, 2 upper shoulder
    ("pad", "u1", (3,)),
])
