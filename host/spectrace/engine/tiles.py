"""Renders split into tiles: bands of whole film rows, each rendered on its own (in this process, or by a cluster's
workers, spectrace.distributed) and merged into one film on the host.

Every tile holds all the samples of its pixels, added in sample order by the same kernel as a whole-film render (the
launch's global offset gives each pixel its own work-item id, spectrace.engine.renderer), so the merged film is
bit-identical to a one-piece render with the same seed on the same device type, however the tiles are spread over
workers, and when a lost tile is rendered again. The merge is generic over the film's saved-state buffers
(spectrace.film.state.RenderState): each is pixel-major, so a tile is one slice along the pixel axis of every buffer,
whatever channels the film accumulates.

A tiled render's progress is which tiles are done (a TileMap): its checkpoints (format 3, spectrace.engine.
checkpoint) hold the merged buffers and that map, and a resumed render renders only the tiles not done.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from spectrace.engine.checkpoint import Checkpoint, RenderIdentity, TileMap, identity_mismatch, write_checkpoint
from spectrace.errors import SpectraceError
from spectrace.film.image import Image
from spectrace.film.state import STATE_LAYOUT, RenderState, dropped_samples_problem
from spectrace.integrators import INTEGRATORS

if TYPE_CHECKING:
    from spectrace.device import Device
    from spectrace.engine.renderer import Renderer
    from spectrace.engine.scene_buffers import SceneBuffers
    from spectrace.film.setup import FilmSetup
    from spectrace.scene.model import Scene

# Tiles by default: at most this many pixels, and at least MIN_TILES of them (when the film has the rows), so that
# work spreads over several workers and a lost tile costs little; per-tile work stays far above a Dask task's
# overhead (docs/distributed.md has the model and the measurements).
DEFAULT_TILE_PIXELS = 65536
MIN_TILES = 16
MIXED_DEVICES_KEY = "devices_mixed"


@dataclass(frozen=True)
class TilePlan:
    """A width x height film cut into bands of `rows` rows, top to bottom (the last band may be shorter)."""

    width: int
    height: int
    rows: int

    @property
    def count(self) -> int:
        return -(-self.height // self.rows)

    def pixels(self, index: int) -> tuple[int, int]:
        """The tile's pixels [begin, end) in the film's row-major pixel order."""
        first = index * self.rows
        return first * self.width, min(self.height, first + self.rows) * self.width


def plan_tiles(width: int, height: int, rows: int | None = None, where: str = "--tile-rows") -> TilePlan:
    """Tiles of `rows` rows (default: at most DEFAULT_TILE_PIXELS pixels, at least MIN_TILES tiles)."""
    if rows is None:
        rows = max(1, min(DEFAULT_TILE_PIXELS // width, -(-height // MIN_TILES)))
    if isinstance(rows, bool) or not (isinstance(rows, int) and rows >= 1):
        raise SpectraceError(f"rows per tile must be a whole number >= 1, got {rows!r}", where=where)
    return TilePlan(width, height, min(rows, height))


@dataclass
class TileResult:
    """One rendered tile: its slice of every saved-state buffer, (tile pixels, values per pixel), and where and how
    long it ran."""

    index: int
    buffers: dict[str, np.ndarray]
    device: str
    seconds: float


def _per_pixel(array: np.ndarray, pixels: int) -> np.ndarray:
    return array.reshape(pixels, -1)


def _state_shape(name: str, pixels: int, per_pixel: int) -> tuple[int, ...]:
    """A saved-state buffer's shape as the film saves it (spectrace.film.state.STATE_LAYOUT): flat where the layout
    leaves the count per pixel open (the bands), (pixels,) for one value, (pixels, k) for several."""
    layout = STATE_LAYOUT.get(name, (None, per_pixel))[1]
    if layout is None:
        return (pixels * per_pixel,)
    return (pixels, per_pixel) if per_pixel > 1 else (pixels,)


def render_tile(renderer: Renderer, plan: TilePlan, index: int, spp: int) -> TileResult:
    """Render tile `index` to `spp` samples per pixel on `renderer` (a renderer of the whole film: the tile's pixels
    keep their place in it, and with it their sample sequences)."""
    begin, end = plan.pixels(index)
    # Only the tile's pixels: those a padded launch wrote past its end are cleared by their own tile, before it.
    renderer.film.reset_pixels(begin, end)
    renderer.pixel_range = (begin, end)
    try:
        renderer.render(spp=spp)
    finally:
        renderer.pixel_range = (0, renderer.pixel_count)
    film = renderer.film
    return TileResult(index, film.read_state_pixels(begin, end), renderer.device.report.key, film.render_seconds)


@dataclass
class TileJob:
    """Everything a worker needs to render tiles of one film, with no file system shared with the client: the scene,
    its buffers already built (BVH included), the device to open and the film's spectral bands. The scene goes whole,
    shapes included, although their triangles are in `buffers` too: a renderer also decides from them (which shapes
    emit, whether every material is diffuse, the bounds that distant and environment light paths start outside),
    and a worker deciding otherwise than the client would render other bits."""

    scene: Scene
    buffers: SceneBuffers
    plan: TilePlan
    spp: int
    device: str | None = None
    spectral_bins: int = 0
    spectral_range_nm: tuple[float, float] = (360.0, 830.0)
    key: str = ""  # the render's identity digest: workers cache one renderer per key
    kernels_digest: str = ""  # the client's kernel sources: a worker with others would render other bits

    @classmethod
    def make(
        cls,
        scene: Scene,
        buffers: SceneBuffers,
        plan: TilePlan,
        spp: int,
        device: str | None,
        spectral_bins: int,
        spectral_range_nm: tuple[float, float],
        key: str,
        kernels_digest: str = "",
    ) -> TileJob:
        shipped = replace(scene, notes={})
        return cls(shipped, buffers, plan, spp, device, spectral_bins, spectral_range_nm, key, kernels_digest)

    def film(self) -> FilmSetup:
        """The film the tiles are rendered into, as each worker's renderer sets it up."""
        from spectrace.film.setup import FilmSetup

        return FilmSetup.of(self.scene, self.buffers.cmf, self.spectral_bins, self.spectral_range_nm)

    def renderer(self, device: Device | str | None = None) -> Renderer:
        """A renderer of the whole film on this machine, after checking that its kernels are the client's."""
        from spectrace import resources
        from spectrace.device.program_cache import kernels_digest
        from spectrace.engine.renderer import Renderer

        if self.kernels_digest and kernels_digest(resources.kernels_dir()) != self.kernels_digest:
            import socket

            raise SpectraceError(
                f"the worker on {socket.gethostname()} has other spectrace kernels than the client (another "
                f"version?): its tiles would not merge bit for bit; install the client's version there"
            )

        return Renderer(
            self.scene,
            device if device is not None else self.device,
            spectral_bins=self.spectral_bins,
            spectral_range_nm=self.spectral_range_nm,
            buffers=self.buffers,
        )


class TileRunner(Protocol):
    """Renders the given tiles of a job somewhere, handing each result to `done` as it arrives (in any order), and
    returns when all are done or, asked between results, `stop` says True."""

    def run(self, job: TileJob, indices: list[int], done: Callable[[TileResult], None], stop: Callable[[], bool]): ...


class LocalTiles:
    """Tiles rendered one after another in this process, on one device (a resumed tiled render without a cluster)."""

    def __init__(self, device: Device | str | None = None):
        self.device = device
        self.renderer: Renderer | None = None

    def run(self, job: TileJob, indices: list[int], done: Callable[[TileResult], None], stop: Callable[[], bool]):
        if self.renderer is None:
            self.renderer = job.renderer(self.device)
        for index in indices:
            if stop():
                return
            done(render_tile(self.renderer, job.plan, index, job.spp))


@dataclass
class TiledFilm:
    """The host film of a tiled render: the merged buffers, which tiles they hold, and the devices that made them."""

    plan: TilePlan
    spp: int
    buffers: dict[str, np.ndarray] = field(default_factory=dict)
    done: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    devices: set[str] = field(default_factory=set)
    render_seconds: float = 0.0

    def __post_init__(self) -> None:
        if self.done.size == 0:
            self.done = np.zeros(self.plan.count, bool)

    @property
    def remaining(self) -> list[int]:
        return [int(index) for index in np.flatnonzero(~self.done)]

    def add(self, result: TileResult) -> None:
        pixels = self.plan.width * self.plan.height
        begin, end = self.plan.pixels(result.index)
        for name, values in result.buffers.items():
            if name not in self.buffers:
                self.buffers[name] = np.zeros(_state_shape(name, pixels, values.shape[1]), values.dtype)
            _per_pixel(self.buffers[name], pixels)[begin:end] = values
        self.done[result.index] = True
        self.devices.add(result.device)
        self.render_seconds += result.seconds

    def state(self) -> RenderState:
        return RenderState(self.spp if self.done.any() else 0, self.render_seconds, self.buffers)

    @property
    def device(self) -> str:
        """The device key, or every key joined by '; ' when tiles ran on different device types."""
        return "; ".join(sorted(self.devices))

    def checkpoint(self, identity: RenderIdentity) -> Checkpoint:
        return Checkpoint(identity, self.state(), self.device, TileMap(self.plan.rows, self.done.copy()))

    @classmethod
    def from_checkpoint(cls, checkpoint: Checkpoint, identity: RenderIdentity, spp: int, where: str) -> TiledFilm:
        """The film of a tiled checkpoint, after checking it belongs to this render (same identity and spp)."""
        if checkpoint.tiles is None:
            raise SpectraceError(
                "the checkpoint holds a render that was not split into tiles: resume it without --workers/--cluster",
                where=where,
            )
        if problem := identity_mismatch(checkpoint.identity, identity):
            raise SpectraceError(problem, where=where)
        done = checkpoint.tiles.done
        if done.any() and checkpoint.state.samples_done != spp:
            raise SpectraceError(
                f"the checkpoint's finished tiles hold {checkpoint.state.samples_done} spp, this render asks for "
                f"{spp} (a tiled render resumes at its own spp)",
                where=where,
            )
        plan = TilePlan(identity.width, identity.height, checkpoint.tiles.rows)
        devices = set(checkpoint.device.split("; ")) if done.any() and checkpoint.device else set()
        return cls(plan, spp, dict(checkpoint.state.buffers), done.copy(), devices, checkpoint.state.render_seconds)

    def image(self, scene: Scene, film: FilmSetup, extra: dict | None = None) -> Image:
        """The merged image of `scene`'s tiles on `film` (TileJob.film)."""
        labels = {"tiles": f"{int(self.done.sum())}/{self.plan.count}", "tile_rows": self.plan.rows, **(extra or {})}
        if len(self.devices) > 1:
            # Bit-identity holds per device type only: the merged image says it mixes them.
            labels[MIXED_DEVICES_KEY] = "yes"
        image = film.image(self.state(), scene.seed, self.device, scene.exposure, labels)
        # The samples of the finished tiles only: an interrupted render's other pixels hold none.
        samples = image.spp * image.width * image.height * int(self.done.sum()) // max(self.plan.count, 1)
        if problem := dropped_samples_problem(image.dropped_samples, samples, scene):
            raise SpectraceError(problem)
        return image


class PeriodicTileCheckpoints:
    """A tiled render's checkpoint file, written at most every `interval_seconds` as tiles arrive and at the end."""

    def __init__(self, path: Path, identity: RenderIdentity, interval_seconds: float, warn=lambda message: None):
        self.path, self.identity, self.interval_seconds, self.warn = path, identity, interval_seconds, warn
        self.last_saved = time.monotonic()

    def maybe_save(self, film: TiledFilm) -> None:
        if time.monotonic() - self.last_saved >= self.interval_seconds:
            self.save(film)

    def save(self, film: TiledFilm) -> None:
        self.last_saved = time.monotonic()
        try:
            write_checkpoint(self.path, film.checkpoint(self.identity))
        except OSError as error:
            self.warn(f"could not write checkpoint {self.path} ({error.strerror or error}); rendering goes on")


def render_tiles(
    job: TileJob,
    runner: TileRunner,
    film: TiledFilm | None = None,
    progress: Callable[[int, int], None] | None = None,
    stop: Callable[[], bool] | None = None,
    checkpoints: PeriodicTileCheckpoints | None = None,
) -> TiledFilm:
    """Render the tiles `film` does not hold yet (all, without a film) with `runner`, merging each as it arrives;
    progress(tiles done, tiles) after each. Ends early when `stop` says True (asked between tiles)."""
    film = film if film is not None else TiledFilm(job.plan, job.spp)
    should_stop = stop or (lambda: False)

    def done(result: TileResult) -> None:
        film.add(result)
        if progress is not None:
            progress(int(film.done.sum()), film.plan.count)
        if checkpoints is not None:
            checkpoints.maybe_save(film)

    if progress is not None:
        progress(int(film.done.sum()), film.plan.count)
    runner.run(job, film.remaining, done, should_stop)
    if checkpoints is not None and film.done.any():
        checkpoints.save(film)
    return film


def whole_film_rows(scene: Scene, tile_rows: int | None, where: str = "--tile-rows") -> int | None:
    """The rows per tile for `scene`: `tile_rows` as given, except for the integrators whose splats or photons land
    in any pixel (their SPLATS: light, bdpt, sppm), which render the whole film as one tile on one worker (a smaller
    tile asked for is refused)."""
    if INTEGRATORS[scene.integrator].SPLATS is None:
        return tile_rows
    if tile_rows is not None and tile_rows < scene.height:
        raise SpectraceError(
            f"integrator '{scene.integrator}' renders the whole film as one tile (its contributions land in any "
            f"pixel): leave the rows per tile out, or give at least the film's {scene.height}",
            where=where,
        )
    return scene.height
