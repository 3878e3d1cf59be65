"""The Restrepo Velez walls with 2-block return walls, where dynamic relaxation and the static
solver disagreed (docs/history/walls_that_meet_record.md, "The 2-block rows against dynamic relaxation").

* S11 with 2-block returns: dynamic relaxation (tolerance 1e-3) ended at lambda 0.005, its
  first load step, though the static path holds equilibria (residual 1e-8) up to 0.078. The
  step had stalled over 5 x the time steps of the dead load's relaxation; the wall's lateral
  response is a slower mode than its settling (the first live steps converge in 1 300-3 000
  time steps against 177), so that stall proved no mechanism. A failure judged by a stall
  window that a later converged step outgrows is now tried again.
* S13 with 2-block returns, where the static path certifies a fold of its path as the
  collapse: tests/cases/test_peaks_not_folds.py.
"""

from __future__ import annotations

import pytest

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation


def test_dynamic_relaxation_passes_a_stall_judged_against_the_dead_load():
    case = build_case("S11", restraint="return-walls", return_blocks=2)
    dr = DynamicRelaxation(case.model, DRSettings(tolerance=1e-3, max_load_factor=0.01))
    history = dr.run()
    # before: "collapse" at 0.00498, its first step to 0.005 stalled over 885 time steps
    assert history.status == "completed", history.reason
    assert history.steps[-1].load_factor == pytest.approx(0.01)
    dead, first = history.steps[0].iterations, history.steps[1].iterations
    assert first > 5 * dead  # the first live step is slower than the dead load's window
