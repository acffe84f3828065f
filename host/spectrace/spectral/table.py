"""`SpectrumTable`: every spectrum of a scene in one flat float32 array for the device.

Spectrum k occupies `data[offset : offset + row_size]` with its samples at the table's wavelengths: the common grid
`GRID_NM` (row_size = GRID_SIZE), or the 1 nm grid of a film's own range (`film.wavelengths`), filled by each
spectrum's `on_wavelengths`, which refuses a spectrum that does not reach that far. The kernels lerp inside that
slice. Identical spectra (equal after rounding to float32) are stored once.
"""

import numpy as np

from spectrace.spectral.grid import GRID_NM, GRID_SIZE
from spectrace.spectral.spectrum import Spectrum


class SpectrumTable:
    def __init__(self, wavelengths_nm: np.ndarray | None = None, extend_rgb: bool = False) -> None:
        """wavelengths_nm: the table's grid (default: the common grid); extend_rgb: RGB uplifts may be continued
        beyond the common grid (their sigmoid, a convention)."""
        self.wavelengths_nm = GRID_NM if wavelengths_nm is None else np.asarray(wavelengths_nm, np.float64)
        self.row_size = int(self.wavelengths_nm.size)
        self._common_grid = wavelengths_nm is None or np.array_equal(self.wavelengths_nm, GRID_NM)
        self.extend_rgb = extend_rgb
        self._offsets_by_content: dict[bytes, int] = {}
        self._blocks_by_key: dict[int, tuple[object, int]] = {}
        self._rows: list[np.ndarray] = []
        self._data: np.ndarray | None = None  # built on demand, dropped on add

    def add(self, spectrum: Spectrum) -> int:
        """Store `spectrum` (once) and return the offset, in floats, of its first sample in `data`."""
        if not isinstance(spectrum, Spectrum):
            raise TypeError(f"SpectrumTable.add expects a Spectrum, got {type(spectrum).__name__}")
        if self._common_grid:
            return self._add(spectrum.values)
        return self._add(spectrum.on_wavelengths(self.wavelengths_nm, extend_rgb=self.extend_rgb))

    def add_row(self, values: np.ndarray) -> int:
        """Store GRID_SIZE values that are not a spectrum (a function the kernels tabulate on as many points, such
        as a rough coat's transmittance in cos θ, spectrace.materials.coat) and return their offset. On a table of
        another row size the function is resampled to that many evenly spaced points."""
        if np.shape(values) != (GRID_SIZE,):
            raise ValueError(f"a table row has {GRID_SIZE} values, got shape {np.shape(values)}")
        if not self._common_grid:
            values = np.interp(np.linspace(0.0, 1.0, self.row_size), np.linspace(0.0, 1.0, GRID_SIZE), values)
        return self._add(values)

    def add_block(self, values: np.ndarray, key: object = None) -> int:
        """Store floats that are no function of the wavelength or of anything else (a material's parameter block,
        read by index) and return their offset: consecutive, padded to whole rows, shared with no other entry.
        `key`: an object standing for the block's content (held here), whose block is stored once however often it
        is added, as a live session's edits add every material's again."""
        if key is not None and (known := self._blocks_by_key.get(id(key))) is not None and known[0] is key:
            return known[1]
        values = np.asarray(values, np.float32).ravel()
        rows = max(1, -(-values.size // self.row_size))
        padded = np.zeros(rows * self.row_size, np.float32)
        padded[: values.size] = values
        offset = len(self._rows) * self.row_size
        self._rows.extend(padded.reshape(rows, self.row_size))
        self._data = None
        if key is not None:
            self._blocks_by_key[id(key)] = (key, offset)
        return offset

    def _add(self, values: np.ndarray) -> int:
        row = np.asarray(values).astype(np.float32)
        key = row.tobytes()
        offset = self._offsets_by_content.get(key)
        if offset is None:
            offset = len(self._rows) * self.row_size
            self._offsets_by_content[key] = offset
            self._rows.append(row)
            self._data = None
        return offset

    @property
    def data(self) -> np.ndarray:
        """All stored spectra back to back: float32, shape (len(self) * row_size,), read-only."""
        if self._data is None:
            data = np.concatenate(self._rows) if self._rows else np.zeros(0, dtype=np.float32)
            data.setflags(write=False)
            self._data = data
        return self._data

    def __len__(self) -> int:
        """Number of distinct spectra stored."""
        return len(self._rows)
