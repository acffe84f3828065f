"""Textures: one module per type, listed in TEXTURES (docs/textures.md), whose shape `base.TexturePlugin` states.
Each opens with its parameter table (PARAMETERS, spectrace.core.parameters), from which the scene schema builds the
texture's keys, and holds its resolved dataclass (MODEL), `from_spec` (a validated scene table to the dataclass),
`make` (the Python API) and, for image textures, `device_texels` (its texels for one use: sigmoid coefficients of a
reflectance, scalars, spectral bands, with the MIP pyramid when filtered trilinearly). A texture's position in
TEXTURES is its Texture.type code (TEXTURE_<NAME> in kernels/texture.cl: `generated_sources`).

A material parameter whose table entry says `textured` takes a texture wherever it takes a spectrum; its Material
row then holds the texture's index in `<name>_texture` (kernels/types.h). TextureRows writes every texture of a
scene into one Texture array and the shared texel buffer, each texture once however many materials use it.
"""

import numpy as np

from spectrace.core.api_calls import recorded
from spectrace.core.contract import (
    NO_TEXTURE,
    TEXEL_BANDS,
    TEXEL_RGB,
    TEXEL_SCALAR,
    TEXEL_SIGMOID,
    TEXEL_VECTOR,
    TEXTURE_DTYPE,
    GeneratedSources,
)
from spectrace.core.limits import MAX_TEXTURE_BYTES, format_bytes
from spectrace.core.registry import Registry
from spectrace.errors import SpectraceError
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import (
    bitmap,
    checkerboard,
    directionmix,
    dots,
    fbm,
    marble,
    mesh_attribute,
    mix,
    scale,
    spectral,
    storage,
    windy,
    wrinkled,
)
from spectrace.textures.base import TexturePlugin
from spectrace.textures.bitmap import BitmapTexture
from spectrace.textures.checkerboard import CheckerboardTexture
from spectrace.textures.directionmix import DirectionMixTexture
from spectrace.textures.dots import DotsTexture
from spectrace.textures.mapping import MAPPINGS
from spectrace.textures.mapping import device_floats as mapping_floats
from spectrace.textures.mesh_attribute import MeshAttributeTexture
from spectrace.textures.mix import MixTexture
from spectrace.textures.scale import ScaleTexture
from spectrace.textures.shared import FILTERS, WRAPS, ImageTextures, value_problem
from spectrace.textures.solid import SolidTexture
from spectrace.textures.spectral import SpectralTexture

# Scene-file type -> module; the position is the Texture.type code.
TEXTURES = Registry[TexturePlugin](
    "texture",
    (bitmap, spectral, checkerboard, scale, mix, dots, fbm, wrinkled, windy, marble, mesh_attribute, directionmix),
)
# Each texture an API constructor makes remembers its arguments, by which a live session edits it (core/api_calls.py).
for _module in TEXTURES.values():
    _module.make = recorded(_module.make)  # type: ignore[method-assign]
# Those made of other textures: their operands are spectra and image textures only (the kernel does not recurse).
COMPOSITE_TEXTURES = tuple(name for name, module in TEXTURES.items() if module.COMPOSITE)
# Solid textures are looked up at the surface point, not at uv (textures/solid.py); like image textures they are
# operands of composites, but have no texels.
SOLID_TEXTURES = tuple(module.MODEL for module in TEXTURES.values() if getattr(module, "SOLID", False))
SOLID_TEXTURE_CODES = [TEXTURES.codes[name] for name, module in TEXTURES.items() if getattr(module, "SOLID", False)]
# Attribute textures read the mesh at the hit (textures/mesh_attribute.py): operands of composites too, with neither
# texels nor texture coordinates.
ATTRIBUTE_TEXTURES = tuple(module.MODEL for module in TEXTURES.values() if getattr(module, "ATTRIBUTE", False))
IMAGE_TEXTURES = tuple(
    module.MODEL
    for module in TEXTURES.values()
    if not module.COMPOSITE and not getattr(module, "SOLID", False) and not getattr(module, "ATTRIBUTE", False)
)
INNER_TEXTURES = IMAGE_TEXTURES + SOLID_TEXTURES + ATTRIBUTE_TEXTURES  # what a composite's operands may be
# Those that pick one of two sides (color0, color1) at the point: their rows and checks are alike.
TWO_SIDED = (CheckerboardTexture, DotsTexture)
# Those whose value is computed from their operands' (spectra or inner textures) at the point.
BLENDS = (ScaleTexture, MixTexture, DirectionMixTexture)
_MODELS = tuple(module.MODEL for module in TEXTURES.values())


def generated_sources() -> GeneratedSources:
    """TEXTURE_<NAME> and TEXTURE_TYPE_COUNT, which every kernel that reads textures is built with."""
    return GeneratedSources(TEXTURES.kernel_defines("TEXTURE"))


def is_texture(value: object) -> bool:
    return isinstance(value, _MODELS)


def check_texture_values(texture, kind: str, where: str, upper: float | None = None) -> None:
    """A texture's values fit a use: a reflectance's lie in [0, 1]; a scalar texture ("float") has one channel
    (a checkerboard's sides: constant spectra or one-channel images) and its values lie in [0, upper]; an emission
    is an image texture (a bitmap or a spectral texture) of values >= 0. An "amount" (a mix's) is a float in
    [0, 1], or a solid noise texture of any values, which the mix holds to [0, 1] as pbrt-v4's does."""
    if kind == "amount":
        if isinstance(texture, SolidTexture) and texture.channels == 1:
            return
        if isinstance(texture, DirectionMixTexture):
            # A mix material chooses its material before the hit's shading normal is formed.
            raise SpectraceError("a mix's amount takes no directionmix texture", where=where)
        kind, upper = "float", 1.0
    if isinstance(texture, MeshAttributeTexture):
        mesh_attribute.record_use(texture, kind, where, upper)
        return
    if kind == "emission" and not isinstance(texture, IMAGE_TEXTURES):
        raise SpectraceError(
            f"an emission texture is a bitmap or a spectral texture, not a {texture_module(texture).NAME}", where=where
        )
    if isinstance(texture, BLENDS):
        _check_composite(texture, kind, where, upper)
        return
    if isinstance(texture, SolidTexture):
        _check_solid(texture, kind, where, upper)
        return
    if isinstance(texture, TWO_SIDED):
        if kind == "float":
            for side in (texture.color0, texture.color1):
                if isinstance(side, Spectrum):
                    if np.ptp(side.values) > 0.0:
                        raise SpectraceError(
                            f"a scalar {texture.source}'s sides are numbers ({{ value = ... }}) or grey images, not "
                            "spectra that vary with the wavelength",
                            where=where,
                        )
                else:
                    check_texture_values(side, kind, where, upper)
        elif kind == "spectrum":
            upper = 1.0
        # Its sides were resolved as values >= 0: the bound is the using parameter's (a reflectance's 1, a number's
        # range), checked here for every use.
        if upper is not None and (high := scalar_range(texture)[1]) > upper + 1e-6:
            why = ", which as a reflectance would create energy" if kind == "spectrum" else ""
            raise SpectraceError(f"{texture.source} has values above {upper:g} (max {high:.4g}){why}", where=where)
        return
    if kind == "float" and not (isinstance(texture, BitmapTexture) and texture.channels == 1):
        raise SpectraceError(
            f"texture '{texture.source}' has {texture.channels} channels; this parameter needs one (a grey image)",
            where=where,
        )
    if problem := value_problem(texture.values, 1.0 if kind == "spectrum" else upper, reflectance=kind == "spectrum"):
        raise SpectraceError(f"texture '{texture.source}' {problem}", where=where)


ImageTextures.models, ImageTextures.check = INNER_TEXTURES, check_texture_values


def _check_solid(texture: SolidTexture, kind: str, where: str, upper: float | None) -> None:
    """A solid texture fits a use: marble is a reflectance; the noise textures are numbers, whose range must lie
    within the use's bound (a reflectance's [0, 1], a number's [0, upper])."""
    low, high = texture.value_range()
    if kind == "float" and texture.channels != 1:
        raise SpectraceError(f"a {texture.source} texture is a colour; this parameter needs a number", where=where)
    bound = 1.0 if kind == "spectrum" else upper
    if low < 0.0 or (bound is not None and high > bound + 1e-6):
        use = "a reflectance" if kind == "spectrum" else "this parameter"
        raise SpectraceError(
            f"a {texture.source} texture takes values in [{low:.3g}, {high:.3g}], outside what {use} takes "
            f"([0, {bound if bound is not None else 'inf'}]); use it as a mix's amount",
            where=where,
        )


def reflectance_or_texture(source, where: str):
    """A textured reflectance parameter's value: a texture (its values checked to lie in [0, 1])
    as it is, anything else as `reflectance`."""
    if is_texture(source):
        check_texture_values(source, "spectrum", where)
        return source
    from spectrace.spectral import spectrum_input

    return spectrum_input.reflectance(source, where)


def number_or_texture(source, parameter, where: str | None = None):
    """A textured number's value (a `roughness`): a one-channel texture whose values lie in
    the parameter's range as it is, anything else checked as a number in that range."""
    if is_texture(source):
        check_texture_values(source, "float", where or parameter.name, upper=parameter.range.high)
        return source
    return parameter.check(source, where)


def _check_composite(texture, kind: str, where: str, upper: float | None) -> None:
    """A scale's or mix's operands fit the use (as a checkerboard's sides do), and a scaled reflectance or number
    stays within its bound (a mix of values within a bound stays within it)."""
    for operand in texture.operands:
        if isinstance(operand, Spectrum):
            if kind == "float" and np.ptp(operand.values) > 0.0:
                raise SpectraceError(
                    f"a scalar {texture.source} texture's operands are numbers or grey images, not spectra that vary "
                    "with the wavelength",
                    where=where,
                )
        elif is_texture(operand) and isinstance(texture, MixTexture) and operand is texture.amount:
            check_texture_values(operand, "amount", where)
        elif is_texture(operand):
            check_texture_values(operand, "float" if kind == "float" or operand is _factor(texture) else kind, where)
    bound = 1.0 if kind == "spectrum" else upper
    if bound is not None and (high := value_range(texture)[1]) > bound + 1e-6:
        raise SpectraceError(f"{texture.source} texture has values above {bound:g} (max {high:.4g})", where=where)


def _factor(texture):
    """The operand of a composite that is a number rather than a spectrum: a scale's factor, a mix's amount."""
    if isinstance(texture, ScaleTexture):
        return texture.scale
    return texture.amount if isinstance(texture, MixTexture) else None


def value_range(value) -> tuple[float, float]:
    """The smallest and largest value a texture or spectrum takes anywhere on a surface and at any wavelength (a
    scale's: its operands' ranges multiplied, all being >= 0; a mix's: the hull of its two sides')."""
    if isinstance(value, ScaleTexture):
        (low, high), (f_low, f_high) = value_range(value.tex), value_range(value.scale)
        return low * f_low, high * f_high
    if isinstance(value, (MixTexture, DirectionMixTexture)):
        ranges = [value_range(side) for side in (value.tex1, value.tex2)]
        return min(r[0] for r in ranges), max(r[1] for r in ranges)
    return scalar_range(value)


def scalar_range(value) -> tuple[float, float]:
    """The smallest and largest value a scalar parameter (a number, or a one-channel texture checked by
    check_texture_values) takes anywhere on a surface: every filter blends texels with convex weights and every MIP
    level averages the one before, so no lookup leaves the texels' range."""
    if isinstance(value, TWO_SIDED):
        ranges = [scalar_range(side) for side in (value.color0, value.color1)]
        return min(r[0] for r in ranges), max(r[1] for r in ranges)
    if isinstance(value, BLENDS):
        return value_range(value)
    if isinstance(value, SolidTexture):
        return value.value_range()
    if isinstance(value, MeshAttributeTexture):
        return 0.0, 0.0  # its values are the meshes', checked against each use once they meet (mesh_attribute.py)
    if isinstance(value, Spectrum):
        return float(value.values.min()), float(value.values.max())
    if isinstance(value, IMAGE_TEXTURES):
        return float(value.values.min()), float(value.values.max())
    return float(value), float(value)


def uv_textures(textures: dict) -> dict:
    """Those of `textures` (by name) that are looked up at texture coordinates: all but mesh attributes (and
    composites made of nothing else)."""
    return {
        name: texture
        for name, texture in textures.items()
        if not isinstance(texture, MeshAttributeTexture)
        and not (
            isinstance(texture, BLENDS)
            and all(isinstance(o, (MeshAttributeTexture, Spectrum, int, float)) for o in texture.operands)
        )
    }


def texture_module(texture):
    return TEXTURES.for_model(texture)


def texel_format_of(texture, kind: str) -> int:
    """What an image texture's texels hold for a use of `kind` (as its module's device_texels makes them)."""
    if isinstance(texture, SpectralTexture):
        return TEXEL_BANDS
    return {"float": TEXEL_SCALAR, "vector": TEXEL_VECTOR, "emission": TEXEL_RGB}.get(kind, TEXEL_SIGMOID)


def device_bytes(texture, kind: str) -> int:
    """An estimate (exact for power-of-two sizes) of the texel bytes a texture takes on the device, from its size
    and values before anything is converted (its storage as `storage.predicted_storage` says: a sigmoid texture
    predicted half may need float, twice this, once converted): what the scene's texture budget is checked
    against before anything is converted."""
    if isinstance(texture, TWO_SIDED):
        return sum(device_bytes(side, kind) for side in (texture.color0, texture.color1) if is_texture(side))
    if isinstance(texture, (SolidTexture, MeshAttributeTexture)):
        return 0  # a few numbers, no texels (a mesh attribute's values are counted as they are stored)
    if isinstance(texture, BLENDS):
        factor = _factor(texture)
        return sum(
            device_bytes(operand, "float" if operand is factor else kind)
            for operand in texture.operands
            if is_texture(operand)
        )
    height, width = texture.values.shape[:2]
    channels = 3 if isinstance(texture, BitmapTexture) and kind != "float" else texture.channels
    pyramid = 4.0 / 3.0 if texture.placement.filter == "trilinear" else 1.0
    value_bytes = storage.BYTES[storage.predicted_storage(texel_format_of(texture, kind), texture.values)]
    return int(width * height * channels * value_bytes * pyramid)


class TextureRows:
    """The Texture rows of a scene and their texels, appended to the texel buffer the lights share (float4 chunks;
    a texture's data starts on a float4 boundary, its values stored as `storage` chooses). `bytes` counts the texel
    bytes of the textures added."""

    def __init__(self, table: SpectrumTable, texel_chunks: list[np.ndarray]):
        self.table = table
        self.texel_chunks = texel_chunks
        self.rows: list[np.ndarray] = []
        # Keyed by the texture itself (textures compare and hash by identity), which the key keeps alive: an id()
        # would be handed on to a new texture once the first was freed, and the new one given the old one's row.
        self.index: dict[tuple[object, str, tuple[int, ...]], int] = {}
        self.bytes = 0
        self.sizes: list[int] = []  # each row's texels in float4s (0: a composite's row, which has none)
        self.free: list[int] = []  # rows whose texture the scene uses no more (`release`): slots to take again
        self.rewritten = False  # a free slot was taken: rows and texels changed where they lie
        self.light_texels: dict = {}  # lights' images and sampling tables in the texels, by content (LightRows)
        self.attribute_rows: list[tuple[int, object, str]] = []  # mesh attribute rows to fill: (row, texture, kind)
        self.attributes_written = False  # their tables follow the triangles', written once the scene is built

    def release(self, textures: set) -> None:
        """Let `textures` go (nothing of the scene uses them any more): their rows, and their texels, are taken by
        the next textures added whose texels are as long, so that editing an image does not grow the buffer."""
        for key in [key for key in self.index if key[0] in textures]:
            self.free.append(self.index.pop(key))

    def _free_slot(self, size: int) -> int | None:
        slot = next((row for row in self.free if self.sizes[row] == size), None)
        if slot is not None:
            self.free.remove(slot)
        return slot

    def _check_budget(self, total: int, texture, where: str | None) -> None:
        if total > MAX_TEXTURE_BYTES:
            raise SpectraceError(
                f"the scene's textures need {format_bytes(total)} of device memory (texture '{texture.source}' "
                f"brings it there); at most {format_bytes(MAX_TEXTURE_BYTES)} are allowed: use smaller images",
                where=where,
            )

    def array(self) -> np.ndarray:
        return np.array(self.rows, TEXTURE_DTYPE) if self.rows else np.zeros(1, TEXTURE_DTYPE)

    def add(self, texture, kind: str, where: str | None = None, basis: list[int] | None = None) -> int:
        """The index of `texture`'s row for a use of `kind` ("spectrum": a reflectance, "float": a scalar, or
        "emission": a light's radiance, an RGB bitmap's texels weighting the spectra at the table offsets `basis`),
        added when new."""
        key = (texture, kind, tuple(basis or ()))
        if key in self.index:
            return self.index[key]
        self._check_budget(self.bytes + device_bytes(texture, kind), texture, where)
        row = np.zeros((), TEXTURE_DTYPE)
        row["uv_transform"] = texture.placement.uv_transform
        row["side_spectrum"] = -1
        row["side_texture"] = NO_TEXTURE
        row["type"] = TEXTURES.codes[texture_module(texture).NAME]
        if texture.placement.mapping != "uv":  # its rows ahead of its texels (kernels/texture_mapping.cl)
            row["mapping"] = MAPPINGS[texture.placement.mapping]
            row["mapping_offset"] = 4 * sum(len(c) for c in self.texel_chunks)
            self.texel_chunks.append(mapping_floats(texture.placement).reshape(-1, 4))
        size, slot = 0, None
        if isinstance(texture, TWO_SIDED):
            for i, side in enumerate((texture.color0, texture.color1)):
                if isinstance(side, Spectrum):
                    row["side_spectrum"][i] = self.table.add(side)
                elif isinstance(side, INNER_TEXTURES):
                    row["side_texture"][i] = self.add(side, kind, where)
                else:
                    raise SpectraceError(f"a {texture.source}'s sides are spectra or image textures", where=where)
        elif isinstance(texture, BLENDS):
            sides = (texture.tex,) if isinstance(texture, ScaleTexture) else (texture.tex1, texture.tex2)
            for i, side in enumerate(sides):
                if isinstance(side, Spectrum):
                    row["side_spectrum"][i] = self.table.add(side)
                elif isinstance(side, INNER_TEXTURES):
                    row["side_texture"][i] = self.add(side, kind, where)
                else:
                    raise SpectraceError(f"a {texture.source} texture's operands are spectra or image textures", where)
            factor = _factor(texture)
            row["factor_texture"] = NO_TEXTURE
            if isinstance(texture, DirectionMixTexture):
                row["uv_transform"] = (*texture.dir, 0.0)  # the kernel's dir (texture_direction_mix.cl)
            elif isinstance(factor, INNER_TEXTURES):
                row["factor_texture"] = self.add(factor, "float", where)
            elif isinstance(factor, Spectrum):
                row["factor"] = float(factor.values[0])  # a constant (checked)
            else:
                row["factor"] = float(factor)
        elif isinstance(texture, MeshAttributeTexture):
            # Its table and values are written once the triangles' slots are known (engine/mesh_attribute_rows.py).
            if self.attributes_written:
                raise SpectraceError(
                    "a live edit cannot add a mesh_attribute texture (its tables are written with the triangles): "
                    "load the scene again",
                    where=where,
                )
            row["factor"] = texture.scale
        elif isinstance(texture, SolidTexture):
            values = np.asarray(texture_module(texture).device_solid(texture, self.table), np.float32)
            chunk = values.reshape(-1, 4)
            row["data_offset"] = 4 * sum(len(c) for c in self.texel_chunks)
            self.texel_chunks.append(chunk)
        else:
            texel_format, channels, levels = texture_module(texture).device_texels(texture, kind)
            if basis is not None:
                row["basis_offset"] = basis
            row["texel_format"], row["channels"] = texel_format, channels
            row["height"], row["width"] = levels[0].shape[:2]
            row["levels"] = len(levels)
            row["wrap"] = WRAPS[texture.placement.wrap]
            row["filter"] = FILTERS[texture.placement.filter]
            if isinstance(texture, SpectralTexture):
                row["band_first_nm"] = texture.wavelengths_nm[0]
                row["band_step_nm"] = (
                    texture.wavelengths_nm[1] - texture.wavelengths_nm[0] if texture.channels > 1 else 1.0
                )
            row["storage"] = storage.storage(texel_format, levels, texture.values)
            stored = storage.encode(texel_format, int(row["storage"]), levels)
            chunk = np.zeros(((len(stored) + 15) // 16, 4), np.float32)
            chunk.view(np.uint8).ravel()[: len(stored)] = stored
            size = len(chunk)
            slot = self._free_slot(size)
            if slot is not None:  # over the texels of a texture let go
                row["data_offset"] = self.rows[slot]["data_offset"]
                texels = np.concatenate(self.texel_chunks)  # a copy: buffers handed out before keep theirs
                start = int(row["data_offset"]) // 4
                texels[start : start + size] = chunk
                self.texel_chunks[:] = [texels]
            else:
                row["data_offset"] = 4 * sum(len(c) for c in self.texel_chunks)
                self._check_budget(self.bytes + len(stored), texture, where)
                self.bytes += len(stored)
                self.texel_chunks.append(chunk)
        if not size:  # a composite's row, with no texels of its own
            slot = self._free_slot(0)
        if slot is not None:
            self.rows[slot] = row
            self.rewritten = True
        else:
            self.rows.append(row)
            self.sizes.append(size)
            slot = len(self.rows) - 1
        self.index[key] = slot
        if isinstance(texture, MeshAttributeTexture):
            self.attribute_rows.append((slot, texture, kind))
        return slot
