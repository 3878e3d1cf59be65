"""The static path at folds: a stop where the tangent is singular along the load is a peak
or a fold of the path, and only a look above it tells them apart.

S13 of Restrepo Velez with 2-block return walls (``build_case("S13",
restraint="return-walls", return_blocks=2)``): work control gets stuck at lambda 0.0855
(Newton finds no correction that lowers the residual in any direction forward) while its
curve still rises at 0.17 of its elastic slope: a corner, where the branch the path followed
ends. The tangent there, taken past the kink, is singular along the load, yet a damped motion
from that state comes to rest 0.5-1 % higher, with equilibria up to 0.110 under the
associative bound 0.116 (docs/walls_that_meet.md). The instability rule (the reference's
damped motion at lambda (1 + bracket)) decides every such stop.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.dynamic_relaxation.integrator import _converged_creep
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSettings, StaticSolver
from masonry_dem.solvers.static.certificate import (
    curve_slope,
    still_rising,
)


def test_the_instability_rule_passes_the_folds_of_s13_2():
    """The path passes the first fold of S13/2 (0.0855) and those after it, and the
    collapse is the rule's (no rest above it), under the associative bound."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    hist = StaticSolver(case.model, case.settings).run()
    assert hist.status == "collapse", hist.reason
    assert 1.2 * 0.08551 < hist.collapse_multiplier <= dem_upper_bound(case.model).load_factor
    assert hist.certificate.instability.startswith("no rest")


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
def test_a_search_that_runs_off_at_a_rising_corner_is_not_the_collapse():
    """S6 with 2-block return walls: the searches from the state at lambda 0.0455 run past
    the displacement limit (14.1 mm, half the smallest moving block) while the curve still
    rose into it at 0.8 of its elastic slope, the state itself inside the range. The
    instability rule finds the wall at rest above that stop and the load goes on to a
    collapse under the associative bound 0.1133."""
    case = build_case("S6", restraint="return-walls", return_blocks=2)
    hist = StaticSolver(case.model, case.settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert 2.0 * 0.0455 < hist.collapse_multiplier <= dem_upper_bound(case.model).load_factor


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
