"""The corrector's line search (``StaticSettings.line_search``): what a trial step of a Newton
search must lower to be taken.

Proves: whatever the merit, a converged state is an exact equilibrium of the law, so each
reaches the closed forms (a block tilting at s / a, a squat block sliding at mu, a free wall
tilting at t / H, all within 1e-6: the plateau of work control is the rigid-block limit,
which the elastic joints do not move); the natural merit of a trial is the size of the
simplified Newton correction, so at the start of a step (t = 0) it is the Newton
correction's own size, and a bad choice is named.
"""

from __future__ import annotations

import pytest

from helpers.walls import tilted, tilted_panel
from masonry_dem.geometry.builders import add_base, running_bond_wall, single_block
from masonry_dem.model import InterfaceMaterial, Model
from masonry_dem.solvers.incremental import StaticSettings, pushover
from masonry_dem.solvers.static.solver import StaticSolver

MERITS = ("residual", "natural")


def _collapse(model: Model, merit: str) -> float:
    h = pushover(model, StaticSettings(line_search=merit))
    assert h.status == "collapse", h.reason
    return h.collapse_multiplier


@pytest.mark.parametrize("merit", MERITS)
def test_a_block_tilts_at_s_over_a_with_every_merit(merit):
    a, s = 0.2, 0.1
    blocks, base = add_base(single_block(a, 0.25, s, 20e3))
    assert _collapse(tilted(blocks, base), merit) == pytest.approx(s / a, rel=1e-6)


@pytest.mark.parametrize("merit", MERITS)
def test_a_squat_block_slides_at_mu_with_every_merit(merit):
    blocks, base = add_base(single_block(0.05, 0.25, 0.2, 20e3))  # s / a = 4 > mu
    material = InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.45)
    assert _collapse(tilted(blocks, base, material), merit) == pytest.approx(0.45, rel=1e-6)


@pytest.mark.parametrize("merit", MERITS)
def test_a_free_wall_tilts_at_t_over_h_with_every_merit(merit):
    a, s, courses = 0.081, 0.07, 9
    blocks, base = add_base(running_bond_wall(4, courses, a, 0.21, s, 20e3))
    lam = _collapse(tilted(blocks, base), merit)
    assert lam == pytest.approx(s / (courses * a), rel=1e-6)


def test_an_unknown_line_search_is_named():
    with pytest.raises(ValueError, match="line_search"):
        StaticSettings(line_search="directional")  # type: ignore[arg-type]


def _failed_work_searches(model: Model) -> tuple[StaticSolver, list]:
    """The pushover with the residual merit, and each of its work-control searches that
    failed: (arguments, the solver's state before it)."""
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


def _replay(model: Model, merit: str, failed: list) -> list[bool]:
    """Each recorded search again, from its recorded state, with ``merit``."""
    solver = StaticSolver(model, StaticSettings(line_search=merit))
    assert solver.run().status == "collapse"  # the scales and limits of the path
    converged = []
    for args, kw, (q, plastic, cracked), before in failed:
        solver.q, solver.plastic, solver.cracked = q.copy(), plastic.copy(), cracked.copy()
        solver.last_increment = before
        converged.append(solver.equilibrate(*args, **kw).ok)
    return converged


def test_the_natural_merit_converges_work_searches_the_residual_merit_fails():
    """Work control asks for a step of w; with the residual merit 17 of the panel's
    controlled searches fail (the steps folds and the stop check ask for included). From
    the same states, with the same trust radius, the natural merit (the simplified Newton
    correction, which the joints' stiff normal rows do not dominate) converges 3 of them
    (measured; 21 and 5 before the work steps near the stop were bounded, session 20).
    Replayed with the residual merit, every one fails again: the replay is faithful, so the
    difference is the merit's."""
    model = tilted_panel()
    _, failed = _failed_work_searches(model)
    assert len(failed) >= 10
    assert not any(_replay(model, "residual", failed))
    assert sum(_replay(model, "natural", failed)) >= 3


def test_the_natural_merit_at_the_start_is_the_newton_correction():
    """At t = 0 the simplified Newton correction is the Newton correction itself, under load
    control and under control of a displacement (its lambda correction included): the
    trial's merit and the reference it is compared with measure the same thing, so a step
    is taken when the linear model's (1 - t) reduction is approached."""
    model = tilted_panel()
    solver = StaticSolver(model, StaticSettings(line_search="natural"))
    problem = solver.problem
    q = solver.q
    residual, _, response = solver.residual(q, 0.05)
    lu = problem.factor(response)
    dq = lu.solve(residual)
    live = lu.solve(problem.F_live)
    assert solver.natural_norm(lu, residual, q, None, live) == pytest.approx(
        problem.correction_norm(dq), rel=1e-12
    )
    c = problem.F_live / float(problem.F_live @ problem.F_live)  # w, work-conjugate
    control = (c, 1e-4, 1e-4)
    dlam = (control[1] - float(c @ q[problem.free]) - float(c @ dq)) / float(c @ live)
    controlled = dq + dlam * live
    assert abs(float(c @ controlled) - control[1]) < 1e-12 * control[1]
    assert solver.natural_norm(lu, residual, q, control, live) == pytest.approx(
        problem.correction_norm(controlled), rel=1e-12
    )
