"""Surface detail: the keys every material takes besides its own (docs/textures.md, "Surface detail"): a normal map
or a bump map, which turn the shading normal the BSDF's frame follows, and an opacity, which cuts the surface out
where it is below 1. They live on the material (its `detail`) and at the end of its Material row
(kernels/types.h); the kernels read them in kernels/surface_detail.cl (the normals) and kernels/scene.cl (the
opacity of every visibility query).

`two_sided = false` makes a reflecting material black seen from the back of its surface (the side away from its
winding's normal), as Mitsuba 3's BSDFs are outside a `twosided` wrapper; materials that transmit have two sides by
nature and ignore it.

A normal map holds tangent-space directions n = 2 c − 1 per texel, +z out of the surface, x along the direction
in which u grows, y = z × x (the OpenGL convention, green up in an image seen upright from the front; Mitsuba 3's
`normalmap` and pbrt-v4 build the same frame). With `normal_map_handedness`, y = w (z × x), w = ±1 the handedness
of the triangle's texture layout (−1 where the layout is mirrored, so that green stays up the image there too), the
bitangent glTF 2.0 (3.7.2.1: cross(normal, tangent.xyz) · w) and Blender's MikkTSpace tangents define. A bump map
holds heights: `bump_scale` scene units per texture value.
"""

import dataclasses
import functools
import inspect
from collections.abc import Callable
from dataclasses import dataclass

from spectrace.core.parameters import Parameter, Range
from spectrace.errors import SpectraceError

OPACITY_RANGE = Range(0.0, 1.0)
PARAMETERS = (
    Parameter(
        "normal_map",
        "texture",
        default=None,
        doc="tangent-space normals n = 2 c − 1 of a raw 3-channel `bitmap` (+z out of the surface, x along +u, "
        "y = z × x: the OpenGL convention); replaces the shading normal",
        type_doc="texture",
    ),
    Parameter(
        "bump_map",
        "texture",
        default=None,
        doc="heights (a raw one-channel `bitmap`, or a `checkerboard`) whose gradient tilts the shading normal; "
        "not with `normal_map`",
        type_doc="texture",
    ),
    Parameter(
        "bump_scale",
        "float",
        unit="scene units",
        default=1.0,
        doc="the height of a bump map value of 1",
    ),
    Parameter(
        "opacity",
        "float",
        default=1.0,
        range=OPACITY_RANGE,
        doc="the probability that a ray meets the surface; elsewhere it passes as if the surface were not there "
        "(cut-outs); not on emitters nor on shapes with an interior",
        type_doc="float or texture in [0, 1]",
        textured=True,
    ),
    Parameter(
        "two_sided",
        "bool",
        default=True,
        doc="false: a reflecting material reflects only on the front of its surface (the side its vertex normals "
        "point to, or its winding's normal on a flat mesh) and is black from the back, as Mitsuba 3's BSDFs outside "
        "`twosided`; ignored by materials that transmit",
    ),
    Parameter(
        "shadowing_function",
        "bool",
        default=False,
        doc="true: with a normal or bump map, the BSDF's value is scaled by the shadowing term of Conty Estevez, "
        "Pearce & Kulla 2019 of the light's direction (Mitsuba 3's `use_shadowing_function`, which Mitsuba turns "
        "on by default): it darkens steep maps under grazing light",
    ),
    Parameter(
        "normal_map_handedness",
        "bool",
        default=False,
        doc="true: a normal map's y axis is w (z × x), w = −1 on faces whose texture layout is mirrored, so green "
        "points up the image on both halves of a mirrored layout (glTF 2.0's and Blender's tangent frame; the glTF "
        "importer sets it); false: y = z × x everywhere (Mitsuba 3's and pbrt-v4's)",
    ),
)
NAMES = tuple(p.name for p in PARAMETERS)
_BY_NAME = {p.name: p for p in PARAMETERS}


@dataclass(frozen=True, eq=False)
class SurfaceDetail:
    """A material's surface detail; a field at its default changes nothing."""

    normal_map: object = None  # a BitmapTexture of 3 raw channels
    bump_map: object = None  # a scalar texture (BitmapTexture of 1 channel, or CheckerboardTexture)
    bump_scale: float = 1.0
    opacity: object = 1.0  # a float, or a scalar texture
    two_sided: bool = True
    shadowing_function: bool = False
    normal_map_handedness: bool = False

    @property
    def is_cut_out(self) -> bool:
        """Whether rays may pass through the surface."""
        return not isinstance(self.opacity, float) or self.opacity < 1.0

    def textures(self) -> dict:
        from spectrace.textures import is_texture

        return {
            name: getattr(self, name)
            for name in ("normal_map", "bump_map", "opacity")
            if is_texture(getattr(self, name))
        }


def check_texture(texture, name: str, where: str) -> None:
    """A texture fits its detail key: a normal map is a 3-channel bitmap, a bump map or opacity a one-channel one
    (or a checkerboard); normal and bump maps hold data, so an sRGB-decoded image is refused."""
    from spectrace.textures import check_texture_values
    from spectrace.textures.bitmap import BitmapTexture
    from spectrace.textures.checkerboard import CheckerboardTexture
    from spectrace.textures.solid import refuse_solid

    if getattr(texture.placement, "mapping", "uv") != "uv":  # surface_detail.cl reads these at the surface's uv
        raise SpectraceError(f"{name} takes no {texture.placement.mapping} mapping (it reads the surface's uv)", where)
    if name == "normal_map":
        if not isinstance(texture, BitmapTexture):
            raise SpectraceError("a normal map is a `bitmap` texture", where=where)
        if texture.channels != 3:
            raise SpectraceError(
                f"normal map '{texture.source}' has {texture.channels} channel{'s' * (texture.channels != 1)}; "
                "a normal map needs 3 (RGB)",
                where=where,
            )
    elif not isinstance(texture, (BitmapTexture, CheckerboardTexture)):
        raise SpectraceError(f"{name} takes a `bitmap` or `checkerboard` texture", where=where)
    else:
        for side in (texture.color0, texture.color1) if isinstance(texture, CheckerboardTexture) else ():
            refuse_solid(side, name, where)
        check_texture_values(texture, "float", where)
        if name == "opacity" and isinstance(texture, BitmapTexture) and float(texture.values.max()) > 1.0 + 1e-6:
            raise SpectraceError(
                f"opacity texture '{texture.source}' has values above 1 (max {float(texture.values.max()):.4g})",
                where=where,
            )
    if name in ("normal_map", "bump_map") and getattr(texture, "srgb_decoded", False):
        raise SpectraceError(
            f"{name.replace('_', ' ')} '{texture.source}' is read as sRGB colours; it holds data: give raw = true",
            where=where,
        )


def detail(
    normal_map=None,
    bump_map=None,
    bump_scale=1.0,
    opacity=1.0,
    two_sided=True,
    where=None,
    shadowing_function=False,
    normal_map_handedness=False,
) -> SurfaceDetail | None:
    """The SurfaceDetail of checked values, or None when every one is at its default. `where(name)` is the key
    path of a key in errors (the Python API's keyword names when None)."""
    from spectrace.textures import is_texture

    def at(name: str) -> str:
        return where(name) if where is not None else name

    if normal_map is not None and bump_map is not None:
        raise SpectraceError("a material takes a normal map or a bump map, not both", where=at("bump_map"))
    for name, value in (("normal_map", normal_map), ("bump_map", bump_map)):
        if value is not None:
            if not is_texture(value):
                raise SpectraceError(f"{name} takes a texture, got {type(value).__name__}", where=at(name))
            check_texture(value, name, at(name))
    scale = _BY_NAME["bump_scale"].check(bump_scale, at("bump_scale"))
    if is_texture(opacity):
        check_texture(opacity, "opacity", at("opacity"))
    else:
        opacity = _BY_NAME["opacity"].check(opacity, at("opacity"))
    flags = (
        ("two_sided", two_sided),
        ("shadowing_function", shadowing_function),
        ("normal_map_handedness", normal_map_handedness),
    )
    for name, flag in flags:
        if not isinstance(flag, bool):
            raise SpectraceError(f"{name} must be true or false, got {flag!r}", where=at(name))
    if normal_map is None and bump_map is None and not is_texture(opacity) and opacity == 1.0 and two_sided:
        return None
    return SurfaceDetail(normal_map, bump_map, scale, opacity, two_sided, shadowing_function, normal_map_handedness)


def cut_out_problem(material, emits: bool, has_interior: bool) -> str | None:
    """Why a shape may not take `material` for an opacity below 1, or None: an emitter would shine through its own
    holes for next-event estimation but not for the paths that meet it, and a cut-out boundary would not say which
    medium a ray is in."""
    detail = getattr(material, "detail", None)
    if detail is None or not detail.is_cut_out:
        return None
    if emits:
        return "an emitter must be opaque, but its material has an opacity"
    if has_interior:
        return "a shape with an interior must be opaque, but its material has an opacity"
    return None


def with_detail(material, surface: SurfaceDetail | None):
    return material if surface is None else dataclasses.replace(material, detail=surface)


def accepting_detail(make: Callable) -> Callable:
    """A material module's `make` that also takes the surface-detail keywords (the API's constructors, spectrace.<
    material>): written once here rather than in every module."""

    @functools.wraps(make)
    def detailed(
        *args,
        normal_map=None,
        bump_map=None,
        bump_scale=1.0,
        opacity=1.0,
        two_sided=True,
        shadowing_function=False,
        normal_map_handedness=False,
        **kwargs,
    ):
        return with_detail(
            make(*args, **kwargs),
            detail(
                normal_map,
                bump_map,
                bump_scale,
                opacity,
                two_sided,
                shadowing_function=shadowing_function,
                normal_map_handedness=normal_map_handedness,
            ),
        )

    signature = inspect.signature(make)
    extra = [
        inspect.Parameter(p.name, inspect.Parameter.KEYWORD_ONLY, default=p.default if p.default is not None else None)
        for p in PARAMETERS
    ]
    detailed.__signature__ = signature.replace(parameters=[*signature.parameters.values(), *extra])  # type: ignore[attr-defined]
    detailed.__doc__ = (make.__doc__ or "") + (
        "\n\nEvery material also takes normal_map or bump_map (with bump_scale, scene units), opacity (a number "
        "or texture in [0, 1]), two_sided (False: black from the back, for reflecting materials) and "
        "shadowing_function (True: Mitsuba 3's shadowing term on normal- and bump-mapped surfaces), "
        "normal_map_handedness (True: glTF's tangent frame, green up the image on mirrored layouts): "
        'docs/textures.md, "Surface detail".'
    )
    return detailed
