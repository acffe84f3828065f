"""The Python API: build scenes from Python objects and render them, with no scene file and no command line.

Every helper here produces the same model objects (`spectrace.scene.model`) the TOML loader produces, with the
same meaning and units as the scene format's keys (docs/scene-format.md), so a scene built here renders exactly
like the same scene written as TOML. docs/python-api.md shows it in use.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from contextlib import contextmanager
from numbers import Real
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np

from spectrace import lights, materials, textures
from spectrace.core.api_calls import recorded
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.film.colour_output import Adaptation, ColourSpace, WhiteBalance
from spectrace.film.image import Image
from spectrace.geometry import primitives
from spectrace.geometry.analytic import (
    ANALYTIC_SHAPES,
    AnalyticSurface,
    CutError,
    cut_parameters,
    object_tessellation,
    similarity_problem,
)
from spectrace.geometry.curves import checked_curve_type, checked_curves, curve_surface
from spectrace.geometry.grid_volume import GridVolume, box_matrix, make_grid
from spectrace.geometry.mesh import TriangleMesh, faces_problem, shading_normals
from spectrace.geometry.sdf_grid import make_sdf_grid, read_sdf_grid
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.lights.base import vector3
from spectrace.scene.model import (
    AreaEmitter,
    Instance,
    InstancedObject,
    Medium,
    Scene,
    Shape,
)
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike, rgb_emission, rgb_reflectance, spectrum  # noqa: F401

if TYPE_CHECKING:
    import rich.console
    import trimesh
    from numpy.typing import ArrayLike

    from spectrace.device import Device
    from spectrace.engine.checkpoint import PeriodicCheckpoints
    from spectrace.engine.job import RenderJob
    from spectrace.engine.meters import MeterReading

ProgressOption = bool | Literal["auto"] | Callable[[int, int], None] | None


# ---------------------------------------------------------------- spectra


# Texture constructors (docs/textures.md): each texture module's `make`, `spectrace.<API_NAME>`, as the materials'
# are theirs.
globals().update({module.API_NAME: module.make for module in textures.TEXTURES.values()})


# ---------------------------------------------------------------- geometry


def mesh_from_trimesh(mesh: trimesh.Trimesh | trimesh.Scene) -> TriangleMesh:
    """A `TriangleMesh` with the vertices and faces of a trimesh mesh (a trimesh Scene is merged into one mesh,
    with its node transforms applied). Vertex order and winding are kept: the front of a face is the side its
    counter-clockwise winding faces."""
    single: Any = mesh.to_mesh() if hasattr(mesh, "to_mesh") else mesh  # a trimesh.Scene merged, or anything else
    if not (hasattr(single, "vertices") and hasattr(single, "faces")):
        raise SpectraceError(f"expected a trimesh.Trimesh or trimesh.Scene, got {type(single).__name__}")
    try:
        vertices, faces = np.asarray(single.vertices, np.float64), np.asarray(single.faces)
    except (TypeError, ValueError) as exc:
        raise SpectraceError(f"the mesh's vertices or faces are not arrays of numbers ({exc})", where="mesh") from None
    if vertices.ndim != 2 or vertices.shape[1:] != (3,):
        raise SpectraceError(f"the mesh's vertices must be (N, 3), got shape {vertices.shape}", where="mesh")
    if faces.ndim != 2 or faces.shape[1:] != (3,) or len(faces) == 0:
        raise SpectraceError("the mesh has no triangles", where="mesh")
    if faces.dtype.kind not in "iu":
        raise SpectraceError(f"the mesh's faces must be vertex indices (integers), got {faces.dtype}", where="mesh")
    if not np.all(np.isfinite(vertices)):
        raise SpectraceError("the mesh has NaN or infinite vertex coordinates", where="mesh")
    if problem := faces_problem(faces, len(vertices)):
        raise SpectraceError(f"the mesh's {problem}", where="mesh")
    return TriangleMesh(vertices=vertices, faces=faces.astype(np.int64))


def transformed(mesh: TriangleMesh, steps: Iterable[Mapping[str, Any]]) -> TriangleMesh:
    """`mesh` moved by transform steps written as in a scene file, applied first step first:
    {"translate": [x, y, z]}, {"scale": s or [sx, sy, sz]}, {"rotate": {"axis": [x, y, z], "angle": degrees}},
    {"matrix": 4x4 rows}."""
    as_dicts = [dict(step) for step in steps]
    return apply_transform(mesh, transform_matrix(as_dicts, where="transform")) if as_dicts else mesh


# ---------------------------------------------------------------- scene objects


# One constructor per material, `spectrace.<type>(...)`: its module's `make`, which takes the parameters of its
# table with their defaults (docs/scene-format.md) and spectra in any SpectrumLike form.
globals().update({name: module.make for name, module in materials.MATERIALS.items()})


@recorded
def area_emitter(
    radiance: SpectrumLike, two_sided: bool = False, scale: float = 1.0, polarization: str | None = None
) -> AreaEmitter:
    """Makes a shape a light of radiance L(λ) x scale, W/(m² sr nm); one-sided emitters shine toward the side
    their triangles' winding faces. `radiance` may be an emission texture (docs/textures.md): a bitmap of linear
    sRGB (each texel the D65-based emission of its colour) or a spectral texture (each texel its radiance).
    `polarization`: the Stokes state of its light, "linear <degrees>", "circular" or "unpolarized"
    (docs/polarization.md)."""
    import dataclasses

    from spectrace.lights import area
    from spectrace.textures import check_texture_values, is_texture

    scale = area.PARAMETERS[2].check(scale)
    if is_texture(radiance):
        check_texture_values(radiance, "emission", "radiance")
        made = area.emitter(radiance, two_sided, scale)
    else:
        radiance_spectrum = spectrum_input.emission(radiance, "radiance").scaled(scale)
        made = AreaEmitter(radiance=radiance_spectrum, two_sided=bool(two_sided))
    if polarization is None:
        return made
    return dataclasses.replace(made, stokes=area.emitter_stokes(str(polarization), None, "polarization"))


@recorded
def medium(
    sigma_a: SpectrumLike = 0.0,
    sigma_s: SpectrumLike = 0.0,
    scale: float = 1.0,
    g: float = 0.0,
    preset: str | None = None,
    density: GridVolume | None = None,
    emission: SpectrumLike | None = None,
) -> Medium:
    """A homogeneous medium for a closed shape's `interior` (docs/media.md), as a scene file's `interior` key:
    absorption σa(λ) and scattering σs(λ) in 1/scene unit (a linear sRGB triple becomes a smooth spectrum with
    that colour, unbounded), or a measured `preset` ("skin1", "marble", "wholemilk", ...: Jensen et al. 2001;
    "lowfat_milk", "espresso", ...: Narasimhan et al. 2006; in 1/mm); either times `scale`. g: Henyey–Greenstein
    asymmetry in (−1, 1), 0 isotropic. `density` (see `density_grid`) makes the medium heterogeneous: its
    coefficients times the grid's density. `emission` (any
    spectrum form of an emitter's radiance) makes it glow: σa Le of radiance per unit length, Le the emission times
    the grid's emission scale and normalised blackbody where it has them (default 1 with such grids)."""
    from spectrace.spectral.media_presets import coefficient_spectrum, preset_coefficients

    if not (isinstance(scale, Real) and math.isfinite(scale) and scale > 0):
        raise SpectraceError(f"scale must be a finite number > 0, got {scale!r}", where="scale")
    if not (isinstance(g, Real) and -1.0 < g < 1.0):
        raise SpectraceError(f"g must lie in (-1, 1), got {g!r}", where="g")
    if density is not None and not isinstance(density, GridVolume):
        raise SpectraceError(
            f"density must be a grid (see density_grid()), got {type(density).__name__}", where="density"
        )
    glow = None if emission is None else spectrum_input.emission(emission, "emission")
    if glow is None and density is not None and (density.emission is not None or density.temperature is not None):
        glow = Spectrum.constant(1.0)  # the grids' glow as they give it
    if preset is not None:
        if not (_is_zero(sigma_a) and _is_zero(sigma_s)):
            raise SpectraceError("give either preset or sigma_a/sigma_s", where="preset")
        sigma_a_spectrum, sigma_s_spectrum = preset_coefficients(preset, float(scale), float(g), where="preset")
        return Medium(
            sigma_a=sigma_a_spectrum, sigma_s=sigma_s_spectrum, g=float(g), name=preset, density=density, emission=glow
        )

    def coefficient(source: SpectrumLike, what: str) -> Spectrum:
        if spectrum_input.is_rgb(source):
            result = coefficient_spectrum(cast("Sequence[float]", source), name=what, where=what)
        else:
            result = spectrum_input.within_bounds(spectrum(source), True, what)
        return result.scaled(float(scale))

    return Medium(
        sigma_a=coefficient(sigma_a, "sigma_a"),
        sigma_s=coefficient(sigma_s, "sigma_s"),
        g=float(g),
        density=density,
        emission=glow,
    )


def density_grid(
    density: ArrayLike,
    albedo: ArrayLike | None = None,
    box: Sequence[Sequence[float]] = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
    transform: Iterable[Mapping[str, Any]] = (),
    outside: str = "empty",
    emission: ArrayLike | None = None,
    temperature: ArrayLike | None = None,
) -> GridVolume:
    """A voxel grid for `medium(density=...)` (docs/media.md): `density` shaped (nz, ny, nx) (x fastest, as
    numpy's C order), values ≥ 0 at the voxels' centres, looked up trilinearly, or (nz, ny, nx, 3) for a linear
    sRGB density uplifted per voxel (σt varying with λ); `albedo` an optional grid of the same shape in [0, 1]
    multiplying σs, or shaped (nz, ny, nx, 3) for a linear sRGB albedo uplifted per voxel; filling `box` (two
    corners), then moved by `transform` steps (as `transformed`), in the scene's space; `outside` what it holds
    outside the box: "empty" (the medium ends there), "clamp" (its faces' values) or "repeat" (copies of itself);
    `emission` (≥ 0) and `temperature` (kelvin) optional grids of the density's shape making a glowing medium's
    emission vary: its spectrum times the scale, times a blackbody at the temperature normalised to its peak."""
    if np.shape(box) != (2, 3):
        raise SpectraceError(f"box must be two corners [x, y, z], got shape {np.shape(box)}", where="box")
    matrix = box_matrix(*np.asarray(box, np.float64))
    steps = [dict(step) for step in transform]
    if steps:
        matrix = transform_matrix(steps, where="transform") @ matrix
    return make_grid(
        np.asarray(density),
        matrix,
        None if albedo is None else np.asarray(albedo),
        where="density",
        outside=outside,
        emission=None if emission is None else np.asarray(emission),
        temperature=None if temperature is None else np.asarray(temperature),
    )


def _is_zero(source: SpectrumLike) -> bool:
    return isinstance(source, Real) and source == 0


def shape(
    geometry: TriangleMesh
    | Literal["rectangle", "cube", "sphere", "disk", "cylinder", "prism", "teapot"]
    | trimesh.Trimesh,
    material=None,
    emitter: AreaEmitter | None = None,
    transform: Iterable[Mapping[str, Any]] = (),
    name: str = "",
    interior: Medium | None = None,
    face_normals: bool | None = None,
    tessellated: bool = False,
    center: Sequence[float] | None = None,
    radius: float | None = None,
    flip_normals: bool = False,
    phi_max: float | None = None,
    z_min: float | None = None,
    z_max: float | None = None,
    inner_radius: float | None = None,
) -> Shape:
    """A shape: a `TriangleMesh`, a trimesh mesh, or a built-in ("rectangle" [-1, 1]² at z = 0 facing +z, "cube"
    [-1, 1]³, "sphere" of radius 1, "prism" the equilateral prism of side 2 and length 2 along z, "teapot" the Utah
    teapot standing on the origin, y up, body radius 1; "disk" of radius 1 at z = 0 facing +z, "cylinder" of radius
    1 along z from 0 to 1, open), moved by `transform` steps (see `transformed`). Built-ins face outward, as a
    dielectric needs. `interior` (see `medium`) fills a closed shape, whose faces must wind outward; without a
    material its boundary is index-matched (rays cross it unchanged), and an emitter without a material is a light
    seen through (it emits, reflects nothing and hides nothing: Mitsuba's null bsdf). `face_normals` as the scene
    key: True shades with the face normals (facets), False smoothly (normals computed for a mesh without its own),
    None keeps the mesh's own normals (the sphere's are radial, the teapot's its surface's; the other built-ins have
    none). "sphere", "disk" and "cylinder" are exact (analytic) surfaces, unless `tessellated` (or
    face_normals=True, which asks for facets) makes them triangles; an analytic sphere's transform must scale
    uniformly. A sphere's `radius` and `center` place it before `transform`; `flip_normals` turns their front
    (normal, emitting side) inward (the disk's to -z). Partial shapes, as pbrt-v4's: `phi_max` (degrees) keeps the
    azimuths [0, phi_max]; a sphere's `z_min`, `z_max` (heights in [-radius, radius]) the band between; a disk's
    `inner_radius` (a fraction of its radius) cuts a hole."""
    if material is None and interior is None and emitter is None:
        raise SpectraceError(
            "a shape needs a material (only a shape with an interior or an emitter may omit it)", where="material"
        )
    if interior is not None and not isinstance(interior, Medium):
        raise SpectraceError(
            f"interior must be a Medium (see medium()), got {type(interior).__name__}", where="interior"
        )
    if face_normals is not None and not isinstance(face_normals, bool):
        raise SpectraceError(f"face_normals must be True, False or None, got {face_normals!r}", where="face_normals")
    cut_keys = (phi_max, z_min, z_max, inner_radius)
    if any(key is not None for key in cut_keys) and not (isinstance(geometry, str) and geometry in ANALYTIC_SHAPES):
        raise SpectraceError("phi_max, z_min, z_max and inner_radius cut a sphere, disk or cylinder", where="phi_max")
    if isinstance(geometry, str) and geometry in ANALYTIC_SHAPES:
        for key, value in zip(("phi_max", "z_min", "z_max", "inner_radius"), cut_keys, strict=True):
            if value is not None and not (isinstance(value, Real) and math.isfinite(value)):
                raise SpectraceError(f"{key} must be a finite number, got {value!r}", where=key)
        # A bad radius is reported below, by its own key.
        sphere_radius = float(radius) if isinstance(radius, Real) and radius > 0 else 1.0
        try:
            cuts = cut_parameters(geometry, *cut_keys, radius=sphere_radius)
        except CutError as cut_problem:
            raise SpectraceError(str(cut_problem), where=cut_problem.key) from None
        if cuts and interior is not None:
            raise SpectraceError(
                "a partial shape encloses no volume: an interior needs a closed shape", where="interior"
            )
        if interior is not None and geometry != "sphere":
            raise SpectraceError(f"a {geometry} encloses no volume: an interior needs a closed shape", where="interior")
        steps = [dict(step) for step in transform]
        if (center is not None or radius is not None) and geometry != "sphere":
            raise SpectraceError(f"center and radius are a sphere's, not a {geometry}'s (use transform)")
        if center is not None:
            steps.insert(0, {"translate": list(vector3(center, "center"))})
        if radius is not None:
            if not (isinstance(radius, Real) and math.isfinite(radius) and radius > 0):
                raise SpectraceError(f"radius must be a finite number > 0, got {radius!r}", where="radius")
            steps.insert(0, {"scale": float(radius)})
        matrix = transform_matrix(steps, where="transform") if steps else np.eye(4)
        if not (tessellated or face_normals):
            if geometry == "sphere" and (problem := similarity_problem(matrix)):
                raise SpectraceError(f"{problem}; tessellated=True takes any", where="transform")
            surface = AnalyticSurface(geometry, matrix, flip_normals=bool(flip_normals), **cuts)
            return Shape(
                mesh=surface.tessellation(),
                material=material,
                emitter=emitter,
                name=name or geometry,
                interior=interior,
                analytic=surface,
            )
        local = AnalyticSurface(geometry, np.eye(4), **cuts).tessellation() if cuts else object_tessellation(geometry)
        mesh = apply_transform(local, matrix)
        if flip_normals:
            mesh = mesh.flipped()
        mesh = shading_normals(mesh, face_normals, computed=False)
        return Shape(mesh=mesh, material=material, emitter=emitter, name=name or geometry, interior=interior)
    if isinstance(geometry, str):
        if geometry not in primitives.BUILTIN_SHAPES:
            raise SpectraceError(f"unknown built-in shape '{geometry}' (use {', '.join(primitives.BUILTIN_SHAPES)})")
        mesh = primitives.BUILTIN_SHAPES[geometry]()
        name = name or geometry
    elif isinstance(geometry, TriangleMesh):
        mesh = geometry
    else:
        mesh = mesh_from_trimesh(geometry)
    mesh = shading_normals(transformed(mesh, transform), face_normals, computed=not isinstance(geometry, str))
    return Shape(mesh=mesh, material=material, emitter=emitter, name=name, interior=interior)


def sdf_grid(
    values: ArrayLike | str | Path,
    material=None,
    transform: Iterable[Mapping[str, Any]] = (),
    normals: Literal["smooth", "analytic"] = "smooth",
    name: str = "",
    interior: Medium | None = None,
) -> Shape:
    """A signed-distance grid shape (Mitsuba 3's sdfgrid; docs/scene-format.md): `values` shaped (nz, ny, nx) (x
    fastest, as numpy's C order), or a one-channel Mitsuba volume file, sampled at the voxels' corners over the unit
    cube, positive outside; the surface is the zero set of their trilinear interpolant. `transform` steps (as
    `transformed`) place the cube; `normals` shade with the blended voxel gradients ("smooth") or the interpolant's
    own ("analytic"). It has no texture coordinates and cannot emit."""
    if material is None and interior is None:
        raise SpectraceError("an SDF grid needs a material (or an interior)", where="material")
    if isinstance(values, (str, Path)):
        values = read_sdf_grid(Path(values), where="values")
    matrix = transform_matrix([dict(step) for step in transform], where="transform") if transform else np.eye(4)
    surface = make_sdf_grid(values, matrix, normals, where="values")
    return Shape(
        mesh=surface.tessellation(), material=material, name=name or "sdfgrid", interior=interior, analytic=surface
    )


def curve(
    points,
    material=None,
    basis: Literal["linear", "bspline"] = "linear",
    transform: Iterable[Mapping[str, Any]] = (),
    name: str = "",
    interior: Medium | None = None,
    uv_convention: Literal["pbrt", "mitsuba"] = "pbrt",
    curve_type: Literal["tube", "flat", "ribbon"] = "tube",
    curve_normals=None,
) -> Shape:
    """Curves (hair, fur, wires: docs/scene-format.md, "Curves"): `points` one curve's control points, rows of
    (x, y, z, radius), or a list of curves; `basis` "linear" (a sphere swept from point to point: Mitsuba 3's
    linearcurve) or "bspline" (the uniform cubic B-spline of the points, centre and radius: Mitsuba 3's
    bsplinecurve). `transform` moves the points and leaves the radii as given (as Mitsuba 3 does). Intersected
    exactly as swept spheres, one BVH primitive per segment; a curve cannot emit. `uv_convention`: pbrt-v4's
    texture coordinates (u along each curve, v across it) or Mitsuba 3's (u around, v along all the curves).
    `curve_type` "tube" (the swept sphere), or pbrt-v4's "flat" (a strip of the same width facing each ray) or
    "ribbon" (a strip oriented by `curve_normals`, an (x, y, z) row per point of each linear curve)."""
    if material is None and interior is None:
        raise SpectraceError("a curve needs a material", where="material")
    if uv_convention not in ("pbrt", "mitsuba"):
        raise SpectraceError(f"uv_convention must be pbrt or mitsuba, got {uv_convention!r}", where="uv_convention")
    curves = checked_curves(points, basis, "points")
    normals = checked_curve_type(curve_type, curves, curve_normals, basis, uv_convention, lambda name: name)
    matrix = transform_matrix([dict(step) for step in transform], where="transform") if transform else None
    surface = curve_surface(curves, basis, matrix, uv_convention=uv_convention, curve_type=curve_type, normals=normals)
    if surface.count == 0:
        raise SpectraceError("the curves have no segment of any length", where="points")
    return Shape(
        mesh=surface.tessellation(), material=material, name=name or "curve", interior=interior, analytic=surface
    )


def instanced_object(shapes: Sequence[Shape], name: str = "") -> InstancedObject:
    """A group of shapes (meshes, built with `shape` in the object's own space) declared once and placed by
    `instance` any number of times, stored once on the device (Mitsuba 3's shapegroup, pbrt-v4's ObjectBegin).
    Analytic spheres, disks and cylinders stay exact under any instance transform; emitters cannot be instanced:
    place the emitting shape as a shape of its own."""
    shapes = list(shapes)
    if not shapes or not all(isinstance(s, Shape) for s in shapes):
        raise SpectraceError("an instanced object needs one or more shapes (see shape())", where=name or "object")
    for s in shapes:
        if s.emitter is not None:
            raise SpectraceError(f"shape '{s.name}': emitters cannot be instanced (place the emitting shape itself)")
    return InstancedObject(shapes=shapes, name=name)


def instance(obj: InstancedObject, transform: Iterable[Mapping[str, Any]] = (), name: str = "") -> Instance:
    """`obj` placed in the scene by `transform` steps (as for `shape`; a 4 x 4 `matrix` step takes any affine map,
    mirrors included); put the result in `Scene(instances=[...])`."""
    if not isinstance(obj, InstancedObject):
        raise SpectraceError(f"instance() places an InstancedObject, got {type(obj).__name__}")
    steps = [dict(step) for step in transform]
    matrix = transform_matrix(steps, where="transform") if steps else np.eye(4)
    return Instance(object=obj, to_world=matrix, name=name or obj.name)


# One constructor per light, `spectrace.<API_NAME>(...)`: its module's `make`, which takes the parameters of its
# table (docs/python-api.md).
globals().update({m.API_NAME: m.make for m in lights.LIGHTS.values() if m.API_NAME is not None})


# ---------------------------------------------------------------- rendering


@contextmanager
def _no_bar(callback: Callable[[int, int], None] | None):
    yield callback


def render_passes(
    renderer: Renderer,
    spp: int | None = None,
    *,
    pass_spp: int | None = None,
    progress: ProgressOption = "auto",
    stop: Callable[[], bool] | None = None,
    checkpoints: PeriodicCheckpoints | None = None,
    console: rich.console.Console | None = None,
    each_pass: Callable[[], None] | None = None,
) -> Image:
    """The render loop that `render()` and `spectrace render` share: run `renderer`'s passes up to `spp` samples
    per pixel (default: its scene's) and return the `Image` of the samples done.

    progress: as in `render()` (the bar: `spectrace.progress`, drawn on `console` outside Jupyter). stop: asked
    between passes; when it says True the loop ends early with the samples done so far. checkpoints: a
    `spectrace.engine.checkpoint.PeriodicCheckpoints`, offered the state after every pass and saved at the end
    (also after a stop), so that the file always holds whole passes. each_pass: called after every pass (the
    image streamed to a viewer).
    """
    from spectrace.progress import in_notebook, progress_bar

    total = spp if spp is not None else renderer.scene.spp
    show_bar = progress is True or (progress == "auto" and in_notebook())
    reporter = (
        progress_bar(total, renderer.samples_done, console)
        if show_bar
        else _no_bar(progress if callable(progress) else None)
    )
    with reporter as draw:

        def on_pass(done: int, total: int) -> None:
            if draw is not None:
                draw(done, total)
            if checkpoints is not None:
                checkpoints.maybe_save()
            if each_pass is not None:
                each_pass()

        image = renderer.render(spp=total, pass_spp=pass_spp, progress=on_pass, should_stop=stop)
    if checkpoints is not None and renderer.samples_done > 0:
        checkpoints.save()
    return image


def render(
    scene: Scene,
    spp: int | None = None,
    device: Device | str | None = None,
    progress: ProgressOption = "auto",
    pass_spp: int | None = None,
    *,
    spectral_bins: int = 0,
    colour_space: ColourSpace | str = ColourSpace.SRGB,
    white_balance: WhiteBalance | str | None = None,
    adaptation: Adaptation | str = Adaptation.BRADFORD,
    aovs: str | Sequence[str] | None = None,
    client: Any = None,
    tile_rows: int | None = None,
    display_server: str | None = None,
) -> Image:
    """Render `scene` to `spp` samples per pixel (default: the scene's) and return the `Image`.

    device: a Device, a selection string ("pocl", "gpu", a key from `spectrace devices`) or None (automatic).
    progress: True draws a progress bar (a notebook widget under Jupyter when tqdm is installed), False or None
    none, a callable is called as progress(samples_done, samples_total) after each pass; "auto" draws a bar
    only inside Jupyter. spectral_bins > 0 also keeps that many equal wavelength bands over the film's wavelengths
    (film.wavelengths, 360..830 nm by default) per pixel (`image.spectral`, band-averaged radiance in
    W/(m² sr nm)). colour_space, white_balance and adaptation set how the image converts to RGB (see
    `spectrace.film.colour_output` and docs/colour.md). aovs: AOVs
    recorded by the same paths and kept in `image.aovs` ("albedo", "normal", "depth", "position", "variance", as
    a sequence or a comma-separated string; None keeps the scene's `film.aovs`; see `spectrace.film.aovs`);
    `spectrace.denoise(image)` needs albedo and normal.
    client: a Dask distributed Client: the render runs split into tiles of `tile_rows` rows on its workers, each
    opening `device` there (docs/distributed.md); the image is bit-identical to one rendered here on the same
    device type, and one progress bar counts tiles.
    display_server: "HOST:PORT" of a tev viewer (tev's default port is 14158) shown the image as it converges
    (linear RGB of `colour_space`, as `image.to_rgb()`); a viewer absent or gone is one warning, and the render
    goes on. Not with `client`.
    """
    if not isinstance(scene, Scene):
        raise SpectraceError(
            f"render() needs a spectrace.Scene, got {type(scene).__name__} (load_scene(path) reads a file)"
        )
    from spectrace.engine.job import RenderJob

    job = RenderJob.make(
        scene,
        spp=spp,
        pass_spp=pass_spp,
        spectral_bins=spectral_bins,
        tile_rows=tile_rows,
        aovs=aovs,
        device=device,
        colour_space=colour_space,
        white_balance=white_balance,
        adaptation=adaptation,
        display_server=display_server,
    )
    if client is not None:
        if job.display_server is not None:
            raise SpectraceError("display_server streams a render in this process; it does not go with client")
        image = _render_on_client(job, client, progress)
    elif job.display_server is not None:
        image = _render_shown(job, progress)
    else:
        from spectrace.session import Session

        # One render is a session's first passes: the same build, kept open for nothing more.
        with Session.for_job(job) as session:
            image = render_passes(session.renderer, pass_spp=job.pass_spp, progress=progress)
    return job.finish(image)


def _render_shown(job: RenderJob, progress: ProgressOption) -> Image:
    """The render with its image streamed to the job's display server (warnings through `warnings.warn`)."""
    import warnings

    from spectrace.engine.display_stream import RenderDisplay
    from spectrace.session import Session

    name = job.scene.source.stem if job.scene.source is not None else "spectrace"
    with Session.for_job(job) as session:
        renderer = session.renderer
        display = RenderDisplay(job, name, lambda message: warnings.warn(message, RuntimeWarning, stacklevel=1))
        try:
            image = render_passes(
                renderer, pass_spp=job.pass_spp, progress=progress, each_pass=lambda: display.after_pass(renderer)
            )
        except BaseException:
            display.close()
            raise
    display.finish(image)
    return image


def _render_on_client(job: RenderJob, client: Any, progress: ProgressOption) -> Image:
    from spectrace.distributed import DaskTiles
    from spectrace.engine.tiles import render_tiles
    from spectrace.progress import in_notebook, progress_bar

    tiles, _ = job.tiles()
    show_bar = progress is True or (progress == "auto" and in_notebook())
    reporter = (
        progress_bar(tiles.plan.count, 0, unit="tiles")
        if show_bar
        else _no_bar(progress if callable(progress) else None)
    )
    with reporter as draw:
        film = render_tiles(tiles, DaskTiles(client), progress=draw)
    return film.image(job.scene, tiles.film())


def measure_radiance(
    scene: Scene,
    origin: Sequence[float] | np.ndarray,
    direction: Sequence[float] | np.ndarray,
    wavelengths_nm: Sequence[float] | np.ndarray | None = None,
    *,
    streams: int = 64,
    samples_per_item: int = 32,
    seed: int = 0,
    device: Device | str | None = None,
) -> MeterReading:
    """The spectral radiance arriving at `origin` seen looking along `direction`, W/(m² sr nm), at each of
    `wavelengths_nm` (default every 5 nm over 360-830 nm), with standard errors from `streams` independent
    estimates; the reading's Y is the luminance in cd/m² (a radiance meter, `spectrace.engine.meters`)."""
    from spectrace.core import limits
    from spectrace.engine.meters import DEFAULT_WAVELENGTHS_NM, RadianceMeter, measure

    for name, count in (("streams", streams), ("samples_per_item", samples_per_item)):
        if problem := limits.whole_number_problem(name, count) or (
            f"{name} must be at least 1, got {count}" if count < 1 else None
        ):
            raise SpectraceError(problem)
    if problem := limits.seed_problem(seed):
        raise SpectraceError(problem)
    meter = RadianceMeter(vector3(origin, "origin"), vector3(direction, "direction"))
    wavelengths = DEFAULT_WAVELENGTHS_NM if wavelengths_nm is None else wavelengths_nm
    return measure(
        scene,
        meter,
        wavelengths_nm=wavelengths,
        streams=streams,
        samples_per_item=samples_per_item,
        seed=seed,
        device=device,
    )
