"""Non-associative (zero dilatancy) limit analysis: the iteration of Gilbert, Casapulla & Ahmed
(2006) on frozen friction capacities."""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
from scipy import sparse

from masonry_dem.model import Model

from .backends import solve_associative, solve_clarabel
from .budget import spent
from .columns import FrozenFriction, Patterns, full_lp, solve_frozen_columns, solve_frozen_full
from .formulation import Problem, Solution, associative_columns
from .interface import ASSOCIATIVE_GRID, grid_points, lobatto_rule, resultant_columns
from .progress import report
from .result import LimitAnalysisResult, finish
from .selection import (
    LAMBDA_SLACK,
    action_weights,
    elastic_state,
    least_energy_frozen,
    nearest_by_columns,
    nearest_optimum,
)

log = logging.getLogger(__name__)

#: the non-associative iteration halves its relaxation each time lambda turns back (and
#: doubles it, up to the given one, after three steps the same way), down to
_SMALLEST_RELAXATION = 1.0 / 64
#: unit shear forces (t1, t2, n) along the interface's two axes
_PLANE_SHEAR = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


# --------------------------------------------------------------------------- non-associative
def frozen_layout(
    model: Model, actions: np.ndarray, grid: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (m, K, 2), frozen compressions (m, K) and cohesive shears (m, K) of the DEM's
    reading of the actions: ``ft - fn`` spread uniformly over the reduced rectangle
    centred on the resultant (Figure 10). With a cohesion of its own, the whole
    rectangle's n x n points follow (K = 2 n^2), with no compression and the shear the
    joint keeps at its tension cap, ``(c - mu ft) A`` by their Lobatto weights: the joint's
    ``mu (ft A - fn) + (c - mu ft) A = c A - mu fn``, the law's (docs/solvers.md: the rest
    of the joint sits at the cap). Without, the cohesive shears are zeros."""
    its = model.interfaces
    ft = model.tensile_strength * its.area
    cap = np.maximum(ft - actions[:, 2], 0.0)
    safe = np.where(cap > 0, cap, 1.0)
    # centre of the compression: m1 = -cap y2c, m2 = cap y1c
    y1c = np.where(cap > 0, actions[:, 4] / safe, 0.0)
    y2c = np.where(cap > 0, -actions[:, 3] / safe, 0.0)
    y1c = np.clip(y1c, -its.l1 / 2, its.l1 / 2)
    y2c = np.clip(y2c, -its.l2 / 2, its.l2 / 2)
    l1r = np.maximum(its.l1 - 2 * np.abs(y1c), 0.0)
    l2r = np.maximum(its.l2 - 2 * np.abs(y2c), 0.0)
    pts, w = grid_points(l1r, l2r, grid, np.stack([y1c, y2c], axis=1))
    area = l1r * l2r
    # a degenerate rectangle (a line or a corner): the Lobatto weights of its sides
    _, wl = lobatto_rule(grid)
    wu = np.outer(wl, wl).ravel() / 4.0
    share = np.where(area[:, None] > 0, w / np.where(area > 0, area, 1.0)[:, None], wu[None, :])
    frozen = cap[:, None] * share
    beyond = model.cohesion_beyond_friction
    if not beyond.any():
        return pts, frozen, np.zeros_like(frozen)
    whole, wa = grid_points(its.l1, its.l2, grid)
    none = np.zeros_like(frozen)
    return (
        np.concatenate([pts, whole], axis=1),
        np.concatenate([frozen, none], axis=1),
        np.concatenate([none, beyond[:, None] * wa], axis=1),
    )


def non_associative(
    problem: Problem,
    grid: int,
    dirs: np.ndarray | None,
    tolerance: float,
    max_iterations: int,
    relaxation: float,
    result,
    column_generation: bool = True,
    nearest: bool = False,
    start: str = "elastic",
) -> LimitAnalysisResult:
    """The iteration on frozen capacities, from ``start`` (``STARTS``). With HiGHS (``dirs``
    the pyramid's edges), each frozen-capacity LP is solved by ``column_generation``
    (``columns``: the same optimum on a master of a few thousand columns, started from
    the previous iteration's patterns) or, False, in full; ``nearest``: then, among its
    optimal force distributions, the one whose normal actions are nearest the frozen ones
    (``selection``), so that the answer does not depend on the order of the columns."""
    model = problem.model
    m = model.interfaces.count
    start_relaxation = relaxation
    first, size = solve_associative(problem, ASSOCIATIVE_GRID, dirs)
    if first.status != "optimal":
        return finish(problem, first, size, result, iterations=1, load_factors=())
    # the associative multiplier bounds every zero-dilatancy one of the same cone from above
    # (Radenkovic's first theorem): the proven side of the estimate
    upper = float(first.lam)
    select_rows, select_weights = action_weights(model.interfaces.l1, model.interfaces.l2)
    selections = selection_rounds = 0
    # a cohesion beyond mu ft: the frozen shear capacities grow by it (``frozen_layout``)
    own_cohesion = bool(model.cohesion_beyond_friction.any())
    # the least-normal-actions start has the associative LP's friction columns only: with a
    # cohesion of its own the start is the associative optimum as the solver gave it
    if nearest and dirs is not None and not own_cohesion:
        # the associative LP is as degenerate: its optimum with the least normal actions
        # (fn, m1, m2 nearest the unloaded state), so that the start is unique too
        R0, _ = associative_columns(model, ASSOCIATIVE_GRID, dirs)
        A0 = (sparse.diags(select_weights) @ R0.tocsr()[select_rows]).tocsr()
        E0 = (problem.H_T @ R0).tocsc()
        least = nearest_optimum(
            E0, problem.live, problem.rhs, None, first.lam, A0, np.zeros(len(select_rows))
        )
        if least.status == "optimal":
            first.info_actions = (problem.a0 + R0 @ least.x).reshape(-1, 6)  # type: ignore[attr-defined]
            selections += 1
    actions = first.info_actions  # type: ignore[attr-defined]
    if start == "elastic":
        rest = elastic_state(problem)
        if rest is None:
            log.debug("no elastic dead-load state: the iteration starts from the associative")
            start = "associative"
        else:
            actions = rest
    # the normal forces at the corners (rocking, tension) stay associative
    corners, _ = grid_points(model.interfaces.l1, model.interfaces.l2, 2)
    iface4 = np.repeat(np.arange(m), 4)
    normal = np.zeros((4 * m, 3))
    normal[:, 2] = -1.0
    R_n = resultant_columns(corners.reshape(-1, 2), normal, iface4, m)
    lams: list[float] = []
    sol = first
    patterns: Patterns | None = None
    rounds = columns = full_lps = 0
    kw: dict = {"info": {"associative": upper, "start": start}}
    for it in range(1, max_iterations + 1):
        if spent():  # the analysis's time budget (``budget``), between two solves
            detail = f"its time ran out after {it - 1} non-associative solves"
            sol = Solution("budget", detail=detail)
            return finish(
                problem, sol, size, result, iterations=it - 1, load_factors=tuple(lams), **kw
            )
        pts, cap, cohesive = frozen_layout(model, actions, grid)
        K = pts.shape[1]
        iface = np.repeat(np.arange(m), K)
        yk = pts.reshape(-1, 2)
        mu = np.repeat(model.friction, K)
        capk = cap.ravel()
        offset = cohesive.ravel() if own_cohesion else None
        if dirs is None:
            shear = np.zeros((m * K, 2, 3))
            shear[:, 0, 0] = 1.0
            shear[:, 1, 1] = 1.0
            R_s = resultant_columns(
                np.repeat(yk, 2, axis=0), shear.reshape(-1, 3), np.repeat(iface, 2), m
            )
            R = sparse.hstack([R_n, R_s], format="csc")
            E = (problem.H_T @ R).tocsc()
            sol = solve_clarabel(
                E, problem.live, problem.rhs, m * K, mu, capk, 4 * m, offset=offset
            )
            if sol.status == "infeasible":
                sol = Solution("dead load", detail=f"{sol.detail} (frozen capacities)")
        else:
            D = dirs.shape[0]
            scale = mu
            if offset is not None:
                # a point with a cohesive shear o: edges e_d (not mu e_d) on the capacity
                # mu cap + o, so that mu = 0 carries o too; the others as they were
                cohesive_point = offset > 0
                scale = np.where(cohesive_point, 1.0, mu)
                capk = np.where(cohesive_point, mu * capk + offset, capk)
            force = np.zeros((m * K, D, 3))
            force[:, :, :2] = scale[:, None, None] * dirs[None, :, :]
            R_s = resultant_columns(
                np.repeat(yk, D, axis=0), force.reshape(-1, 3), np.repeat(iface, D), m
            )
            R = sparse.hstack([R_n, R_s], format="csc")
            friction = FrozenFriction((problem.H_T @ R_s).tocsc(), capk, m, K, D)
            E = (problem.H_T @ R_n).tocsc()
            if column_generation:
                sol, patterns, stats = solve_frozen_columns(
                    E, friction, problem.live, problem.rhs, patterns, sol.duals
                )
                rounds += stats.rounds
                columns = stats.columns
                full_lps += stats.full
                kw["info"].update(pricing_rounds=rounds, patterns=columns, full_lps=full_lps)
            else:
                sol = solve_frozen_full(E, friction, problem.live, problem.rhs)
            if sol.status == "infeasible":
                sol = Solution("dead load", detail=f"{sol.detail} (frozen capacities)")
            elif sol.status == "optimal" and nearest:
                target = select_weights * (actions.ravel() - problem.a0)[select_rows]
                if column_generation:  # the QP by columns too, from this LP's patterns
                    A_n = (sparse.diags(select_weights) @ R_n.tocsr()[select_rows]).tocsr()
                    chosen, more = nearest_by_columns(
                        E, friction, problem.live, problem.rhs, sol.lam, A_n, target, patterns
                    )
                    selection_rounds += more
                else:
                    E_full, C = full_lp(E, friction)
                    A = (sparse.diags(select_weights) @ R.tocsr()[select_rows]).tocsr()
                    chosen = nearest_optimum(
                        E_full, problem.live, problem.rhs, (C, capk), sol.lam, A, target
                    )
                if chosen.status == "optimal":
                    sol.x = chosen.x
                    selections += 1
                else:
                    log.debug("non-associative iteration %d: %s", it, chosen.detail)
                kw["info"]["nearest_optima"] = selections
                kw["info"]["selection_rounds"] = selection_rounds
        if dirs is None:
            size = (E.shape[1] + 1, E.shape[0])
        else:  # the full LP's, whether solved in full or by column generation
            size = (R.shape[1] + 1, E.shape[0] + m * K)
        if sol.status != "optimal":
            return finish(problem, sol, size, result, iterations=it, load_factors=tuple(lams), **kw)
        new = (problem.a0 + R @ sol.x).reshape(-1, 6)
        sol.info_actions = new  # type: ignore[attr-defined]
        lams.append(sol.lam)
        report("non-associative", it, sol.lam, sol.lam)
        if start == "elastic":
            # the next capacities from the optimum elastic joints would take (least
            # complementary energy), not from the solver's, one of many, which may hold a
            # self-stress no load path makes; a shade below lambda, where the frozen
            # capacities hold more than the optimal face. The frozen capacity at the
            # reduced rectangle's corners only (grid 2): the same shear, more torsion, so
            # every LP optimum is among its states, on a sixteenth of the cones
            pts2, cap2, cohesive2 = frozen_layout(model, actions, 2)
            K2 = pts2.shape[1]  # 4, or 8 with the whole rectangle's corners (cohesion)
            shear2 = np.tile(_PLANE_SHEAR, (K2 * m, 1))
            iface2 = np.repeat(np.arange(m), K2)
            R_st = resultant_columns(
                np.repeat(pts2.reshape(-1, 2), 2, axis=0), shear2, np.repeat(iface2, 2), m
            )
            # with the pyramid, the circle through its edges holds every LP optimum
            rho = 1.0 if dirs is None else float(np.hypot(*dirs[0]))
            radius = rho * np.repeat(model.friction, K2) * cap2.ravel()
            if own_cohesion:
                radius = radius + rho * cohesive2.ravel()
            state = least_energy_frozen(problem, R_n, R_st, radius, sol.lam * (1 - LAMBDA_SLACK))
            if state is not None:
                new = state
        # the LPs are degenerate: the actions may jump between equivalent vertices while
        # lambda settles, so the test is on lambda (its last three values)
        last = lams[-3:]
        settled = len(last) == 3 and max(last) - min(last) <= tolerance * max(abs(last[-1]), 1e-12)
        log.debug("non-associative iteration %d: lambda = %.6g", it, sol.lam)
        if settled:
            note = proven(sol.lam, upper)
            if sol.lam > upper:  # a state no Coulomb joint carries: the proven side instead
                note = (
                    f"the iteration settled at {sol.lam:.6g}, above the associative multiplier, "
                    "which bounds every zero-dilatancy one of the same cone (Radenkovic): "
                    "lambda is that bound, a heuristic estimate"
                )
                sol.lam = upper
            out = finish(problem, sol, size, result, iterations=it, load_factors=tuple(lams), **kw)
            return replace(out, reason=f"{out.reason}; {note}")
        if len(lams) > 2 and (lams[-1] - lams[-2]) * (lams[-2] - lams[-3]) < 0:
            relaxation = max(relaxation / 2, _SMALLEST_RELAXATION)  # it oscillates: damp it
        elif len(lams) > 3 and np.all(np.diff(lams[-4:]) * (lams[-1] - lams[-2]) > 0):
            # three steps the same way: the damping outlived the oscillation, and a small
            # relaxation creeps towards the fixed point by a few per mille a solve
            relaxation = min(2 * relaxation, start_relaxation)
        actions = actions + relaxation * (new - actions)
    tail = ", ".join(f"{x:.5g}" for x in lams[-4:])
    return result(
        "failed",
        float("nan"),
        f"the non-associative iteration did not settle in {max_iterations} solves "
        f"(last lambdas {tail})",
        iterations=max_iterations,
        load_factors=tuple(lams),
        variables=size[0],
        constraints=size[1],
        **kw,
    )


def proven(lam: float, upper: float) -> str:
    """What is proven of a non-associative multiplier, in one clause of the reason."""
    return (
        "a heuristic estimate (no theorem bounds the zero-dilatancy multiplier from below, "
        f"and the iteration is not proved to converge): the associative {upper:.6g} bounds "
        f"it from above (Radenkovic), {upper / lam - 1:+.1%} from this"
    )
