"""`mesh_attribute`: a mesh's own per-vertex or per-face values as a texture, Mitsuba 3's `mesh_attribute`. The
texture names the attribute (`vertex_<name>`: values at the vertices, blended across each triangle by the hit's
barycentrics; `face_<name>`: one value per face) and each mesh that wears it supplies its own values (a PLY file's
extra vertex or face properties, spectrace.geometry.ply; the API's `attributes`), times `scale`. Three channels are
a linear RGB colour, each vertex's uplifted to its smooth spectrum as a bitmap's texels are and the spectra blended;
one channel is a number, the same at every wavelength (a roughness, a mix's amount).

The values are known only once the texture meets its meshes, so the checks of a use (a reflectance's [0, 1], a
number's one channel and range) are recorded as the scene resolves (`uses`) and made when the scene's buffers are
built (engine/mesh_attribute_rows.py). Device form: kernels/texture_mesh_attribute.cl. docs/textures.md."""

from dataclasses import dataclass, field

from spectrace.core.parameters import REQUIRED, Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.textures.shared import Placement

NAME = "mesh_attribute"
API_NAME = "mesh_attribute"
COMPOSITE = False
ATTRIBUTE = True  # read from the mesh at the hit, with neither texels of its own nor texture coordinates
ATTRIBUTE_PARAMETER = Parameter(
    "attribute",
    "string",
    default=REQUIRED,
    doc="the mesh attribute: `vertex_<name>` (interpolated across each triangle) or `face_<name>` (constant per "
    "face), as Mitsuba 3 names a PLY file's extra properties (e.g. `vertex_color` from `r g b` or `color_0..2`)",
)
SCALE = Parameter("scale", "float", default=1.0, range=Range(0.0, None), doc="multiplies the attribute's values")
PARAMETERS = (ATTRIBUTE_PARAMETER, SCALE)
MITSUBA_PLUGINS = ("mesh_attribute",)
PBRT_TEXTURES: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4 has no mesh attribute texture"
PREFIXES = ("vertex_", "face_")


@dataclass(frozen=True, eq=False)
class MeshAttributeTexture:
    """Attribute `attribute` of the mesh that is hit, times `scale`. `uses`: (kind, upper bound, where) of each
    use the scene made of it, checked against every mesh that wears it once the buffers are built."""

    attribute: str
    scale: float = 1.0
    source: str = "mesh_attribute"
    placement: Placement = Placement()  # unused: nothing is looked up at uv
    uses: list = field(default_factory=list, compare=False, repr=False)

    @property
    def face(self) -> bool:
        return self.attribute.startswith("face_")


MODEL = MeshAttributeTexture


def checked_name(name: str, where: str | None) -> str:
    if not isinstance(name, str) or not name.startswith(PREFIXES) or len(name) <= len("face_"):
        raise SpectraceError(
            f"a mesh attribute's name starts with vertex_ or face_ (as Mitsuba 3 names them), got {name!r}",
            where=where or "attribute",
        )
    return name


def from_spec(spec, resolver, key: str) -> MeshAttributeTexture:
    return MeshAttributeTexture(checked_name(spec.attribute, resolver.where(f"{key}.attribute")), float(spec.scale))


def make(attribute: str, *, scale: float = 1.0) -> MeshAttributeTexture:
    """The mesh's attribute `attribute` ("vertex_color", "face_weight", ...) as a texture, times `scale`: each mesh
    that wears it supplies its values (a PLY file's extra properties, or `spectrace.mesh(..., attributes=...)`)."""
    return MeshAttributeTexture(checked_name(attribute, "attribute"), float(SCALE.check(scale, "scale")))


def record_use(texture: MeshAttributeTexture, kind: str, where: str, upper: float | None) -> None:
    """Remembers a use (checked when the texture meets its meshes): an emission is refused now, as the lights'
    images are looked up at uv with no mesh at hand."""
    if kind == "emission":
        raise SpectraceError("an emission texture is a bitmap or a spectral texture, not a mesh_attribute", where=where)
    bound = 1.0 if kind == "spectrum" else upper
    if (kind, bound, where) not in texture.uses:  # a scene resolved again (a live session) adds none
        texture.uses.append((kind, bound, where))


def use_problem(texture: MeshAttributeTexture, values) -> tuple[str, str] | None:
    """(where, why) a mesh's values of the attribute (count, channels), times the scale, do not fit a recorded
    use; None when they fit all."""
    channels = values.shape[1]
    low, high = float(values.min()) * texture.scale, float(values.max()) * texture.scale
    for kind, bound, where in texture.uses:
        if kind in ("float", "vector") and channels != 1:
            return where, f"has {channels} channels; this parameter needs one"
        if low < 0.0:
            return where, f"has negative values (min {low:.4g})"
        if bound is not None and high > bound + 1e-6:
            why = ", which as a reflectance would create energy" if kind == "spectrum" else ""
            return where, f"has values above {bound:g} (max {high:.4g}){why}"
    return None


def from_mitsuba(importer, texture, properties) -> dict | None:
    """Mitsuba 3's `mesh_attribute`: its `name` and `scale`."""
    name = importer.child(properties, "name", texture)
    table: dict = {"type": NAME, "attribute": importer.text(name)}
    if "scale" in properties:
        table["scale"] = importer.number(properties["scale"])
    for key in properties:
        if key not in ("name", "scale"):
            importer.unsupported_plugin(texture, f" with {key}")
    return table


def to_mitsuba(texture: MeshAttributeTexture, exporter) -> dict:
    return {"type": "mesh_attribute", "name": texture.attribute, "scale": texture.scale}
