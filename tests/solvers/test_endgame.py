"""The endgame at the peak (``run_off``, ``corner_transient``; docs/solvers.md, "The endgame
at the peak (session 19)").

A pseudo-transient step is the overdamped motion D dq/dt = R(q) that the corner check runs
(backward-Euler steps of the same equation, from a converged state of the path, to a lambda
a ``transient_rise`` above it). When that motion runs past the displacement limit toward
lambda T, the wall found no rest at T from that branch: the corner check's verdict. With
``run_off = "carry"`` (the default) every later pseudo-transient step or check of the same
branch whose target is T or more is answered by that run-off and not run again; ``"stop"``
ends the path at the run-off; ``"ignore"`` is session 18's path.

Proves:

- the closed forms are found with every endgame: a block on a base tilts at s/a, a
  free-standing wall at t/H (the weight's moment about the toe, W t / 2, against the live
  load's, lambda W H / 2), within 1e-6;
- the evidence the rule takes: from the block's collapse state, the pseudo-transient motion
  to 1.005 x s/a runs past the displacement limit and so does the implicit check's, while
  both come to rest at 0.98 x s/a (the two motions agree on each side of the peak);
- on the S5 U wall, whose first pseudo-transient step at the peak runs off: the same
  collapse multiplier to 1e-9 without the second pseudo-transient step and the implicit
  check (no implicit step), and fewer factorizations than ``"ignore"``; ``"stop"`` keeps
  the collapse within the bracket tolerance, a little lower (no halvings after the run-off);
- a fold whose rest lies above the stop is still passed: S13 with 2-block return walls stops
  above 1.01 x 0.10819 (its explicit check's last stop) with either ``corner_transient``;
- bad settings are named.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import pytest

from helpers.walls import TILTED, assert_closed_form, tilted_block
from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSettings, StaticSolver
from masonry_dem.solvers.static.outcome import Failure

ENDGAMES = [
    {"run_off": "carry"},
    {"run_off": "stop"},
    {"run_off": "ignore"},
    {"corner_transient": False},
]


@pytest.mark.parametrize("endgame", ENDGAMES, ids=lambda e: "-".join(map(str, e.values())))
@TILTED
def test_every_endgame_finds_the_closed_forms(build, endgame):
    assert_closed_form(build, StaticSettings(**endgame))


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


def _u_wall(**changes):
    case = build_case("S5", restraint="return-walls", return_blocks=4)
    solver = StaticSolver(case.model, replace(case.settings, **changes))
    hist = solver.run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    return solver, hist


def test_a_run_off_answers_the_later_checks_of_its_branch(caplog):
    """S5 with 4-block return walls (the U wall of ``bench_walls_that_meet``): at its peak the
    first pseudo-transient step runs past the displacement limit at 1.005 x the state; the
    path then closes in on the peak by halved steps and, stuck, would ask a second
    pseudo-transient step and the implicit check (74 steps measured) the same question.
    Carried, the run-off answers both: no implicit step, the same collapse."""
    with caplog.at_level(logging.DEBUG, logger="masonry_dem.solvers.static.paths"):
        carried, found = _u_wall()
    ignored, before = _u_wall(run_off="ignore")
    assert found.collapse_multiplier == pytest.approx(before.collapse_multiplier, rel=1e-9)
    assert carried.implicit_steps == 0 < ignored.implicit_steps
    assert carried.factorizations < ignored.factorizations
    assert found.certificate is not None and found.certificate.corner
    assert "pseudo-transient step of the same branch" in found.certificate.reason
    assert "ran past the displacement limit toward" in caplog.text
    assert "a pseudo-transient motion from this branch ran past" in found.reason
    stopped, early = _u_wall(run_off="stop")
    assert early.collapse_multiplier <= found.collapse_multiplier
    assert early.collapse_multiplier == pytest.approx(
        found.collapse_multiplier, rel=stopped.settings.bracket_tolerance
    )
    assert stopped.factorizations < carried.factorizations


@pytest.mark.parametrize("corner_transient", [True, False])
def test_the_last_fold_of_s13_2_is_still_passed(corner_transient):
    """S13/2: the explicit check stopped at 0.10819 with rest 1 % above; the implicit check
    passes it (session 18). Neither endgame rule may turn that fold into a peak."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    settings = replace(case.settings, corner_transient=corner_transient)
    hist = StaticSolver(case.model, settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier is not None
    assert hist.collapse_multiplier > 1.01 * 0.10819, hist.reason
    assert hist.collapse_multiplier <= dem_upper_bound(case.model).load_factor


@pytest.mark.parametrize(("field", "value"), [("run_off", "maybe"), ("corner_transient", "yes")])
def test_bad_endgame_settings_are_named(field, value):
    with pytest.raises(ValueError, match=field):
        StaticSettings(**{field: value})
