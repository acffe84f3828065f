"""`spectrace bench quality`'s error at budget (spectrace.benchmarks.quality._at_budget) against closed forms: an
error whose square falls as a power of the time, with the reference's noise added in quadrature."""

import math

import pytest

from spectrace.benchmarks.quality import _at_budget

NOISE = 0.002


def _row(seconds: float, rate: float) -> dict:
    """A render of 100 spp per second taking `seconds` whose error net of the reference's noise is seconds^(-rate/2):
    MSE ∝ time^-rate."""
    return {"spp": round(100 * seconds), "seconds": seconds, "rmse": math.sqrt(seconds**-rate + NOISE**2)}


@pytest.mark.parametrize("rate", [1.0, 1.5])
def test_two_powers_of_two_interpolate_at_their_rate(rate):
    """Sobol's lower and upper powers of two: the error at the budget is the power law's, whatever its rate."""
    row = {**_row(2.56, rate), "above": _row(5.12, rate)}
    assert _at_budget(row, "rmse", NOISE, 4.0) == pytest.approx(4.0 ** (-rate / 2), rel=1e-9)


def test_one_render_scales_as_one_over_time():
    """Independent samples: variance ∝ 1/time from the one render."""
    assert _at_budget(_row(3.0, 1.0), "rmse", NOISE, 4.0) == pytest.approx(4.0**-0.5, rel=1e-9)
