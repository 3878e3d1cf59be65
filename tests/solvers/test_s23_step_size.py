"""S23's collapse multiplier and the step size of its path: the path's own stop does not move
with ``initial_step`` and ``max_step``."""

from __future__ import annotations

from dataclasses import replace

import pytest

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.static.solver import StaticSolver


@pytest.mark.parametrize("divisor", [1, 2, 4])
def test_s23_does_not_move_with_the_step_size(divisor):
    """S23 (a wall with openings, 253 blocks), its path with ``initial_step`` and
    ``max_step`` divided by 1, 2 and 4: within 1 % of 0.08472, the value the path converges
    to as the steps shrink (0.084719-0.084720 from x1 to x1/8). The corner check is off: it
    is the path's own stop that must not move (with the check, the stop at 0.0847 is a fold
    the check passes, test_certificate)."""
    case = build_case("S23")
    s = case.settings
    settings = replace(
        s,
        initial_step=s.initial_step / divisor,
        max_step=s.max_step / divisor,
        fold_check_time_steps=0,
    )
    hist = StaticSolver(case.model, settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(0.08472, rel=0.01)
