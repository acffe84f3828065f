"""The parameter tables that materials and lights open with: one `Parameter` per scene key.

A table is the one place a key's type, unit, default and allowed range are written. The scene schema builds its
fields from it (scene/schema.py), the Python API takes its defaults and checks its ranges with it (api.py), and
tests check that docs/scene-format.md and docs/materials.md say the same (tests/materials, tests/lights).
"""

from dataclasses import dataclass
from numbers import Real

from spectrace.errors import SpectraceError

# GGX α below which a surface is smooth, a delta lobe (GGX_SMOOTH_ALPHA in kernels/microfacet.cl).
SMOOTH_ALPHA = 1e-3


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED = _Required()  # a key without a default


@dataclass(frozen=True)
class Range:
    """An interval of numbers; an end that is None is unbounded."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def __str__(self) -> str:
        if self.high is None:
            return f"{'>' if self.low_open else '>='} {self.low:g}"
        if self.low is None:
            return f"{'<' if self.high_open else '<='} {self.high:g}"
        return f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}{')' if self.high_open else ']'}"

    @property
    def bounded(self) -> bool:
        return self.low is not None and self.high is not None

    def contains(self, value: float) -> bool:
        if self.low is not None and not (value > self.low if self.low_open else value >= self.low):
            return False
        return self.high is None or (value < self.high if self.high_open else value <= self.high)

    def constraints(self) -> dict:
        """The same interval as pydantic Field constraints (gt/ge, lt/le)."""
        bounds = {}
        if self.low is not None:
            bounds["gt" if self.low_open else "ge"] = self.low
        if self.high is not None:
            bounds["lt" if self.high_open else "le"] = self.high
        return bounds


@dataclass(frozen=True)
class Parameter:
    """One key of a material or light.

    type: "spectrum", "float", "vector" (3 floats), "string", "bool", or a kind the schema knows ("metal", "ior").
    unit: as the docs write it ("" when a plain number needs none). default: REQUIRED, None (optional, no value),
    or the value (a spectrum's default is the constant it equals). range: the allowed numbers (for a spectrum:
    what every wavelength's value must satisfy). doc: the meaning, as the docs' table says it. type_doc /
    default_doc: how the docs' table writes the type and default where the generated text would not do.
    api_name: the Python API's name for the key when it differs. schema_range: False where a check of the whole
    table (the module's SPEC_CHECKS) reports the range instead of the field's own constraint. textured: the key also
    takes a texture (spectrace.textures; a one-channel one for a "float"), which the material's row refers to by its
    texture index, in the row field `texture_field` (default `<name>_texture`).
    """

    name: str
    type: str
    unit: str = ""
    default: object = REQUIRED
    range: Range | None = None
    doc: str = ""
    type_doc: str | None = None
    default_doc: str | None = None
    api_name: str | None = None
    schema_range: bool = True
    textured: bool = False
    texture_field: str | None = None

    @property
    def row_texture_field(self) -> str:
        """The Material row field that holds the index of this key's texture."""
        return self.texture_field or f"{self.name}_texture"

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    @property
    def number_default(self) -> float:
        """The default of a key whose default is a number, typed as one (dataclass fields, the API's signatures)."""
        if isinstance(self.default, bool) or not isinstance(self.default, (int, float)):
            raise TypeError(f"{self.name}'s default {self.default!r} is not a number")
        return self.default

    def range_problem(self, value) -> str | None:
        """Why `value` is not a number within the range, or None."""
        if (
            not isinstance(value, bool)
            and isinstance(value, Real)
            and (self.range is None or self.range.contains(float(value)))
        ):
            return None
        if self.range is None:
            return f"{self.name} must be a number, got {value!r}"
        unit = f" {self.unit}" if self.unit and self.unit != "dimensionless" else ""
        return f"{self.name} must {'lie in' if self.range.bounded else 'be'} {self.range}{unit}, got {value!r}"

    def check(self, value, where: str | None = None) -> float:
        """`value` as a float, or a SpectraceError naming the key when it is not a number within the range."""
        if problem := self.range_problem(value):
            raise SpectraceError(problem, where=where or self.api_name or self.name)
        return float(value)

    def doc_type(self) -> str:
        """The docs' "type, unit" column."""
        if self.type_doc is not None:
            return self.type_doc
        text = self.type
        if self.textured:
            text += " or texture" if self.type == "spectrum" else " or grey texture"
        if self.range is not None and self.range.bounded:
            text += f" in {self.range}"
        if self.unit:
            text += f", {self.unit}"
        if self.range is not None and not self.range.bounded:
            text += f", {self.range}".replace(">=", "≥").replace("<=", "≤")
        return text

    def doc_default(self) -> str:
        """The docs' "default" column."""
        if self.default_doc is not None:
            return self.default_doc
        if self.required:
            return "required"
        if self.default is None:
            return "—"
        if self.type == "spectrum":
            return f"`{{ value = {self.default:g} }}`"
        if isinstance(self.default, bool):
            return str(self.default).lower()
        if isinstance(self.default, float):
            return f"{self.default:g}"
        # As a scene file writes them: TOML strings are double-quoted, and a vector is an array.
        if isinstance(self.default, str):
            return f'`"{self.default}"`'
        if isinstance(self.default, (list, tuple)):
            return f"`[{', '.join(f'{value:g}' for value in self.default)}]`"
        return f"`{self.default!r}`"


ROUGHNESS_RANGE = Range(0.0, 1.0)


def roughness(default: float, doc: str) -> Parameter:
    """The GGX α every rough material shares (Mitsuba 3's `alpha`); a one-channel texture makes it vary over the
    surface (the Material row's `alpha` then holds the texture's largest value, which decides the BSDF's flags)."""
    return Parameter("roughness", "float", default=default, range=ROUGHNESS_RANGE, doc=doc, textured=True)


# The microfacet distributions of the rough materials (MICROFACET_DISTRIBUTIONS in spectrace.core.contract).
DISTRIBUTIONS = ("ggx", "beckmann")
DEFAULT_DISTRIBUTION = "ggx"


def distribution() -> Parameter:
    """The microfacet distribution of a rough material's lobe (Mitsuba 3's `distribution`; GGX by default here,
    Beckmann by default in Mitsuba)."""
    return Parameter(
        "distribution",
        "distribution",
        default=DEFAULT_DISTRIBUTION,
        default_doc=f'`"{DEFAULT_DISTRIBUTION}"`',
        type_doc='`"ggx"` or `"beckmann"`',
        doc="microfacet distribution of the rough lobe (docs/materials.md); `roughness` is its α",
    )


def check_distribution(value: str, where: str = "distribution") -> str:
    """`value` if it names a distribution, else a SpectraceError naming the key."""
    if value not in DISTRIBUTIONS:
        raise SpectraceError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, got {value!r}", where=where)
    return value


def reflectance(
    default: object,
    doc: str,
    name: str = "reflectance",
    default_doc: str | None = None,
    textured: bool = False,
    texture_field: str | None = None,
) -> Parameter:
    """A spectrum bounded by [0, 1] at every wavelength (or, when textured, a texture of such spectra)."""
    return Parameter(
        name,
        "spectrum",
        default=default,
        range=Range(0.0, 1.0),
        doc=doc,
        default_doc=default_doc,
        textured=textured,
        texture_field=texture_field,
    )


def specular_tint(doc: str) -> Parameter:
    """The optional tint of a conductor's or dielectric's lobes: a reflectance or a texture, stored where the
    reflectance of the other materials is (Material.reflectance_offset / reflectance_texture)."""
    return reflectance(
        None, doc, name="specular_tint", default_doc="none (1)", textured=True, texture_field="reflectance_texture"
    )
