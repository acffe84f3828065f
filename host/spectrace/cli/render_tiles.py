"""`spectrace render --workers N | --cluster ADDRESS`, and --resume of a tiled checkpoint: the render split into
tiles (spectrace.engine.tiles), on Dask workers (spectrace.distributed) or, resuming without a cluster, here."""

from __future__ import annotations

from pathlib import Path

import typer

from spectrace.cli.common import console
from spectrace.errors import SpectraceError


def _say(text: str) -> None:
    console.say(text)


def render_tiled(
    job,
    output: Path,
    *,
    xyz: bool,
    quiet: bool,
    state_file: Path | None,
    checkpoint_interval: float,
    saved,
    resume: Path | None,
    cluster: str | None,
    workers: int | None,
    cluster_timeout: float,
    noisy: Path | None = None,
) -> None:
    """Render `job` (a spectrace.engine.job.RenderJob) split into tiles, then write its files."""
    from spectrace.cli.render_output import write_render
    from spectrace.engine.stop_signals import StopOnSignals
    from spectrace.engine.tiles import LocalTiles, PeriodicTileCheckpoints, TiledFilm

    if cluster is not None and workers is not None:
        raise SpectraceError("give --cluster or --workers, not both", where="--workers")
    if job.kernel != "megakernel":
        raise SpectraceError("a render split into tiles runs the megakernel only", where="--kernel")
    if cluster is not None or workers is not None:
        from spectrace.distributed import check_cluster_options, require_distributed

        require_distributed("--cluster" if cluster is not None else "--workers")  # before any work: say what to install
        check_cluster_options(cluster, workers, cluster_timeout)
    rows = saved.tiles.rows if saved is not None and saved.tiles is not None else job.tile_rows
    if saved is not None and saved.tiles is not None and job.tile_rows is not None and job.tile_rows != rows:
        raise SpectraceError(f"the checkpoint's tiles have {rows} rows", where="--tile-rows")
    tiles, identity = job.tiles(rows)
    film = None
    if saved is not None and resume is not None:
        film = TiledFilm.from_checkpoint(saved, identity, tiles.spp, str(resume))
        _say(f"resumed {resume}: {int(film.done.sum())}/{film.plan.count} tiles done")
    saver = None
    if state_file is not None:
        saver = PeriodicTileCheckpoints(state_file, identity, checkpoint_interval, warn=lambda m: _say(f"warning: {m}"))
    left = tiles.plan.count - (int(film.done.sum()) if film is not None else 0)
    if workers is not None and workers > max(left, 1):
        # A worker renders whole tiles: the others would only start, load the scene and wait.
        _say(f"note: {left} tiles to render, so {max(left, 1)} of the {workers} workers asked for are started")
        workers = max(left, 1)
    with StopOnSignals() as stop:
        if cluster is None and workers is None:
            _say(f"rendering {left} of {tiles.plan.count} tiles of {tiles.plan.rows} rows here")
            film = _run(tiles, LocalTiles(job.device), film, quiet, stop, saver)
        else:
            from spectrace.distributed import DaskTiles, connect, shipped_bytes

            with connect(cluster, workers, cluster_timeout) as client:
                count = len(client.scheduler_info().get("workers", {}))
                _say(
                    f"cluster: {count} workers; {tiles.plan.count} tiles of {tiles.plan.rows} rows; "
                    f"{shipped_bytes(tiles) / 2**20:.2f} MiB of scene to each worker"
                )
                film = _run(tiles, DaskTiles(client), film, quiet, stop, saver)
        interrupted = stop.requested
    if not film.done.any():
        raise SpectraceError("interrupted before the first tile finished; nothing written")
    if not film.done.all() and state_file is None:
        _save_unasked_checkpoint(film, identity, output)
    image = film.image(job.scene, tiles.film())
    image = write_render(
        job, image, output, include_xyz=xyz, state_file=state_file, noisy=noisy, device=job.device, log=_say
    )
    partial = not film.done.all()
    note = f" (interrupted: partial image, {int(film.done.sum())}/{film.plan.count} tiles)" if partial else ""
    _say(f"wrote {output}: {image.width}x{image.height}, {image.spp} spp, {image.render_seconds:.2f} s of tiles{note}")
    if len(film.devices) > 1:
        _say(f"warning: tiles ran on different devices ({film.device}): equally valid, not bit-identical to one")
    if image.dropped_samples:
        _say(f"warning: {image.dropped_samples} non-finite samples were dropped")
    if interrupted or partial:
        raise typer.Exit(130)


def _save_unasked_checkpoint(film, identity, output: Path) -> None:
    """An interrupted tiled render without --checkpoint keeps its finished tiles beside the image, so that
    --resume can complete it (an existing file of that name is left alone)."""
    from spectrace.engine.checkpoint import write_checkpoint

    path = output.with_name(output.name + ".checkpoint.npz")
    if path.exists():
        _say(f"warning: {path} exists, so the finished tiles were not saved to it (use --checkpoint next time)")
        return
    try:
        write_checkpoint(path, film.checkpoint(identity))
    except OSError as error:
        _say(f"warning: could not write {path} ({error.strerror or error})")
        return
    _say(f"wrote {path}: the finished tiles; --resume {path} completes the render")


def _run(job, runner, film, quiet: bool, stop, saver):
    from contextlib import nullcontext

    from spectrace.engine.tiles import render_tiles
    from spectrace.progress import progress_bar

    count = job.plan.count
    done = int(film.done.sum()) if film is not None else 0
    bar = nullcontext(None) if quiet else progress_bar(count, done, console.rich(), unit="tiles")
    with bar as draw:
        return render_tiles(job, runner, film, progress=draw, stop=stop, checkpoints=saver)
