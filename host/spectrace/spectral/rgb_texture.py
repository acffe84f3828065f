"""RGB textures -> sigmoid-polynomial coefficients per texel, many colours at once.

The vectorised counterpart of `uplift.py`'s `uplift_reflectance` and `illuminant_coefficients`: a texel's
coefficients (lambda in nm, the same convention) come from the coefficient table of `uplift_table.py` by trilinear
interpolation, about a microsecond a colour where the one-colour fit takes 0.3..20 ms. Every colour is computed on
its own (no sums across colours), so a texel's coefficients are the same bits whatever image it is in.

`texture_reflectance_coefficients` and `texture_illuminant_coefficients` add a cache per texture, keyed by a hash
of its decoded (linear) pixels: in memory for this process, and on disk under the cache folder (`uplift/textures`),
bounded in size (least recently used files go first), so loading the same texture again, in this process or
another, reads the result instead of recomputing it.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import threading
from collections import OrderedDict
from pathlib import Path

import numpy as np

from spectrace.cache_folder import cache_root
from spectrace.errors import SpectraceError
from spectrace.io.atomic import write_atomically
from spectrace.spectral import uplift_table
from spectrace.spectral.uplift import _CENTRE_NM, _HALF_SPAN_NM, SATURATED_SIGMOID_ARGUMENT

_CHUNK = 1 << 16  # colours per pass: the temporaries stay in cache; results do not depend on it
_BLACK = np.array([0.0, 0.0, -SATURATED_SIGMOID_ARGUMENT])
_WHITE = np.array([0.0, 0.0, SATURATED_SIGMOID_ARGUMENT])


def _dimensionless_to_nm(coefficients: np.ndarray) -> np.ndarray:
    # a t^2 + b t + c with t = (lambda - m) / h, in powers of lambda; `uplift._dimensionless_to_nm` row-wise.
    a, b, c = coefficients[:, 0], coefficients[:, 1], coefficients[:, 2]
    m, h = _CENTRE_NM, _HALF_SPAN_NM
    return np.stack([a / h**2, b / h - 2 * a * m / h**2, a * m**2 / h**2 - b * m / h + c], axis=1)


def _validated(rgb: np.ndarray, what: str, where: str | None, upper: float | None) -> np.ndarray:
    try:
        values = np.asarray(rgb, dtype=np.float64)
    except (TypeError, ValueError):
        raise SpectraceError(f"{what} must be an array of numbers", where=where) from None
    if values.ndim == 0 or values.shape[-1] != 3:
        raise SpectraceError(f"{what} must have three channels on its last axis, got shape {values.shape}", where=where)
    if not np.all(np.isfinite(values)):
        raise SpectraceError(f"{what} must be finite (it holds NaN or infinite values)", where=where)
    if values.size and values.min() < 0.0:
        raise SpectraceError(f"{what} must not be negative (smallest value {values.min():.6g})", where=where)
    if upper is not None and values.size and values.max() > upper:
        raise SpectraceError(
            f"{what} must lie in [0, {upper:g}] (linear sRGB), largest value {values.max():.6g}", where=where
        )
    return values


def _colour_keys(rgb: np.ndarray) -> np.ndarray:
    """A 64-bit hash of each row's bits: sorting these is several times faster than sorting rows of three floats."""
    bits = np.ascontiguousarray(rgb, dtype=np.float64).view(np.uint64)
    key = bits[:, 0] * np.uint64(0x9E3779B97F4A7C15)
    key = (key ^ bits[:, 1]) * np.uint64(0xC2B2AE3D27D4EB4F)
    return (key ^ bits[:, 2]) * np.uint64(0x165667B19E3779F9)


def _distinct_rows(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(distinct colours, index of each row's colour among them), or None when a hash collision (about never)
    spoils the grouping."""
    _, first, inverse = np.unique(_colour_keys(rgb), return_index=True, return_inverse=True)
    distinct = rgb[first]
    if not np.array_equal(distinct[inverse], rgb):
        return None
    return distinct, inverse


_SAMPLE = 1 << 14


def _worth_grouping(rgb: np.ndarray) -> bool:
    """Whether under ~70 % of the rows are distinct colours, judged from evenly spaced rows: k rows drawn from D
    equally common colours repeat about k^2 / (2 D) times (more when some colours are common, as in photographs,
    which then count as repetitive, rightly). A noise-like texture is then not sorted for nothing."""
    if len(rgb) < 2 * _SAMPLE:
        return True
    sample = rgb[:: len(rgb) // _SAMPLE][:_SAMPLE]
    repeats = _SAMPLE - len(np.unique(_colour_keys(sample)))
    return repeats > _SAMPLE**2 / (2 * 0.7 * len(rgb))


def _reflectance_rows(rgb: np.ndarray) -> np.ndarray:
    """(N, 3) linear sRGB in [0, 1] -> (N, 3) coefficients in nm; a colour repeated in a texture is computed once
    (with the same bits as alone: every colour is computed independently)."""
    if len(rgb) >= _SAMPLE and _worth_grouping(rgb) and (grouped := _distinct_rows(rgb)) is not None:
        distinct, inverse = grouped
        return _distinct_reflectance_rows(distinct)[inverse]
    return _distinct_reflectance_rows(rgb)


def _distinct_reflectance_rows(rgb: np.ndarray) -> np.ndarray:
    table = uplift_table.coefficient_table()
    result = np.empty((len(rgb), 3))
    for first in range(0, len(rgb), _CHUNK):
        chunk = rgb[first : first + _CHUNK]
        largest = chunk.max(axis=1)
        black = largest == 0.0
        white = chunk.min(axis=1) == 1.0  # as `uplift_reflectance`: the constants, which no finite fit reaches
        inside = ~(black | white)
        out = result[first : first + _CHUNK]
        out[black] = _BLACK
        out[white] = _WHITE
        out[inside] = _dimensionless_to_nm(uplift_table.coefficients_from_table(table, chunk[inside]))
    return result


def reflectance_coefficients(rgb: np.ndarray, where: str | None = None) -> np.ndarray:
    """Linear sRGB reflectances (..., 3) in [0, 1] -> sigmoid-polynomial coefficients (..., 3), lambda in nm.

    The same model and convention as `uplift_reflectance` (black and white give its constants); a colour's
    spectrum reproduces it under D65 to the Delta E stated in `uplift_table.py`. `where` is named in errors.
    """
    values = _validated(rgb, "an RGB reflectance texture", where, upper=1.0)
    return _reflectance_rows(values.reshape(-1, 3)).reshape(values.shape)


def illuminant_texture_coefficients(rgb: np.ndarray, where: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Non-negative linear sRGB emission (..., 3) -> (coefficients (..., 3) in nm, multipliers (...)).

    The texel's emission spectrum is multiplier * S(poly)(lambda) * D65_normalised(lambda), the scheme of
    `illuminant_coefficients` (pbrt-v4's): the reflectance fitted to rgb / (2 m), m = max(rgb), scaled by 2 m.
    Black gives multiplier 0.
    """
    values = _validated(rgb, "an RGB emission texture", where, upper=None)
    rows = values.reshape(-1, 3)
    largest = rows.max(axis=1)
    multiplier = 2.0 * largest
    scaled = rows / np.where(largest > 0.0, multiplier, 1.0)[:, None]
    coefficients = _reflectance_rows(scaled)
    return coefficients.reshape(values.shape), multiplier.reshape(values.shape[:-1])


# ---------------------------------------------------------------- per-texture cache

_MAGIC = b"spectrace texture coefficients\n"
_FORMAT = 1
MEMORY_CACHE_BYTES = 512 << 20
DISK_CACHE_BYTES = 1 << 30


def texture_cache_dir() -> Path:
    return cache_root() / "uplift" / "textures"


class _TextureCache:
    """Results by key, least recently used dropped first: in memory up to `MEMORY_CACHE_BYTES`, on disk (one file
    per texture, checked on load, written atomically) up to `DISK_CACHE_BYTES`."""

    def __init__(self) -> None:
        self._memory: OrderedDict[str, tuple[np.ndarray, ...]] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: str, shapes: list[tuple[int, ...]]) -> tuple[np.ndarray, ...] | None:
        with self._lock:
            if key in self._memory:
                self._memory.move_to_end(key)
                return self._memory[key]
        arrays = self._read(key, shapes)
        if arrays is not None:
            self._remember(key, arrays)
        return arrays

    def put(self, key: str, arrays: tuple[np.ndarray, ...]) -> None:
        for array in arrays:
            array.setflags(write=False)
        self._remember(key, arrays)
        self._write(key, arrays)

    def clear_memory(self) -> None:
        with self._lock:
            self._memory.clear()

    def _remember(self, key: str, arrays: tuple[np.ndarray, ...]) -> None:
        with self._lock:
            self._memory[key] = arrays
            self._memory.move_to_end(key)
            while (
                len(self._memory) > 1 and sum(a.nbytes for v in self._memory.values() for a in v) > MEMORY_CACHE_BYTES
            ):
                self._memory.popitem(last=False)

    @staticmethod
    def _read(key: str, shapes: list[tuple[int, ...]]) -> tuple[np.ndarray, ...] | None:
        path = texture_cache_dir() / f"{key}.bin"
        try:
            blob = path.read_bytes()
        except OSError:
            return None
        arrays = _deserialise(blob, key, shapes)
        with contextlib.suppress(OSError):
            if arrays is None:
                path.unlink()  # damaged: recomputed and rewritten by the caller
            else:
                os.utime(path)  # recently used: evicted last
        return arrays

    @staticmethod
    def _write(key: str, arrays: tuple[np.ndarray, ...]) -> None:
        folder = texture_cache_dir()
        blob = _serialise(arrays, key)
        try:
            write_atomically(folder / f"{key}.bin", lambda temporary: temporary.write_bytes(blob))
            _evict(folder, keep=f"{key}.bin")
        except OSError:
            pass  # an unwritable cache costs a recomputation next time, nothing more


def _serialise(arrays: tuple[np.ndarray, ...], key: str) -> bytes:
    data = b"".join(np.ascontiguousarray(array, dtype="<f8").tobytes() for array in arrays)
    header = {"format": _FORMAT, "key": key, "sha256": hashlib.sha256(data).hexdigest()}
    return _MAGIC + json.dumps(header, sort_keys=True).encode() + b"\n" + data


def _deserialise(blob: bytes, key: str, shapes: list[tuple[int, ...]]) -> tuple[np.ndarray, ...] | None:
    if not blob.startswith(_MAGIC):
        return None
    header_end = blob.find(b"\n", len(_MAGIC))
    try:
        header = json.loads(blob[len(_MAGIC) : header_end]) if header_end > 0 else None
    except ValueError:
        return None
    data = blob[header_end + 1 :]
    sizes = [int(np.prod(shape)) for shape in shapes]
    if (
        not isinstance(header, dict)
        or header.get("format") != _FORMAT
        or header.get("key") != key
        or len(data) != 8 * sum(sizes)
        or header.get("sha256") != hashlib.sha256(data).hexdigest()
    ):
        return None
    flat = np.frombuffer(data, dtype="<f8").astype(np.float64)
    if not np.all(np.isfinite(flat)):
        return None
    arrays, offset = [], 0
    for shape, size in zip(shapes, sizes):
        array = flat[offset : offset + size].reshape(shape)
        array.setflags(write=False)
        arrays.append(array)
        offset += size
    return tuple(arrays)


def _evict(folder: Path, keep: str) -> None:
    """Remove the least recently used files until the folder fits in `DISK_CACHE_BYTES`."""
    entries = []
    for entry in os.scandir(folder):
        if entry.name.endswith(".bin") and entry.is_file(follow_symlinks=False):
            try:
                status = entry.stat(follow_symlinks=False)
            except OSError:
                continue
            entries.append((status.st_mtime_ns, entry.name, status.st_size))
    total = sum(size for _, _, size in entries)
    for _, name, size in sorted(entries):
        if total <= DISK_CACHE_BYTES:
            break
        if name == keep:
            continue
        try:
            (folder / name).unlink()
        except OSError:
            continue
        total -= size


_cache = _TextureCache()


def _texture_key(kind: str, pixels: np.ndarray) -> str:
    digest = hashlib.sha256(f"{kind} {_FORMAT} {pixels.shape} {uplift_table.table_identity()}".encode())
    digest.update(np.ascontiguousarray(pixels, dtype="<f8").data)
    return digest.hexdigest()


def texture_reflectance_coefficients(rgb: np.ndarray, where: str | None = None) -> np.ndarray:
    """`reflectance_coefficients` of a whole texture, cached per texture (module docstring); read-only result."""
    values = _validated(rgb, "an RGB reflectance texture", where, upper=1.0)
    key = _texture_key("reflectance", values)
    cached = _cache.get(key, [values.shape])
    if cached is not None:
        return cached[0]
    coefficients = _reflectance_rows(values.reshape(-1, 3)).reshape(values.shape)
    _cache.put(key, (coefficients,))
    return coefficients


def texture_illuminant_coefficients(rgb: np.ndarray, where: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """`illuminant_texture_coefficients` of a whole texture, cached per texture; read-only results."""
    values = _validated(rgb, "an RGB emission texture", where, upper=None)
    key = _texture_key("illuminant", values)
    cached = _cache.get(key, [values.shape, values.shape[:-1]])
    if cached is not None:
        return cached[0], cached[1]
    coefficients, multiplier = illuminant_texture_coefficients(values)
    _cache.put(key, (coefficients, multiplier))
    return coefficients, multiplier
