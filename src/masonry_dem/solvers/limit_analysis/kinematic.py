"""The associative problem with the exact cone, solved in its kinematic form by Clarabel.

Unknowns: the velocities u of the free DOFs (the equilibrium rows' scaling). Constraints: the
live load does unit work, ``(F_live / |F_live|) . u = 1``, and every contact point of every
interface opens at least by mu times its slip, ``(v_n, mu v_t1, mu v_t2)(y) in SOC(3)``, with
the relative velocity at y affine in u (``H`` and the point's lever arms). Objective: the
work of the dead load and of the tensile resistance, ``lambda = -(rhs / |F_live|) . u``.
The statics come back as the cone's duals: point k carries a compression ``|F_live| z0`` and
a friction ``-|F_live| mu (z1, z2)``.

Why this form and not the static one (``backends.solve_clarabel``, still used by the
non-associative iteration): its answer is a mechanism, admissible to Clarabel's primal
tolerance whatever the units, so lambda is a kinematic multiplier (never below the
exact one but by that tolerance), and it is scale-free (the same 23 iterations and lambda to
1e-15 on a ladder wall and on the same wall scaled by 20 or 0.05). The static form stopped
"Solved" at 0.449 and 0.440 on that wall (exact 0.465658) with mechanisms 0.7 and 1.2 % off
admissible, by the units of the loads; it also needs a feasibility solve at lambda = 0 first.
Its KKT system is smaller too (6 per block plus 3 per point, against 3 per point plus 6 per
block plus 4 per point)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy import sparse

from masonry_dem.assembly.compatibility import compatibility_matrix

from .budget import CLARABEL_ITERATIONS, clarabel_room, solver_seconds
from .formulation import Problem, Solution, cohesive_grid, cohesive_points, lambda_cap
from .interface import grid_points


def corner_velocity_rows(
    problem: Problem, grid: int, friction: np.ndarray | None = None
) -> sparse.csc_matrix:
    """(3 m K, n_free) rows ``(v_n, mu v_t1, mu v_t2)`` of the relative velocity at the K grid
    points of every interface, per unit of the scaled free DOFs; built in one call.
    ``friction`` (m,) in place of the model's (ones: the slip itself)."""
    model = problem.model
    its = model.interfaces
    m = its.count
    H = compatibility_matrix(model.blocks, its).tocsr()
    Hs = (H[:, problem.free] @ sparse.diags(problem.row_scale)).tocsr()
    y, _ = grid_points(its.l1, its.l2, grid)
    K = y.shape[1]
    k = np.arange(m * K)
    i = k // K
    y1, y2 = y[:, :, 0].ravel(), y[:, :, 1].ravel()
    mu = (model.friction if friction is None else friction)[i]
    # v_n = d3 + d4 y2 - d5 y1; v_t1 = d1 - d6 y2; v_t2 = d2 + d6 y1 (d = H u, 0-based below)
    rows = np.concatenate([3 * k, 3 * k, 3 * k, 3 * k + 1, 3 * k + 1, 3 * k + 2, 3 * k + 2])
    cols = np.concatenate([6 * i + 2, 6 * i + 3, 6 * i + 4, 6 * i, 6 * i + 5, 6 * i + 1, 6 * i + 5])
    vals = np.concatenate([np.ones(m * K), y2, -y1, mu, -mu * y2, mu, mu * y1])
    C = sparse.csr_matrix((vals, (rows, cols)), shape=(3 * m * K, 6 * m))
    return (C @ Hs).tocsc()


#: Clarabel's settings for the kinematic SOCP: no iterative refinement (every mechanism is
#: checked by ``mechanism_violation`` anyway, and the refinement cost CPU without moving
#: lambda; docs/limit_analysis.md, "Where the time goes")
CLARABEL_OPTIONS: dict[str, Any] = {"iterative_refinement_enable": False}
#: from this many velocities (6 per free block) Clarabel factorizes its KKT system with
#: ``faer`` (supernodal LDL^T, whose supernodes pay once the fronts are large) on one
#: thread, below with ``qdldl`` (same section of docs/limit_analysis.md)
SUPERNODAL_FROM = 10_000


def clarabel_options(velocities: int) -> dict[str, Any]:
    """Clarabel's settings for a kinematic SOCP of ``velocities`` unknowns, within the
    analysis's budget (``budget``)."""
    limits = {"max_iter": CLARABEL_ITERATIONS, "time_limit": solver_seconds()}
    if velocities >= SUPERNODAL_FROM:
        return {**CLARABEL_OPTIONS, **limits, "direct_solve_method": "faer", "max_threads": 1}
    return {**CLARABEL_OPTIONS, **limits, "direct_solve_method": "qdldl"}


def solve_kinematic_clarabel(
    problem: Problem, grid: int, options: Mapping[str, Any] | None = None
) -> tuple[Solution, np.ndarray, int]:
    """min -(rhs/|live|) . u s.t. (live/|live|) . u = 1, corner rows in SOC(3). Returns the
    solution (``x``: per point (c, t1, t2), the layout of ``associative_columns``, then
    with a cohesion of its own the cohesive shears, ``slip_columns``; ``duals``:
    the mechanism u; ``iterations`` and ``setup_seconds``, Clarabel's), and the points per
    interface. ``options`` override ``clarabel_options`` (Clarabel's settings by name)."""
    import clarabel

    G = corner_velocity_rows(problem, grid)
    n_points = G.shape[0] // 3
    n_u = G.shape[1]
    norm = max(float(np.linalg.norm(problem.live)), 1e-300)
    live, rhs = problem.live / norm, problem.rhs / norm
    A = sparse.vstack([sparse.csc_matrix(live.reshape(1, -1)), -G], format="csc")
    q = -rhs
    # a cohesion beyond mu ft: at each of its points (``cohesive_points``, on the cohesion's
    # own grid) an epigraph variable tau_k >= |v_t| (its own SOC) whose dissipation
    # o_k tau_k joins the objective
    slipping, _, offset = cohesive_points(problem.model, grid)
    p = slipping.size
    if p:
        ones = np.ones(problem.model.interfaces.count)
        slip = corner_velocity_rows(problem, cohesive_grid(grid), ones).tocsr()
        rows = np.stack([3 * slipping + 1, 3 * slipping + 2], axis=1).ravel()
        T = slip[rows]  # (2p, n_u): the slip velocities of the cohesive points
        tau = sparse.csc_matrix((-np.ones(p), (3 * np.arange(p), np.arange(p))), shape=(3 * p, p))
        order = np.stack([3 * np.arange(p) + 1, 3 * np.arange(p) + 2], axis=1).ravel()
        place = sparse.csc_matrix((np.ones(2 * p), (order, np.arange(2 * p))), shape=(3 * p, 2 * p))
        A = sparse.bmat(
            [[A, sparse.csc_matrix((A.shape[0], p))], [-(place @ T), tau]], format="csc"
        )
        q = np.concatenate([q, offset / norm])
    A.sort_indices()
    b = np.zeros(A.shape[0])
    b[0] = 1.0
    cones = [clarabel.ZeroConeT(1)] + [clarabel.SecondOrderConeT(3)] * (n_points + p)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    for name, value in {**clarabel_options(n_u), **(options or {})}.items():
        setattr(settings, name, value)
    t0 = time.process_time()
    clarabel_room(A)
    n_x = n_u + p
    out = clarabel.DefaultSolver(sparse.csc_matrix((n_x, n_x)), q, A, b, cones, settings)
    setup = time.process_time() - t0
    sol = out.solve()
    word = str(sol.status)
    K = n_points // max(problem.model.interfaces.count, 1)
    if word in ("MaxIterations", "MaxTime"):  # its budget (``budget``) stopped it
        return Solution("budget", detail=f"Clarabel: {word} (kinematic)"), np.zeros(0), K
    if "PrimalInfeasible" in word:  # no admissible mechanism does work on the live load
        return Solution("unbounded", detail=f"Clarabel: {word} (kinematic)"), np.zeros(0), K
    if "DualInfeasible" in word:  # mechanisms of unbounded negative work: no statics at all
        return Solution("dead load", detail=f"Clarabel: {word} (kinematic)"), np.zeros(0), K
    if word not in ("Solved", "AlmostSolved"):
        return Solution("error", detail=f"Clarabel: {word} (kinematic)"), np.zeros(0), K
    u = np.asarray(sol.x)[:n_u]
    lam = float(q @ np.asarray(sol.x))
    if lam >= lambda_cap(problem.live, problem.rhs) * (1 - 1e-3):
        return Solution("unbounded", detail="Clarabel: lambda reached its cap"), np.zeros(0), K
    if lam < 0:
        detail = f"Clarabel: the weakest mechanism needs lambda = {lam:.4g} < 0"
        return Solution("dead load", detail=detail), np.zeros(0), K
    z = np.asarray(sol.z)[1:].reshape(-1, 3)
    mu = np.repeat(problem.model.friction, K)
    x = np.column_stack(
        [norm * z[:n_points, 0], -norm * mu * z[:n_points, 1], -norm * mu * z[:n_points, 2]]
    ).ravel()
    if p:  # then the cohesive shears (t1, t2), the duals of the slip cones (``slip_columns``)
        x = np.concatenate([x, -norm * z[n_points:, 1:].ravel()])
    detail = f"Clarabel: {word} (kinematic, {sol.iterations} iterations)"
    answer = Solution("optimal", lam, x, u, detail, int(sol.iterations), setup)
    return answer, u, K
