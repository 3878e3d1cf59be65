"""Displacement control, the path follower that drives one DOF to a target with lambda
free (``StaticSolver.run(control=...)``): its steps, its damped motions past folds of the
controlled path with the controlled displacement held (a testing machine's: Kelley & Keyes
1998, pseudo-transient continuation), and why it stops where the controlled DOF has a limit
point
(docs/solvers.md, "Displacement control"; the measurements: docs/history/solvers_record.md,
"Invariance", its paragraph "Load against displacement control"). It shares the step rule
(:class:`StepController`) and the trust radius of a controlled step
(:func:`~masonry_dem.solvers.static.paths.control_radius`) with the other followers.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

import numpy as np

from masonry_dem.results import History
from masonry_dem.solvers.static.outcome import Status, StopReason
from masonry_dem.solvers.static.paths import Record, control_radius
from masonry_dem.solvers.static.settings import DisplacementControl
from masonry_dem.solvers.static.steps import StepController

if TYPE_CHECKING:
    from masonry_dem.solvers.static.path_solver import PathSolver

log = logging.getLogger(__name__)

#: halvings of a controlled step in a row after which the path is taken to fold there (a
#: second halving that fails too: halved steps close in on a fold, a step merely too long
#: passes after one)
FOLD_CUTS = 2
#: displacement control is stuck after this many halvings of its step in a row
MAX_CONTROL_CUTS = 12

#: d u / d lambda of a controlled DOF below this fraction of its rate on the first live-load
#: step (or negative) at the state where displacement control is stuck: a limit point of the
#: controlled DOF (docs/history/solvers_record.md, "Invariance", its paragraph "Load against
#: displacement control")
TURN_RATE = 0.1


def control_rate(solver: PathSolver, c: np.ndarray) -> float:
    """d(c.q)/d lambda along the tangent of the last converged state: c.K_t^-1 F_L, how fast
    the controlled displacement grows with the load there."""
    _, _, response = solver.residual(solver.q, solver.load_factor)
    return float(c @ solver.problem.factor(response).solve(solver.problem.F_live))


def _control_turn(solver: PathSolver, hist: History, c: np.ndarray) -> str:
    """Why displacement control cannot go on: the controlled displacement's rate of growth
    with the load at the last state, against the first live-load step's (a limit point of
    the controlled DOF, where it stops growing or turns back while the load still rises,
    cannot be passed by prescribing that DOF)."""
    free = solver.problem.asm.free_index
    rate = control_rate(solver, c)
    first = 0.0
    if len(hist.steps) > 1:
        du = float(c @ (hist.steps[1].q.reshape(-1)[free] - hist.steps[0].q.reshape(-1)[free]))
        dlam = float(hist.steps[1].load_factor - hist.steps[0].load_factor)
        first = du / dlam if dlam != 0 else 0.0
    relative = rate / first if first != 0 else math.nan
    if math.isfinite(relative) and relative < TURN_RATE:
        return (
            f"the controlled displacement grows with the load at {relative:.2g} of its rate on "
            f"the first step (d u / d lambda {rate:.3g}): a limit point of the controlled DOF "
            f"(it stops growing or turns back while lambda can still rise), which prescribing "
            f"that DOF cannot pass; load or work control follows the path on"
        )
    return (
        f"the controlled displacement still grows with the load ({relative:.2g} of its rate on "
        f"the first step): no equilibrium with a larger controlled displacement near this state"
    )


def _moved_to(solver: PathSolver, c: np.ndarray, goal: float) -> np.ndarray:
    """Where the held motion past a fold starts: the last converged state moved along the
    tangent response to the live load (K_t^-1 F_L) until c.q reaches ``goal``, the whole wall
    moving with the controlled DOF as its equilibrium would. Moving the controlled DOF alone
    strains the joints beside it only, and a brittle joint there may crack for it; where the
    controlled DOF does not grow with the load (a limit point of its own) it moves alone,
    the time steps then spreading it."""
    free = solver.problem.asm.free_index
    _, _, response = solver.residual(solver.q, solver.load_factor)
    rate = solver.problem.factor(response).solve(solver.problem.F_live)
    du = goal - float(c @ solver.q[free])
    q = solver.q.copy()
    along = float(c @ rate)
    if along > 0 and np.all(np.isfinite(rate)):
        q[free] += du / along * rate
    else:
        q[free] += du / float(c @ c) * c
    return q


def displacement_control(
    solver: PathSolver, hist: History, record: Record, control: DisplacementControl, dof: int
) -> None:
    s = solver.settings
    position = np.flatnonzero(solver.problem.asm.free_index == dof)
    if position.size == 0:
        raise ValueError(f"control dof {control.dof} of block {control.block} is fixed")
    k = int(position[0])
    if control.steps < 1:
        raise ValueError(f"control steps must be at least 1, got {control.steps!r}")
    unit = np.zeros(solver.problem.asm.n_free)
    unit[k] = 1.0
    du_nominal = control.target / control.steps
    direction = float(np.sign(du_nominal))
    step = StepController(abs(du_nominal), s.growth, cap=abs(du_nominal))
    lam = 0.0
    u = float(solver.q[dof])
    moved_from = -1  # the step from which the last damped motion started
    turned = []  # (lambda before, lambda after) of the damped motions past folds

    def reached() -> bool:
        return abs(u - control.target) <= 1e-12 * abs(control.target)

    while not reached() and len(hist.steps) < s.max_steps:
        goal = u + step.size * direction
        if (goal - control.target) * np.sign(du_nominal) > 0:
            goal = control.target
        out = solver.equilibrate(
            lam,
            control=(unit, goal, abs(goal - u)),
            radius=control_radius(solver, unit, goal - u),
        )
        if out.ok:
            record(out)
            lam, u = out.load_factor, goal
            step.grow(out.iterations)
            step.cuts = 0
        else:
            step.cut()
            if step.cuts == FOLD_CUTS and moved_from != len(hist.steps):
                # the controlled path folds (a joint that cracks, starts to slide or rock
                # and sheds load): halved steps only close in on the fold. A test under
                # displacement control passes it as its machine does: the displacement moved
                # to the step's goal and held there while the wall moves, damped, to rest,
                # the load the reaction (pseudo-transient continuation of the controlled
                # equilibrium: Kelley & Keyes 1998; the viscous stabilisation of a
                # displacement-controlled step). A damped motion under a load held above
                # the fold's instead ratchets the load up by that rise at every fold
                # (docs/history/solvers_record.md, "Issue 41: displacement control on
                # shear walls")
                moved_from = len(hist.steps)
                moved = solver.damped_motion(lam, held=(unit, _moved_to(solver, unit, goal)))
                log.debug(
                    "displacement control stuck at u=%.6g, lambda=%.6g; damped motion held "
                    "at u=%.6g: %s",
                    u,
                    lam,
                    goal,
                    f"at rest at lambda {moved.load_factor:.6g}" if moved.ok else moved.reason,
                )
                if moved.ok:
                    record(moved)
                    before = lam
                    lam, u = float(moved.load_factor), float(moved.q[dof])
                    turned.append((before, lam))
                    step.size = max(step.size, abs(du_nominal))
                    step.cuts = 0
                    continue
            if step.cuts > MAX_CONTROL_CUTS:
                hist.end(
                    Status.FAILED,
                    StopReason.CONTROL_STUCK,
                    f"displacement control stuck at {u:.4g} (lambda {lam:.6g}): {out.reason}; "
                    + _control_turn(solver, hist, unit),
                )
                break
    else:
        # the loop ends on its condition: the target reached, or the step budget spent
        if reached():
            hist.end(
                Status.COMPLETED,
                StopReason.CONTROL_REACHED,
                f"control displacement reached {u:.6g}",
            )
        else:
            hist.end(
                Status.FAILED,
                StopReason.CONTROL_BUDGET,
                f"max_steps={s.max_steps} spent at {u:.6g} of the target "
                f"{control.target:.6g} ({u / control.target:.1%})",
            )
    if turned:
        drops = [t for t in turned if t[1] < t[0]]
        hist.reason += (
            f"; {len(turned)} damped motion(s) past folds of the controlled path, the "
            f"controlled displacement held (first at lambda {turned[0][0]:.6g})"
        )
        if drops:
            worst = min(drops, key=lambda t: t[1] - t[0])
            hist.reason += (
                f", {len(drops)} of them shedding load (the largest drop: lambda "
                f"{worst[0]:.6g} -> {worst[1]:.6g})"
            )
    lams = hist.load_factors
    peak = int(np.argmax(lams))
    hist.collapse_bracket = (float(lams[peak]), float(lams[peak]))
