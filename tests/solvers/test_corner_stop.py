"""Where a stuck path is at a corner (docs/history/solvers_record.md, "S23's stop").

Work control, stuck at a kink of the law, asks whether the curve still rose into its last
state: then the path is at a corner (a fold or a peak) and the implicit check relaxes a
little above it; otherwise, with a tangent singular along the load, the state is taken as
the peak. The rise is the secant of the last three steps, the span over which work control
calls a curve flat. The last halved step alone, as short as the control can tell, may lose
a trace of load (S23: 5e-7 of lambda over 1.9e-6 m) while the curve still rose into the
fold at 1e-2 of the elastic slope; read on that one step the fold at 0.11136 was a peak,
1.1 % below the step-converged path (0.11260, growth 1.025 and steps bounded to 1.25e-4 of
lambda, in that section).

Proves:

- the closed forms are unchanged: a block on a base tilts at s/a, a free-standing wall at
  t/H, within 1e-6;
- S23 passes its fold at 0.11136 and stops within 0.1 % of the step-converged 0.11260,
  a certified collapse.
"""

from __future__ import annotations

import pytest

from helpers.walls import TILTED, assert_closed_form
from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.static import StaticSolver

# S23's collapse multiplier on its finest path (growth 1.025, tail_resolution 1.25e-4,
# collapse_at "onset"; docs/history/solvers_record.md, "The step near the peak")
S23_FINEST = 0.11260


@TILTED
def test_the_closed_forms_stand(build):
    assert_closed_form(build)


@pytest.mark.slow
def test_s23_passes_the_fold_a_halved_step_dipped_at():
    case = build_case("S23")
    hist = StaticSolver(case.model, case.settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert hist.certificate is not None and hist.certificate.holds
    assert hist.collapse_multiplier == pytest.approx(S23_FINEST, rel=1e-3)
    # a path on which the fold at 0.11136 was passed, not called a peak
    assert max(st.load_factor for st in hist.steps) > 1.005 * 0.1113649
