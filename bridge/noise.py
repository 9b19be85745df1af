"""Seeded noise streams, drawn in vectorised blocks.

All randomness of a run comes from the scenario seed. Each consumer (IMU
white noise, IMU bias walk, baro, mag, GNSS, vibration phases, JSBSim's
turbulence seed) gets its own stream, keyed by the seed and the stream name
(`scenario.draw_rng`). A stream draws standard normals row by row in C order,
so the values a consumer sees do not depend on the block size: a block of
1024 rows and two blocks of 512 give the same numbers (a test pins this).
Blocks amortise the numpy call (~1 us) over many physics steps.
"""

from __future__ import annotations

import numpy as np

from silbridge.bridge.scenario import draw_rng

DEFAULT_BLOCK_ROWS = 1024


class NormalRows:
    """Rows of `width` standard normals (times `scale` per column) from one named stream.

    ``next_row()`` returns a list of floats (scalar code), ``take(n)`` an
    (n, width) float64 array, ``next_block()`` the next `block_rows` rows.
    """

    def __init__(self, seed: int, name: str, width: int, block_rows: int = DEFAULT_BLOCK_ROWS,
                 scale=None):
        if block_rows < 1:
            raise ValueError("block_rows must be >= 1")
        self._rng = draw_rng(seed, "noise:" + name)
        # Optional per-column scale applied once per block (sigma of each channel).
        self._scale = None if scale is None else np.asarray(scale, dtype=float)
        self.width = width
        self.block_rows = block_rows
        self._block = np.empty((0, width))
        self._flat: list = []
        self._pos = 0          # next row within _block

    def _refill(self) -> None:
        self._block = self._rng.standard_normal((self.block_rows, self.width))
        if self._scale is not None:
            self._block *= self._scale
        self._flat = []
        self._pos = 0

    def next_row(self) -> list:
        if self._pos >= self._block.shape[0]:
            self._refill()
        if not self._flat:
            self._flat = self._block.ravel().tolist()
        w = self.width
        i = self._pos * w
        self._pos += 1
        return self._flat[i:i + w]

    def take(self, n: int) -> np.ndarray:
        if n <= self._block.shape[0] - self._pos:
            out = self._block[self._pos:self._pos + n]
            self._pos += n
            return out
        parts = []
        while n > 0:
            if self._pos >= self._block.shape[0]:
                self._refill()
            k = min(n, self._block.shape[0] - self._pos)
            parts.append(self._block[self._pos:self._pos + k])
            self._pos += k
            n -= k
        return np.concatenate(parts) if len(parts) > 1 else parts[0]

    def next_block(self) -> np.ndarray:
        return self.take(self.block_rows)

    def current_block(self) -> tuple[np.ndarray, int]:
        """(the block the next row comes from, that row's index in it), a fresh block
        when this one is used up: for a reader in C that takes the rows in place and says
        afterwards where it stopped (`seek`)."""
        if self._pos >= self._block.shape[0]:
            self._refill()
        return self._block, self._pos

    def seek(self, pos: int) -> None:
        """The rows of the current block before `pos` were taken elsewhere (current_block)."""
        if not 0 <= pos <= self._block.shape[0]:
            raise ValueError(f"row {pos} is outside the block of {self._block.shape[0]} rows")
        self._pos = pos
