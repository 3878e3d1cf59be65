"""Both relaxations side by side (``corner_check = "race"``; docs/solvers.md, "Both
relaxations side by side (session 20)").

At a corner the implicit check (:meth:`Relaxations.implicit_motion`, one factorization a
step) runs beside dynamic relaxation, an implicit step for each ``fold_check_time_steps`` /
``corner_check_steps`` time steps, advanced from the relaxation's probes; the first verdict
decides: either at rest is a fold, the implicit motion past the displacement limit a peak.

Proves:

- the closed forms are found with ``"race"``: a block on a base tilts at s/a, a
  free-standing wall at t/H, within 1e-6;
- a peak is still a peak: from the block's collapse state the race to 1.005 x s/a finds no
  rest (the falling block's dynamic relaxation runs past the displacement limit before
  the implicit motion is asked), to 0.98 x s/a it finds an equilibrium within the
  tolerance; the S5 U wall, its
  check asked (``run_off = "ignore"``), collapses at the default's multiplier to 1e-9 and
  pays time steps for its run-off, at most one probe window beyond the budgets' rate;
- S13 with 2-block return walls passes its last fold (above 1.01 x 0.10819) at the
  default's collapse multiplier to 1e-9, with fewer implicit steps;
- with ``corner_race_window = "effort"`` (its relaxation stalled against the implicit
  motion's effort so far) S13/2 collapses at ``"mixed"``'s multiplier to 1e-9 with fewer
  time steps and factorizations and no more implicit steps, and S23 (whose rests the
  first probe's Newton finds) at ``"mixed"``'s multiplier to 1e-9.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from helpers.walls import TILTED, assert_closed_form, tilted_block
from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.static import StaticSettings, StaticSolver

RACE = StaticSettings(corner_check="race")


@TILTED
def test_the_race_finds_the_closed_forms(build):
    assert_closed_form(build, RACE)


def test_the_race_tells_the_block_s_peak_from_rest_below_it():
    model, closed_form = tilted_block()
    solver = StaticSolver(model, RACE)
    solver.run()
    start = (solver.q.copy(), solver.cracked.copy())
    s = solver.settings
    rate = s.fold_check_time_steps / s.corner_check_steps
    solver.time_steps = solver.implicit_steps = 0
    solver.restore(*start)
    above = solver.race(
        (1.0 + s.transient_rise) * closed_form, closed_form, s.fold_check_time_steps
    )
    assert above is None
    # the falling block's kinetic energy never peaks, so no probe asks the implicit motion:
    # dynamic relaxation's own run-off decides
    assert solver.implicit_steps * rate <= solver.time_steps
    solver.restore(*start)
    below = solver.race(0.98 * closed_form, closed_form, s.fold_check_time_steps)
    assert below is not None and below.ok
    assert solver.residual(below.q, 0.98 * closed_form)[1] <= s.tolerance


def test_the_u_wall_s_peak_is_still_a_peak():
    case = build_case("S5", restraint="return-walls", return_blocks=4)
    settings = replace(case.settings, run_off="ignore")
    runs = {}
    for check in ("mixed", "race"):
        solver = StaticSolver(case.model, replace(settings, corner_check=check))
        runs[check] = (solver, solver.run(monitor=case.monitor))
    (mixed, before), (race, found) = runs["mixed"], runs["race"]
    assert found.status == "collapse", found.reason
    assert found.certificate is not None and found.certificate.corner
    assert found.collapse_multiplier == pytest.approx(before.collapse_multiplier, rel=1e-9)
    assert mixed.time_steps == 0 < race.time_steps
    s = race.settings
    rate = s.fold_check_time_steps / s.corner_check_steps
    assert race.time_steps <= rate * race.implicit_steps + s.fold_probe_every + rate


def test_the_last_fold_of_s13_2_is_passed_at_the_same_lambda():
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    runs = {}
    for check in ("mixed", "race"):
        solver = StaticSolver(case.model, replace(case.settings, corner_check=check))
        runs[check] = (solver, solver.run(monitor=case.monitor))
    (mixed, before), (race, found) = runs["mixed"], runs["race"]
    assert found.status == "collapse", found.reason
    assert found.collapse_multiplier is not None
    assert found.collapse_multiplier > 1.01 * 0.10819, found.reason
    assert found.collapse_multiplier == pytest.approx(before.collapse_multiplier, rel=1e-9)
    assert 0 < race.implicit_steps < mixed.implicit_steps


@pytest.mark.parametrize("value", [-1, 2.5, "fast"])
def test_a_bad_race_rate_is_named(value):
    with pytest.raises(ValueError, match="corner_race_rate"):
        StaticSettings(corner_race_rate=value)


def test_race_is_a_corner_check():
    with pytest.raises(ValueError, match="corner_check"):
        StaticSettings(corner_check="sprint")


def test_a_relaxation_that_stalls_against_the_effort_leaves_the_fold_to_the_implicit_motion():
    # S13/2's folds: where the implicit motion rests first, its relaxation gives up within
    # the window "bounded" gives it, so the race costs no more than "mixed"
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    runs = {}
    for check, window in (("mixed", "budget"), ("race", "effort")):
        settings = replace(case.settings, corner_check=check, corner_race_window=window)
        solver = StaticSolver(case.model, settings)
        runs[check] = (solver, solver.run(monitor=case.monitor))
    (mixed, before), (race, found) = runs["mixed"], runs["race"]
    assert found.status == "collapse", found.reason
    assert found.collapse_multiplier == pytest.approx(before.collapse_multiplier, rel=1e-9)
    assert race.time_steps < mixed.time_steps
    assert race.factorizations < mixed.factorizations
    assert race.implicit_steps <= mixed.implicit_steps


@pytest.mark.parametrize("value", ["quarter", 4, None])
def test_a_bad_race_window_is_named(value):
    with pytest.raises(ValueError, match="corner_race_window"):
        StaticSettings(corner_race_window=value)


def test_the_probe_is_asked_before_the_stall_is_judged():
    # S23's rests are found by the first probe's Newton, at a state whose residual has not
    # halved: judged stalled first, the race would lose them and S23's higher peak
    case = build_case("S23")
    peaks = {}
    for check, window in (("mixed", "budget"), ("race", "effort")):
        settings = replace(case.settings, corner_check=check, corner_race_window=window)
        peaks[check] = StaticSolver(case.model, settings).run(monitor=case.monitor)
    assert peaks["race"].status == "collapse", peaks["race"].reason
    assert peaks["race"].collapse_multiplier == pytest.approx(
        peaks["mixed"].collapse_multiplier, rel=1e-9
    )
