"""The step near the peak (solvers/static/steps.py, ``tail_cap``; docs/history/solvers_record.md,
"The step near the peak"): on a curve whose slope fades, the path stops three steps after its slope
fell below ``flat_slope`` of the elastic one; the paths of every step length coincide, so the
answer moves with the steps only through the load those steps gain.

Proves:

- the arithmetic of the cap: a step at the stop's slope gains at most ``flat_slope`` x
  |lambda| (the cap is the elastic displacement at lambda); before the displacement limit a step goes no further than the limit or no
  longer than its gain at the last step's slope allows; off, or without an elastic slope,
  there is no cap;
- with the cap, the closed-form collapses hold to 1e-6: a block on its base tilts at s/a
  and slides at mu, a free-standing wall tilts at t/H;
- with the cap (the default), 4-5's lambda no longer moves with growth:
  tests/solvers/test_step_convergence.py;
- bad values are refused.
"""

from __future__ import annotations

import math

import pytest

from helpers.walls import CLOSED_FORMS
from masonry_dem.solvers.incremental import pushover
from masonry_dem.solvers.static import StaticSettings
from masonry_dem.solvers.static.steps import tail_cap


def test_the_cap_bounds_the_gain_of_a_step_at_the_stop_slope() -> None:
    # lambda 2, elastic slope 400 per m, flat_slope 1e-3: a step at the stop's slope gains
    # 0.4 h, which is 1e-3 x 2 at h = 5e-3 m (the elastic displacement at lambda, 2 / 400)
    cap = tail_cap(2.0, 400.0, 1e-3, 1e-3)
    assert cap == pytest.approx(5e-3, rel=1e-15)
    assert 1e-3 * 400.0 * cap == pytest.approx(1e-3 * 2.0, rel=1e-15)
    assert tail_cap(-2.0, 400.0, 1e-3, 1e-3) == cap  # by |lambda|
    assert tail_cap(2.0, 400.0, 1e-3, 5e-4) == pytest.approx(2.5e-3, rel=1e-15)


def test_the_cap_before_the_displacement_limit() -> None:
    base = tail_cap(2.0, 400.0, 1e-3, 1e-3)  # 5e-3 m
    # the limit beyond the cap: the cap alone
    assert tail_cap(2.0, 400.0, 1e-3, 1e-3, slope=0.01, to_limit=0.01) == base
    # the limit within it, the last step at 10 x the stop's slope: a step gains 4 h, at most
    # 2e-3 at h = 5e-4; the limit 1e-4 ahead is nearer, so the step goes that far
    assert tail_cap(2.0, 400.0, 1e-3, 1e-3, slope=0.01, to_limit=1e-4) == pytest.approx(5e-4)
    # the limit 2e-3 ahead: the step lands on it
    assert tail_cap(2.0, 400.0, 1e-3, 1e-3, slope=0.01, to_limit=2e-3) == 2e-3
    # a flatter last step (or none measured) is bounded as at the stop's slope
    assert tail_cap(2.0, 400.0, 1e-3, 1e-3, slope=1e-4, to_limit=1e-4) == base
    assert tail_cap(2.0, 400.0, 1e-3, 1e-3, slope=math.nan, to_limit=1e-4) == base


def test_no_cap_when_off_or_without_an_elastic_slope() -> None:
    assert tail_cap(2.0, 400.0, 1e-3, 0.0) == math.inf
    assert tail_cap(2.0, 400.0, 0.0, 1e-3) == math.inf
    assert tail_cap(2.0, 0.0, 1e-3, 1e-3) == math.inf
    assert tail_cap(2.0, math.nan, 1e-3, 1e-3) == math.inf


@pytest.mark.parametrize("model, closed_form", CLOSED_FORMS.values(), ids=CLOSED_FORMS.keys())
def test_the_cap_keeps_the_closed_form_collapses(model, closed_form):
    hist = pushover(model(), StaticSettings(bracket_tolerance=1e-7))
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(closed_form, rel=1e-6)


@pytest.mark.parametrize("name, value", [("flat_slope", math.inf), ("flat_slope", math.nan)])
def test_bad_values_are_refused(name, value):
    with pytest.raises(ValueError, match=name):
        StaticSettings(**{name: value})
