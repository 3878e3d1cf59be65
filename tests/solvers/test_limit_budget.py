"""Every backend of the limit analysis within a budget: a time limit for the analysis and an
iteration limit per solve; a solve they stop ends "failed" with the solver's own words and no
multiplier, never a hang or a traceback. With no backend given, the size chooses it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import masonry_dem as md
from helpers.walls import on_base
from masonry_dem.solvers.limit_analysis import analysis, backends, kinematic, limit_analysis
from masonry_dem.solvers.limit_analysis.budget import budget, seconds_left, spent


def held_wall(n: int, courses: int) -> md.Model:
    """A running-bond wall out of plane, its left column held in u1 and u3 (the issue's
    kind: 0.081 x 0.21 x 0.07 m blocks)."""
    return on_base(md.running_bond_wall(n, courses, 0.081, 0.21, 0.07, 20e3), left=["u1", "u3"])


@pytest.fixture(scope="module")
def small() -> md.Model:
    return held_wall(6, 8)  # 48 blocks and the base


@pytest.fixture(scope="module")
def large() -> md.Model:
    return held_wall(16, 20)  # 331 blocks: HiGHS's LP takes seconds, Clarabel 0.1-0.4 s


def stopped(out) -> bool:
    return (
        out.status == "failed"
        and math.isnan(out.load_factor)
        and out.reason.startswith("stopped by the solver's time or iteration limit")
        and out.summary()["lambda"] is None
    )


@pytest.mark.parametrize(
    "options, words",
    [
        ({"backend": "highs"}, "HiGHS: Time limit reached"),
        ({"backend": "clarabel"}, "Clarabel: MaxTime"),
        ({"backend": "highs", "associative": False}, "Time limit reached"),
        ({"backend": "clarabel", "associative": False}, "Clarabel: MaxTime"),
    ],
    ids=["HiGHS", "Clarabel", "HiGHS non-associative", "Clarabel non-associative"],
)
def test_a_backend_out_of_time_stops_with_a_status(large, options, words):
    """A millisecond for solves that need tens to thousands of them: each backend stops at
    its time limit and says so (HiGHS's own status, Clarabel's MaxTime)."""
    out = limit_analysis(large, time_limit=1e-3, **options)
    assert stopped(out), out.reason
    assert words in out.reason


def test_a_backend_out_of_iterations_stops_with_a_status(small, monkeypatch):
    """The iteration limits: HiGHS's interior point method held to one iteration, Clarabel
    to two (the analysis needs tens)."""
    full = limit_analysis(small, backend="highs")
    assert full.status == "collapse", full.reason
    monkeypatch.setattr(backends, "HIGHS_IPM_ITERATIONS", 1)
    out = limit_analysis(small, backend="highs")
    assert stopped(out) and "Iteration limit reached" in out.reason, out.reason
    monkeypatch.setattr(kinematic, "CLARABEL_ITERATIONS", 2)
    out = limit_analysis(small, backend="clarabel")
    assert stopped(out) and "Clarabel: MaxIterations (kinematic)" in out.reason, out.reason
    monkeypatch.setattr(backends, "CLARABEL_ITERATIONS", 2)
    out = limit_analysis(small, backend="clarabel", associative=False)
    assert stopped(out) and "MaxIterations" in out.reason, out.reason


def test_a_budget_with_time_to_spare_changes_nothing(small):
    """The same multiplier with the default budget and with a generous one."""
    a = limit_analysis(small, backend="clarabel")
    b = limit_analysis(small, backend="clarabel", time_limit=1e5)
    assert a.status == b.status == "collapse"
    assert a.load_factor == b.load_factor


def test_the_budget_holds_inside_its_block_only():
    assert math.isinf(seconds_left()) and not spent()
    with budget(1e-9):
        assert spent() and seconds_left() == 0.0
        with budget(100.0):
            assert 99.0 < seconds_left() <= 100.0
        assert spent()
    assert math.isinf(seconds_left())


@pytest.mark.parametrize("value", [0, -1.0, math.inf, math.nan, True, "10", None])
def test_a_time_limit_out_of_range_is_refused_by_name(small, value):
    with pytest.raises(ValueError, match=r"time_limit must be a finite number of seconds > 0"):
        limit_analysis(small, time_limit=value)


def test_with_no_backend_given_the_size_chooses_it(small, large):
    """HiGHS's LP below ``EXACT_CONE_FROM`` free DOFs, Clarabel's exact cone from it; a
    cone or a backend named is obeyed at any size."""
    assert int(np.count_nonzero(small.free)) < analysis.EXACT_CONE_FROM
    assert int(np.count_nonzero(large.free)) >= analysis.EXACT_CONE_FROM
    a = limit_analysis(small)
    assert (a.backend, a.cone) == ("highs", "circumscribed")
    b = limit_analysis(large)
    assert (b.backend, b.cone, b.status) == ("clarabel", "exact", "collapse")
    assert analysis.choose_backend(large, "inscribed") == "highs"
    assert analysis.choose_backend(small, "exact") == "clarabel"
    # the exact cone lies inside the circumscribed pyramid: its multiplier is not larger
    pyramid = limit_analysis(small, backend="highs").load_factor
    exact = limit_analysis(small, backend="clarabel").load_factor
    assert exact <= pyramid * (1 + 1e-6)


def test_the_non_associative_iteration_stops_between_its_solves(small, monkeypatch):
    """The budget is checked before every frozen-capacity solve: spent after the
    associative start, the iteration stops there with no lambda."""
    from masonry_dem.solvers.limit_analysis import non_associative

    monkeypatch.setattr(non_associative, "spent", lambda: True)
    out = limit_analysis(small, associative=False, backend="highs")
    assert stopped(out), out.reason
    assert "its time ran out after 0 non-associative solves" in out.reason
