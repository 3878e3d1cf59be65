"""The static path at folds: a stop where the tangent is singular along the load is a peak
or a fold of the path, and only a look above it tells them apart.

S13 of Restrepo Velez with 2-block return walls (``build_case("S13",
restraint="return-walls", return_blocks=2)``): work control gets stuck at lambda 0.0855
(Newton finds no correction that lowers the residual in any direction forward, the
pseudo-transient step finds no rest) while its curve still rises at 0.17 of its elastic
slope: a corner, where the branch the path followed ends. The tangent there, taken past the
kink, is singular along the load, so on 6305d5c the dynamic-relaxation check of the stop
was skipped and 0.0855 was certified as the collapse multiplier, yet a damped relaxation
from that state comes to rest 0.5-1 % higher and Newton polishes it to the static tolerance
(tests/cases/test_return_walls_against_dr.py), with equilibria up to 0.110 under the
associative bound 0.116 (docs/walls_that_meet.md). With ``fold_check_time_steps`` a stop
at a corner is checked whatever its tangent; with Newton tried from the relaxation's states
on the way (``fold_probe_every``) the check passes a fold in 500-14 000 time steps where the
relaxation alone needed 50 000 or more, so it is on by default (20 000 since the creep of a
snap-through is kept undamped, ``fold_creep_cos``; 30 000 before) and the path passes
the folds of S13/2 up to 0.108 (docs/history/solvers_record.md, "A corner is checked").
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.dynamic_relaxation.integrator import _converged_creep
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSettings, StaticSolver
from masonry_dem.solvers.static.certificate import (
    curve_slope,
    moved_from_dead_load,
    still_rising,
)
from masonry_dem.solvers.static.outcome import StopReason


def test_without_the_corner_check_the_first_fold_of_s13_2_is_certified():
    """The trade-off of ``fold_check_time_steps = 0`` (fast, and the fold taken for the
    peak), as on d01d26a: pinned, and the certificate says where the path stopped: at a
    corner, still rising at 0.17 of its elastic slope, unchecked."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    solver = StaticSolver(
        case.model, replace(case.settings, fold_check_time_steps=0, transient_reach=0.0)
    )
    history = solver.run()
    assert history.status == "collapse"
    assert history.collapse_multiplier == pytest.approx(0.08551, rel=1e-3)
    assert solver.time_steps == 0
    cert = history.certificate
    assert cert.corner and cert.curve_slope == pytest.approx(0.17, abs=0.02)
    assert "not checked (fold_check_time_steps = 0)" in cert.reason


def test_fold_check_time_steps_must_be_a_count():
    with pytest.raises(ValueError, match="fold_check_time_steps"):
        StaticSettings(fold_check_time_steps=-1)


@pytest.mark.parametrize(
    ("path_w", "path_lam", "slope", "rising"),
    [
        # elastic slope 2: a last step at d lambda / d w = 1 is half of it, rising
        ([0.0, 1.0, 2.0], [0.0, 2.0, 3.0], 0.5, True),
        # flat to 1e-4 of the elastic slope (flat_slope 1e-3): not rising
        ([0.0, 1.0, 2.0], [0.0, 2.0, 2.0002], 1e-4, False),
        # falling past the peak: negative slope
        ([0.0, 1.0, 2.0], [0.0, 2.0, 1.0], -0.5, False),
        # turned back in w while gaining load (a snap-back): still rising
        ([0.0, 1.0, 0.9], [0.0, 2.0, 2.1], math.inf, True),
        # back in w while losing load: d lambda / d w > 0, yet the curve did not rise
        ([0.0, 1.0, 0.9], [0.0, 2.0, 1.9], -math.inf, False),
        # no move at all
        ([0.0, 1.0, 1.0], [0.0, 2.0, 2.0], -math.inf, False),
        # one state: no step
        ([0.0], [0.0], math.nan, False),
    ],
    ids=["rising", "flat", "falling", "snap-back", "back-and-down", "still", "one-state"],
)
def test_one_measure_of_a_corner_serves_the_stop_check_and_the_certificate(
    path_w, path_lam, slope, rising
):
    """``certificate.curve_slope`` on hand-made curves (elastic slope 2): the d lambda / d w
    of the last step over the elastic slope. Work control's stop check and the certificate
    both call it (before, the path counted a step that turned back in w while gaining load
    as rising and the certificate did not: its slope came out negative)."""
    value = curve_slope(path_w, path_lam, 2.0)
    if math.isnan(slope):
        assert math.isnan(value)
    else:
        assert value == pytest.approx(slope, rel=1e-9)
    assert still_rising(value, StaticSettings().flat_slope) is rising
    assert math.isnan(curve_slope([0.0, 1.0], [0.0, 1.0], 0.0))  # no elastic slope


@pytest.mark.slow
def test_a_search_that_runs_off_at_a_rising_corner_is_measured_once_and_checked():
    """S6 with 2-block return walls. Without the corner check and with the pseudo-transient
    step's rise of 0.5 % only (``transient_reach=0``, as on d01d26a) the path stops
    at lambda 0.0455, where the searches from the last state run past the displacement limit
    (14.1 mm, half the smallest moving block) while the curve still rose into it at 0.8 of
    its elastic slope. The stop reason then gave the limit as if a mechanism had formed,
    and the certificate measured 0.68 mm: two measures of one limit. Now both measure the
    state from the dead-load state (elastic displacement under the dead load never
    counts) and say the same: no state left the range, only the searches ran past it. By
    default such a stop is a corner too, and the check passes it: the path goes on to a
    certified collapse at 0.108, under the associative bound 0.1133."""
    case = build_case("S6", restraint="return-walls", return_blocks=2)
    solver = StaticSolver(
        case.model, replace(case.settings, fold_check_time_steps=0, transient_reach=0.0)
    )
    hist = solver.run(monitor=case.monitor)
    assert hist.status == "failed" and hist.stop is StopReason.DISPLACEMENT_LIMIT
    moved = moved_from_dead_load(solver.problem, hist, solver.q)
    assert moved < solver.limit  # the state is inside the range
    path_reason = hist.reason.split("; not a certified collapse: ")[0]
    assert f"({moved:.3g} m from the dead-load state)" in path_reason
    assert f"limit {solver.limit:.3g} m" in path_reason
    assert f"is {moved:.3g} m from the dead-load state (limit {solver.limit:.3g} m" in (
        hist.certificate.reason
    )
    assert "no state left the small-displacement range" in hist.certificate.reason
    checked = StaticSolver(case.model, case.settings)
    hist = checked.run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert 2.0 * 0.0455 < hist.collapse_multiplier <= dem_upper_bound(case.model).load_factor
    assert checked.implicit_steps > 0


def test_a_creep_is_kept_only_where_its_direction_has_converged():
    """``_converged_creep``: the direction of the creep, unit in the mass norm, where it
    points the way the one before did (mass-weighted cosine above the threshold); None
    for the first window, a turn, a reversal or no motion."""
    mass = np.array([4.0, 1.0, 9.0])
    creep = np.array([1.0, 2.0, 0.0])
    kept = _converged_creep(creep, 0.5 * creep, mass, 0.95)
    assert kept is not None
    assert float(kept @ (mass * kept)) == pytest.approx(1.0)
    assert np.allclose(kept, creep / math.sqrt(8.0))
    assert _converged_creep(creep, None, mass, 0.95) is None
    assert _converged_creep(creep, -creep, mass, 0.95) is None
    # orthogonal in the mass norm (4 * 1 * 1 - 1 * 2 * 2 = 0): a turn
    assert _converged_creep(creep, np.array([1.0, -2.0, 0.0]), mass, 0.95) is None
    assert _converged_creep(np.zeros(3), creep, mass, 0.95) is None
