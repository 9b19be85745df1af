"""The /fc/ftn1 and /fc/ftn2 channels: the in-flight FFT's results, as ArduCopter logs them.

ArduCopter writes FTN1 (TimeUS, PkAvg, BwAvg, SnX/Y/Z, FtX/Y/Z, FH, Tc) and FTN2 (TimeUS, Id,
PkX/Y/Z, BwX/Y/Z, EnX/Y/Z; Id 0 always, 1 and 2 when more than one peak is tracked) at 10 Hz
while FFT_ENABLE is set (AP_GyroFFT::write_log_messages). The C core appends the same rows at
10 Hz of IMU time straight into the log's queues (fc_sil/ext/core_fft.c, bind_fft_log); these
are their numpy views (declared in fc_sil/ftn_rows.py). Tc is the sim time the latest FFT frame took [us] (the core has no
wall clock; ArduCopter logs its thread's cycle time). ArduCopter sends no FFT message over
MAVLink, and neither does silbridge.
"""

from __future__ import annotations

from silbridge.fc_sil.ftn_rows import FTN1_CHANNEL, FTN1_DTYPE, FTN2_CHANNEL, FTN2_DTYPE

__all__ = ["FTN1_CHANNEL", "FTN1_DTYPE", "FTN2_CHANNEL", "FTN2_DTYPE", "bind_ftn"]


def bind_ftn(writer, core_c, enabled: bool) -> None:
    """Have the C core append FTN rows to `writer` (a LogWriter) while the FFT runs; the
    channels exist only in a log whose FC has FFT_ENABLE set, as in ArduCopter's."""
    if not enabled:
        core_c.bind_fft_log(None, None)
        return
    writer.declare(FTN1_CHANNEL, FTN1_DTYPE)
    writer.declare(FTN2_CHANNEL, FTN2_DTYPE)
    core_c.bind_fft_log(writer.queue(FTN1_CHANNEL), writer.queue(FTN2_CHANNEL))
