"""Renders and experiments on many machines through Dask distributed (the `distributed` extra,
docs/distributed.md): a `LocalCluster` of worker processes on this machine, or any Dask scheduler (SLURM or PBS
through dask-jobqueue, Kubernetes, `dask scheduler` by hand).

A render goes out as tiles (spectrace.engine.tiles): the client builds the scene's buffers once and ships them to
the workers through Dask (no shared file system); each worker opens its own OpenCL device, builds (and caches, on
disk as always and in memory for the next tile) its kernels, and renders whole tiles. Dask reruns the tiles of a
worker that dies on another; a tile is a pure function of the job, so the merged film stays bit-identical.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import signal
import threading
import warnings
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

from spectrace.engine.tiles import TileJob, TileResult, render_tile
from spectrace.errors import SpectraceError

if TYPE_CHECKING:
    from distributed import Client

    from spectrace.engine.renderer import Renderer

INSTALL_HINT = 'needs Dask distributed, which is not installed: pip install "spectrace[distributed]"'
DEFAULT_CONNECT_TIMEOUT_S = 30.0
# Waiting for a scheduler: from a moment to a day (a batch queue may take hours to start one; "forever" is a hang).
MIN_CONNECT_TIMEOUT_S = 0.1
MAX_CONNECT_TIMEOUT_S = 86400.0
# How often the client, waiting for tiles, looks whether Ctrl-C asked it to stop.
_STOP_POLL_S = 0.2


def require_distributed(where: str) -> Any:
    try:
        import distributed
    except ImportError:
        raise SpectraceError(INSTALL_HINT, where=where) from None
    return distributed


def local_worker_limit() -> int:
    """The most worker processes a LocalCluster may start: this machine's cores (those this process may run on).
    Each worker renders on its own OpenCL device, which already uses every core (or a GPU), so more processes
    only compete for them, while each holds the scene and a whole-size film in memory."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # no affinity call on this platform (macOS, Windows)
        return max(1, os.cpu_count() or 1)


def check_cluster_options(cluster: str | None, workers: int | None, timeout_s: float) -> None:
    """One line for options that could never connect: both or neither of a scheduler and local workers, a number
    of local workers outside 1 .. local_worker_limit(), a timeout that is not a number of seconds in
    [MIN_CONNECT_TIMEOUT_S, MAX_CONNECT_TIMEOUT_S]."""
    if (cluster is None) == (workers is None):
        raise SpectraceError(
            "give either a scheduler address or a number of local workers",
            where="--cluster" if cluster is not None else "--workers",
        )
    if workers is not None:
        limit = local_worker_limit()
        if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= limit:
            raise SpectraceError(
                f"a LocalCluster takes 1 to {limit} worker processes (this machine's cores: each worker's device "
                f"already uses all of them), got {workers!r}",
                where="--workers",
            )
    seconds_ok = isinstance(timeout_s, (int, float)) and not isinstance(timeout_s, bool)
    if not (seconds_ok and MIN_CONNECT_TIMEOUT_S <= timeout_s <= MAX_CONNECT_TIMEOUT_S):
        raise SpectraceError(
            f"must be a number of seconds from {MIN_CONNECT_TIMEOUT_S:g} to {MAX_CONNECT_TIMEOUT_S:g} (a day), "
            f"got {timeout_s!r}",
            where="--cluster-timeout",
        )


@contextlib.contextmanager
def connect(
    cluster: str | None = None, workers: int | None = None, timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S
) -> Iterator[Client]:
    """A Dask client of the scheduler at `cluster` (tcp://host:8786), or of a LocalCluster of `workers` worker
    processes (one thread each: a worker's OpenCL device already uses all its cores) started and stopped here."""
    check_cluster_options(cluster, workers, timeout_s)
    distributed = require_distributed("--cluster" if cluster is not None else "--workers")
    if workers is not None:
        with _workers_ignoring_ctrl_c():
            local = distributed.LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",  # any free port: the scheduler's HTTP server starts even without a dashboard
                silence_logs=logging.CRITICAL,
            )
        with local, distributed.Client(local) as client:
            yield client
        return
    try:
        client = distributed.Client(cluster, timeout=timeout_s)
    except (OSError, TimeoutError, ValueError) as error:
        detail = " ".join(str(error).split()) or type(error).__name__
        raise SpectraceError(f"cannot reach the Dask scheduler ({detail})", where=f"--cluster {cluster}") from None
    with client:
        yield client


@contextlib.contextmanager
def _workers_ignoring_ctrl_c() -> Iterator[None]:
    """Ctrl-C in a terminal signals the whole process group, the LocalCluster's workers too: they would die with a
    traceback each while the client is writing the finished tiles. Worker processes started while SIGINT is
    ignored inherit that (Python and asyncio leave an ignored SIGINT alone); the client stops them itself."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


# ---------------------------------------------------------------- worker side

_WORKER_LOCK = threading.Lock()  # one tile at a time per worker process: the renderer and its device are shared
_WORKER_RENDERERS: dict[tuple[str, str | None], Renderer] = {}


def _the_job(job: TileJob) -> TileJob:
    return job


def render_tile_task(job: TileJob, index: int) -> TileResult:
    """A Dask task: tile `index` of `job`, on this worker's renderer of the job (built on its first tile)."""
    with _WORKER_LOCK:
        key = (job.key, job.device)
        renderer = _WORKER_RENDERERS.get(key)
        if renderer is None:
            _WORKER_RENDERERS.clear()  # one render at a time: free the last one's device memory first
            renderer = _WORKER_RENDERERS[key] = job.renderer()
        return render_tile(renderer, job.plan, index, job.spp)


# ---------------------------------------------------------------- client side


def shipped_bytes(job: TileJob) -> int:
    """Bytes of the job as pickled for the workers: what each worker receives once per render."""
    return len(pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL))


def task_failure(error: BaseException, what: str) -> SpectraceError:
    """A worker's failure as one line: the project's own errors as they are, a worker that kept dying (Dask gives
    up after a few deaths of the workers running the same task) or anything else by its type and message."""
    if isinstance(error, SpectraceError):
        return error
    name = type(error).__name__
    detail = " ".join(str(error).split())
    if name == "KilledWorker":
        return SpectraceError(f"the workers running {what} died repeatedly (out of memory, killed, crashed?)")
    return SpectraceError(f"a worker failed on {what} ({name}: {detail})" if detail else f"a worker failed ({name})")


class DaskTiles:
    """Renders tiles as Dask tasks on `client`'s workers (a spectrace.engine.tiles.TileRunner)."""

    def __init__(self, client: Client):
        self.client = client

    def run(self, job: TileJob, indices: list[int], done: Callable[[TileResult], None], stop: Callable[[], bool]):
        distributed = require_distributed("--cluster")
        if not indices:
            return
        # The job goes to the cluster once, as a task that returns it: a worker fetches it once from whichever worker
        # holds it, and when every holder is lost the scheduler recomputes it from the task (scattered data would be
        # lost for good, and with it every tile still to render).
        with warnings.catch_warnings():
            # Dask warns of a large graph (a big scene's buffers in the task): sending them with the task is the
            # point, see above.
            warnings.filterwarnings("ignore", message="Sending large graph", category=UserWarning)
            shipped = self.client.submit(_the_job, job, pure=False)
        futures = [self.client.submit(render_tile_task, shipped, index, pure=False) for index in indices]
        tiles = {future.key: index for future, index in zip(futures, indices)}
        pending = set(futures)
        try:
            while pending:
                if stop():
                    return
                try:
                    finished, pending = distributed.wait(pending, timeout=_STOP_POLL_S, return_when="FIRST_COMPLETED")
                except TimeoutError:
                    continue
                for future in finished:
                    try:
                        result = future.result()
                    except Exception as error:  # the task's own exception, re-raised here by Dask
                        if stop():  # Ctrl-C reaches a LocalCluster's workers too: their loss is the stop's
                            return
                        raise task_failure(error, f"tile {tiles.get(future.key, '?')}") from None
                    done(result)
        finally:
            if pending:
                self.client.cancel(list(pending))
