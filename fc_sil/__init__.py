"""silbridge.fc_sil: the SIL flight controller.

A portable C core (fc_sil/core: float32, no heap, no globals, no OS calls)
runs once per IMU sample and once per PWM period; Python drives it through
the compiled extension `_core` (fc_sil/ext). `FlightCore` (fc_sil.flight_core)
steps the whole chain on record batches; `fc_sil.blocks` wraps each block for
tests and experiments, through the test-only extension `_blocks`
(fc_sil/ext/blocks); `fc_sil.params` holds every parameter's declaration.
"""

from .status import STATUS_DTYPE

__all__ = ["STATUS_DTYPE"]
