"""Checkpoints: the whole state of a render in one file, so that an interrupted render continues exactly.

Both samplers are counter-based (a sample's random numbers depend only on seed, pixel, sample index and draw)
and every pixel adds its samples to the film in sample order, so the accumulated buffers and the number of
samples done are the entire state: a render continued from them produces the same floats, bit for bit, as one
that never stopped (on the same device).

A checkpoint is an uncompressed .npz (no pickled objects), written atomically, holding `format`, the identity
of the render (`width`, `height`, `seed`, `scene_digest`, `kernels_digest`), `samples_done`, `render_seconds`,
`device`, one `state_<name>` array per accumulation buffer (`film`, `ray_counts`, `spectral_film`), and `checksum`,
a SHA-256 of every other entry (name, type, shape and bytes): a file damaged on disk or edited by hand is refused
rather than continued into a render. Reading also checks each buffer's type and shape against the film size and
that the sums are finite. Files of format 1 (no checksum) are still read, with those explicit checks only.
What the state is (its buffers, their layout, saving it from and restoring it to the device) is the film's
(spectrace.film.state); this module adds the render's identity and the file.

A render split into tiles (spectrace.engine.tiles) saves format 3: the same entries plus `tile_rows` (film rows
per tile) and `tiles_done` (one bool per tile): the tiles marked done hold all `samples_done` samples per pixel,
the others none. Older readers refuse the format rather than continue such a file as a uniform render.
"""

from __future__ import annotations

import hashlib
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from spectrace import resources
from spectrace.core import limits
from spectrace.device.program_cache import kernels_digest
from spectrace.engine.memory import scene_arrays
from spectrace.engine.scene_buffers import render_params
from spectrace.errors import SpectraceError
from spectrace.film.state import RenderState, state_problem
from spectrace.integrators import INTEGRATORS
from spectrace.io.atomic import write_atomically
from spectrace.io.input_files import regular_file

if TYPE_CHECKING:
    from spectrace.engine.renderer import Renderer
    from spectrace.engine.scene_buffers import SceneBuffers
    from spectrace.scene.model import Scene

CHECKPOINT_FORMAT = "spectrace-checkpoint-2"
TILED_CHECKPOINT_FORMAT = "spectrace-checkpoint-3"
_FORMAT_WITHOUT_CHECKSUM = "spectrace-checkpoint-1"
# The scene digest starts from this fixed string, not from the format's name: a new file format must not make
# every checkpoint already saved look like one of another scene.
_SCENE_DIGEST_SALT = "spectrace-checkpoint-1"
_STATE_PREFIX = "state_"
_CHECKSUM = "checksum"


@dataclass(frozen=True)
class RenderIdentity:
    """What a checkpoint must share with the render that resumes it. The spp target is not part of it: a resumed
    render may go on to more samples than the interrupted one asked for."""

    width: int
    height: int
    seed: int
    scene_digest: str  # every array and parameter the kernels read (geometry, spectra, camera, depth, ...)
    kernels_digest: str  # the kernel sources: other code would continue with other numbers


@dataclass(frozen=True)
class TileMap:
    """Which tiles of a tiled render are finished: tiles of `rows` film rows each, top to bottom."""

    rows: int
    done: np.ndarray  # bool, one per tile


@dataclass
class Checkpoint:
    identity: RenderIdentity
    state: RenderState
    device: str  # the device key the samples so far ran on
    tiles: TileMap | None = None  # a tiled render's finished tiles; None: every pixel holds samples_done samples


def _update_with_array(digest, name: str, array: np.ndarray) -> None:
    array = np.ascontiguousarray(array)
    digest.update(f"\0{name}\0{array.dtype.str}\0{array.shape}\0".encode())
    digest.update(array.tobytes())


def scene_digest(renderer: Renderer) -> str:
    """SHA-256 of everything the render's kernels read except the sample range, and of the program settings."""
    return buffers_digest(renderer.scene, renderer.buffers, renderer.spectral_bins, renderer.spectral_range_nm)


def buffers_digest(
    scene: Scene, buffers: SceneBuffers, spectral_bins: int, spectral_range_nm: tuple[float, float]
) -> str:
    """scene_digest of a render not yet on a device (a tiled render's client holds no renderer)."""
    digest = hashlib.sha256(_SCENE_DIGEST_SALT.encode())
    settings: tuple = (scene.integrator, spectral_bins, tuple(spectral_range_nm), scene.sampler)
    # The integrator's own build settings decide its numbers too; its run-time ones (BDPT's light subpaths shared by
    # groups of pixels) are fields of the params hashed below.
    settings += tuple(INTEGRATORS[scene.integrator].defines(scene).values())
    digest.update(repr(settings).encode())
    _update_with_array(digest, "params", render_params(scene, buffers, 0, 0))
    for name, array in scene_arrays(buffers).items():
        _update_with_array(digest, name, array)
    response = scene.film_response
    if not response.is_default:  # (the default film's table is the scene's CMF array, hashed above)
        digest.update(repr(response.channel_names).encode())
        _update_with_array(digest, "film_table", response.device_table())
    return digest.hexdigest()


def render_identity(renderer: Renderer) -> RenderIdentity:
    if problem := renderer.integrator.CHECKPOINT_PROBLEM:
        raise SpectraceError(problem)
    return scene_identity(renderer.scene, renderer.buffers, renderer.spectral_bins, renderer.spectral_range_nm)


def scene_identity(
    scene: Scene, buffers: SceneBuffers, spectral_bins: int, spectral_range_nm: tuple[float, float]
) -> RenderIdentity:
    return RenderIdentity(
        scene.width,
        scene.height,
        scene.seed,
        buffers_digest(scene, buffers, spectral_bins, spectral_range_nm),
        kernels_digest(resources.kernels_dir()),
    )


def save_checkpoint(path: str | Path, renderer: Renderer, identity: RenderIdentity | None = None) -> Checkpoint:
    """Write the renderer's current state to `path` atomically (an older checkpoint survives any crash).
    `identity`, when given, is render_identity(renderer) computed earlier (it hashes every scene array)."""
    identity = identity if identity is not None else render_identity(renderer)
    checkpoint = Checkpoint(identity, renderer.film.save_state(), renderer.device.report.key)
    write_checkpoint(path, checkpoint)
    return checkpoint


def write_checkpoint(path: str | Path, checkpoint: Checkpoint) -> None:
    identity, state = checkpoint.identity, checkpoint.state
    payload: dict[str, Any] = {
        "format": np.array(CHECKPOINT_FORMAT if checkpoint.tiles is None else TILED_CHECKPOINT_FORMAT),
        "width": np.int64(identity.width),
        "height": np.int64(identity.height),
        "seed": np.int64(identity.seed),
        "scene_digest": np.array(identity.scene_digest),
        "kernels_digest": np.array(identity.kernels_digest),
        "samples_done": np.int64(state.samples_done),
        "render_seconds": np.float64(state.render_seconds),
        "device": np.array(checkpoint.device),
        **{_STATE_PREFIX + name: np.ascontiguousarray(array) for name, array in state.buffers.items()},
    }
    if checkpoint.tiles is not None:
        payload["tile_rows"] = np.int64(checkpoint.tiles.rows)
        payload["tiles_done"] = np.asarray(checkpoint.tiles.done, bool)
    payload[_CHECKSUM] = np.array(_checksum(payload))

    def write(temp: Path) -> None:
        with open(temp, "wb") as stream:  # a stream: np.savez would append .npz to a file name
            np.savez(stream, **payload)

    write_atomically(Path(path), write)


def _checksum(fields: dict) -> str:
    digest = hashlib.sha256()
    for name in sorted(fields):
        if name != _CHECKSUM:
            _update_with_array(digest, name, np.asarray(fields[name]))
    return digest.hexdigest()


def read_checkpoint(path: str | Path) -> Checkpoint:
    """Read a checkpoint file; SpectraceError naming the file if it is missing, damaged or not a checkpoint."""
    path = regular_file(path, what="checkpoint file")
    if not zipfile.is_zipfile(path):
        raise SpectraceError("not a spectrace checkpoint (not an .npz archive, or truncated)", where=str(path))
    try:
        with np.load(path, allow_pickle=False) as data:
            if problem := _inflation_problem(data):
                raise SpectraceError(f"damaged checkpoint: {problem}", where=str(path))
            fields = {name: data[name] for name in data.files}
    except SpectraceError:
        raise
    except Exception as error:  # numpy and zipfile raise many types for damaged files
        detail = " ".join(str(error).split()) or type(error).__name__
        raise SpectraceError(f"not a readable spectrace checkpoint ({detail})", where=str(path)) from None
    try:
        file_format = str(fields["format"])
        if file_format not in (CHECKPOINT_FORMAT, TILED_CHECKPOINT_FORMAT, _FORMAT_WITHOUT_CHECKSUM):
            raise SpectraceError(
                f"checkpoint format '{file_format}' is not '{CHECKPOINT_FORMAT}' (written by "
                f"another version of spectrace?)",
                where=str(path),
            )
        if file_format != _FORMAT_WITHOUT_CHECKSUM and str(fields[_CHECKSUM]) != _checksum(fields):
            raise SpectraceError(
                "the checkpoint's checksum does not match its contents: the file is damaged", where=str(path)
            )
        identity = RenderIdentity(
            int(fields["width"]),
            int(fields["height"]),
            int(fields["seed"]),
            str(fields["scene_digest"]),
            str(fields["kernels_digest"]),
        )
        buffers = {
            name[len(_STATE_PREFIX) :]: array for name, array in fields.items() if name.startswith(_STATE_PREFIX)
        }
        state = RenderState(int(fields["samples_done"]), float(fields["render_seconds"]), buffers)
        device = str(fields["device"])
        tiles = None
        if file_format == TILED_CHECKPOINT_FORMAT:
            tiles = TileMap(int(fields["tile_rows"]), np.asarray(fields["tiles_done"]))
    except (KeyError, TypeError, ValueError) as error:
        raise SpectraceError(f"not a spectrace checkpoint (missing or malformed {error})", where=str(path)) from None
    if problem := (_state_problem(identity, state) or _tiles_problem(identity, tiles)):
        raise SpectraceError(f"damaged checkpoint: {problem}", where=str(path))
    return Checkpoint(identity, state, device, tiles)


# The most a compressed member that is not a film buffer may inflate to: the others are numbers, names and the
# tile map (one flag per tile, at most one a film row).
_SMALL_MEMBER_BYTES = 1 << 20
# An .npy member's header before its data (numpy.lib.format pads it to a multiple of 64 bytes; 64 KiB is its
# version 2 limit).
_NPY_HEADER_BYTES = 1 << 16


def _inflation_problem(data: Any) -> str | None:
    """Why a member of the checkpoint's archive would inflate to more than its role allows, or None. spectrace
    writes the members stored (not compressed), which cannot inflate; a compressed one (an archive repacked, or
    made to harm) is bounded before numpy reads it: a film buffer by what its layout takes for the film size the
    checkpoint states, a buffer of bands (any number of them) by the overall limit on compressed inputs, every
    other member by 1 MiB. zipfile stops each member at the size its entry declares, so the declared size is the
    bound to check."""
    from spectrace.film.state import STATE_LAYOUT
    from spectrace.io.compressed import max_inflated_bytes

    packed = [info for info in data.zip.infolist() if info.compress_type != zipfile.ZIP_STORED]
    state = [info for info in packed if info.filename.startswith(_STATE_PREFIX)]
    for info in packed:
        if info not in state and info.file_size > _SMALL_MEMBER_BYTES:
            return f"member '{info.filename}' would inflate to {limits.format_bytes(info.file_size)}, more than 1 MiB"
    if not state:
        return None
    width, height = int(data["width"]), int(data["height"])
    if problem := limits.film_size_problem(width, height):
        return problem
    for info in state:
        dtype, per_pixel = STATE_LAYOUT.get(info.filename[len(_STATE_PREFIX) :].removesuffix(".npy"), (None, 0))
        if dtype is None:  # an unknown buffer, refused by name once read: a small member until then
            most, role = _SMALL_MEMBER_BYTES, "what a member other than a known film buffer may hold"
        elif per_pixel is None:
            most, role = max_inflated_bytes(), "the limit on a compressed input"
        else:
            most = width * height * per_pixel * np.dtype(dtype).itemsize + _NPY_HEADER_BYTES
            role = f"what a {width}x{height} film's buffer takes"
        if info.file_size > most:
            return (
                f"member '{info.filename}' would inflate to {limits.format_bytes(info.file_size)}, more than "
                f"{limits.format_bytes(most)} ({role})"
            )
    return None


def _tiles_problem(identity: RenderIdentity, tiles: TileMap | None) -> str | None:
    if tiles is None:
        return None
    if not 1 <= tiles.rows <= identity.height:
        return f"tile_rows {tiles.rows} is outside 1..{identity.height}"
    count = -(-identity.height // tiles.rows)
    if tiles.done.dtype != bool or tiles.done.shape != (count,):
        return (
            f"tiles_done must be {count} booleans (tiles of {tiles.rows} rows), "
            f"got {tiles.done.dtype} of shape {tiles.done.shape}"
        )
    return None


def _state_problem(identity: RenderIdentity, state: RenderState) -> str | None:
    """Why a checkpoint's numbers cannot be the state of a render, or None (checked even when the checksum holds:
    a file written by a faulty run, or by hand, can be consistent and still wrong)."""
    if problem := (limits.film_size_problem(identity.width, identity.height) or limits.seed_problem(identity.seed)):
        return problem
    return state_problem(state, identity.width, identity.height)


def identity_mismatch(saved: RenderIdentity, current: RenderIdentity) -> str | None:
    """Why a render with identity `current` cannot continue a checkpoint of `saved`, or None."""
    if (saved.width, saved.height) != (current.width, current.height):
        return (
            f"the checkpoint is of a {saved.width}x{saved.height} film but this render is "
            f"{current.width}x{current.height}"
        )
    if saved.seed != current.seed:
        return f"the checkpoint was rendered with seed {saved.seed} but this render uses seed {current.seed}"
    if saved.kernels_digest != current.kernels_digest:
        return (
            "the checkpoint was rendered by other kernel sources (spectrace was updated or its kernels edited), "
            "so the samples would not continue the same sequence; render afresh without --resume"
        )
    if saved.scene_digest != current.scene_digest:
        return (
            "the checkpoint belongs to another scene or other settings (scene file, meshes, spectra, camera, "
            "max_depth, integrator, sampler, spectral bins); render afresh without --resume"
        )
    return None


def restore_checkpoint(renderer: Renderer, checkpoint: Checkpoint, where: str) -> RenderIdentity:
    """Load `checkpoint` into `renderer`, after checking that it belongs to this very render (`where` names the
    checkpoint in errors). Returns the render's identity, which hashes every scene array: for the checkpoints the
    render goes on to write (PeriodicCheckpoints' `identity`)."""
    if checkpoint.tiles is not None:
        raise SpectraceError(
            "the checkpoint holds a render split into tiles: it continues tile by tile (spectrace render --resume "
            "does so; the megakernel only)",
            where=where,
        )
    identity = render_identity(renderer)
    if problem := identity_mismatch(checkpoint.identity, identity):
        raise SpectraceError(problem, where=where)
    renderer.film.restore_state(checkpoint.state, where=where)
    return identity


def resume_render(renderer: Renderer, path: str | Path) -> Checkpoint:
    """Read the checkpoint at `path` and load it into `renderer` (see restore_checkpoint)."""
    checkpoint = read_checkpoint(path)
    restore_checkpoint(renderer, checkpoint, str(path))
    return checkpoint


class PeriodicCheckpoints:
    """Saves a renderer's state to one file at most every `interval_seconds` (0: whenever asked), for a render
    loop's progress callback (`identity`: the renderer's render_identity, when already computed). A failed write is
    reported through `warn` and the render goes on: losing the render because a checkpoint could not be written
    would defeat the checkpoint's purpose."""

    def __init__(
        self,
        path: str | Path,
        renderer: Renderer,
        interval_seconds: float,
        warn=lambda message: None,
        clock=time.monotonic,
        identity: RenderIdentity | None = None,
    ):
        if renderer.integrator.CHECKPOINT_PROBLEM:
            render_identity(renderer)  # refuses before the first pass, not after it
        self.path = Path(path)
        self.renderer = renderer
        self.interval_seconds = interval_seconds
        self.warn = warn
        self.clock = clock
        self.last_saved = clock()
        self.saved_samples: int | None = None  # samples per pixel in the file, once this object wrote it
        # The render does not change: its arrays are hashed once (here, or by restore_checkpoint on --resume).
        self._identity = identity

    def maybe_save(self) -> bool:
        if self.clock() - self.last_saved < self.interval_seconds:
            return False
        return self.save()

    def save(self) -> bool:
        """Write now; False (after a warning) if the file could not be written."""
        self.last_saved = self.clock()
        if self.saved_samples == self.renderer.samples_done:
            return True  # the file already holds exactly this state
        if self._identity is None:
            self._identity = render_identity(self.renderer)
        try:
            save_checkpoint(self.path, self.renderer, self._identity)
        except OSError as error:
            self.warn(f"could not write checkpoint {self.path} ({error.strerror or error}); rendering goes on")
            return False
        self.saved_samples = self.renderer.samples_done
        return True
