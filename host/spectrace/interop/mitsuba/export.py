"""A loaded spectrace `Scene` as a Mitsuba 3 scene dictionary (`mitsuba.load_dict`), for side-by-side renders.

The export is meant to make Mitsuba do exactly the work spectrace does, so that timings and images compare:
- geometry: every shape's world-space triangles, float32, as binary PLY files in a folder the caller owns, with
  its vertex normals when it has them (smooth shading) and `face_normals` otherwise (flat, as spectrace; the
  winding decides the front side in both renderers), and its texture coordinates as spectrace uses them (Mitsuba
  reads a PLY's u, v as stored, so both look textures up at the same st);
- textures: each texture module's `to_mitsuba` (spectrace.textures.<name>): a bitmap becomes Mitsuba's `bitmap`
  reading a float OpenEXR of the texels spectrace decoded, written next to the meshes; a checkerboard, Mitsuba's
  `checkerboard`; a spectral texture has no Mitsuba counterpart and is refused;
- spectra: every spectrum as Mitsuba's `regular` spectrum on spectrace's own 1 nm grid (360-830 nm), so both
  interpolate the same samples linearly;
- materials and lights: each module's `to_mitsuba` (spectrace.materials.<name>, spectrace.lights.<name>) gives its
  entry; spectrace's diffuse reflects on both faces, so it becomes `twosided` around `diffuse` (a material with
  two_sided = false, the BSDF alone); Mitsuba's `area`
  emitter is one-sided toward the face normal, as spectrace's default;
- camera: the same origin/target/up (Mitsuba's `lookat` puts image-right along forward x up, as spectrace does),
  fov and fov_axis (a thin lens's aperture and focus; an orthographic view's width as to_world's scale); the
  scene's pixel filter (Mitsuba's filters have fixed radii: another radius is refused);
- film: `hdrfilm` with pixel_format "xyz". Both renderers estimate ∫ L (x̄, ȳ, z̄) dλ with the CIE 1931 2°
  functions on 360-830 nm and the same wavelength pdf, but divide by different constants: spectrace by ∫ ȳ dλ of
  its table (trapezoid rule, 106.857), Mitsuba 3 by its fixed MI_CIE_Y_NORMALIZATION (1/106.750), so Mitsuba's
  XYZ is 0.1 % higher for every spectrum (measured: 1.00098 ± 0.00003 for a constant radiance 1).
  `mitsuba_film_xyz` rescales Mitsuba's image to spectrace's convention before any comparison;
- integrator: `path` (or `ptracer` for the light tracer) with the same max_depth, rr_depth and hide_emitters
  (spectrace's hide_environment where the scene has no area lights). Both count max_depth in path segments and start
  Russian roulette once `rr_depth` bounces have happened, with survival probability min(max throughput, 0.95).

What has no faithful counterpart (a material or light whose module has no `to_mitsuba`: spot lights, whose falloff
profile differs in Mitsuba, environment maps from images; spectral textures, trilinear filtering; pictures on
lights, two-sided area lights, the `direct` integrator) is refused with a SpectraceError naming it.
"""

from pathlib import Path

import numpy as np

from spectrace.cameras import CAMERAS
from spectrace.errors import SpectraceError
from spectrace.geometry.grid_volume import vol_bytes
from spectrace.geometry.mesh import TriangleMesh
from spectrace.geometry.sdf_grid import SdfGridSurface
from spectrace.integrators import INTEGRATORS
from spectrace.lights import LIGHTS, area
from spectrace.materials import MATERIALS
from spectrace.scene.model import Scene
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from spectrace.textures import is_texture, texture_module


def regular_spectrum(spectrum: Spectrum) -> dict:
    """Mitsuba's piecewise-linear spectrum on spectrace's uniform 1 nm grid (its `regular` plugin: an O(1) lookup,
    where `irregular` searches the wavelength list, so the peer is not slowed by the export). A spectrum that is 0
    everywhere is Mitsuba's `uniform` 0: its `regular` plugin refuses one without probability mass."""
    if not np.any(spectrum.values):
        return {"type": "uniform", "value": 0.0}
    return {
        "type": "regular",
        "wavelength_min": float(GRID_NM[0]),
        "wavelength_max": float(GRID_NM[-1]),
        "values": ", ".join(f"{v:.9g}" for v in spectrum.values),
    }


def write_binary_ply(mesh: TriangleMesh, path: Path) -> None:
    """Float32 positions (and unit normals nx, ny, nz when the mesh has vertex normals; texture coordinates u, v,
    spectrace's, when it has them), the mesh's attributes as `<name>_0..` properties of its vertices or faces (which
    Mitsuba 3's PLY reader names `vertex_<name>`, `face_<name>` again) and int32 triangles."""
    columns, names = [mesh.vertices], ["x", "y", "z"]
    if mesh.normals is not None:
        length = np.linalg.norm(mesh.normals, axis=1, keepdims=True)
        columns.append(np.divide(mesh.normals, length, out=np.zeros_like(mesh.normals), where=length > 0))
        names += ["nx", "ny", "nz"]
    if mesh.uvs is not None:
        columns.append(mesh.uvs)
        names += ["u", "v"]
    face_columns: list[np.ndarray] = []
    face_names: list[str] = []
    for attribute, values in (mesh.attributes or {}).items():
        element, stem = attribute.split("_", 1)
        channels = [f"{stem}_{k}" for k in range(values.shape[1])]
        (columns if element == "vertex" else face_columns).append(values)
        (names if element == "vertex" else face_names).extend(channels)
    vertices = np.ascontiguousarray(np.concatenate(columns, axis=1), dtype="<f4")
    faces = np.empty(
        len(mesh.faces), dtype=[("n", "u1"), ("index", "<i4", (3,))] + [(name, "<f4") for name in face_names]
    )
    faces["n"] = 3
    faces["index"] = mesh.faces
    if face_columns:
        for name, column in zip(face_names, np.concatenate(face_columns, axis=1).T, strict=True):
            faces[name] = column
    properties = "".join(f"property float {name}\n" for name in names)
    face_properties = "".join(f"property float {name}\n" for name in face_names)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertices)}\n{properties}"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\n{face_properties}end_header\n"
    )
    with open(path, "wb") as out:
        out.write(header.encode("ascii"))
        out.write(vertices.tobytes())
        out.write(faces.tobytes())


def _refuse(what: str, scene: Scene) -> SpectraceError:
    return SpectraceError(
        f"cannot export to Mitsuba 3 faithfully: {what}", where=str(scene.source) if scene.source else None
    )


class MitsubaExport:
    """What the modules' `to_mitsuba(model, exporter)` use: `spectrum` (a Mitsuba spectrum entry, or a texture's
    where a parameter holds one), `material` (another material's entry, for a mix), `refuse` (the error for what
    has no faithful counterpart), for the texture modules `write_linear_image` and `uv_transform`, and for the
    cameras' `camera_to_world`."""

    def __init__(self, scene: Scene, folder: Path):
        self.scene = scene
        self.folder = folder
        # Each array written with its file, found again by identity and kept alive: an id() alone would be handed
        # on once a caller's temporary (a grey image repeated into RGB) was freed, and the next image given its file.
        self._images: list[tuple[np.ndarray, Path]] = []

    def spectrum(self, value) -> dict:
        if not is_texture(value):
            return regular_spectrum(value)
        module = texture_module(value)
        if not hasattr(module, "to_mitsuba"):
            raise self.refuse(f"a {module.NAME} texture ('{value.source}'): {module.MITSUBA_NONE}")
        if value.placement.mapping != "uv":  # Mitsuba 3 textures read the surface's uv only
            raise self.refuse(f"a {module.NAME} texture ('{value.source}') with a {value.placement.mapping} mapping")
        return module.to_mitsuba(value, self)

    def material(self, material) -> dict:
        """A material's Mitsuba entry (a composite's `to_mitsuba` exports its materials through it)."""
        to_mitsuba = _MATERIAL_EXPORTS.get(type(material))
        if to_mitsuba is None:
            raise self.refuse(f"material {type(material).__name__} is not exported yet")
        detail = material.detail
        if detail is not None and (detail.normal_map, detail.bump_map, detail.opacity) != (None, None, 1.0):
            raise self.refuse("surface detail (normal or bump map, opacity) is not exported yet")
        entry = to_mitsuba(material, self)
        if detail is not None and not detail.two_sided and entry["type"] == "twosided":
            entry = entry["bsdf"]  # Mitsuba's BSDF alone is one-sided, black from the back
        return entry

    def refuse(self, what: str) -> SpectraceError:
        return _refuse(what, self.scene)

    def write_linear_image(self, values: np.ndarray) -> Path:
        """A float OpenEXR (R, G, B) of linear values in the export's folder, once per array."""
        from spectrace.io.exr import write_exr

        for written, path in self._images:
            if written is values:
                return path
        path = self.folder / f"texture_{len(self._images)}.exr"
        write_exr(path, np.asarray(values, np.float32), None, {})
        self._images.append((values, path))
        return path

    @staticmethod
    def camera_to_world(camera, scale: float | None = None):
        """Mitsuba's to_world of a camera: its lookat, scaled by `scale` across the view (an orthographic view's
        half width)."""
        to_world = _lookat(camera.origin, camera.target, camera.up)
        if scale is None:
            return to_world
        import mitsuba as mi  # the caller has chosen a variant

        return to_world @ mi.ScalarTransform4f().scale([scale, scale, 1.0])

    @staticmethod
    def uv_transform(scale, offset):
        """Mitsuba's to_uv for uv' = uv · scale + offset."""
        import mitsuba as mi  # the caller has chosen a variant

        translate = mi.ScalarTransform4f().translate([float(offset[0]), float(offset[1]), 0.0])
        return translate @ mi.ScalarTransform4f().scale([float(scale[0]), float(scale[1]), 1.0])


# Resolved model -> its module's `to_mitsuba`; a model without one is refused.
_MATERIAL_EXPORTS = {m.MODEL: m.to_mitsuba for m in MATERIALS.values() if hasattr(m, "to_mitsuba")}
_LIGHT_EXPORTS = {m.MODEL: m.to_mitsuba for m in LIGHTS.values() if hasattr(m, "to_mitsuba")}


def _light_entry(light, exporter: MitsubaExport) -> dict:
    to_mitsuba = _LIGHT_EXPORTS.get(type(light))
    if to_mitsuba is None:
        raise exporter.refuse(f"{type(light).__name__} has no equivalent Mitsuba emitter")
    return to_mitsuba(light, exporter)


# Mitsuba 3's samplers; "independent" is its default, the stratified ones are its counterparts of spectrace's Sobol.
MITSUBA_SAMPLERS = ("independent", "stratified", "multijitter", "orthogonal", "ldsampler")


def scene_to_mitsuba_dict(
    scene: Scene, mesh_folder: Path, spp: int | None = None, sampler: str = "independent"
) -> dict:
    """The scene as a `mitsuba.load_dict` dictionary; meshes are written into `mesh_folder` (kept by the caller
    until Mitsuba has loaded them). `sampler` is one of MITSUBA_SAMPLERS: the samplers differ in error at equal spp,
    not in what they estimate."""
    if sampler not in MITSUBA_SAMPLERS:
        raise SpectraceError(
            f"unknown Mitsuba sampler '{sampler}'; samplers: {', '.join(MITSUBA_SAMPLERS)}", where="--peer-sampler"
        )
    # The integrators whose module has a Mitsuba 3 counterpart with the same max_depth and rr_depth meaning.
    exported = {name: to for name, module in INTEGRATORS.items() if (to := getattr(module, "to_mitsuba", None))}
    if scene.integrator not in exported:
        raise _refuse(
            f"integrator '{scene.integrator}' (only {' and '.join(repr(name) for name in exported)} map onto "
            "Mitsuba's path and particle tracers)",
            scene,
        )
    has_area_lights = any(shape.emitter is not None for shape in scene.shapes)
    if scene.hide_environment and not scene.hide_emitters and has_area_lights:
        raise _refuse("hide_environment with area lights (Mitsuba's hide_emitters hides both)", scene)
    mesh_folder = Path(mesh_folder)
    mesh_folder.mkdir(parents=True, exist_ok=True)
    camera = scene.camera
    exporter = MitsubaExport(scene, mesh_folder)
    entries: dict = {
        "type": "scene",
        "integrator": {
            **exported[scene.integrator](scene),
            "max_depth": int(scene.max_depth),
            "rr_depth": int(scene.rr_depth),
            "hide_emitters": bool(scene.hide_emitters or scene.hide_environment),
        },
        "sensor": {
            **_sensor(scene, exporter),
            # Mitsuba's own default (0.01) where ours is 0: it needs a positive plane.
            **({"near_clip": float(camera.near_clip)} if camera.near_clip > 0.0 else {}),
            # Mitsuba's default far clip is 10 000 scene units; spectrace's none.
            **({"far_clip": float(camera.far_clip)} if camera.far_clip is not None else {}),
            "sampler": {"type": sampler, "sample_count": int(spp or scene.spp)},
            "film": {
                "type": "hdrfilm",
                "width": int(scene.width),
                "height": int(scene.height),
                "pixel_format": "xyz",
                "rfilter": _rfilter(scene),
            },
        },
    }
    materials: dict[int, str] = {}

    def shape_entry(shape, file_stem: str) -> dict:
        # A light without material is crossed unchanged by every ray: Mitsuba's null bsdf.
        seen_through = shape.material is None and getattr(shape, "interior", None) is None
        to_mitsuba = _MATERIAL_EXPORTS.get(type(shape.material))
        if to_mitsuba is None and not seen_through:
            raise exporter.refuse(f"shape '{shape.name}': material {type(shape.material).__name__} is not exported yet")
        if getattr(shape, "interior", None) is not None:
            raise exporter.refuse(f"shape '{shape.name}': an interior medium is not exported yet")
        detail = shape.material.detail if shape.material is not None else None
        if detail is not None and (detail.normal_map, detail.bump_map, detail.opacity) != (None, None, 1.0):
            raise exporter.refuse(
                f"shape '{shape.name}': surface detail (normal or bump map, opacity) is not exported yet"
            )
        bsdf = {"type": "null"}
        if not seen_through:
            if id(shape.material) not in materials:
                name = f"material_{len(materials)}"
                entries[name] = exporter.material(shape.material)
                materials[id(shape.material)] = name
            bsdf = {"type": "ref", "id": materials[id(shape.material)]}
        # Mitsuba's own analytic shape, in the same object space; one with pbrt's texture coordinates (a disk or
        # sphere imported from pbrt-v4) or a partial one (Mitsuba has none) as its tessellation.
        analytic = shape.analytic
        if isinstance(analytic, SdfGridSurface):  # Mitsuba's sdfgrid, from a volume file of the same samples
            path = mesh_folder / f"{file_stem}.vol"
            path.write_bytes(vol_bytes(analytic.values))
            entry = {
                "type": "sdfgrid",
                "filename": str(path),
                "normals": analytic.normals,
                "to_world": _transform(analytic.to_world),
                "bsdf": bsdf,
            }
        elif analytic is not None and not analytic.partial and not (analytic.pbrt_uv and analytic.kind != "cylinder"):
            # Mitsuba turns a sphere's normals inward under a mirroring to_world (measured: an emitting sphere
            # scaled by (-1, 1, 1) renders black from outside); spectrace's sphere faces out whatever the matrix.
            # Its disk and cylinder keep their fronts under a mirror, as spectrace's do.
            mirrored = shape.analytic.kind == "sphere" and np.linalg.det(shape.analytic.linear) < 0
            entry = {
                "type": shape.analytic.kind,
                "to_world": _transform(shape.analytic.to_world),
                "flip_normals": bool(shape.analytic.flip_normals) != bool(mirrored),
                "bsdf": bsdf,
            }
        else:
            path = mesh_folder / f"{file_stem}.ply"
            write_binary_ply(shape.mesh, path)
            entry = {
                "type": "ply",
                "filename": str(path),
                "face_normals": shape.mesh.normals is None,
                "bsdf": bsdf,
            }
        if shape.emitter is not None:
            entry["emitter"] = area.to_mitsuba(shape.emitter, exporter, f"shape '{shape.name}'")
        return entry

    for index, shape in enumerate(scene.shapes):
        entries[f"shape_{index}"] = shape_entry(shape, f"shape_{index}")
    # Objects as Mitsuba's shapegroups (each stored once there too), instances as its instances.
    groups: dict[int, str] = {}
    for index, instance in enumerate(scene.instances):
        if id(instance.object) not in groups:
            group = groups[id(instance.object)] = f"object_{len(groups)}"
            entries[group] = {"type": "shapegroup"} | {
                f"shape_{k}": shape_entry(shape, f"{group}_shape_{k}") for k, shape in enumerate(instance.object.shapes)
            }
        entries[f"instance_{index}"] = {
            "type": "instance",
            "shapegroup": {"type": "ref", "id": groups[id(instance.object)]},
            "to_world": _transform(np.asarray(instance.to_world, np.float64)),
        }
    for index, light in enumerate(scene.lights):
        entries[f"light_{index}"] = _light_entry(light, exporter)
    return entries


def mitsuba_film_xyz(xyz: np.ndarray, mi) -> np.ndarray:
    """Mitsuba's film XYZ (`mi` with a spectral variant set) in spectrace's normalisation, ∫ L cmf dλ / ∫ ȳ dλ."""
    from spectrace.spectral.colorimetry import CIE_Y_INTEGRAL

    return np.asarray(xyz, dtype=np.float64) / (float(mi.MI_CIE_Y_NORMALIZATION) * CIE_Y_INTEGRAL)


def _transform(matrix: np.ndarray):
    import mitsuba as mi  # the caller has chosen a variant

    return mi.ScalarTransform4f(np.asarray(matrix, float).tolist())


def _sensor(scene: Scene, exporter: MitsubaExport) -> dict:
    """The camera as a Mitsuba 3 sensor, its module's to_mitsuba."""
    module = CAMERAS[scene.camera.type]
    to_mitsuba = getattr(module, "to_mitsuba", None)
    if to_mitsuba is None:
        raise _refuse(f"camera '{scene.camera.type}' ({getattr(module, 'MITSUBA_NONE', '')})", scene)
    return to_mitsuba(scene.camera, exporter)


def _rfilter(scene: Scene) -> dict:
    """The pixel filter as Mitsuba's rfilter (its module's to_mitsuba), whose radii are fixed: the filters'
    default radii (tent 1, Gaussian 4σ, Mitchell 2)."""
    f = scene.pixel_filter
    fixed = f.plugin.default_radius(f)
    if abs(f.support - fixed) > 1e-9 * fixed:
        raise _refuse(f"a {f.type} filter of radius {f.support:g} (Mitsuba's is {fixed:g})", scene)
    return f.plugin.to_mitsuba(f)


def _lookat(origin, target, up):
    import mitsuba as mi  # the caller has chosen a variant

    return mi.ScalarTransform4f().look_at(
        origin=list(map(float, origin)), target=list(map(float, target)), up=list(map(float, up))
    )
