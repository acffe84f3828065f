"""`SpectrumTable`: every spectrum of a scene in one flat float32 array for the device.

Spectrum k occupies `data[offset : offset + GRID_SIZE]` with its samples at `GRID_NM`; the kernels
lerp inside that slice. Identical spectra (equal after rounding to float32) are stored once.
"""

import numpy as np

from spectrace.spectral.grid import GRID_SIZE
from spectrace.spectral.spectrum import Spectrum


class SpectrumTable:
    def __init__(self) -> None:
        self._offsets_by_content: dict[bytes, int] = {}
        self._rows: list[np.ndarray] = []
        self._data: np.ndarray | None = None  # built on demand, dropped on add

    def add(self, spectrum: Spectrum) -> int:
        """Store `spectrum` (once) and return the offset, in floats, of its first sample in `data`."""
        if not isinstance(spectrum, Spectrum):
            raise TypeError(f"SpectrumTable.add expects a Spectrum, got {type(spectrum).__name__}")
        return self.add_row(spectrum.values)

    def add_row(self, values: np.ndarray) -> int:
        """Store GRID_SIZE values that are not a spectrum (a function the kernels tabulate on as many points, such
        as a rough coat's transmittance in cos θ, spectrace.materials.coat) and return their offset."""
        if np.shape(values) != (GRID_SIZE,):
            raise ValueError(f"a table row has {GRID_SIZE} values, got shape {np.shape(values)}")
        row = np.asarray(values).astype(np.float32)
        key = row.tobytes()
        offset = self._offsets_by_content.get(key)
        if offset is None:
            offset = len(self._rows) * GRID_SIZE
            self._offsets_by_content[key] = offset
            self._rows.append(row)
            self._data = None
        return offset

    @property
    def data(self) -> np.ndarray:
        """All stored spectra back to back: float32, shape (len(self) * GRID_SIZE,), read-only."""
        if self._data is None:
            data = np.concatenate(self._rows) if self._rows else np.zeros(0, dtype=np.float32)
            data.setflags(write=False)
            self._data = data
        return self._data

    def __len__(self) -> int:
        """Number of distinct spectra stored."""
        return len(self._rows)
