"""The TOML scene format, as validated pydantic models. docs/scene-format.md documents every key and unit.

Only the shape of the input is checked here; references between sections (a shape's material, a named spectrum)
and files on disk are resolved by scene.loader, which reports errors with the same key paths.
"""

import dataclasses
import functools
import operator
from types import SimpleNamespace
from typing import TYPE_CHECKING, Annotated, Any, Literal, Protocol, TypeAlias

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    StrictBool,
    Tag,
    create_model,
    field_validator,
    model_validator,
)
from pydantic import Strict as StrictMode

from spectrace.cameras import CAMERAS
from spectrace.cameras import shared as camera_shared
from spectrace.core import limits
from spectrace.core.parameters import DISTRIBUTIONS, Parameter
from spectrace.film.response import observer_problem, wavelength_range_problem
from spectrace.geometry.analytic import cut_parameters
from spectrace.integrators import INTEGRATORS, settings_problem
from spectrace.lights import LIGHTS, area
from spectrace.materials import MATERIALS, surface
from spectrace.pixel_filters import PIXEL_FILTERS
from spectrace.scene.model import DEFAULT_SAMPLER, SamplerType
from spectrace.spectral.metals import METALS
from spectrace.textures import COMPOSITE_TEXTURES, TEXTURES

FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
# A TOML array read as a fixed-length tuple: strict validation takes only Python tuples, and the parsed file holds
# lists, so the tuple alone is lax; its items stay strict.
Vector3 = Annotated[tuple[FiniteFloat, FiniteFloat, FiniteFloat], StrictMode(False)]
FloatPair = Annotated[tuple[FiniteFloat, FiniteFloat], StrictMode(False)]


class Strict(BaseModel):
    # strict: a value of the wrong type is refused, not converted: `width = true` or `max_depth = true` is not 1,
    # `spp = "4"` not 4, `spp = 4.0` not 4, `two_sided = 1` not true. An integer is a float (a float key takes 2).
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


class SamplerSpec(Strict):
    type: SamplerType = Field(default=DEFAULT_SAMPLER, description="see docs/sampling.md")
    spp: int = Field(default=16, gt=0)
    seed: int = Field(default=0, ge=0, le=limits.MAX_SEED)

    @field_validator("spp")
    @classmethod
    def _spp_within_limit(cls, value: int) -> int:
        if problem := limits.spp_problem(value):
            raise ValueError(problem)
        return value


SPECTRUM_SOURCES = ("rgb", "value", "blackbody", "spectrum", "values", "file")


class SpectrumSpec(Strict):
    """One spectrum, from exactly one source, times `scale`.

    rgb: linear sRGB triple, uplifted (reflectance: bounded smooth spectrum; emission: D65-shaped white);
    value: a constant; spectrum: the name of a [spectra.NAME] entry or a library spectrum ("cornell_box/light",
    "cornell_box/reflectance:white", "cie:D65"); values: inline "wavelength:value" pairs; file (+ column): a CSV.
    """

    rgb: Vector3 | None = None
    value: FiniteFloat | None = None
    blackbody: FiniteFloat | None = Field(default=None, description="temperature in kelvin; peak normalised to 1")
    display: str | None = Field(default=None, description="emission only: a display name or CSV; rgb is its drive")
    image: str | None = Field(default=None, description="with display: a picture (PNG, JPEG, EXR) it shows")
    encoding: Literal["linear", "srgb", "gamma2.2"] = "linear"
    white_luminance: FiniteFloat | None = Field(default=None, gt=0.0, description="cd/m² of the display's white")
    spectrum: str | None = None
    values: str | list[FloatPair] | None = None
    file: str | None = None
    column: str | None = None
    scale: FiniteFloat = 1.0

    @model_validator(mode="after")
    def _exactly_one_source(self) -> "SpectrumSpec":
        sources = [k for k in SPECTRUM_SOURCES if getattr(self, k) is not None]
        if self.display is not None:
            if (self.rgb is None) == (self.image is None) or sources not in (["rgb"], []):
                raise ValueError("a display spectrum needs exactly one of rgb (a triple) or image (a picture)")
        elif self.image is not None:
            raise ValueError("image needs display (the display that shows it)")
        elif len(sources) != 1:
            given = ", ".join(sources) if sources else "none"
            raise ValueError(f"give exactly one of {', '.join(SPECTRUM_SOURCES)} (given: {given})")
        if self.display is None and (self.encoding != "linear" or self.white_luminance is not None):
            raise ValueError("encoding and white_luminance only apply to a display spectrum")
        if self.blackbody is not None and self.blackbody <= 0:
            raise ValueError(f"blackbody temperature must be > 0 K, got {self.blackbody}")
        if self.column is not None and self.file is None:
            raise ValueError("column is only meaningful with file")
        if self.scale < 0:
            raise ValueError(f"scale must be >= 0, got {self.scale}")
        return self


class NamedSpectrumSpec(Strict):
    """A [spectra.NAME] entry: a spectrum defined once and referred to by name."""

    values: str | list[FloatPair] | None = None
    file: str | None = None
    column: str | None = None
    library: str | None = None

    @model_validator(mode="after")
    def _exactly_one_source(self) -> "NamedSpectrumSpec":
        sources = [k for k in ("values", "file", "library") if getattr(self, k) is not None]
        if len(sources) != 1:
            raise ValueError("give exactly one of values, file, library")
        return self


class SellmeierSpec(Strict):
    sellmeier: Annotated[
        tuple[FiniteFloat, FiniteFloat, FiniteFloat, FiniteFloat, FiniteFloat, FiniteFloat], StrictMode(False)
    ] = Field(description="B1, B2, B3, C1, C2, C3 of n² = 1 + Σ B λ²/(λ² − C), λ in µm, C in µm²")


class CauchySpec(Strict):
    cauchy: FloatPair = Field(description="a, b of n = a + b/λ², λ in µm, b in µm²")


class TransformStep(Strict):
    translate: Vector3 | None = None
    scale: FiniteFloat | Vector3 | None = None
    rotate: dict | None = None
    matrix: list[list[FiniteFloat]] | None = None

    @model_validator(mode="after")
    def _exactly_one(self) -> "TransformStep":
        given = [k for k in ("translate", "scale", "rotate", "matrix") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("each transform step has exactly one of translate, scale, rotate, matrix")
        return self


# Materials and lights: one spec per module of spectrace.materials / spectrace.lights, told apart by `type`, its
# fields made from the module's parameter table (docs/materials.md describes each model).
_ANNOTATIONS = {
    "spectrum": SpectrumSpec,
    "float": FiniteFloat,
    "vector": Vector3,
    "string": str,
    "bool": bool,
    "int": int,
    "metal": Literal[METALS],
    "distribution": Literal[DISTRIBUTIONS],
    "coat_transmission": Literal["smooth", "rough"],
    "ior": FiniteFloat | str | SellmeierSpec | CauchySpec,
    "uv": FiniteFloat | FloatPair,
    "transform": list[TransformStep],  # a solid texture's placement, as a shape's transform
    "wrap": Literal["repeat", "mirror", "clamp"],
    "filter": Literal["nearest", "bilinear", "trilinear"],
    "mapping": Literal["uv", "spherical", "cylindrical", "planar"],  # a 2D texture's (textures/mapping.py)
    "axis": Literal["x", "y"],
    "materials": Annotated[tuple[str, str], StrictMode(False)],  # a mix's two materials, by their names in [materials]
    "material": str,  # a fluorescent material's base, by its name in [materials]
}


# Textures (docs/textures.md): inline, `{ texture = "bitmap", file = "wood.png" }`, the key `texture` naming the type;
# or a [textures.NAME] table with `type`, referred to as `{ texture = "NAME" }`. A texture's own textured keys (a
# checkerboard's colours, a scale's or mix's operands) take spectra or image textures, not another composite.
class TextureRefSpec(Strict):
    """{ texture = "NAME" }: a [textures.NAME] entry of this file."""

    texture: str


def _texture_model(module, key: str, textured_annotation) -> type[Strict]:
    fields: dict[str, Any] = {key: (Literal[module.NAME], ...)}
    for parameter in module.PARAMETERS:
        if parameter.textured and parameter.type == "float":
            # A composite's factor (scale's `scale`, mix's `amount`): a number, or an image texture (checked as read).
            annotation = _number_or_texture(FiniteFloat, textured_annotation) if textured_annotation else FiniteFloat
            fields[parameter.name] = (annotation, Field(default=parameter.default, description=parameter.doc))
            continue
        annotation, field = _field(parameter)
        if parameter.textured:
            annotation = textured_annotation
        fields[parameter.name] = (annotation, field)
    kind = "Named" if key == "type" else "Inline"
    return create_model(
        f"{kind}{module.NAME.capitalize()}TextureSpec", __base__=Strict, __doc__=module.__doc__, **fields
    )


def _spectrum_or_texture(inline: dict[str, type[Strict]], spectrum: bool = True):
    """A spectrum table, an inline texture (told apart by the type its `texture` names) or a reference; without
    `spectrum`, a texture only."""

    def tag(value) -> str:
        if isinstance(value, dict):
            kind = value.get("texture")
        else:
            kind = getattr(value, "texture", None)
        if kind is None and spectrum:
            return "spectrum"
        return kind if kind in inline else "reference"

    members = [Annotated[SpectrumSpec, Tag("spectrum")]] if spectrum else []
    members += [Annotated[TextureRefSpec, Tag("reference")]]
    members += [Annotated[model, Tag(name)] for name, model in inline.items()]
    return Annotated[functools.reduce(operator.or_, members), Discriminator(tag)]


def _number_or_texture(number, textured):
    """A textured number (a `roughness`): the number itself, or a texture, inline or by name (`textured`: the same
    union for spectra, whose non-number members are the textures)."""

    def tag(value) -> str:
        return "number" if isinstance(value, (int, float)) else "texture"

    return Annotated[
        Annotated[number, Tag("number")] | Annotated[textured, Tag("texture")],
        Discriminator(tag),
    ]


def _field(parameter: Parameter) -> tuple:
    if parameter.type == "texture":  # a material's own texture of data (principled's anisotropic_direction)
        return SpectrumOrTexture | None, Field(default=None, description=parameter.doc)
    annotation: Any = _ANNOTATIONS[parameter.type]
    default: object
    if parameter.required:
        default = ...
    elif parameter.default is None:
        annotation, default = annotation | None, None
    elif parameter.type == "spectrum":
        default = SpectrumSpec(value=parameter.number_default)
    elif isinstance(parameter.default, tuple):
        default = tuple(parameter.default)
    else:
        default = parameter.default
    constraints = (
        parameter.range.constraints()
        if parameter.type in ("float", "int") and parameter.range is not None and parameter.schema_range
        else {}
    )
    description = f"{parameter.unit}: {parameter.doc}" if parameter.unit else parameter.doc
    if parameter.textured and parameter.type == "float":
        # The range constrains the number; a texture's values are checked as it is read.
        annotation, constraints = _number_or_texture(Annotated[annotation, Field(**constraints)], TextureOnly), {}
    return annotation, Field(default=default, description=description, **constraints)


def _after(check):
    """A module's check of a whole table as a model validator: it raises ValueError, as pydantic expects."""

    def validate(self):
        check(self)
        return self

    return model_validator(mode="after")(validate)


# Composites (a checkerboard, scale, mix) take spectra and image textures, not other composites.
_IMAGE_TEXTURES = {name: m for name, m in TEXTURES.items() if name not in COMPOSITE_TEXTURES}
if TYPE_CHECKING:
    InnerSpectrumOrTexture: TypeAlias = Any
    SpectrumOrTexture: TypeAlias = Any
    TextureOnly: TypeAlias = Any
    NamedTextureSpec: TypeAlias = Any
else:
    InnerSpectrumOrTexture = _spectrum_or_texture(
        {name: _texture_model(m, "texture", None) for name, m in _IMAGE_TEXTURES.items()}
    )
    _INLINE_TEXTURES = {name: _texture_model(m, "texture", InnerSpectrumOrTexture) for name, m in TEXTURES.items()}
    SpectrumOrTexture = _spectrum_or_texture(_INLINE_TEXTURES)
    TextureOnly = _spectrum_or_texture(_INLINE_TEXTURES, spectrum=False)
    NamedTextureSpec = Annotated[
        functools.reduce(operator.or_, (_texture_model(m, "type", InnerSpectrumOrTexture) for m in TEXTURES.values())),
        Field(discriminator="type"),
    ]


def _spec_model(module, name: str, type_default=..., extra: dict | None = None) -> type[Strict]:
    fields: dict[str, Any] = {"type": (Literal[module.NAME], type_default)}
    for parameter in module.PARAMETERS:
        annotation, field = _field(parameter)
        textured_spectrum = parameter.textured and parameter.type == "spectrum"
        fields[parameter.name] = (SpectrumOrTexture if textured_spectrum else annotation, field)
    fields |= extra or {}
    return create_model(
        name,
        __base__=Strict,
        __doc__=module.__doc__,
        __validators__={check.__name__: _after(check) for check in getattr(module, "SPEC_CHECKS", ())},
        **fields,
    )


if TYPE_CHECKING:
    IntegratorName: TypeAlias = str
else:  # the registry's names, as a Literal: pydantic lists them when another is given
    IntegratorName = Literal[tuple(INTEGRATORS)]


class _IntegratorKeys(Strict):
    """The checks of the [integrator] table beyond each key's own: max_depth 0 means nothing, and a key of some
    integrators is refused for the others (spectrace.integrators.settings_problem)."""

    type: IntegratorName = "path"

    @field_validator("max_depth", check_fields=False)
    @classmethod
    def _depth_not_zero(cls, value: int) -> int:
        if value == 0:
            raise ValueError("max_depth must be -1 (unbounded) or >= 1")
        return value

    @model_validator(mode="after")
    def _keys_of_this_integrator(self) -> "_IntegratorKeys":
        if problem := settings_problem(self.type, self):
            raise ValueError(problem)
        return self


def _integrator_fields() -> dict[str, Any]:
    """Every integrator's keys (their PARAMETERS, in the registry's order); a key that only some take says which."""
    fields: dict[str, Any] = {}
    for plugin in INTEGRATORS.values():
        for parameter in plugin.PARAMETERS:
            if parameter.name in fields:
                continue
            owners = [name for name, p in INTEGRATORS.items() if parameter in p.PARAMETERS]
            if len(owners) < len(INTEGRATORS):
                parameter = dataclasses.replace(parameter, doc=f"{' and '.join(owners)} only: {parameter.doc}")
            fields[parameter.name] = _field(parameter)
    return fields


if TYPE_CHECKING:
    IntegratorSpec: TypeAlias = Any
else:
    IntegratorSpec = create_model("IntegratorSpec", __base__=_IntegratorKeys, **_integrator_fields())


class TableSpec(Protocol):
    """A model built from a parameter table: its `type`, and fields known only once the table has made it."""

    @property
    def type(self) -> str: ...

    def __getattr__(self, name: str) -> Any: ...


def _surface_detail_fields() -> dict[str, Any]:
    """The keys every material takes besides its own (spectrace.materials.surface): textures (normal_map,
    bump_map), a number (bump_scale), a number or texture (opacity), whose range the loader checks, and a boolean
    (two_sided, shadowing_function)."""
    fields: dict[str, Any] = {}
    for parameter in surface.PARAMETERS:
        annotation, field = _field(parameter) if parameter.type in ("float", "bool") else (None, None)
        if parameter.type == "texture":
            annotation, field = SpectrumOrTexture | None, Field(default=None, description=parameter.doc)
        elif parameter.textured:
            annotation = FiniteFloat | SpectrumOrTexture
            field = Field(default=parameter.default, description=parameter.doc)
        fields[parameter.name] = (annotation, field)
    return fields


MATERIAL_SPECS = {
    name: _spec_model(module, f"{name.capitalize()}MaterialSpec", extra=_surface_detail_fields())
    for name, module in MATERIALS.items()
}
if TYPE_CHECKING:  # the models are made at import, so a type checker sees them only as tables with a type
    MaterialSpec: TypeAlias = TableSpec
    EmitterSpec: TypeAlias = TableSpec
else:
    MaterialSpec = Annotated[functools.reduce(operator.or_, MATERIAL_SPECS.values()), Field(discriminator="type")]
    EmitterSpec = _spec_model(area, "EmitterSpec", type_default="area")  # a shape's area light


class DensityGridSpec(Strict):
    """A heterogeneous medium's voxel grid (docs/media.md): a Mitsuba volume `file` (.vol) or inline `values` (x
    fastest) of `resolution` [nx, ny, nz], one value a voxel or three (a colour), or neither: a density of 1; an
    optional albedo grid of the same size, and for a glowing medium an emission scale grid and a temperature grid
    (kelvin: blackbody emission); filling `box` (two corners), then moved by `transform` (in the scene's
    space, not the shape's); `outside`: what it holds outside the box (empty, clamp: its faces' values, repeat:
    copies of itself). A NanoVDB `file` (.nvdb) is placed by its own index-to-world map instead of `box`."""

    file: str | None = None
    values: list[FiniteFloat] | None = None
    resolution: Annotated[tuple[int, int, int], StrictMode(False)] | None = None
    albedo_file: str | None = None
    albedo_values: list[FiniteFloat] | None = None
    emission_file: str | None = None
    emission_values: list[FiniteFloat] | None = None
    temperature_file: str | None = None
    temperature_values: list[FiniteFloat] | None = None
    grid: str | None = Field(default=None, description="a NanoVDB file's float grid to read (default: density)")
    temperature_offset: FiniteFloat = 0.0
    temperature_scale: FiniteFloat = 1.0
    box: Annotated[tuple[Vector3, Vector3], StrictMode(False)] = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    transform: list[TransformStep] = []
    outside: Literal["empty", "clamp", "repeat"] = "empty"

    @model_validator(mode="after")
    def _one_source(self) -> "DensityGridSpec":
        if self.file is not None and self.values is not None:
            raise ValueError("give either file or values")
        if self.file is None and self.values is None and self.albedo_file is None and self.albedo_values is None:
            raise ValueError("give either file or values (or only an albedo grid, over a density of 1)")
        if (self.values is not None or self.albedo_values is not None) and self.resolution is None:
            raise ValueError("values need resolution = [nx, ny, nz]")
        for name in ("albedo", "emission", "temperature"):
            if getattr(self, f"{name}_file") is not None and getattr(self, f"{name}_values") is not None:
                raise ValueError(f"give {name}_file or {name}_values, not both")
            if getattr(self, f"{name}_values") is not None and self.resolution is None:
                raise ValueError(f"{name}_values need resolution = [nx, ny, nz]")
        return self


class InteriorSpec(Strict):
    """A homogeneous medium filling a closed shape (docs/media.md): coefficients sigma_a, sigma_s in 1/scene unit
    (each a spectrum; an omitted one is 0), or a measured `preset` (its table is in 1/mm); either way times
    `scale`. g: Henyey–Greenstein asymmetry (0 isotropic, > 0 forward). emission: a glowing medium's radiance
    spectrum Le, emitted as σa Le per unit length (default 1 where the density grid has emission or temperature
    grids)."""

    preset: str | None = None
    sigma_a: SpectrumSpec | None = None
    sigma_s: SpectrumSpec | None = None
    scale: FiniteFloat = Field(default=1.0, gt=0.0, description="multiplies the coefficients")
    g: FiniteFloat = Field(default=0.0, gt=-1.0, lt=1.0)
    density: DensityGridSpec | None = None
    emission: SpectrumSpec | None = None

    @model_validator(mode="after")
    def _preset_or_coefficients(self) -> "InteriorSpec":
        coefficients = self.sigma_a is not None or self.sigma_s is not None
        if (self.preset is not None) == coefficients:
            raise ValueError("give either preset or sigma_a and/or sigma_s")
        return self


class ShapeSpec(Strict):
    type: Literal["mesh", "rectangle", "cube", "sphere", "disk", "cylinder", "prism", "teapot", "sdfgrid", "curve"]
    file: str | None = None
    shape_index: Annotated[int, Field(ge=0, strict=True)] | None = None  # which mesh of a .serialized file
    material: str | None = None
    emitter: EmitterSpec | None = None
    interior: InteriorSpec | None = None
    transform: list[TransformStep] = []
    name: str | None = None
    # true: shade with the face normals (facets); false: smooth, with normals computed when a mesh file has none;
    # unset: a mesh file's own normals if it has any, the sphere's radial ones (docs/scene-format.md)
    face_normals: StrictBool | None = None
    # sphere, disk, cylinder: true renders triangles (the icosphere, a polar grid, a ring of quads) instead of the
    # exact surface (docs/scene-format.md)
    tessellated: StrictBool | None = None
    # sphere, disk, cylinder: their front (normal, emitting side) faces inward, or the disk's -z side
    flip_normals: StrictBool | None = None
    # sphere, disk, cylinder: "pbrt" gives them pbrt-v4's texture coordinates instead of Mitsuba 3's; curve:
    # "mitsuba" gives it Mitsuba 3's instead of pbrt-v4's (docs/scene-format.md)
    uv_convention: Literal["mitsuba", "pbrt"] | None = None
    # sphere only: placed before `transform`, as Mitsuba 3's center and radius are before its to_world
    center: Vector3 | None = None
    radius: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None
    # partial shapes (pbrt-v4's phimax, zmin/zmax, innerradius; docs/scene-format.md): the azimuths kept, degrees;
    # the sphere's heights kept, in [-radius, radius]; the disk's hole, a fraction of its radius
    phi_max: FiniteFloat | None = None
    z_min: FiniteFloat | None = None
    z_max: FiniteFloat | None = None
    inner_radius: FiniteFloat | None = None
    # sdfgrid (geometry/sdf_grid.py): its samples inline, [z][y][x], instead of a volume file; its shading normals
    grid: list[list[list[FiniteFloat]]] | None = None
    normals: Literal["smooth", "analytic"] | None = None
    # curve (docs/scene-format.md, "Curves"): one curve's control points, rows of x, y, z, radius (or `file`, a
    # Mitsuba 3 curve file of many); "linear" joins them, "bspline" is their uniform cubic B-spline
    points: list[list[FiniteFloat]] | None = None
    basis: Literal["linear", "bspline"] | None = None
    open_ends: StrictBool | None = None  # curve: no sphere closes its ends (default: a B-spline's)
    # curve: a round "tube" (default) or pbrt-v4's "flat" strip facing each ray or "ribbon" oriented by
    # curve_normals, one x, y, z row per point (kernels/curve_ribbon.cl)
    curve_type: Literal["tube", "flat", "ribbon"] | None = None
    curve_normals: list[list[FiniteFloat]] | None = None

    @model_validator(mode="after")
    def _file_for_meshes(self) -> "ShapeSpec":
        if self.type == "mesh" and self.file is None:
            raise ValueError("a mesh shape needs file")
        if self.type == "sdfgrid" and (self.file is None) == (self.grid is None):
            raise ValueError("an sdfgrid shape needs either file (a volume file) or grid (its samples), not both")
        if self.type != "sdfgrid" and (self.grid is not None or self.normals is not None):
            raise ValueError(f"grid and normals are an sdfgrid's, not a {self.type}'s")
        if self.type == "sdfgrid" and self.emitter is not None:
            raise ValueError("an sdfgrid cannot emit (it has no area sampling, as in Mitsuba 3)")
        if self.type == "curve":
            curve_spec_problem(self)
        elif self.points is not None or self.basis is not None or self.open_ends is not None:
            raise ValueError(f"points, basis and open_ends are a curve's, not a {self.type}'s")
        elif self.curve_type is not None or self.curve_normals is not None:
            raise ValueError(f"curve_type and curve_normals are a curve's, not a {self.type}'s")
        if self.type not in ("mesh", "sdfgrid", "curve") and self.file is not None:
            raise ValueError(f"a {self.type} shape takes no file")
        if self.shape_index is not None and not (self.file or "").lower().endswith(".serialized"):
            raise ValueError("shape_index picks a mesh of a Mitsuba .serialized file; this shape has none")
        if self.material is None and self.interior is None and self.emitter is None:
            raise ValueError("a shape needs material (only a shape with an interior or an emitter may omit it)")
        if self.type in ("rectangle", "disk", "cylinder") and self.interior is not None:
            raise ValueError(f"a {self.type} encloses no volume: an interior needs a closed shape")
        if (self.center is not None or self.radius is not None) and self.type != "sphere":
            raise ValueError(f"center and radius are a sphere's, not a {self.type}'s (use transform)")
        if self.flip_normals is not None and self.type not in ("sphere", "disk", "cylinder"):
            raise ValueError(
                f"flip_normals is for sphere, disk and cylinder (a mirroring transform turns a {self.type})"
            )
        if self.uv_convention is not None and self.type not in ("sphere", "disk", "cylinder", "curve"):
            raise ValueError(f"uv_convention is for sphere, disk, cylinder and curve, not a {self.type}")
        if self.tessellated is not None and self.type not in ("sphere", "disk", "cylinder"):
            raise ValueError(f"tessellated is for the analytic shapes (sphere, disk, cylinder), not a {self.type}")
        cut_keys = (self.phi_max, self.z_min, self.z_max, self.inner_radius)
        if any(key is not None for key in cut_keys):
            if self.type not in ("sphere", "disk", "cylinder"):
                raise ValueError(
                    f"phi_max, z_min, z_max and inner_radius cut a sphere, disk or cylinder, not a {self.type}"
                )
            if cut_parameters(self.type, *cut_keys, radius=self.radius or 1.0) and self.interior is not None:
                raise ValueError("a partial shape encloses no volume: an interior needs a closed shape")
        return self


def curve_spec_problem(spec: ShapeSpec) -> None:
    """A curve shape's keys that cannot go together (raises ValueError)."""
    if (spec.file is None) == (spec.points is None):
        raise ValueError("a curve needs either file (a curve file) or points (one curve's x, y, z, radius rows)")
    if spec.emitter is not None:
        raise ValueError("a curve cannot emit light")
    if spec.interior is not None:
        raise ValueError("a curve holds no interior (its back faces are not intersected)")
    if spec.shape_index is not None or spec.face_normals is not None or spec.tessellated is not None:
        raise ValueError("shape_index, face_normals and tessellated are not a curve's keys")


_LIGHT_SPEC_NAMES = {"constant": "ConstantEnvironmentSpec", "envmap": "EnvironmentMapSpec"}
LIGHT_SPECS = {
    name: _spec_model(module, _LIGHT_SPEC_NAMES.get(name, f"{name.capitalize()}LightSpec"))
    for name, module in LIGHTS.items()
}
if TYPE_CHECKING:
    LightSpec: TypeAlias = TableSpec
else:
    LightSpec = Annotated[functools.reduce(operator.or_, LIGHT_SPECS.values()), Field(discriminator="type")]


def _camera_spec(module) -> type[Strict]:
    """A camera type's keys: the shared ones (spectrace.cameras.shared), then its module's."""
    table = SimpleNamespace(
        NAME=module.NAME,
        PARAMETERS=camera_shared.PARAMETERS + module.PARAMETERS,
        SPEC_CHECKS=getattr(module, "SPEC_CHECKS", ()),
        __doc__=module.__doc__,
    )
    model = _spec_model(table, f"{module.NAME.capitalize()}CameraSpec", type_default=module.NAME)
    checked = [p for p in table.PARAMETERS if p.type == "float" and p.range is not None and not p.schema_range]
    if not checked:
        return model

    def in_range(cls, value, info):
        parameter = next(p for p in checked if p.name == info.field_name)
        if value is not None and (problem := parameter.range_problem(value)):
            raise ValueError(problem)
        return value

    validator: Any = field_validator(*(p.name for p in checked))(classmethod(in_range))
    return create_model(model.__name__, __base__=model, __validators__={"_in_range": validator})


def _type_or(default: str):
    """The discriminator of a table whose `type` may be left out (then `default`)."""

    def tag(value) -> str:
        return value.get("type", default) if isinstance(value, dict) else getattr(value, "type", default)

    return Discriminator(tag)


CAMERA_SPECS = {name: _camera_spec(module) for name, module in CAMERAS.items()}
_FILTER_SPECS = {
    name: create_model(
        f"{name.capitalize()}FilterSpec",
        __base__=Strict,
        **{"type": (Literal[name], ...)} | {parameter.name: _field(parameter) for parameter in module.PARAMETERS},
    )
    for name, module in PIXEL_FILTERS.items()
}
if TYPE_CHECKING:
    CameraSpec: TypeAlias = TableSpec
    PixelFilterSpec: TypeAlias = Any
else:
    CameraSpec = Annotated[
        functools.reduce(operator.or_, (Annotated[m, Tag(n)] for n, m in CAMERA_SPECS.items())),
        _type_or("perspective"),
    ]
    PixelFilterSpec = (
        Literal[tuple(PIXEL_FILTERS)]
        | Annotated[functools.reduce(operator.or_, _FILTER_SPECS.values()), Field(discriminator="type")]
        | None
    )


class FilmSpec(Strict):
    width: int = Field(gt=0)
    height: int = Field(gt=0)
    exposure: FiniteFloat = Field(
        default=0.0,
        ge=-limits.MAX_EXPOSURE_STOPS,
        le=limits.MAX_EXPOSURE_STOPS,
        description="stops: RGB output x 2**exposure",
    )
    filter: PixelFilterSpec = Field(default=None, description="the pixel's reconstruction filter (default box)")
    aovs: list[Literal["albedo", "normal", "depth", "position", "variance", "stokes", "dolp", "aolp"]] = Field(
        default_factory=list, description="AOVs written beside the image (EXR channels)"
    )
    observer: str = Field(default="CIE 1931 2°", description="CIE observer of the film's X, Y, Z and RGB outputs")
    observers: list[str] = Field(default_factory=list, description="more observers, X, Y, Z each as EXR channels")
    sensor: str | None = Field(default=None, description="CSV of measured channel sensitivities, as EXR channels")
    sensor_white: str | None = Field(
        default=None, description="CIE illuminant: white balance and colour correction of a 3-channel sensor"
    )

    wavelengths: FloatPair = Field(
        default=(360.0, 830.0), description="nm: the film's wavelength range (1 nm grid); spectra must cover it"
    )
    extend_rgb: StrictBool = Field(
        default=False, description="RGB uplifts continue (their sigmoid) beyond the visible when wavelengths go there"
    )

    @field_validator("wavelengths")
    @classmethod
    def _wavelength_range(cls, value: tuple[float, float]) -> tuple[float, float]:
        if problem := wavelength_range_problem(value):
            raise ValueError(problem)
        return value

    @field_validator("observer")
    @classmethod
    def _known_observer(cls, value: str) -> str:
        if problem := observer_problem(value):
            raise ValueError(problem)
        return value

    @field_validator("observers")
    @classmethod
    def _known_observers(cls, value: list[str]) -> list[str]:
        for label in value:
            if problem := observer_problem(label):
                raise ValueError(problem)
        if len(set(value)) != len(value):
            raise ValueError("an observer is listed twice")
        return value

    @field_validator("width", "height")
    @classmethod
    def _side_within_limit(cls, value: int, info) -> int:
        if problem := limits.film_side_problem(info.field_name, value):
            raise ValueError(problem)
        return value

    @model_validator(mode="after")
    def _pixels_within_limit(self) -> "FilmSpec":
        if problem := limits.film_size_problem(self.width, self.height):
            raise ValueError(problem)
        return self


class ObjectSpec(Strict):
    """A group of shapes declared once in its own space and placed by `instances` (Mitsuba 3's shapegroup, pbrt-v4's
    ObjectBegin/ObjectEnd); not rendered by itself."""

    shapes: list[ShapeSpec] = Field(min_length=1)


class InstanceSpec(Strict):
    """One placement of an object (Mitsuba 3's instance, pbrt-v4's ObjectInstance)."""

    object: str
    transform: list[TransformStep] = []
    name: str | None = None


class SceneSpec(Strict):
    camera: CameraSpec
    film: FilmSpec
    integrator: IntegratorSpec = IntegratorSpec()
    sampler: SamplerSpec = SamplerSpec()
    spectra: dict[str, NamedSpectrumSpec] = {}
    textures: dict[str, NamedTextureSpec] = {}
    materials: dict[str, MaterialSpec] = {}
    shapes: list[ShapeSpec] = []
    lights: list[LightSpec] = []
    objects: dict[str, ObjectSpec] = {}
    instances: list[InstanceSpec] = []

    @model_validator(mode="after")
    def _one_environment(self) -> "SceneSpec":
        if sum(1 for light in self.lights if LIGHTS[light.type].IS_ENVIRONMENT) > 1:
            raise ValueError("at most one environment light (constant or envmap)")
        return self
