"""The reach of a work step (solvers/static/steps.py; docs/history/solvers_record.md, "The reach of
a work step"): the step rule of work control and its first step.

Proves:

- the arithmetic of the rule: it grows the step by ``growth`` after at most
  ``easy_iterations`` and keeps it otherwise, never beyond the cap;
- work control's first step is the last load step's increment of w.
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers.walls import on_base
from masonry_dem.geometry.builders import running_bond_wall
from masonry_dem.solvers.static import StaticSettings
from masonry_dem.solvers.static.steps import StepController


def test_the_easy_rule_grows_after_easy_steps_only_and_keeps_the_cap():
    """The easy rule grows by 1.5 after at most 6 and keeps the step after 7."""
    step = StepController(1.0, 1.5, easy_iterations=6)
    step.grow(6)
    assert step.size == 1.5
    step.grow(7)
    assert step.size == 1.5
    capped = StepController(1.0, 1.5, cap=1.2)
    capped.grow(1)
    assert capped.size == 1.2
    step.cut()
    assert (step.size, step.cuts) == (0.75, 1)


def _first_work_step(settings: StaticSettings) -> tuple[float, float]:
    """(the first step of w work control asks for, the last load step's increment of w) on a
    free-standing 4 x 9 wall, recorded from the searches the path followers ask for."""
    from masonry_dem.solvers.static.solver import StaticSolver

    solver = StaticSolver(
        on_base(running_bond_wall(4, 9, 0.081, 0.21, 0.07, 20e3), kn=2.4e9), settings
    )
    calls: list[tuple[float, object, bool, int]] = []
    accepted: list[tuple[float, np.ndarray]] = []  # (lambda, q) of each recorded state
    plain, accept = solver.equilibrate, solver.accept

    def recording(load_factor, *args, **kwargs):
        out = plain(load_factor, *args, **kwargs)
        calls.append((float(load_factor), kwargs.get("control"), bool(out.ok), len(accepted)))
        return out

    def keeping(out, step, value):
        accepted.append((float(out.load_factor), out.q.reshape(-1).copy()))
        return accept(out, step, value)

    solver.equilibrate = recording  # type: ignore[method-assign]
    solver.accept = keeping  # type: ignore[method-assign]
    hist = solver.run()
    assert hist.status == "collapse", hist.reason
    first = next(i for i, call in enumerate(calls) if call[1] is not None)
    failed = calls[first - 1]
    assert failed[1] is None and not failed[2]  # the load step that failed hands over
    free = solver.problem.asm.free_index
    c = solver.problem.F_live / np.linalg.norm(solver.problem.F_live)
    # the last two states load control recorded before it handed over
    (_, q0), (_, q1) = accepted[calls[first][3] - 2 : calls[first][3]]
    last = float(c @ (q1[free] - q0[free]))
    return calls[first][1][2], last


def test_the_first_work_step_is_the_last_load_step():
    """Exact: work control's first step is the last load step's increment of w."""
    asked, last = _first_work_step(StaticSettings())
    assert asked == pytest.approx(last, rel=1e-9)
