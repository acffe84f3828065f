"""`directionmix`: two textures (or spectra) blended by how the surface faces a direction, pbrt-v4's `directionmix`
(its DirectionMixTexture, "Physically Based Rendering", 4th ed., sec. 10.3.3): value = a · tex1 + (1 − a) · tex2
with a = |n · dir|, n the unit geometric normal at the point and dir a unit world-space direction (pbrt-v4 normalises
its `dir` after taking it to world space, and defaults it to +y). tex1 shows where the surface faces along ±dir,
tex2 where it lies edge-on to it; as a mix's, its operands are spectra or image textures and a blend of
reflectances in [0, 1] stays in [0, 1]. The normal is the surface's own, as pbrt-v4's TextureEvalContext carries
its interaction's n: a smooth mesh blends by its facets, not by the normals its vertices interpolate, and a normal
or bump map does not turn it. Mitsuba 3 has no such texture. kernels/texture_direction_mix.cl, docs/textures.md."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.textures.shared import Placement, api_operand

NAME = "directionmix"
API_NAME = "directionmix_texture"
COMPOSITE = True
DEFAULT_DIR = (0.0, 1.0, 0.0)  # pbrt-v4's
PARAMETERS = (
    Parameter(
        "tex1",
        "spectrum",
        default=0.0,
        range=Range(0.0, 1.0),
        doc="the value where the surface faces along ±dir (|n · dir| = 1)",
        textured=True,
    ),
    Parameter(
        "tex2",
        "spectrum",
        default=1.0,
        range=Range(0.0, 1.0),
        doc="the value where the surface is edge-on to dir (n · dir = 0)",
        textured=True,
    ),
    Parameter(
        "dir",
        "vector",
        "",
        DEFAULT_DIR,
        default_doc="[0, 1, 0]",
        doc="the world-space direction (normalised; not zero): the value is a · tex1 + (1 − a) · tex2, a = |n · dir| "
        "of the unit geometric normal n (a facet's own on a smooth mesh)",
    ),
)
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no direction mix texture"
PBRT_TEXTURES = ("directionmix",)


@dataclass(frozen=True, eq=False)
class DirectionMixTexture:
    """|n · dir| · tex1 + (1 − |n · dir|) · tex2: tex1, tex2 Spectra or image textures, dir a unit world-space
    vector."""

    tex1: object
    tex2: object
    dir: tuple[float, float, float] = DEFAULT_DIR
    source: str = "directionmix"
    placement: Placement = Placement()  # unused: each operand places itself

    @property
    def operands(self) -> tuple:
        return (self.tex1, self.tex2)


MODEL = DirectionMixTexture


def unit_dir(value, where: str | None) -> tuple[float, float, float]:
    """`value` (3 finite numbers, not all 0) normalised."""
    vector = np.asarray(value, np.float64)
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise SpectraceError(f"dir is 3 finite numbers, got {value!r}", where=where)
    norm = float(np.linalg.norm(vector))
    if not norm > 0.0:
        raise SpectraceError("dir must not be zero", where=where)
    x, y, z = (vector / norm).tolist()
    return x, y, z


def from_spec(spec, resolver, key: str) -> DirectionMixTexture:
    sides = [
        resolver.spectrum_or_texture(getattr(spec, name), f"{key}.{name}", "spectrum", inner=True)
        for name in ("tex1", "tex2")
    ]
    return DirectionMixTexture(sides[0], sides[1], unit_dir(spec.dir, resolver.where(f"{key}.dir")))


def make(tex1=0.0, tex2=1.0, dir=DEFAULT_DIR) -> DirectionMixTexture:  # noqa: A002 (pbrt-v4's name)
    """|n · dir| · tex1 + (1 − |n · dir|) · tex2 at a surface of unit geometric normal n, as pbrt-v4's `directionmix`
    texture: tex1, tex2 reflectances (anything `spectrum` takes, an RGB triple, or an image texture), dir a
    world-space direction (normalised)."""
    return DirectionMixTexture(api_operand(tex1, "tex1"), api_operand(tex2, "tex2"), unit_dir(dir, "dir"))


def from_pbrt(context, texture, uv) -> dict:
    """pbrt-v4's `directionmix` (tex1 0 and tex2 1 by default, either a value or a texture of the same kind), its
    `dir` (default +y) taken through the transform in effect where the texture was declared, normalised."""
    table: dict = {"texture": NAME}
    declared = next(t for t in context.scene.textures.values() if t.entity is texture)
    for side, default in (("tex1", 0.0), ("tex2", 1.0)):
        value = context.spectrum(texture, side, "albedo")
        if value is None and declared.value_type == "spectrum":
            value = context.texture_reference(texture, side)
        elif value is None and (reference := texture.find(side, "texture")) is not None:
            # A float operand texture goes inline (a constant as its number, an imagemap as its table).
            key = ("float", str(reference.values[0]))
            if key not in context.scene.textures:
                raise context.error(reference.location, f'"{reference.label()}" names a Texture not defined')
            value = context.texture_table(context.scene.textures[key].entity)
        table[side] = value or {"value": default}
    direction = context.vector(texture, "dir", list(DEFAULT_DIR))
    if not np.any(direction):
        raise context.error(texture.location, f'{texture.label()}: "dir" must not be zero')
    table["dir"] = [round(c, 12) for c in context.direction(np.asarray(declared.world_from_texture), direction)]
    return table
