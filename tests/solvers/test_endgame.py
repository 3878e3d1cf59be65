"""The endgame at the peak (docs/history/solvers_record.md, "The endgame at the peak").

A pseudo-transient step is the overdamped motion D dq/dt = R(q) that the corner check runs
(backward-Euler steps of the same equation, from a converged state of the path, to a lambda
a ``transient_rise`` above it). When that motion runs past the displacement limit toward
lambda T, the wall found no rest at T from that branch: the corner check's verdict. Every
later pseudo-transient step or check of the same branch whose target is T or more is
answered by that run-off and not run again.

Proves:

- the evidence the rule takes: from the block's collapse state, the pseudo-transient motion
  to 1.005 x s/a runs past the displacement limit and so does the implicit check's, while
  both come to rest at 0.98 x s/a (the two motions agree on each side of the peak);
- on the S5 U wall, whose first pseudo-transient step at the peak runs off: the later
  checks of its branch are answered by the run-off (no implicit step), and the certificate
  and the reason say so;
- a fold whose rest lies above the stop is still passed: S13 with 2-block return walls stops
  above 1.01 x 0.10819 (its explicit check's last stop).
"""

from __future__ import annotations

import logging

import pytest

from helpers.walls import tilted_block
from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSettings, StaticSolver
from masonry_dem.solvers.static.outcome import Failure


def test_the_pseudo_transient_motion_and_the_check_agree_on_each_side_of_a_peak():
    """The block at s/a: above the peak both overdamped motions run past the displacement
    limit (the run-off the path takes as a verdict), below it both come to rest."""
    model, closed_form = tilted_block()
    solver = StaticSolver(model, StaticSettings())
    hist = solver.run()
    assert hist.collapse_multiplier == pytest.approx(closed_form, rel=1e-6)
    start = (solver.q.copy(), solver.cracked.copy())
    rise = 1.0 + solver.settings.transient_rise
    for relax in (solver.pseudo_transient, solver.implicit_relaxation):
        solver.restore(*start)
        above = relax(rise * closed_form)
        assert above.failure is Failure.DISPLACEMENT_LIMIT, (relax.__name__, above.reason)
        solver.restore(*start)
        below = relax(0.98 * closed_form)
        assert below.ok, (relax.__name__, below.reason)
        assert solver.residual(below.q, 0.98 * closed_form)[1] <= solver.settings.tolerance


@pytest.mark.slow
def test_a_run_off_answers_the_later_checks_of_its_branch(caplog):
    """S5 with 4-block return walls (the U wall of ``bench_walls_that_meet``): at its peak the
    first pseudo-transient step runs past the displacement limit at 1.005 x the state; the
    path then closes in on the peak by halved steps and, stuck, would ask a second
    pseudo-transient step and the implicit check the same question. The run-off answers
    both: no implicit step."""
    case = build_case("S5", restraint="return-walls", return_blocks=4)
    solver = StaticSolver(case.model, case.settings)
    with caplog.at_level(logging.DEBUG, logger="masonry_dem.solvers.static.paths"):
        found = solver.run(monitor=case.monitor)
    assert found.status == "collapse", found.reason
    assert solver.implicit_steps == 0
    assert found.certificate is not None and found.certificate.corner
    assert "pseudo-transient step of the same branch" in found.certificate.reason
    assert "ran past the displacement limit toward" in caplog.text
    assert "a pseudo-transient motion from this branch ran past" in found.reason


@pytest.mark.slow
def test_the_last_fold_of_s13_2_is_still_passed():
    """S13/2: the explicit check stopped at 0.10819 with rest 1 % above; the implicit check
    passes it (session 18). The endgame rule may not turn that fold into a peak."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    hist = StaticSolver(case.model, case.settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier is not None
    assert hist.collapse_multiplier > 1.01 * 0.10819, hist.reason
    assert hist.collapse_multiplier <= dem_upper_bound(case.model).load_factor
