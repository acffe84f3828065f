"""Next-event estimation picks a light and places the point on it from one 2D number (pick_light_reusing in
kernels/lights.cl): the pick must follow the lights' pmf exactly, and the first coordinate, rescaled within the
picked light's share of the CDF, must again cover [0, 1) evenly, so the point sampling stays uniform and keeps the
sampler's stratification."""

import numpy as np


def test_pick_follows_the_pmf_and_the_rescaled_number_is_uniform(kernel_runner):
    pmf = np.array([0.1, 0.0, 0.6, 0.3])  # a light of zero power must never be picked
    cdf = np.concatenate([[0.0], np.cumsum(pmf)]).astype(np.float32)
    cdf[-1] = 1.0
    n = 1 << 16
    u = np.zeros((n, 2), np.float32)
    u[:, 0] = (np.arange(n) + 0.5) / n  # a regular grid: every light gets exactly its share
    u[:, 1] = np.random.default_rng(1).random(n, dtype=np.float32)
    runner = kernel_runner("testing/light_pick.cl")
    picked = np.empty(n, np.int32)
    rescaled = np.empty((n, 2), np.float32)
    args = [
        runner.buffer(cdf),
        np.int32(len(pmf)),
        runner.buffer(u),
        runner.buffer(picked, True),
        runner.buffer(rescaled, True),
        np.int32(n),
    ]
    runner.run("pick_reusing", n, args, {3: picked, 4: rescaled})

    # The light whose float32 CDF interval [cdf[i], cdf[i + 1]) holds u.x, and so (up to that rounding) its pmf share.
    np.testing.assert_array_equal(picked, np.searchsorted(cdf[1:], u[:, 0], side="right"))
    assert np.all(np.abs(np.bincount(picked, minlength=len(pmf)) - pmf * n) <= 1)
    np.testing.assert_array_equal(rescaled[:, 1], u[:, 1])  # the second coordinate is untouched
    for light in np.flatnonzero(pmf):
        mine = rescaled[picked == light, 0].astype(np.float64)
        expected = (u[picked == light, 0] - cdf[light]) / pmf[light]
        np.testing.assert_allclose(mine, expected, atol=1e-5)
        assert mine.min() >= 0.0 and mine.max() < 1.0
        # Evenly spread: the grid's points of this light fall one per cell of a grid as fine over [0, 1).
        counts = np.bincount((mine * len(mine)).astype(int), minlength=len(mine))
        assert counts.max() <= 2 and np.count_nonzero(counts) >= 0.99 * len(mine)
