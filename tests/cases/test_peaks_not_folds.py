"""A certified collapse is a peak of the wall, not a fold of the path (issue 18, item 2;
docs/history/solvers_record.md, "Peaks and folds: the audit").

The invariant: from the state of a certified collapse at lambda_c (its plastic part and
cracks held), the reference analysis's damped motion at its own, finer time-step tolerance
(:meth:`QuasiStatic.move_to_rest`, the pushover's instability rule run four times more
finely) at 1.01 lambda_c runs past the displacement limit: no rest. A rest above lambda_c
would prove the stop a fold of the path, with the wall's collapse higher up. Each test also
checks that the motion did run (it measures its displacement limit from the state it starts
from, as every search of the path does).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.quasi_static import QuasiStatic
from masonry_dem.solvers.static import StaticSolver

RISE = 0.01


def _certified(case, bound: float | None) -> tuple[StaticSolver, float]:
    """(solver, collapse multiplier)."""
    solver = StaticSolver(case.model, case.settings, bound=bound)
    history = solver.run(monitor=case.monitor)
    assert history.status == "collapse", history.reason
    assert history.certificate is not None and history.certificate.holds
    assert history.collapse_multiplier is not None
    return solver, history.collapse_multiplier


def _relax_above(solver: StaticSolver, peak: float, budget: int) -> tuple[bool, int]:
    """From the last converged state (at or below ``peak``), the reference's damped motion
    at 1 % above the collapse multiplier: (whether it came to rest, its time steps)."""
    reference = QuasiStatic(solver.model, problem=solver.problem)
    reference.settings = replace(reference.settings, max_time_steps=budget)
    reference.start_from(solver.q, solver.plastic, solver.cracked, solver.judge().origin)
    motion = reference.move_to_rest((1.0 + RISE) * peak)
    assert motion.rest or motion.past_limit, motion.reason  # a verdict, either way
    return motion.rest, motion.time_steps


@pytest.mark.slow
def test_a_certified_collapse_of_s15_has_no_equilibrium_1_percent_above_it():
    """S15 (Table 2, columns): certified at 0.273 under its bound 0.547; the motion at
    1.01 x that leaves the small-displacement range (a mechanism forms)."""
    case = build_case("S15")
    bound = dem_upper_bound(case.model).load_factor
    solver, peak = _certified(case, bound)
    start = np.abs(solver.q.reshape(-1, 6)[:, :3]).max()
    assert start < solver.limit  # the relaxation starts inside its displacement limit
    rest, time_steps = _relax_above(solver, peak, budget=20_000)
    assert time_steps > 1  # the motion ran
    assert not rest, "a rest 1 % above a certified collapse: a fold"


def test_a_certified_collapse_of_s12_has_no_equilibrium_1_percent_above_it():
    """S12 (Table 2, columns): certified at 0.1362 in a state 15.0 mm from the unloaded wall,
    past the limit of 14.1 mm measured from there. Measured from the state it starts from,
    the motion at 1.01 x the collapse forms a mechanism (passes half a block)."""
    case = build_case("S12")
    solver, peak = _certified(case, None)
    rest, time_steps = _relax_above(solver, peak, budget=20_000)
    assert time_steps > 1  # the motion ran
    assert not rest, "a rest 1 % above a certified collapse: a fold"


@pytest.mark.slow
def test_a_certified_collapse_of_s13_with_2_block_returns_has_no_equilibrium_above_it():
    """The path folds at 0.0855, 0.0938, 0.0948, 0.1036 and 0.1082 (a wall with return
    walls that settles joint by joint): the collapse lies past them (the highest equilibrium
    dynamic relaxation finds from the unloaded wall is 0.110, the associative bound 0.1164),
    and 1 % above it the reference's motion finds no rest. The bound is left out of the run:
    it holds there, and costs a limit analysis."""
    case = build_case("S13", restraint="return-walls", return_blocks=2)
    solver = StaticSolver(case.model, case.settings)
    history = solver.run(monitor=case.monitor)
    peak = history.collapse_multiplier
    assert history.status == "collapse" and peak is not None, history.reason
    assert peak > 1.01 * 0.10819  # past the fold the explicit check certified
    rest, time_steps = _relax_above(solver, peak, budget=20_000)
    assert time_steps > 1
    assert not rest, f"a rest at {(1 + RISE) * peak:.4f} after {time_steps} time steps"
