"""Newton's basin on walls that meet (docs/history/solvers_record.md, "Newton's basin on walls
that meet").

Proves: on a 3 x 13 panel with a free edge, the work searches that find no descent stop next
to a kink of the law along their Newton direction (the merit falls up to it and not beyond).
"""

from __future__ import annotations

import numpy as np

from helpers.walls import tilted_panel
from masonry_dem.solvers.incremental import StaticSettings
from masonry_dem.solvers.static.outcome import Failure
from masonry_dem.solvers.static.solver import StaticSolver


def test_a_search_with_no_descent_stops_on_a_kink():
    """Each work search of the panel that fails with "no correction lowers the residual" is
    run again from its state (``benchmarks/newton_basin.py`` takes them apart). At the state
    where it stops, along the controlled Newton direction of its tangent, the merit does
    not fall at the full step, falls at some step of 8^-3 of it or shorter (the linear model
    holds up to there: measured 8^-4 to 8^-10), and, on 18 of the 19 (at least 90 %
    asserted), at the next longer step, where it no longer falls, some joint's flags have
    changed: the search stopped next to a kink of the law that the direction crosses. (On
    the 19th the merit rises at 8^-2 and 8^-3 with no change of state: the curved return
    of a sliding joint.)"""
    model = tilted_panel()
    solver = StaticSolver(model, StaticSettings())
    plain = solver.equilibrate
    failed = []

    def recording(*args, **kw):
        state = (solver.q.copy(), solver.plastic.copy(), solver.cracked.copy())
        out = plain(*args, **kw)
        if kw.get("control") is not None and out.failure == Failure.NO_DESCENT:
            failed.append((out, kw["control"], state))
        return out

    solver.equilibrate = recording  # type: ignore[method-assign]
    assert solver.run().status == "collapse"
    assert len(failed) >= 10
    p = solver.problem
    free = p.asm.free_index
    on_a_kink = 0
    for out, (c, goal, size), (_, plastic, cracked) in failed:
        solver.plastic, solver.cracked = plastic, cracked  # the law state of that search
        q, lam = out.q, float(out.load_factor)
        residual, _, response = solver.residual(q, lam)

        def merit(qq, ll, c=c, goal=goal, size=size):
            return solver.residual(qq, ll)[1] + abs(float(c @ qq[free]) - goal) / size

        lu = p.factor(response)
        dq = lu.solve(residual)
        live = lu.solve(p.F_live)
        dlam = (goal - float(c @ q[free]) - float(c @ dq)) / float(c @ live)
        dq = dq + dlam * live
        start = merit(q, lam)
        falls, flags = [], []
        for k in range(11):
            t = 8.0**-k
            qt = q.copy()
            qt[free] += t * dq
            falls.append(merit(qt, lam + t * dlam) < (1.0 - 1e-4 * t) * start)
            flags.append(
                bool(np.any(solver.residual(qt, lam + t * dlam)[2].flags != response.flags))
            )
        assert not falls[0]
        first = falls.index(True)  # the longest step that lowers the merit
        assert first >= 3
        on_a_kink += flags[first - 1]  # beyond that step a joint has crossed a kink
    assert on_a_kink >= 0.9 * len(failed)
