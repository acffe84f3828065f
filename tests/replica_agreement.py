"""Comparing two renderers by independent replicas: each gives several images of a few samples per pixel, and the
means over pixel blocks and over the whole image must agree within a number of standard errors of the difference,
estimated from the replicas' spread."""

import numpy as np


def spectrace_replicas(renderer, replicas: int, replica_spp: int) -> np.ndarray:
    """(replicas, height, width, 3) film XYZ: consecutive sample ranges of one render, which are independent."""
    sums = []
    for replica in range(1, replicas + 1):
        renderer.render(spp=replica * replica_spp, pass_spp=replica_spp)
        sums.append(renderer.image().xyz.astype(np.float64) * renderer.samples_done)
    return np.diff(np.stack([np.zeros_like(sums[0]), *sums]), axis=0) / replica_spp


def assert_replicas_agree(ours: np.ndarray, theirs: np.ndarray, block: int, sigmas: float = 5.0) -> None:
    """Both (replicas, size, size, 3): block means and whole-image means within `sigmas` standard errors."""
    n = ours.shape[1] // block

    def block_means(images: np.ndarray) -> np.ndarray:
        return images.reshape(len(images), n, block, n, block, 3).mean(axis=(2, 4))

    for reduce in (block_means, lambda images: images.mean(axis=(1, 2))):
        a, b = reduce(ours), reduce(theirs)
        difference = a.mean(axis=0) - b.mean(axis=0)
        standard_error = np.sqrt(a.var(axis=0, ddof=1) / len(a) + b.var(axis=0, ddof=1) / len(b))
        assert np.all(np.abs(difference) <= sigmas * standard_error), np.max(np.abs(difference) / standard_error)


def assert_renders_like_mitsuba(mi, path, device, replicas: int, replica_spp: int, block: int, ours=None) -> np.ndarray:
    """Mitsuba 3 (`mi`, a spectral variant) renders the XML at `path` and spectrace renders its import of the same
    file (of `ours` where given: the same scene with another integrator, say) as `replicas` independent images of
    `replica_spp` samples each; their linear sRGB must agree (assert_replicas_agree). Returns Mitsuba's images, for
    the caller's check that the comparison saw what it was meant to."""
    from spectrace.engine.renderer import Renderer
    from spectrace.interop.mitsuba_xml import load_mitsuba_scene
    from spectrace.spectral import xyz_to_linear_srgb

    scene = mi.load_file(str(path))
    by_mitsuba = np.stack([np.array(mi.render(scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])
    renderer = Renderer(load_mitsuba_scene(path if ours is None else ours), device)
    assert_replicas_agree(xyz_to_linear_srgb(spectrace_replicas(renderer, replicas, replica_spp)), by_mitsuba, block)
    return by_mitsuba
