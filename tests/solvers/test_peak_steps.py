"""The step near the peak (solvers/static/steps.py, ``tail_cap``; docs/solvers.md, "The step
near the peak"): on a curve whose slope fades, the path stops three steps after its slope fell
below ``flat_slope`` of the elastic one; the paths of every step length coincide, so the
answer moves with the steps only through the load those steps gain.

Proves:

- the arithmetic of the cap: a step at the stop's slope gains at most ``tail_resolution`` x
  |lambda| (the cap is ``tail_resolution`` / ``flat_slope`` times the elastic displacement
  at lambda); before the displacement limit a step goes no further than the limit or no
  longer than its gain at the last step's slope allows; off, or without an elastic slope,
  there is no cap;
- with the cap, alone or with ``collapse_at = "onset"``, the closed-form collapses hold to
  1e-6: a block on its base tilts at s/a and slides at mu, a free-standing wall tilts at
  t/H;
- with the cap alone (the default), 4-5's lambda no longer moves with growth:
  tests/solvers/test_step_convergence.py;
- on the 4-5 pressure wall the option's lambda with the default growth (1.5) lies within
  0.1 % of its own with growth 1.025, and within 0.1 % of the finest path (growth 1.025,
  tail_resolution 1.25e-4, measured 9 149), where the default's lies 0.6 % above it;
- the reported lambda is a converged state of the path; with the onset, the highest before
  the three flat steps, below the last;
- bad values are refused.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from helpers.walls import CLOSED_FORMS
from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.incremental import pushover
from masonry_dem.solvers.static import StaticSettings, StaticSolver
from masonry_dem.solvers.static.outcome import StopReason
from masonry_dem.solvers.static.steps import tail_cap

OPTION = {"tail_resolution": 1e-3, "collapse_at": "onset"}
CAP = {"tail_resolution": 1e-3}


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


@pytest.mark.parametrize("option", [CAP, OPTION], ids=["cap", "cap and onset"])
@pytest.mark.parametrize("model, closed_form", CLOSED_FORMS.values(), ids=CLOSED_FORMS.keys())
def test_the_option_keeps_the_closed_form_collapses(option, model, closed_form):
    hist = pushover(model(), StaticSettings(bracket_tolerance=1e-7, **option))
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(closed_form, rel=1e-6)


def _lambda(case, **changes) -> float:
    settings = replace(case.settings, **changes)
    hist = StaticSolver(case.model, settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    lam = float(hist.collapse_multiplier)
    # the report is a converged state of the path; with the onset, one below its last three
    assert lam in hist.load_factors.tolist()
    if changes.get("collapse_at") == "onset":
        assert hist.stop is StopReason.STIFFNESS_LOST
        assert lam == max(hist.load_factors[:-3]) < max(hist.load_factors)
    return lam


def test_pressure_wall_lambda_no_longer_moves_with_growth() -> None:
    """4-5 (measured): default 9 208 (growth 1.5) and 9 166 (1.025); with the option 9 151
    and 9 149; the finest path 9 149. The uncapped steps' 0.6 % above the finest is the load
    that their three long flat steps gained; bounded, the option's is under 0.1 % either
    way."""
    case = build_case("4-5")
    option, fine = (_lambda(case, growth=g, **OPTION) for g in (1.5, 1.025))
    assert abs(option / fine - 1) < 1e-3
    assert abs(option / 9149.1 - 1) < 1e-3
    assert _lambda(case, tail_resolution=0.0) / 9149.1 - 1 > 4e-3  # the uncapped steps


@pytest.mark.parametrize(
    "name, value", [("tail_resolution", -1e-3), ("tail_resolution", math.nan), ("collapse_at", "x")]
)
def test_bad_values_are_refused(name, value):
    with pytest.raises(ValueError, match=name):
        StaticSettings(**{name: value})
