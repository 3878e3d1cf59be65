"""The cost of passing a fold (``corner_rest``; docs/solvers.md, "The cost of passing a fold
(session 20)").

With ``corner_check = "mixed"`` (the default), where the implicit check comes to rest at a
fold, dynamic relaxation still looks for its own rest at the same lambda, and the path goes
on from it (the overdamped motion may settle in another equilibrium than the damped
dynamic one: S23's first fold). ``corner_rest = "bounded"`` (the default) gives that
relaxation the check's own effort at the rate the two budgets are set by,
``fold_check_time_steps`` time steps for ``corner_check_steps`` implicit steps; where it
finds no rest within that, the path goes on from the implicit rest. ``"dynamic"`` gives it
its whole budget (session 19).

Proves:

- the closed forms are found with either ``corner_rest``: a block on a base tilts at s/a, a
  free-standing wall at t/H, within 1e-6;
- S13 with 2-block return walls passes its last fold (above 1.01 x 0.10819) with
  ``"bounded"`` at the collapse multiplier of ``"dynamic"``, with fewer time steps and
  factorizations; its time steps stay within the bound, fold_check_time_steps x implicit
  steps / corner_check_steps;
- S23, whose first fold's two rests lead to peaks 2.5 % apart, keeps dynamic relaxation's
  rest (the higher peak) with ``"bounded"``, for fewer time steps;
- a bad setting is named.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from helpers.walls import TILTED, assert_closed_form
from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.static import StaticSettings, StaticSolver

RESTS = ["dynamic", "bounded"]


@pytest.mark.parametrize("rest", RESTS)
@TILTED
def test_either_rest_finds_the_closed_forms(build, rest):
    assert_closed_form(build, StaticSettings(corner_rest=rest))


def test_a_bounded_rest_passes_the_folds_of_s13_2_for_less():
    """S13/2 passes 3-6 folds at corners, each checked by the implicit relaxation and then
    by dynamic relaxation; bounded by the check's effort, the relaxation finds the same
    rests or leaves the path to the implicit ones, at the same collapse multiplier."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    runs = {}
    for rest in RESTS:
        solver = StaticSolver(case.model, replace(case.settings, corner_rest=rest))
        runs[rest] = (solver, solver.run(monitor=case.monitor))
    for _, hist in runs.values():
        assert hist.status == "collapse", hist.reason
        assert hist.collapse_multiplier is not None
        assert hist.collapse_multiplier > 1.01 * 0.10819, hist.reason
    (full, dynamic), (bounded, found) = runs["dynamic"], runs["bounded"]
    assert found.collapse_multiplier == pytest.approx(dynamic.collapse_multiplier, rel=1e-9)
    assert bounded.time_steps < full.time_steps
    assert found.factorizations < dynamic.factorizations
    s = bounded.settings
    per_step = s.fold_check_time_steps / s.corner_check_steps
    assert 0 < bounded.time_steps <= per_step * bounded.implicit_steps


def test_s23_keeps_the_rests_of_dynamic_relaxation():
    """S23: the implicit rest at its first fold leads to a lower peak (0.1098) than dynamic
    relaxation's (0.1126); the bounded relaxation still finds that rest, so the collapse
    multiplier is that of ``"dynamic"``."""
    case = build_case("S23")
    runs = []
    for rest in RESTS:
        solver = StaticSolver(case.model, replace(case.settings, corner_rest=rest))
        runs.append((solver, solver.run(monitor=case.monitor)))
    (full, dynamic), (bounded, found) = runs
    assert found.status == dynamic.status == "collapse", found.reason
    assert found.collapse_multiplier == pytest.approx(dynamic.collapse_multiplier, rel=1e-12)
    assert found.collapse_multiplier > 0.112
    # at its last fold neither relaxation finds its own rest (the path goes on from the
    # implicit one): the bounded one gives up sooner
    assert 0 < bounded.time_steps < full.time_steps
    assert found.factorizations <= dynamic.factorizations


def test_a_bad_corner_rest_is_named():
    with pytest.raises(ValueError, match="corner_rest"):
        StaticSettings(corner_rest="implicit")
