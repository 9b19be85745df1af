"""silbridge.fc_sil: the SIL flight controller.

A portable C core (fc_sil/core: float32, no heap, no globals, no OS calls)
runs once per IMU sample and once per PWM period; Python drives it through
the compiled extension `_core` (fc_sil/ext). `FlightCore` (fc_sil.flight_core)
steps the whole chain on record batches; `fc_sil.params` holds every
parameter's declaration. The tests bind each block on its own with cffi, from
the core's headers (tests/fc_sil/fc_blocks.py).
"""

from .status import STATUS_DTYPE

__all__ = ["STATUS_DTYPE"]
