"""lambda of a pressure wall and the length of the work steps (docs/history/solvers_record.md,
"Step convergence of the collapse multiplier" and "The step near the peak").

The paths of every step length coincide at the same w (to 3e-5 on 4-5): what moves with the
steps is where the path stops. On a curve whose slope fades it stops three steps after its
slope fell below ``flat_slope`` and reports the highest lambda, the last, so the load those
steps gain is in the answer. Unbounded, an easy step is about x = growth - 1 times the
distance travelled, and the answer rises with x: 4-5 gives 9 208 (1.5), 9 172 (1.05),
9 166 (1.025) against 9 149 for the finest path. Bounded by ``tail_resolution`` (the
default), a step at the stop's slope gains at most that fraction of lambda, whatever x.
"""

from __future__ import annotations

from dataclasses import replace

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.static import StaticSolver


def _lambda(case, growth: float, **changes) -> float:
    settings = replace(case.settings, growth=growth, **changes)
    hist = StaticSolver(case.model, settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    return float(hist.collapse_multiplier)


def test_unbounded_steps_carry_their_gain_into_lambda() -> None:
    """Without the bound, halving x from 0.05 to 0.025 moves lambda by under 0.1 % (measured
    0.065 %), while x = 0.5 is above both by 0.2-0.8 % (measured 0.45 %): always above, the
    flat steps gain load."""
    case = build_case("4-5")
    coarse, fine, finer = (_lambda(case, g, tail_resolution=0.0) for g in (1.5, 1.05, 1.025))
    assert abs(fine / finer - 1) < 1e-3
    assert 2e-3 < coarse / finer - 1 < 8e-3


def test_the_default_bound_takes_the_step_out_of_lambda() -> None:
    """With the default ``tail_resolution`` the default growth (1.5) and 1.025 agree within
    0.1 % (measured 9 172.1 and 9 166.1), and both lie above the finest path (9 149.1) by
    less than the three flat steps' bound, 3 x 1e-3."""
    case = build_case("4-5")
    coarse, finer = (_lambda(case, g) for g in (1.5, 1.025))
    assert abs(coarse / finer - 1) < 1e-3
    assert 0 < coarse / 9149.1 - 1 < 3e-3
