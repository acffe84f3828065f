"""The peer benchmark's agreement check: its noise estimate against known Gaussian noise on a shaded image, and
its verdict on images that do and do not differ."""

import numpy as np

from spectrace.benchmarks.image_agreement import compare_regions, region_mean_and_error, region_pixels

SIZE = 120
BOX = {"middle": (0.25, 0.25, 0.75, 0.75)}


def _shaded(rng, sigma):
    """A smooth gradient (the image's shading, which the estimate must ignore) plus independent pixel noise."""
    y, x = np.mgrid[0:SIZE, 0:SIZE] / SIZE
    clean = np.stack([1 + 0.5 * x, 0.5 + y, 0.2 + 0.3 * x * y], axis=-1)
    return clean + rng.normal(0.0, sigma, clean.shape)


def test_standard_error_matches_the_noise_not_the_shading():
    rng = np.random.default_rng(3)
    sigma = 0.05
    pixels = region_pixels(_shaded(rng, sigma), BOX["middle"])
    assert pixels.shape[:2] == (60, 60)
    _, standard_error = region_mean_and_error(pixels)
    # 2 x 60 x 59 squared differences: the variance estimate is good to about 2 %, the error to about 1 %.
    np.testing.assert_allclose(standard_error, sigma / 60, rtol=0.05)


def test_verdicts():
    rng = np.random.default_rng(4)
    first, second = _shaded(rng, 0.05), _shaded(rng, 0.05)
    assert compare_regions(first, second, BOX)[0].agrees
    brighter = compare_regions(first * 1.02, second, BOX)[0]
    assert not brighter.agrees and brighter.relative_difference > 0.015
