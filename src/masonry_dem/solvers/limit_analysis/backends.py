"""The solvers of the convex problem: HiGHS (LP, friction pyramid, scipy's ``linprog``) and
Clarabel (SOCP, exact cone). Each returns a :class:`~.formulation.Solution` whose status is a
word, never an exception."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import sparse

from .budget import CLARABEL_ITERATIONS, HIGHS_IPM_ITERATIONS, clarabel_room, solver_seconds
from .formulation import (
    Problem,
    Solution,
    associative_columns,
    cohesive_columns,
    cohesive_grid,
    cohesive_offsets,
    lambda_cap,
    objective_scale,
    slip_columns,
)
from .kinematic import solve_kinematic_clarabel
from .mirror import mirror_dofs, mirror_pairs
from .normal_ipm import NORMAL_EQUATIONS_FROM, solve_kinematic_normal


def solve_highs(
    E: sparse.csc_matrix,
    live: np.ndarray,
    rhs: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    ineq: tuple[sparse.csc_matrix, np.ndarray] | None = None,
    dead_load_first: bool = True,
) -> Solution:
    """max lambda s.t. E x - lambda live = rhs, [C x <= d], lower <= x <= upper, by HiGHS's
    interior point method (scipy's ``linprog``; the simplex methods were 2-8 times slower on
    these degenerate LPs, benchmarks/bench_limit_analysis.py). First with lambda = 0 (is
    there an equilibrium under the dead load?), then free; ``dead_load_first`` False skips
    the first solve (half the time), and an infeasible free solve is then "infeasible"."""
    from scipy.optimize import linprog

    n_eq, k = E.shape
    A = sparse.hstack([E, sparse.csc_matrix(-live.reshape(-1, 1))], format="csc")
    A_ub = b_ub = None
    if ineq is not None:
        C, d = ineq
        A_ub = sparse.hstack([C, sparse.csc_matrix((C.shape[0], 1))], format="csc")
        b_ub = d
    bounds = np.column_stack([np.concatenate([lower, [0.0]]), np.concatenate([upper, [0.0]])])
    c = np.zeros(k + 1)

    def solve():  # within the analysis's budget (``budget``): a time and an iteration limit.
        # No presolve: HiGHS does not check its time limit everywhere in presolve, and a
        # limit that ran out there was ignored (0.05 s: the whole 5.3 s solve on a
        # 331-block wall); presolve changed neither the time nor lambda on 86-331 blocks
        options = {
            "time_limit": solver_seconds(),
            "maxiter": HIGHS_IPM_ITERATIONS,
            "presolve": False,
        }
        return linprog(c, A_ub, b_ub, A, rhs, bounds=bounds, method="highs-ipm", options=options)

    if dead_load_first:
        res = solve()
        if res.status == 2:
            return Solution("dead load", detail=f"HiGHS: {res.message} (at lambda = 0)")
        if res.status != 0:
            return _highs_error(res)
    cap = lambda_cap(live, rhs)
    bounds[k] = (0.0, cap)
    c[k] = -objective_scale(live)
    res = solve()
    if res.status == 2 and not dead_load_first:
        return Solution("infeasible", detail=f"HiGHS: {res.message}")
    if res.status == 3:
        return Solution("unbounded", detail=f"HiGHS: {res.message}")
    if res.status != 0:
        return _highs_error(res)
    x = np.asarray(res.x)
    if x[k] >= cap * (1 - 1e-3):
        return Solution("unbounded", detail=f"HiGHS: lambda reached its cap {cap:.3g}")
    return Solution(
        "optimal", float(x[k]), x[:k], np.asarray(res.eqlin.marginals), "HiGHS: optimal"
    )


#: HiGHS's status codes as words, for the reasons of failed runs
_HIGHS_WORDS = {1: "iteration limit", 2: "infeasible", 3: "unbounded", 4: "numerical difficulties"}


def _highs_error(res: Any) -> Solution:
    """The ``error`` solution of a HiGHS run that ended with status ``res.status``; the
    ``budget`` one where its time or iteration limit stopped it."""
    if res.status == 1:
        return Solution("budget", detail=f"HiGHS: {res.message}")
    if "memory" in str(res.message).lower():  # the machine's, not the wall's
        raise MemoryError(f"HiGHS: {res.message}")
    word = _HIGHS_WORDS.get(res.status, res.status)
    return Solution("error", detail=f"HiGHS: {word}: {res.message}")


#: Clarabel's status words of a solve its time or iteration limit stopped
CLARABEL_BUDGET = ("MaxIterations", "MaxTime")


def solve_clarabel(
    E: sparse.csc_matrix,
    live: np.ndarray,
    rhs: np.ndarray,
    n_points: int,
    mu: np.ndarray,
    capacity: np.ndarray | None,
    n_normal: int = 0,
    fix_lambda: bool = False,
    offset: np.ndarray | None = None,
) -> Solution:
    """max lambda s.t. E x - lambda live = rhs with, per point, x = (c, t1, t2):
    ``|t| <= mu c + o``, ``c >= 0`` (``capacity`` None), or ``|t| <= mu capacity + o`` and
    then ``n_normal`` leading columns of compressions >= 0; ``o`` the points' cohesive
    shear ``offset`` (``formulation.cohesive_offsets``; None: none)."""
    try:
        import clarabel
    except ImportError as exc:  # pragma: no cover - declared dependency
        return Solution("error", detail=f"clarabel is not installed ({exc})")
    n_eq, k = E.shape
    nvar = k + 1
    A_eq = sparse.hstack([E, sparse.csc_matrix(-live.reshape(-1, 1))], format="csc")
    rows = [A_eq]
    b = [rhs]
    cones: list[Any] = [clarabel.ZeroConeT(n_eq)]
    if capacity is None:
        # s = (mu c, t1, t2) in SOC(3): rows -mu e_c, -e_t1, -e_t2
        p = np.arange(n_points)
        r = np.concatenate([3 * p, 3 * p + 1, 3 * p + 2])
        c = np.concatenate([3 * p, 3 * p + 1, 3 * p + 2])
        v = np.concatenate([-mu, -np.ones(n_points), -np.ones(n_points)])
        G = sparse.csc_matrix((v, (r, c)), shape=(3 * n_points, nvar))
        rows.append(sparse.csc_matrix((-np.ones(n_points), (p, 3 * p)), shape=(n_points, nvar)))
        b.append(np.zeros(n_points))
        cones.append(clarabel.NonnegativeConeT(n_points))
        rows.append(G)
        bb = np.zeros(3 * n_points)
        if offset is not None:  # s = (mu c + o, t1, t2)
            bb[3 * p] = offset
        b.append(bb)
        cones += [clarabel.SecondOrderConeT(3)] * n_points
    else:
        # normal compressions >= 0; per shear point s = (mu cap, t1, t2) in SOC(3)
        if n_normal:
            j = np.arange(n_normal)
            rows.append(sparse.csc_matrix((-np.ones(n_normal), (j, j)), shape=(n_normal, nvar)))
            b.append(np.zeros(n_normal))
            cones.append(clarabel.NonnegativeConeT(n_normal))
        p = np.arange(n_points)
        r = np.concatenate([3 * p + 1, 3 * p + 2])
        c = n_normal + np.concatenate([2 * p, 2 * p + 1])
        G = sparse.csc_matrix((-np.ones(2 * n_points), (r, c)), shape=(3 * n_points, nvar))
        bb = np.zeros(3 * n_points)
        bb[3 * p] = mu * capacity if offset is None else mu * capacity + offset
        rows.append(G)
        b.append(bb)
        cones += [clarabel.SecondOrderConeT(3)] * n_points
    cap = lambda_cap(live, rhs)
    if fix_lambda:  # lambda = 0: is there an equilibrium under the dead load alone?
        rows.insert(1, sparse.csc_matrix(([1.0], ([0], [k])), shape=(1, nvar)))
        b.insert(1, np.zeros(1))
        cones[0] = clarabel.ZeroConeT(n_eq + 1)
    else:  # lambda <= cap: a bounded problem (interior point methods detect unboundedness
        # poorly; docs/limit_analysis.md)
        rows.append(sparse.csc_matrix(([1.0], ([0], [k])), shape=(1, nvar)))
        b.append(np.array([cap]))
        cones.append(clarabel.NonnegativeConeT(1))
    A = sparse.vstack(rows, format="csc")
    A.sort_indices()
    q = np.zeros(nvar)
    q[k] = 0.0 if fix_lambda else -objective_scale(live)
    P = sparse.csc_matrix((nvar, nvar))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    # qdldl, not the default faer: the non-associative iteration's walls are small, where
    # faer took 1.23x qdldl's CPU on one thread and 2.7x on two (the kinematic form's 1 041-block
    # ladder wall, docs/limit_analysis.md "Where the time goes")
    settings.direct_solve_method = "qdldl"
    settings.max_iter = CLARABEL_ITERATIONS
    settings.time_limit = solver_seconds()
    clarabel_room(A)
    solver = clarabel.DefaultSolver(P, q, A, np.concatenate(b), cones, settings)
    sol = solver.solve()
    word = str(sol.status)
    if word in CLARABEL_BUDGET:
        return Solution("budget", detail=f"Clarabel: {word}")
    if "DualInfeasible" in word:
        return Solution("unbounded", detail=f"Clarabel: {word}")
    if "PrimalInfeasible" in word:
        return Solution("infeasible", detail=f"Clarabel: {word}")
    if word not in ("Solved", "AlmostSolved"):
        return Solution("error", detail=f"Clarabel: {word}")
    x = np.asarray(sol.x)
    if not fix_lambda and x[k] >= cap * (1 - 1e-3):
        return Solution("unbounded", detail=f"Clarabel: lambda reached its cap {cap:.3g}")
    z = np.asarray(sol.z)[:n_eq]
    return Solution("optimal", float(x[k]), x[:k], -z, f"Clarabel: {word}")


def solve_associative(
    problem: Problem, grid: int, dirs: np.ndarray | None
) -> tuple[Solution, tuple[int, int]]:
    """The associative problem on an n x n grid: HiGHS on the pyramid ``dirs``, or Clarabel on
    the exact cone (``dirs`` None) in its kinematic form (``kinematic``)."""
    model = problem.model
    R, K = associative_columns(model, grid, dirs)
    if dirs is not None:
        ineq = None
        cohesive = cohesive_columns(model, grid, dirs)  # on the cohesion's own grid
        if cohesive is not None:  # the shear a point carries at its tension cap
            R_c, C_c = cohesive
            C = sparse.hstack([sparse.csr_matrix((C_c.shape[0], R.shape[1])), C_c], format="csc")
            R = sparse.hstack([R, R_c], format="csc")
            ineq = (C, np.ones(C.shape[0]))
        E = (problem.H_T @ R).tocsc()
        size = (E.shape[1] + 1, E.shape[0] + (0 if ineq is None else ineq[1].size))
        k = E.shape[1]
        sol = solve_highs(E, problem.live, problem.rhs, np.zeros(k), np.full(k, np.inf), ineq)
    else:  # velocities of the free DOFs; the live work row and 3 cone rows per point
        size = (problem.H_T.shape[0], 1 + R.shape[1])
        sol = _solve_kinematic(problem, grid)
        slip = slip_columns(model, grid)
        if sol.status == "error":
            # the static form holds the cohesion in each point's cone: one grid for both,
            # the cohesion's (``cohesive_grid``)
            g = grid if slip is None else cohesive_grid(grid)
            R, K = associative_columns(model, g, None)
            sol = _static_clarabel(problem, R, K, g, sol.detail)
        elif slip is not None:  # the kinematic form's cohesive shears follow its points'
            R = sparse.hstack([R, slip], format="csc")
    if sol.status == "optimal":
        sol.info_actions = (problem.a0 + R @ sol.x).reshape(-1, 6)  # type: ignore[attr-defined]
    return sol, size


def _solve_kinematic(problem: Problem, grid: int) -> Solution:
    """The kinematic SOCP: on the normal equations (``normal_ipm``, PARDISO) from
    ``NORMAL_EQUATIONS_FROM`` velocities, where it reaches a certified bracket, on the
    mirror-symmetric mechanisms where the model has a mirror plane (``mirror``); by Clarabel
    below, and wherever the normal equations give up (no PARDISO, no mechanism, no
    statics, a stalled iteration)."""
    velocities = problem.H_T.shape[0]
    # the normal equations have one SOC per point, the slip's; a cohesion beyond mu ft adds
    # a second (its dissipation (c - mu ft) A_k |v_t|), which only Clarabel's form carries
    cohesive = bool(problem.model.cohesion_beyond_friction.any())
    if velocities >= NORMAL_EQUATIONS_FROM and not cohesive:
        # a failure on the symmetric mechanisms goes to Clarabel: if the whole problem had
        # a mechanism, its symmetric part would be one too
        drop = mirror_dofs(problem.model)
        # or a plane that swaps blocks in pairs (a wall pushed out of its plane, symmetric
        # about a vertical plane across it): about half the velocities either way
        pairs = mirror_pairs(problem) if drop is None else None
        out = solve_kinematic_normal(problem, grid, drop=drop, pairs=pairs)
        if out is not None:
            return out[0]
    sol, _, _ = solve_kinematic_clarabel(problem, grid)
    return sol


def _static_clarabel(problem: Problem, R, K: int, grid: int, kinematic_detail: str) -> Solution:
    """The static form, when the kinematic one stalls: on walls with no mechanism (an
    infeasible kinematic problem) Clarabel sometimes stops with "InsufficientProgress"
    instead of an infeasibility certificate; the static form is bounded by
    the lambda cap, which it reaches there ("no collapse"). A feasibility solve at
    lambda = 0 first (Clarabel has no warm start)."""
    E = (problem.H_T @ R).tocsc()
    n_points = R.shape[1] // 3
    mu = np.repeat(problem.model.friction, K)
    args = (E, problem.live, problem.rhs, n_points, mu, None)
    offset = cohesive_offsets(problem.model, grid)
    first = solve_clarabel(*args, fix_lambda=True, offset=offset)
    note = f"{kinematic_detail}; static form: "
    if first.status == "infeasible":
        return Solution("dead load", detail=f"{note}{first.detail} at lambda = 0")
    if first.status != "optimal":
        word = "budget" if first.status == "budget" else "error"
        return Solution(word, detail=f"{note}{first.detail} at lambda = 0")
    sol = solve_clarabel(*args, offset=offset)
    sol.detail = note + sol.detail
    if sol.status == "infeasible":  # stood at lambda = 0, so not expected
        sol.status = "error"
    return sol
