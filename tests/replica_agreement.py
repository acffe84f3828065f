"""Comparing two renderers by independent replicas: each gives several images of a few samples per pixel, and the
means over pixel blocks and over the region the test is about (the whole image unless told) must agree within a
number of standard errors of the difference, estimated from the replicas' spread.

Power. A comparison that passes says only that the renderers differ by less than what it could detect: k standard
errors of the difference. Divided by the mean, that is the smallest relative error the comparison would still catch
(its power); every assertion message states it, per block (the median over lit blocks) and for the region. The
region's power must be 5 % or better, or the test is too weak to tell a right renderer from a wrong one and fails
as a design error: add replicas or samples, or aggregate over a larger region of what the test is about."""

import numpy as np

from stats_toolkit import DesignError

POWER = 0.05


def spectrace_replicas(renderer, replicas: int, replica_spp: int) -> np.ndarray:
    """(replicas, height, width, 3) film XYZ: consecutive sample ranges of one render, which are independent."""
    sums = []
    for replica in range(1, replicas + 1):
        renderer.render(spp=replica * replica_spp, pass_spp=replica_spp)
        sums.append(renderer.image().xyz.astype(np.float64) * renderer.samples_done)
    return np.diff(np.stack([np.zeros_like(sums[0]), *sums]), axis=0) / replica_spp


def difference_and_power(a, b, sigmas: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For replicas of a quantity (replica axis first) from two renderers: the difference of their means in
    standard errors of the difference, and the comparison's power, sigmas standard errors over the mean of both
    (infinite where that mean is 0: nothing there to compare)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    difference = a.mean(axis=0) - b.mean(axis=0)
    standard_error = np.sqrt(a.var(axis=0, ddof=1) / len(a) + b.var(axis=0, ddof=1) / len(b))
    scale = np.abs(a.mean(axis=0) + b.mean(axis=0)) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(standard_error > 0, np.abs(difference) / standard_error, np.where(difference == 0, 0.0, np.inf))
        power = np.where(scale > 0, sigmas * standard_error / scale, np.inf)
    return z, power, scale


def assert_replicas_agree(
    ours: np.ndarray,
    theirs: np.ndarray,
    block: int,
    sigmas: float = 5.0,
    region: np.ndarray | None = None,
    power: float = POWER,
    what: object = "",
) -> float:
    """Both (replicas, height, width, 3): block means, whole-image means per channel and the mean of the three
    channels' sum over `region` (a (height, width) mask; the whole image if None) within `sigmas` standard errors;
    the region's power at most `power`. Returns the region's power."""
    ours, theirs = np.asarray(ours, dtype=np.float64), np.asarray(theirs, dtype=np.float64)
    assert ours.shape[1:] == theirs.shape[1:], f"{what}: images of shapes {ours.shape} and {theirs.shape}"
    height, width = ours.shape[1] // block, ours.shape[2] // block
    mask = np.ones(ours.shape[1:3], dtype=bool) if region is None else np.asarray(region, dtype=bool)
    assert mask.any(), f"{what}: the region holds no pixel"

    def block_means(images: np.ndarray) -> np.ndarray:
        cropped = images[:, : height * block, : width * block]
        return cropped.reshape(len(images), height, block, width, block, 3).mean(axis=(2, 4))

    def region_sum(images: np.ndarray) -> np.ndarray:
        return images[:, mask].sum(axis=-1).mean(axis=-1)

    z_region, power_region, mean_region = difference_and_power(region_sum(ours), region_sum(theirs), sigmas)
    z_blocks, power_blocks, _ = difference_and_power(block_means(ours).sum(-1), block_means(theirs).sum(-1), sigmas)
    lit = np.isfinite(power_blocks)
    median_block = float(np.median(power_blocks[lit])) if lit.any() else float("inf")
    figures = (
        f"{what}: region mean {float(mean_region):.4g} differs by {float(z_region):.2f} standard errors, "
        f"power {float(power_region):.1%} (the smallest relative error {sigmas:g} standard errors would catch); "
        f"{block} x {block}-pixel blocks: power {median_block:.1%} (median over {lit.sum()} lit)"
    )

    if not power_region <= power:
        raise DesignError(f"test design: too weak, power above {power:.0%}: {figures}")
    for reduce in (block_means, lambda images: images.mean(axis=(1, 2))):
        z, _, _ = difference_and_power(reduce(ours), reduce(theirs), sigmas)
        assert np.all(z <= sigmas), f"largest difference {np.max(z):.2f} standard errors; {figures}"
    assert z_region <= sigmas, figures
    return float(power_region)


def assert_renders_like_mitsuba(
    mi, path, device, replicas: int, replica_spp: int, block: int, ours=None, region=None, power: float = POWER
) -> np.ndarray:
    """Mitsuba 3 (`mi`, a spectral variant) renders the XML at `path` and spectrace renders its import of the same
    file (of `ours` where given: the same scene with another integrator, say) as `replicas` independent images of
    `replica_spp` samples each; their linear sRGB must agree (assert_replicas_agree). Returns Mitsuba's images, for
    the caller's check that the comparison saw what it was meant to."""
    from spectrace.engine.renderer import Renderer
    from spectrace.interop.mitsuba import load_mitsuba_scene
    from spectrace.spectral import xyz_to_linear_srgb

    scene = mi.load_file(str(path))
    # [..., :3]: the image, before any channels an integrator adds (Mitsuba's `moment` appends its moments)
    by_mitsuba = np.stack([np.array(mi.render(scene, spp=replica_spp, seed=seed))[..., :3] for seed in range(replicas)])
    renderer = Renderer(load_mitsuba_scene(path if ours is None else ours), device)
    ours_images = xyz_to_linear_srgb(spectrace_replicas(renderer, replicas, replica_spp))
    assert_replicas_agree(ours_images, by_mitsuba, block, region=region, power=power, what=path.name)
    return by_mitsuba
