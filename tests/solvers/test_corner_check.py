"""The corner check, implicit (``Relaxations.implicit_relaxation``; docs/history/solvers_record.md,
"The corner check, implicit").

Where work control gets stuck at a corner (its curve still rising into the last state), the
check looks for rest a little above it, at lambda x (1 + transient_rise): rest found, the
stop was a fold of the path and the path goes on from it; none, a peak. The check relaxes by
linearly implicit Euler steps of the overdamped motion D dq/dt = R(q), one factorization a
step, instead of the explicit dynamic relaxation of ``fold_check_time_steps`` (the path
goes on from dynamic relaxation's rest at a fold, so that it takes the equilibrium the
explicit check took).

Proves, on walls whose answer is known:

- above a peak it finds no rest: a block on a base tilts at s/a, a free-standing wall at
  t/H (closed forms: the weight's moment about the toe, W t / 2, against the live load's,
  lambda W H / 2, for a wall; s / a for a block of height a and thickness s); from the
  certified collapse state the relaxation to 1.005 x the closed form runs past the
  displacement limit or spends its budget, while to 0.98 x it comes to rest (an equilibrium
  of the law within the static tolerance), so the check can fail both ways;
- above a fold it finds rest: S13 with 2-block return walls, whose path without the check
  certifies its first fold at 0.0855 although dynamic relaxation finds rest above it; the
  implicit check passes that fold and every later one, the one at 0.1082 where the explicit
  check found no rest too, to a collapse under the associative bound;
- a check with no verdict within its budget leaves it to dynamic relaxation, to S13/2's
  collapse at 0.1082;
- its settings are checked like every other.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from helpers.walls import tilted_block, tilted_wall
from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSettings, StaticSolver
from masonry_dem.solvers.static.outcome import Failure


@pytest.mark.parametrize("build", [tilted_block, tilted_wall], ids=["block s/a", "wall t/H"])
def test_the_implicit_check_finds_no_rest_above_a_peak_and_rest_below_it(build):
    model, closed_form = build()
    solver = StaticSolver(model, StaticSettings())
    hist = solver.run()
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(closed_form, rel=0.005)
    rise = solver.settings.transient_rise
    start = (solver.q.copy(), solver.cracked.copy())
    above = solver.implicit_relaxation((1.0 + rise) * closed_form)
    assert not above.ok
    assert above.failure in (Failure.DISPLACEMENT_LIMIT, Failure.NO_REST), above.reason
    solver.restore(*start)
    below = solver.implicit_relaxation(0.98 * closed_form)
    assert below.ok, below.reason
    _, rnorm, _ = solver.residual(below.q, 0.98 * closed_form)
    assert rnorm <= solver.settings.tolerance
    assert below.iterations < solver.settings.corner_check_steps


@pytest.mark.slow
def test_the_implicit_check_passes_the_last_fold_of_s13_2():
    """Without the check the path certifies S13/2's first fold, 0.0855; the explicit check
    passes four folds and stops at 0.1082, where a relaxation to 1.01 x still finds rest
    (tests/cases/test_peaks_not_folds.py). The implicit check (it
    decides, and the path goes on from dynamic relaxation's rest where that finds one) finds
    rest at 1.005 x 0.1082 too, and the path stops higher (0.1107 measured; the highest
    equilibrium dynamic relaxation finds from the unloaded wall is 0.110), under the
    associative bound 0.1164."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    solver = StaticSolver(case.model, case.settings)
    hist = solver.run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier is not None
    assert hist.collapse_multiplier > 1.01 * 0.10819, hist.reason
    assert hist.collapse_multiplier <= dem_upper_bound(case.model).load_factor
    assert solver.implicit_steps > 0
    unchecked = StaticSolver(
        case.model, replace(case.settings, fold_check_time_steps=0, transient_reach=0.0)
    ).run(monitor=case.monitor)
    assert unchecked.collapse_multiplier == pytest.approx(0.08551, rel=1e-3)


@pytest.mark.slow
def test_a_check_without_verdict_leaves_it_to_dynamic_relaxation():
    """With a budget of one implicit step no check of S13/2 reaches rest or the displacement
    limit: each falls back to dynamic relaxation, and the path is the explicit check's, to
    its collapse at 0.1082."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    fallback = StaticSolver(case.model, replace(case.settings, corner_check_steps=1))
    found = fallback.run(monitor=case.monitor)
    assert found.collapse_multiplier == pytest.approx(0.10819, rel=1e-3)
    assert fallback.time_steps > 0
    assert fallback.implicit_steps > 0


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("corner_check_steps", 0),
        ("corner_check_rise", -0.5),
        ("corner_check_start", 0.0),
    ],
)
def test_bad_corner_check_settings_are_named(field, value):
    with pytest.raises(ValueError, match=field):
        StaticSettings(**{field: value})
