"""The statistics every Monte Carlo test shares, so that each kind of check is made one way.

- A mean against its expected value within k standard errors (`assert_within_standard_errors`), or against a bound
  (`assert_at_most_within_standard_errors`); `mean_and_standard_error` gives both figures from replicates. A check
  that passes says only that the error is below k standard errors (plus any slack): relative to the expected value,
  that is the smallest error it would still catch, its power (`relative_power`). Every message states it, and a
  check given `power` fails as a design error where it is weaker than that.
- The furnace (`assert_furnace`): the weights of an importance sampler (f cos / pdf, 0 for a failed sample) average
  to the albedo they estimate. A white furnace, where the albedo is exactly known, catches energy lost or gained.
- Reciprocity (`assert_reciprocal`): a BSDF evaluated both ways round gives the same value.
- Pearson's chi-square goodness of fit (`chi_square_p_value`, `assert_chi_square_fits`) of sampled counts against
  the counts a pdf predicts, with one rule for sparse bins (below).

Pooling rule. Pearson's statistic follows its chi-square distribution only when no bin is expected to hold few
samples. Cochran (1954, "Some methods for strengthening the common χ² tests", Biometrics 10:417-451) allows a few
expected counts between 1 and 5; the conservative form used here keeps every expected count at or above 5: all bins
expected to hold fewer than 5 samples are merged into one bin, and if that bin is itself expected below 5 it is
merged into the smallest of the others. Samples that land where the pdf puts nothing are kept in the merged bin, so
they still count against the fit. The degrees of freedom are the number of bins left less one (the sample total is
fixed)."""

import numpy as np
from scipy import stats

SIGMAS = 4.0
MIN_EXPECTED = 5.0
POWER = 0.05


class DesignError(Exception):
    """A check too weak to see the error it is meant to: the test's fault, not the code's. Not an AssertionError,
    so that a test expecting a comparison to fail (pytest.raises(AssertionError)) is not satisfied by it."""


def mean_and_standard_error(values, axis=0) -> tuple[np.ndarray, np.ndarray]:
    """Mean of independent replicates along `axis` and its standard error (sample standard deviation / √n)."""
    values = np.asarray(values, dtype=np.float64)
    n = values.shape[axis]
    return values.mean(axis=axis), values.std(axis=axis, ddof=1) / np.sqrt(n)


def relative_power(expected, standard_error, sigmas: float = SIGMAS, slack: float = 0.0) -> np.ndarray:
    """The smallest relative error a check within `sigmas` standard errors (plus `slack`) would catch: its
    tolerance over |expected| (infinite where expected is 0)."""
    expected, standard_error = np.asarray(expected, dtype=np.float64), np.asarray(standard_error, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(expected != 0, (sigmas * standard_error + slack) / np.abs(expected), np.inf)


def assert_power(expected, standard_error, power: float = POWER, sigmas: float = SIGMAS, slack=0.0, what: object = ""):
    """The check of a mean against `expected` within `sigmas` standard errors (plus `slack`) would catch a relative
    error of `power` in every element: else the test is too weak to tell a right estimator from a wrong one."""
    achieved = relative_power(expected, standard_error, sigmas, slack)
    if not np.all(achieved <= power):
        raise DesignError(
            f"test design: {what}: too weak, power {np.max(achieved):.1%} above {power:.0%} (the smallest relative "
            f"error {sigmas:g} standard errors would catch; more samples, or a larger region)"
        )


def assert_within_standard_errors(
    mean, expected, standard_error, sigmas: float = SIGMAS, slack=0.0, what: object = "", power: float | None = None
) -> None:
    """|mean − expected| ≤ sigmas × standard error + slack, element-wise. `slack` absorbs a known deterministic error
    (float32 rounding, a quadrature's), never the noise. With `power`, the check must also be able to catch that
    relative error (assert_power)."""
    mean, expected, standard_error, slack = (
        np.asarray(x, dtype=np.float64) for x in (mean, expected, standard_error, slack)
    )
    if power is not None:
        assert_power(expected, standard_error, power, sigmas, slack, what)
    deviation = np.abs(mean - expected)
    assert np.all(deviation <= sigmas * standard_error + slack), (
        f"{what}: mean {mean} expected {expected} standard error {standard_error} "
        f"(deviation {np.max(deviation / np.maximum(standard_error, 1e-300)):.3g} standard errors; power "
        f"{np.max(relative_power(expected, standard_error, sigmas, slack)):.1%})"
    )


def assert_at_most_within_standard_errors(
    mean, bound, standard_error, sigmas: float = SIGMAS, slack: float = 0.0, what: object = ""
) -> None:
    """mean ≤ bound + sigmas × standard error + slack, element-wise: a one-sided bound such as energy conservation."""
    mean, bound, standard_error = (np.asarray(x, dtype=np.float64) for x in (mean, bound, standard_error))
    assert np.all(mean <= bound + sigmas * standard_error + slack), (
        f"{what}: mean {mean} above {bound} by more than {sigmas} standard errors {standard_error}"
    )


def assert_furnace(
    weights, albedo, sigmas: float = SIGMAS, slack: float = 0.0, what: object = "", at_most: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Weights of one sample per row (a column per wavelength, if any; a failed sample weighs 0) must be finite and
    non-negative and average to `albedo` within `sigmas` standard errors, or, with `at_most`, not above it. Returns
    the mean and its standard error for further checks."""
    weights = np.asarray(weights, dtype=np.float64)
    assert np.all(np.isfinite(weights)) and np.all(weights >= 0), f"{what}: weights must be finite and non-negative"
    mean, standard_error = mean_and_standard_error(weights, axis=0)
    if at_most:
        assert_at_most_within_standard_errors(mean, albedo, standard_error, sigmas, slack, what)
    else:
        assert_within_standard_errors(mean, albedo, standard_error, sigmas, slack, what)
    return mean, standard_error


def assert_reciprocal(forward, backward, rtol: float, what: object = "") -> None:
    """A BSDF's values for (ωo, ωi) and (ωi, ωo), both already divided by the cosine the evaluation multiplies in
    (and, for refraction, by the squared index of each side), agree. Some pairs must carry light, or the check
    would pass on an all-zero BSDF."""
    forward, backward = np.asarray(forward, dtype=np.float64), np.asarray(backward, dtype=np.float64)
    assert np.any(forward > 0), f"{what}: no pair carries light"
    np.testing.assert_allclose(
        forward, backward, rtol=rtol, atol=1e-6 * max(float(forward.max()), 1e-300), err_msg=str(what)
    )


def pooled_bins(observed, expected, minimum: float = MIN_EXPECTED) -> tuple[np.ndarray, np.ndarray]:
    """Observed and expected counts after the module's pooling rule (every expected count at least `minimum`)."""
    observed = np.asarray(observed, dtype=np.float64).ravel()
    expected = np.asarray(expected, dtype=np.float64).ravel()
    assert observed.shape == expected.shape and np.all(expected >= 0)
    low = expected < minimum
    obs, exp = observed[~low], expected[~low]
    pooled_obs, pooled_exp = observed[low].sum(), expected[low].sum()
    if pooled_exp >= minimum:
        obs, exp = np.append(obs, pooled_obs), np.append(exp, pooled_exp)
    elif (pooled_exp > 0 or pooled_obs > 0) and len(exp):
        smallest = np.argmin(exp)
        obs[smallest] += pooled_obs
        exp[smallest] += pooled_exp
    return obs, exp


def chi_square_p_value(observed, expected, minimum: float = MIN_EXPECTED) -> tuple[float, float, int]:
    """(p value, Pearson's statistic, degrees of freedom) of observed counts against expected counts of the same
    total (within 1 %; the expected counts are scaled to the observed total), after pooling."""
    obs, exp = pooled_bins(observed, expected, minimum)
    assert len(exp) >= 2, "the chi-square test needs at least two bins expected to hold enough samples"
    # A quadrature of the pdf is off by a little; more than 1 % means a bin (such as the samples that fail) is missing.
    assert abs(obs.sum() - exp.sum()) <= 1e-2 * exp.sum(), (
        f"observed total {obs.sum()} differs from expected total {exp.sum()}: give the missing mass its own bin"
    )
    exp = exp * (obs.sum() / exp.sum())
    statistic = float(np.sum((obs - exp) ** 2 / exp))
    dof = len(exp) - 1
    return float(stats.chi2.sf(statistic, dof)), statistic, dof


def assert_chi_square_fits(observed, expected, significance: float, what: object = "") -> float:
    """The counts fit at `significance` (already divided by the number of tests it shares a family with, if any);
    returns the p value."""
    p_value, statistic, dof = chi_square_p_value(observed, expected)
    assert p_value > significance, f"{what}: chi-square {statistic:.1f} on {dof} dof, p = {p_value:.3g}"
    return p_value
