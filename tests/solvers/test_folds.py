"""The static path at folds: a stop where the tangent is singular along the load is a peak
or a fold of the path, and only a look above it tells them apart.

S13 of Restrepo Velez with 2-block return walls (``build_case("S13",
restraint="return-walls", return_blocks=2)``): work control gets stuck at lambda 0.0855
with the tangent singular along the load (Newton finds no correction that lowers the
residual, the pseudo-transient step finds no rest). By default the dynamic-relaxation check
of the stop is skipped at such a state and 0.0855 is certified as the collapse multiplier,
yet a damped relaxation from that state comes to rest 0.5-1 % higher and Newton polishes it
to the static tolerance (tests/cases/test_return_walls_against_dr.py), with equilibria up
to 0.110 under the associative bound 0.116 (docs/walls_that_meet.md). With the check run
there too (``stop_check_singular``) and a budget that covers the fold's settling (about
50 000 time steps at 1.005 x the stop), the path passes that fold and stops at the next
one, 0.0938 (docs/solvers.md, "The stop check: folds and peaks").
"""

from __future__ import annotations

import pytest

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSettings, StaticSolver


def test_the_stop_check_at_a_singular_tangent_passes_the_first_fold_of_s13_2():
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    settings = StaticSettings(stop_check_singular=True, stop_check_time_steps=60_000)
    solver = StaticSolver(case.model, settings)
    history = solver.run()
    # 2bd1bc8 (and the default): collapse at 0.08551 with no time step of relaxation
    assert history.collapse_multiplier is not None, history.reason
    assert history.collapse_multiplier > 1.05 * 0.08551, history.reason
    assert solver.time_steps > 0  # the fold was passed by the relaxation, not by Newton
    # no more than an equilibrium of the wall can carry (the bound is 0.1164)
    assert history.collapse_multiplier <= dem_upper_bound(case.model).load_factor


def test_by_default_the_first_fold_of_s13_2_is_certified():
    """The trade-off the default makes (fast, and the fold taken for the peak): pinned so
    that a change of the default is seen."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    solver = StaticSolver(case.model)
    history = solver.run()
    assert history.status == "collapse"
    assert history.collapse_multiplier == pytest.approx(0.08551, rel=1e-3)
    assert solver.time_steps == 0
