"""The `sppm` integrator, stochastic progressive photon mapping (kernels/integrator_sppm.cl, kernels/sppm.cl): what it
refuses, its per-pixel statistics, and the photon grid built between each iteration's photon and gather launches.

An iteration (one sample per pixel) traces PHOTONS_PER_PIXEL photon paths per pixel; each record carries the hash
bucket of its grid cell (kernels/sppm.cl's sppm_hash, which the gather uses too), and the host sorts the record
slots stably by bucket, so every bucket lists its photons in the order (photon, record) and each pixel's gather adds
them in the same order whatever the split into passes. Only the buckets travel to the host and the slot order back;
the records stay on the device. The cells are as wide as the largest gather radius (with a margin), so a pixel finds
every photon within its radius in the 27 cells around its own.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from spectrace.integrators.base import SHARED_PARAMETERS, RenderHost, Scene, no_defines, no_params
from spectrace.integrators.light import scene_sphere

NAME = "sppm"
# Mitsuba 0.6's photon mappers, which converge to the same image.
MITSUBA_PLUGINS = ("sppm", "photonmapper")
PBRT_INTEGRATORS: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4's sppm converges to the path tracer's image and imports as path (path.py)"
PARAMETERS = SHARED_PARAMETERS
PROGRAMS = {"megakernel": "integrator_sppm.cl"}
SPLATS = "photons"  # a photon adds to every pixel whose radius holds it: whole films only
# Its per-pixel photon statistics (radius, photon count, flux) are not in the film's saved state.
# Of base.FEATURES, what it refuses in any scene (`problem` says why; it refuses more in some scenes).
REFUSES: tuple[str, ...] = ("spectral bands", "AOVs", "pixel filters", "film responses", "media", "glowing media")
# Its general program costs a few of its scenes' own builds: SPECTRACE_GENERAL_KERNELS=common shares it.
SHARES_GENERAL_PROGRAM = True
CHECKPOINT_PROBLEM = (
    "integrator 'sppm' cannot save or resume checkpoints (its photon statistics are not in the film's state); "
    "render without --checkpoint/--resume"
)
defines = no_defines
params = no_params

# The initial gather radius, in pixel footprints at the visible point's distance along the camera path: wide enough
# to find photons from the first iterations, narrow enough that the blur it starts with is a pixel or two.
INITIAL_RADIUS_PIXELS = 3.0
# Photon paths per iteration, per pixel of the film.
PHOTONS_PER_PIXEL = 2
# Photon records per photon path: bounces beyond this many diffuse vertices are left out (Russian roulette has ended
# nearly every path by then).
MAX_PHOTON_RECORDS = 16
# Cells wider than the largest radius by this share, so that float rounding at a cell's edge cannot hide a photon.
CELL_MARGIN = 1.02
SPPM_CAMERAS = ("perspective", "thinlens")
PHOTON_RECORD_BYTES = 4 * 16 + 4 + 4  # position, direction, normal, flux (a float4 each), bucket, slot order
PIXEL_STATE_BYTES = 16 + 16 + 4 + 4  # direct and τ (float4 each), radius, photon count


def _mixes_delta_and_non_delta(material: Any) -> bool:
    """A material whose lobes mix a delta lobe with non-delta ones (a smooth coat over a diffuse base, a roughness
    texture that may reach 0, a mix of such a material or of a delta and a non-delta one): a visible point there
    would drop the delta part of its reflection, and a photon path would leave no photon where a mix picked its
    delta part for the photon's direction, while the visible point's direction picks the other."""
    from spectrace.materials.mix import MixMaterial
    from spectrace.materials.opaque import smooth_everywhere
    from spectrace.materials.plastic import PlasticMaterial

    if isinstance(material, MixMaterial):
        parts = material.materials
        return any(_mixes_delta_and_non_delta(m) for m in parts) or len({m.is_delta for m in parts}) > 1
    roughness = getattr(material, "roughness", None)
    textured = roughness is not None and not isinstance(roughness, (int, float))
    # kernels/microfacet.cl's ggx_lobe_flags: a textured width may be delta at some points and not at others; a
    # plastic's coat adds its lobe to the diffuse base's.
    # A material may state it (a smooth coat over a layered BSDF's non-delta rest: spectrace.materials.layered).
    stated = getattr(material, "mixes_delta_and_non_delta", False)
    return textured or stated or (isinstance(material, PlasticMaterial) and smooth_everywhere(roughness))


def problem(scene: Scene, medium_count: int, spectral_bins: int) -> str | None:
    """Why the `sppm` integrator cannot render this scene as asked, or None."""
    camera_type = scene.camera.type
    if camera_type not in SPPM_CAMERAS:
        known = " and ".join(SPPM_CAMERAS)
        return f"integrator 'sppm' supports the {known} cameras, not {camera_type!r}"
    if medium_count:
        return "integrator 'sppm' does not render participating media; use 'path'"
    if spectral_bins:
        return "integrator 'sppm' does not write spectral bands; render without spectral output or use 'path'"
    if scene.pixel_filter.type != "box":
        return (
            f"integrator 'sppm' estimates whole pixels (the box filter), not a {scene.pixel_filter.type} filter; "
            "use film.filter = \"box\" or 'path'"
        )
    if not scene.film_response.is_default:
        return "integrator 'sppm' renders the default CIE 1931 film only (no observers, sensor or wavelengths)"
    if scene.aovs:
        return "integrator 'sppm' does not record AOVs; leave film.aovs out or use 'path'"
    for shape in scene.shapes:
        if shape.material is not None and _mixes_delta_and_non_delta(shape.material):
            return (
                f"integrator 'sppm' cannot render a {type(shape.material).__name__} whose smooth and rough lobes "
                "share a surface (a smooth coat, textured roughness, a mix of smooth and rough materials): they "
                "would need a visible point on both; use 'path' or 'bdpt'"
            )
    return None


def passes(host: RenderHost, shape: str, spectral_bins: int) -> SppmPasses:
    return SppmPasses(host)


def initial_radius_per_metre(scene: Scene) -> float:
    """The initial gather radius per metre of camera path: INITIAL_RADIUS_PIXELS pixel footprints."""
    _, _, _, up = scene.camera.basis(scene.width / scene.height)
    pixel_angle = 2.0 * float(np.linalg.norm(up)) / scene.height  # tan(fov_y/2)·2 per pixel row
    return INITIAL_RADIUS_PIXELS * pixel_angle


class SppmPasses:
    """The iterations of an `sppm` render: its program's photon and gather kernels, the photon records, the grid and
    the per-pixel statistics."""

    def __init__(self, host: RenderHost):
        self.host = host
        scene = host.scene
        pixels = host.pixel_count
        self.photon_count = pixels * PHOTONS_PER_PIXEL
        depth_slots = scene.max_depth - 2 if scene.max_depth > 0 else MAX_PHOTON_RECORDS
        self.capacity = max(1, min(depth_slots, MAX_PHOTON_RECORDS))
        host.check_memory(
            {
                "photon records": self.photon_count * self.capacity * PHOTON_RECORD_BYTES,
                "pixel statistics": pixels * PIXEL_STATE_BYTES,
            }
        )
        slots = self.photon_count * self.capacity
        self._records = [host.buffer(slots * 16) for _ in range(4)]
        self._buckets = host.buffer(slots * 4)
        # Hash buckets: about two per photon path (most paths leave fewer records than that).
        self._table_size = 1 << max(10, int(math.ceil(math.log2(2 * self.photon_count))))
        self._counts = host.buffer(self.photon_count * 4)
        self._direct = host.buffer(pixels * 16)
        self._tau = host.buffer(pixels * 16)
        self._radius = host.buffer(pixels * 4)
        self._photons = host.buffer(pixels * 4)
        self._gather_kernel = host.kernel("sppm_gather_pass")
        self._photon_kernel = host.kernel("sppm_photon_pass")
        sphere = scene_sphere(scene)
        self._sphere = sphere
        self._origin = np.array([*(sphere[:3] - sphere[3]), 0.0], np.float32)
        self._radius_per_metre = np.float32(initial_radius_per_metre(scene))
        # The first iteration's cells: the largest first radius, at the camera's farthest view of the scene's sphere
        # (camera paths through mirrors may go farther; their radius is cut to the cell).
        reach = float(np.linalg.norm(np.asarray(scene.camera.origin) - sphere[:3])) + float(sphere[3])
        self._first_cell = float(self._radius_per_metre) * reach * CELL_MARGIN
        self.reset()

    def reset(self) -> None:
        for buffer in (self._direct, self._tau, self._radius, self._photons):
            self.host.clear(buffer)
        self.host.finish()

    def _trace_photons(self, sample_index: int, cell_size: float) -> np.ndarray:
        """Runs one iteration's photon paths; returns each record slot's bucket (table size: unused), in the order
        (photon, record)."""
        host = self.host
        host.launch(
            self._photon_kernel,
            host.pixel_count,
            *host.scene_arguments(),
            self._sphere,
            np.int32(sample_index),
            np.int32(self.photon_count),
            np.int32(host.pixel_count),
            np.int32(self.capacity),
            *self._records,
            self._buckets,
            self._counts,
            self._origin,
            np.float32(cell_size),
            np.uint32(self._table_size),
            host.film.ray_count_buffer,
        )
        buckets = np.empty(self.photon_count * self.capacity, np.uint32)
        host.download(buckets, self._buckets)
        host.finish()
        return buckets

    def _grid(self, buckets: np.ndarray) -> tuple[Any, Any]:
        """The used slots sorted by bucket (stable: within one, in the order traced) and each bucket's start."""
        used = np.flatnonzero(buckets < self._table_size).astype(np.int32)
        filed = buckets[used]
        order = used[np.argsort(filed, kind="stable")]
        starts = np.zeros(self._table_size + 1, np.int32)
        np.cumsum(np.bincount(filed, minlength=self._table_size), out=starts[1:])
        # A one-element placeholder where an iteration found no photon (an empty buffer cannot be made).
        order_buffer = self.host.buffer(data=order if len(order) else np.zeros(1, np.int32))
        return order_buffer, self.host.buffer(data=starts)

    def _cell_size(self) -> float:
        """The grid's cell width: the largest radius of a pixel, or the first iterations' bound while none is set. A
        pixel that finds its first visible point later starts within the cell (kernels/sppm.cl), so pixels that see
        nothing (the sky) do not hold the cells at their first width."""
        radius = np.empty(self.host.pixel_count, np.float32)
        self.host.download(radius, self._radius)
        largest = float(radius.max()) if radius.size else 0.0
        return max((largest if largest > 0.0 else self._first_cell) * CELL_MARGIN, 1e-6)

    def run_pass(self, sample_count: int) -> None:
        """Runs `sample_count` iterations."""
        host = self.host
        film = host.film
        with host.render_pass(sample_count) as done:
            for sample_index in range(done, done + sample_count):
                cell_size = self._cell_size()
                order, starts = self._grid(self._trace_photons(sample_index, cell_size))
                host.launch(
                    self._gather_kernel,
                    host.pixel_count,
                    *host.scene_arguments(),
                    host.cmf_buffer,
                    np.int32(sample_index),
                    np.int32(host.pixel_count),
                    self._radius_per_metre,
                    np.float32(self.photon_count),
                    *self._records,
                    order,
                    starts,
                    np.uint32(self._table_size),
                    self._origin,
                    np.float32(cell_size),
                    self._direct,
                    self._tau,
                    self._radius,
                    self._photons,
                    film.xyz_buffer,
                    film.ray_count_buffer,
                )
                host.finish()


def from_mitsuba(importer, element, properties, settings: dict) -> dict:
    """Mitsuba 0.6's sppm and photonmapper: the photon counts, radii and lookup sizes are this integrator's own, so
    they are noted, not followed."""
    settings["type"] = NAME
    own = importer.with_snake_case(  # a 0.x file's names arrive upgraded to snake_case
        "photonCount", "initialRadius", "alpha", "granularity", "maxPasses", "directSamples",
        "glossySamples", "globalPhotons", "causticPhotons", "volumePhotons", "globalLookupRadius",
        "causticLookupRadius", "lookupSize",
    )  # fmt: skip
    if any(name in properties for name in own):
        importer.notes.append(
            f"{importer.at(element)}: integrator '{importer.kind(element)}' imported as 'sppm'; its photon counts "
            "and radii are spectrace's own choice"
        )
    properties.understood(*own)
    return settings
