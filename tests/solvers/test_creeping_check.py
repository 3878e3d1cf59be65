"""A corner check whose motion creeps (docs/history/solvers_record.md, "A motion that creeps").

The implicit corner check (``Relaxations.implicit_relaxation``) gives a verdict only from
its motion: rest (a fold) or past the displacement limit (a peak). A check whose budget
``corner_check_steps`` runs out first hands the question to dynamic relaxation. On the U
6 x 24 wall with 4-block returns the budget before session 19 (200) ran out at a corner whose
motion crept at a steady pace (about 1.5 mm of a 14.1 mm limit) and dynamic relaxation then
found no rest, so the path stopped at 0.2309457; with 500 the same motion comes to rest at
its 450th factorization (3.9 mm from its start, after a last snap-through): a fold, which
the path passes. A verdict read from the motion's pace or trend would have called that fold
a peak, so the verdict stays the motion's and only the budget changes.

Proves:

- the closed forms are found with either budget: a block on a base tilts at s/a, a
  free-standing wall at t/H (the weight's moment about the toe, W t / 2, against the live
  load's, lambda W H / 2), within 1e-6;
- the check's record of its motion (``check_motion``) ends past the displacement limit
  above the block's peak (1.005 x s/a) and within it at rest below (0.98 x s/a), its
  factorization counts increasing;
- S13 with 2-block return walls still passes its last fold (above 1.01 x 0.10819) with
  either budget, at the same collapse multiplier;
- the U 6 x 24 wall's slow fold is passed with a budget of 500: its collapse lies above
  1.003 x 0.2309457, the stop the 200-step budget gave, and the check that found it took
  more than 200 implicit steps.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from helpers.walls import TILTED, assert_closed_form, tilted, tilted_block
from masonry_dem.cases.paper import build_case
from masonry_dem.geometry.builders import add_base
from masonry_dem.geometry.plans import u_wall
from masonry_dem.solvers.static import StaticSettings, StaticSolver

BUDGETS = [200, 500]


@pytest.mark.parametrize("budget", BUDGETS)
@TILTED
def test_either_budget_finds_the_closed_forms(build, budget):
    assert_closed_form(build, StaticSettings(corner_check_steps=budget))


def test_the_check_records_its_motion_on_each_side_of_a_peak():
    """From the block's collapse state: above s/a the motion's last row lies past the
    displacement limit, below it the motion rests within the limit."""
    model, closed_form = tilted_block()
    solver = StaticSolver(model, StaticSettings())
    assert solver.run().collapse_multiplier == pytest.approx(closed_form, rel=1e-6)
    start = (solver.q.copy(), solver.cracked.copy())
    above = solver.implicit_relaxation(1.005 * closed_form)
    assert above.past_limit, above.reason
    rows = solver.check_motion
    assert rows[-1][1] > solver.limit >= max(moved for _, moved, _ in rows[:-1])
    assert [f for f, _, _ in rows] == sorted({f for f, _, _ in rows})
    solver.restore(*start)
    below = solver.implicit_relaxation(0.98 * closed_form)
    assert below.ok, below.reason
    assert 0 < len(solver.check_motion) <= below.iterations
    assert max(moved for _, moved, _ in solver.check_motion) <= solver.limit


@pytest.mark.slow
def test_the_last_fold_of_s13_2_is_passed_with_either_budget():
    """S13/2: the explicit check stopped at 0.10819 with rest 1 % above; the implicit check
    passes it within 200 steps, so a larger budget changes nothing there."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    found = [
        StaticSolver(case.model, replace(case.settings, corner_check_steps=b)).run(
            monitor=case.monitor
        )
        for b in BUDGETS
    ]
    for hist in found:
        assert hist.status == "collapse", hist.reason
        assert hist.collapse_multiplier is not None
        assert hist.collapse_multiplier > 1.01 * 0.10819, hist.reason
    assert found[1].collapse_multiplier == pytest.approx(found[0].collapse_multiplier, rel=1e-12)


@pytest.mark.slow
def test_a_slow_fold_of_a_u_wall_is_passed_with_the_default_budget():
    """U 6 x 24 with 4-block returns (Restrepo Velez's stones, tilted on a fixed base, as
    ``benchmarks/endgame_walls.py`` builds it): with 200 implicit steps (the budget before
    session 19) its check at 0.2309457 gave no verdict and dynamic relaxation no rest, so
    the path stopped there. With 500 (the default) the check's motion comes to rest (450
    factorizations measured): a fold."""
    a, b, s, gamma = 0.02824, 0.07978, 0.03968, 26.8e3
    model = tilted(*add_base(u_wall(6, 24, a, b, s, gamma, return_blocks=4)))
    assert StaticSettings().corner_check_steps == 500
    solver = StaticSolver(model, StaticSettings())
    hist = solver.run()
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier is not None
    assert hist.collapse_multiplier > 1.003 * 0.2309457, hist.reason
    assert solver.implicit_steps > 200
