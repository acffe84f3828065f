"""The shared statistics (tests/stats_toolkit.py) can fail: the chi-square test rejects a sampler whose density is
wrong on half its domain and accepts the right one, its p values are uniform when the sampler is right (so the pooling
rule and the degrees of freedom are honest), the standard-error checks reject a biased mean, and a check too weak
to see a 5 % error, or a replica comparison too noisy to, fails as a design error while one strong enough catches
that error. Fixed seeds."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree
from stats_toolkit import (
    DesignError,
    assert_chi_square_fits,
    assert_furnace,
    assert_reciprocal,
    assert_within_standard_errors,
    chi_square_p_value,
    pooled_bins,
    relative_power,
)

EDGES = np.linspace(0.0, 1.0, 21)


def _linear_density_samples(rng, n: int, factor_on_first_half: float = 1.0) -> np.ndarray:
    """Samples of p(x) = 2x on [0, 1]; with a factor, of p scaled by it on [0, 1/2) and renormalised (rejection:
    each sample on the other half is kept with probability 1 / factor)."""
    x = np.sqrt(rng.random(4 * n))
    if factor_on_first_half != 1.0:
        keep = (x < 0.5) | (rng.random(len(x)) < 1.0 / factor_on_first_half)
        x = x[keep]
    return x[:n]


def _linear_expected(n: int) -> np.ndarray:
    return n * np.diff(EDGES**2)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_right_sampler_is_accepted(seed):
    n = 50_000
    observed = np.histogram(_linear_density_samples(np.random.default_rng(seed), n), EDGES)[0]
    assert_chi_square_fits(observed, _linear_expected(n), 1e-3)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_sampler_off_by_ten_percent_on_half_the_domain_is_rejected(seed):
    n = 50_000
    observed = np.histogram(_linear_density_samples(np.random.default_rng(seed), n, 1.1), EDGES)[0]
    p_value, _, _ = chi_square_p_value(observed, _linear_expected(n))
    assert p_value < 1e-6


# An exponential density cut at 1.5 over 30 bins on [0, 1.5] with 2000 samples: the last bins expect fewer than 5
# samples, so the pooling rule is in play.
TAIL_EDGES = np.linspace(0.0, 1.5, 31)
TAIL_RATE = 4.0


def _tail_expected(n: int) -> np.ndarray:
    cdf = (1 - np.exp(-TAIL_RATE * TAIL_EDGES)) / (1 - np.exp(-TAIL_RATE * TAIL_EDGES[-1]))
    return n * np.diff(cdf)


def _tail_samples(rng, n: int) -> np.ndarray:
    top = 1 - np.exp(-TAIL_RATE * TAIL_EDGES[-1])
    return -np.log1p(-rng.random(n) * top) / TAIL_RATE


def test_pooling_merges_every_sparse_bin_into_one():
    expected = _tail_expected(2000)
    assert np.count_nonzero(expected < 5) >= 3
    obs, exp = pooled_bins(np.zeros_like(expected), expected)
    assert np.all(exp >= 5) and len(exp) == np.count_nonzero(expected >= 5) + 1
    assert exp.sum() == pytest.approx(expected.sum())
    # A sparse remainder below 5 joins the smallest well-filled bin.
    obs, exp = pooled_bins([30, 40, 2, 1], [30.0, 40.0, 1.5, 1.0])
    assert list(exp) == [32.5, 40.0] and list(obs) == [33, 40]


def test_p_values_of_a_right_sampler_are_uniform():
    """Over 2000 seeds, the share of p values below 0.05 is 0.05 within 4 binomial standard errors: a pooling rule or
    a count of degrees of freedom that made the test too strict or too lenient would move it (two degrees of freedom
    too many give 0.025)."""
    n, trials = 2000, 2000
    expected = _tail_expected(n)
    p_values = np.array(
        [
            chi_square_p_value(np.histogram(_tail_samples(np.random.default_rng(seed), n), TAIL_EDGES)[0], expected)[0]
            for seed in range(trials)
        ]
    )
    share = np.mean(p_values < 0.05)
    assert abs(share - 0.05) < 4 * np.sqrt(0.05 * 0.95 / trials), share


def test_samples_where_the_pdf_is_zero_are_rejected():
    """The sampler is right but for 1 % of its samples, put beyond the pdf's support (a bin expected to hold none)."""
    n = 20_000
    rng = np.random.default_rng(7)
    x = _tail_samples(rng, n)
    x[: n // 100] = 2.0
    edges = np.append(TAIL_EDGES, 2.5)
    expected = np.append(_tail_expected(n), 0.0)
    p_value, _, _ = chi_square_p_value(np.histogram(x, edges)[0], expected)
    assert p_value < 1e-6


def test_a_missing_bin_of_expected_mass_is_an_error():
    with pytest.raises(AssertionError, match="missing"):
        chi_square_p_value([50, 40], [50.0, 30.0])


def test_furnace_accepts_an_unbiased_estimator_and_rejects_two_percent_of_bias():
    rng = np.random.default_rng(11)
    n, albedo = 40_000, 0.8
    # A weight of 1 with probability albedo, else 0 (a sampler that absorbs 20 %): standard error 0.2 %.
    weights = (rng.random((n, 4)) < albedo).astype(np.float64)
    mean, standard_error = assert_furnace(weights, albedo)
    assert np.all(standard_error < 0.003)
    with pytest.raises(AssertionError):
        assert_furnace(weights * 1.02, albedo)
    assert_furnace(weights * 0.98, albedo, at_most=True)
    with pytest.raises(AssertionError):
        assert_furnace(weights * 1.02, albedo, at_most=True)
    with pytest.raises(AssertionError, match="finite"):
        assert_furnace(np.append(weights[:, 0], np.nan), albedo)


def test_within_standard_errors_is_a_bound_on_every_element():
    assert_within_standard_errors([1.0, 2.0], [1.03, 1.97], [0.01, 0.01])
    with pytest.raises(AssertionError):
        assert_within_standard_errors([1.0, 2.0], [1.03, 1.95], [0.01, 0.01])


def test_reciprocity_needs_light_and_agreement():
    values = np.linspace(0.1, 1.0, 50)
    assert_reciprocal(values, values * (1 + 1e-5), rtol=1e-4)
    with pytest.raises(AssertionError):
        assert_reciprocal(values, values * (1 + 1e-3), rtol=1e-4)
    with pytest.raises(AssertionError, match="no pair"):
        assert_reciprocal(np.zeros(5), np.zeros(5), rtol=1e-4)


def test_power_is_the_relative_error_the_tolerance_lets_through():
    np.testing.assert_allclose(relative_power([2.0, 4.0], [0.01, 0.01], sigmas=4, slack=0.02), [0.03, 0.015])
    assert relative_power(0.0, 0.01)[()] == np.inf  # nothing to be relative to
    with pytest.raises(DesignError, match="power 8.0%"):
        assert_within_standard_errors(1.0, 1.0, 0.02, power=0.05)  # 4 standard errors of 2 %: blind below 8 %
    assert_within_standard_errors(1.0, 1.0, 0.01, power=0.05)


def _replicas(rng, mean: np.ndarray, noise: float, replicas: int = 8) -> np.ndarray:
    """(replicas, height, width, 3) images of `mean` with independent Gaussian noise of relative size `noise`."""
    return mean * (1.0 + noise * rng.standard_normal((replicas, *mean.shape)))


@pytest.mark.parametrize("seed", range(3))
def test_replica_comparison_states_its_power_and_catches_five_percent(seed):
    """A comparison whose power is under 5 % passes two renders of the same image and fails one 5 % too bright
    (everywhere, or only in the region it is about); one too noisy to tell fails as a design error."""
    rng = np.random.default_rng(seed)
    mean = np.ones((8, 8, 3)) * np.linspace(0.5, 1.5, 8)[:, None, None]
    region = np.zeros((8, 8), dtype=bool)
    region[2:6, 2:6] = True
    brighter = mean * np.where(region, 1.05, 1.0)[..., None]
    # Per pixel 10 %, over 16 pixels of 3 channels and 8 replicas each: power about 5 x 0.1 / sqrt(48 x 4) = 3.6 %.
    power = assert_replicas_agree(_replicas(rng, mean, 0.1), _replicas(rng, mean, 0.1), block=4, region=region)
    assert 0.02 < power < 0.05
    with pytest.raises(AssertionError, match=r"region mean .* differs by .* power [0-9.]+%"):
        assert_replicas_agree(_replicas(rng, brighter, 0.1), _replicas(rng, mean, 0.1), block=4, region=region)
    with pytest.raises(DesignError, match="too weak"):
        assert_replicas_agree(_replicas(rng, mean, 0.3), _replicas(rng, mean, 0.3), block=4, region=region)
