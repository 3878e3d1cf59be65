"""The corrector's line search: a trial step of a Newton search is taken when it lowers the
weighted residual norm plus the control's error.

Proves: each work-control search of a panel that failed fails again when run from the state
recorded before it, with the same trust radius (a replay of a
search is faithful).
"""

from __future__ import annotations

from helpers.walls import tilted_panel
from masonry_dem.model import Model
from masonry_dem.solvers.incremental import StaticSettings
from masonry_dem.solvers.static.solver import StaticSolver


def _failed_work_searches(model: Model) -> tuple[StaticSolver, list]:
    """The pushover, and each of its work-control searches that failed: (arguments, the
    solver's state before it)."""
    failed = []
    solver = StaticSolver(model, StaticSettings())
    plain = solver.equilibrate

    def recording(*args, **kw):
        state = (solver.q.copy(), solver.plastic.copy(), solver.cracked.copy())
        before = solver.last_increment
        out = plain(*args, **kw)
        if kw.get("control") is not None and not out.ok:
            failed.append((args, kw, state, before))
        return out

    solver.equilibrate = recording  # type: ignore[method-assign]
    assert solver.run().status == "collapse"
    return solver, failed


def _replay(model: Model, failed: list) -> list[bool]:
    """Each recorded search again, from its recorded state."""
    solver = StaticSolver(model, StaticSettings())
    assert solver.run().status == "collapse"  # the scales and limits of the path
    converged = []
    for args, kw, (q, plastic, cracked), before in failed:
        solver.q, solver.plastic, solver.cracked = q.copy(), plastic.copy(), cracked.copy()
        solver.last_increment = before
        converged.append(solver.equilibrate(*args, **kw).ok)
    return converged


def test_a_failed_work_search_fails_again_when_replayed():
    """Work control asks for a step of w; 17 of the panel's controlled searches fail (the
    steps folds and the stop check ask for included; measured). Replayed from the same
    states, with the same trust radius, every one fails again."""
    model = tilted_panel()
    _, failed = _failed_work_searches(model)
    assert len(failed) >= 10
    assert not any(_replay(model, failed))
