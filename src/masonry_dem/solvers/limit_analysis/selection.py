"""The second stage of a frozen-capacity LP: among its optimal force distributions, the one
whose normal actions are nearest the frozen ones.

Each frozen-capacity LP of the non-associative iteration is degenerate: many force
distributions reach the same lambda, a solver returns one of them (which one depends on the
order of the columns), and the next iteration's capacities are frozen from it. Here lambda
is held at the first stage's optimum (less ``LAMBDA_SLACK``, relative) and the forces
minimise

    sum_i (fn_i - fn0_i)^2 + (2 (m1_i - m10_i) / l2_i)^2 + (2 (m2_i - m20_i) / l1_i)^2

over the optimal face: the normal force and the two rocking moments of every interface
(the only actions the next frozen layout reads, ``frozen_layout``), the moments as the
forces at the rectangle's edge that make them, measured from the actions the capacities
were frozen from. A strictly convex function of the actions over a convex set has one
minimiser, so the actions returned (not the point forces, which stay free where they do not
move them) are unique: the iteration no longer depends on the order of the columns. The
choice is mechanical: at a fixed point of the iteration the distance is zero, so the rule
prefers the optimum that is consistent with its own capacities. Solved by Clarabel (a
convex QP; an interior point method, so the answer is the analytic centre's limit, not a
vertex) on the full LP's variables.
"""

from __future__ import annotations

import logging

import numpy as np
from scipy import sparse

from masonry_dem.model import Model

from .budget import CLARABEL_ITERATIONS, solver_seconds
from .columns import FrozenFriction, Patterns, edge_multipliers, full_lp
from .formulation import Problem, Solution, associative_columns
from .interface import ASSOCIATIVE_GRID, pyramid_edges

log = logging.getLogger(__name__)

#: the second stage holds lambda >= (1 - LAMBDA_SLACK) times the first stage's optimum: the
#: first stage is accurate to 1e-7 relative (column generation's certified gap, HiGHS's
#: interior point), so a smaller slack could make the optimal face empty
LAMBDA_SLACK = 1e-6


def nearest_optimum(
    E: sparse.csc_matrix,
    live: np.ndarray,
    rhs: np.ndarray,
    ineq: tuple[sparse.csc_matrix, np.ndarray] | None,
    lam: float,
    A: sparse.csr_matrix,
    target: np.ndarray,
) -> Solution:
    """min |A x - target|^2 s.t. E x - l live = rhs, C x <= d, x >= 0, l >= (1 -
    LAMBDA_SLACK) lam. ``A`` (r, k) maps the LP's variables to the weighted actions, ``target``
    (r,) the weighted frozen actions. Returns the solution (``lam`` the first stage's) or,
    where Clarabel fails, an "error" solution naming its status."""
    try:
        import clarabel
    except ImportError as exc:  # pragma: no cover - declared dependency
        return Solution("error", detail=f"clarabel is not installed ({exc})")
    n_eq, k = E.shape
    C, d = ineq if ineq is not None else (sparse.csc_matrix((0, k)), np.zeros(0))
    r = A.shape[0]
    # a force scale, so that the objective is of order one: the frozen actions', or the
    # dead load's (the equilibrium rows are forces) where they are all zero
    scale = max(float(np.abs(target).max(initial=0.0)), float(np.abs(rhs).max(initial=0.0)))
    scale = max(scale, 1e-300)
    nvar = k + 1 + r  # x, lambda, the weighted distances
    eye_r = sparse.identity(r, format="csc")
    rows = [
        sparse.hstack(
            [E, sparse.csc_matrix(-live.reshape(-1, 1)), sparse.csc_matrix((n_eq, r))]
        ),  # equilibrium
        sparse.hstack([A / scale, sparse.csc_matrix((r, 1)), -eye_r]),  # the distances
        sparse.hstack([C, sparse.csc_matrix((C.shape[0], 1 + r))]),  # capacities
        sparse.hstack([-sparse.identity(k + 1), sparse.csc_matrix((k + 1, r))]),  # signs, lambda
    ]
    lam_min = (1 - LAMBDA_SLACK) * lam
    b = np.concatenate([rhs, target / scale, d, np.zeros(k), [-lam_min]])
    cones = [
        clarabel.ZeroConeT(n_eq + r),
        clarabel.NonnegativeConeT(C.shape[0] + k + 1),
    ]
    M = sparse.vstack(rows, format="csc")
    M.sort_indices()
    P = sparse.csc_matrix((np.ones(r), (k + 1 + np.arange(r), k + 1 + np.arange(r))), (nvar, nvar))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.direct_solve_method = "qdldl"
    settings.max_iter = CLARABEL_ITERATIONS
    settings.time_limit = solver_seconds()
    out = clarabel.DefaultSolver(P, np.zeros(nvar), M, b, cones, settings).solve()
    word = str(out.status)
    if word not in ("Solved", "AlmostSolved"):
        return Solution("error", detail=f"Clarabel (the nearest optimum): {word}")
    x = np.asarray(out.x)
    return Solution("optimal", lam, np.maximum(x[:k], 0.0), detail=f"Clarabel: {word}")


def action_weights(l1: np.ndarray, l2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows of the interface actions (6m,) the distance reads, fn, m1 and m2 of every
    interface, and their weights: 1 for fn, 2 / l2 for m1 and 2 / l1 for m2 (the moments as
    the force at the rectangle's edge that makes them)."""
    m = l1.shape[0]
    rows = (6 * np.arange(m)[:, None] + np.array([2, 3, 4])[None, :]).ravel()
    weights = np.column_stack([np.ones(m), 2.0 / l2, 2.0 / l1]).ravel()
    return rows, weights


#: pricing rounds of the nearest optimum by columns before the full QP is solved instead
MAX_SELECTION_ROUNDS = 30
#: a pattern prices out when its reduced cost is below -SELECTION_RTOL times the largest
#: work of a pattern under the duals (Clarabel's duals are accurate to about 1e-8)
SELECTION_RTOL = 1e-8


def nearest_by_columns(
    E_n: sparse.csc_matrix,
    friction: FrozenFriction,
    live: np.ndarray,
    rhs: np.ndarray,
    lam: float,
    A_n: sparse.csr_matrix,
    target: np.ndarray,
    start: Patterns | None,
) -> tuple[Solution, int]:
    """The nearest optimum of a frozen LP solved by column generation: the QP of
    :func:`nearest_optimum` on the master's columns (corner compressions, lambda, the
    patterns, each interface's thetas summing to at most one), with pricing by its duals
    as in ``columns`` (a pattern enters where its work under the equilibrium duals exceeds
    its interface's convexity dual), until none prices out: then the KKT conditions of the
    full QP hold, so its answer is the full QP's. The pyramid's edges carry no normal force
    and no rocking moment, so the distance reads the corner compressions only (``A_n``).
    Returns the solution in the full LP's variables and the pricing rounds; the full QP
    where the rounds run out or Clarabel fails."""
    import clarabel

    n_eq, nn = E_n.shape
    m = friction.m
    r = A_n.shape[0]
    choice, owner = friction.translations()
    if start is not None:
        choice, owner = np.vstack([choice, start.choice]), np.concatenate([owner, start.owner])
    scale = max(float(np.abs(target).max(initial=0.0)), float(np.abs(rhs).max(initial=0.0)))
    scale = max(scale, 1e-300)
    lam_min = (1 - LAMBDA_SLACK) * lam
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.direct_solve_method = "qdldl"
    settings.max_iter = CLARABEL_ITERATIONS
    settings.time_limit = solver_seconds()
    for rounds in range(MAX_SELECTION_ROUNDS):
        settings.time_limit = solver_seconds()
        q = choice.shape[0]
        P_q = friction.columns(choice, owner)
        nvar = nn + 1 + q + r  # c, lambda, thetas, distances
        convex = sparse.csc_matrix((np.ones(q), (owner, np.arange(q))), shape=(m, q))
        M = sparse.vstack(
            [
                sparse.hstack(
                    [
                        E_n,
                        sparse.csc_matrix(-live.reshape(-1, 1)),
                        P_q,
                        sparse.csc_matrix((n_eq, r)),
                    ]
                ),
                sparse.hstack([A_n / scale, sparse.csc_matrix((r, 1 + q)), -sparse.identity(r)]),
                sparse.hstack([sparse.csc_matrix((m, nn + 1)), convex, sparse.csc_matrix((m, r))]),
                sparse.hstack([-sparse.identity(nn + 1 + q), sparse.csc_matrix((nn + 1 + q, r))]),
            ],
            format="csc",
        )
        M.sort_indices()
        sign = np.zeros(nn + 1 + q)
        sign[nn] = -lam_min
        b = np.concatenate([rhs, target / scale, np.ones(m), sign])
        cones = [clarabel.ZeroConeT(n_eq + r), clarabel.NonnegativeConeT(m + nn + 1 + q)]
        d = nn + 1 + q + np.arange(r)
        P = sparse.csc_matrix((np.ones(r), (d, d)), shape=(nvar, nvar))
        out = clarabel.DefaultSolver(P, np.zeros(nvar), M, b, cones, settings).solve()
        if str(out.status) not in ("Solved", "AlmostSolved"):
            break
        z = np.asarray(out.z)
        y = -z[:n_eq]
        w = z[n_eq + r : n_eq + r + m]
        best, gain = friction.best(y)
        excess = gain - w
        size = max(float(np.abs(gain).max(initial=0.0)), float(np.abs(w).max(initial=0.0)))
        priced = np.nonzero(excess > SELECTION_RTOL * max(size, 1e-300))[0]
        x = np.asarray(out.x)
        if priced.size == 0:
            theta = np.maximum(x[nn + 1 : nn + 1 + q], 0.0)
            g = edge_multipliers(friction, choice, owner, theta)
            sol = Solution("optimal", lam, np.concatenate([np.maximum(x[:nn], 0.0), g]))
            sol.detail = f"Clarabel: {out.status}, {rounds} pricing rounds, {q} patterns"
            return sol, rounds
        choice = np.vstack([choice, best[priced]])
        owner = np.concatenate([owner, priced])
    log.debug("the nearest optimum by columns did not close: the full QP instead")
    E, C = full_lp(E_n, friction)
    A = sparse.hstack([A_n, sparse.csr_matrix((r, friction.E_s.shape[1]))], format="csr")
    return nearest_optimum(E, live, rhs, (C, friction.cap), lam, A, target), MAX_SELECTION_ROUNDS


def elastic_state(problem: Problem) -> np.ndarray | None:
    """The joints' actions (m, 6) under the dead load as elastic joints carry them: among
    the statically admissible actions (equilibrium at lambda = 0, the corners' compressions
    in the 8-face pyramid), the one of least complementary energy

        sum_i f1^2 / kt A + f2^2 / kt A + fn^2 / kn A + 12 m1^2 / kn A l2^2
              + 12 m2^2 / kn A l1^2 + 12 m3^2 / kt A (l1^2 + l2^2)

    (a closed joint of stiffness kn, kt per unit area on its l1 x l2 rectangle, A = l1 l2;
    the theorem of least complementary energy, Menabrea's, with the no-tension and friction
    limits as constraints). It holds no self-stress the dead load does not force on elastic
    joints: a head joint between blocks that stand on their own carries nothing. None where
    Clarabel fails."""
    model = problem.model
    weights = energy_weights(model)
    R, _ = associative_columns(model, ASSOCIATIVE_GRID, pyramid_edges(8, "circumscribed"))
    A = (sparse.diags(weights) @ R.tocsr()).tocsr()
    E = (problem.H_T @ R).tocsc()
    # lambda has no column to act on (a zero live load): the dead load's equilibrium
    no_live = np.zeros_like(problem.live)
    sol = nearest_optimum(E, no_live, problem.rhs, None, 0.0, A, -weights * problem.a0)
    if sol.status != "optimal":
        log.debug("the elastic dead-load state: %s", sol.detail)
        return None
    return (problem.a0 + R @ sol.x).reshape(-1, 6)


def energy_weights(model: Model) -> np.ndarray:
    """(6m,) w with the joints' complementary energy ``|w * a|^2`` (up to a constant factor)
    for the actions a (:func:`elastic_state`), scaled to a largest weight of one."""
    its = model.interfaces
    area = its.l1 * its.l2
    n = 1.0 / np.sqrt(np.asarray(model.kn, dtype=float) * area)
    t = 1.0 / np.sqrt(np.asarray(model.kt, dtype=float) * area)
    r12 = np.sqrt(12.0)
    weights = np.column_stack(
        [t, t, n, r12 * n / its.l2, r12 * n / its.l1, r12 * t / np.hypot(its.l1, its.l2)]
    ).ravel()
    return weights / weights.max()  # only the ratios matter; order one for Clarabel


def least_energy_frozen(
    problem: Problem,
    R_n: sparse.csc_matrix,
    R_s: sparse.csc_matrix,
    radius: np.ndarray,
    lam: float,
) -> np.ndarray | None:
    """Among the actions ``a = a0 + R_n c + R_s t`` in equilibrium at ``lam`` with the
    corner compressions ``c >= 0`` and every point's shear ``|t_p| <= radius_p`` (its frozen
    capacity), the one of least complementary energy (:func:`elastic_state`'s): the
    mechanical choice among the optima of a frozen LP held at its lambda, as elastic joints
    would share the load. ``R_s`` has two columns a point (t1, t2). A convex QP by Clarabel;
    (m, 6) actions, or None where it fails."""
    try:
        import clarabel
    except ImportError:  # pragma: no cover - declared dependency
        return None
    model = problem.model
    weights = energy_weights(model)
    n_eq = problem.H_T.shape[0]
    nn, p = R_n.shape[1], R_s.shape[1] // 2
    r = weights.size
    R = sparse.hstack([R_n, R_s], format="csr")
    k = nn + 2 * p
    # t stored per point as (t1, t2); the cone rows (radius, t1, t2) per point
    pts = np.arange(p)
    cone_rows = np.concatenate([3 * pts + 1, 3 * pts + 2])
    cone_cols = nn + np.concatenate([2 * pts, 2 * pts + 1])
    G = sparse.csc_matrix((-np.ones(2 * p), (cone_rows, cone_cols)), shape=(3 * p, k + r))
    h = np.zeros(3 * p)
    h[3 * pts] = radius
    M = sparse.vstack(
        [
            sparse.hstack([problem.H_T @ R, sparse.csc_matrix((n_eq, r))]),
            sparse.hstack([sparse.diags(weights) @ R, -sparse.identity(r)]),
            sparse.hstack([-sparse.identity(nn), sparse.csc_matrix((nn, 2 * p + r))]),
            G,
        ],
        format="csc",
    )
    M.sort_indices()
    b = np.concatenate([problem.rhs + lam * problem.live, -weights * problem.a0, np.zeros(nn), h])
    cones = [clarabel.ZeroConeT(n_eq + r), clarabel.NonnegativeConeT(nn)]
    cones += [clarabel.SecondOrderConeT(3)] * p
    d = k + np.arange(r)
    P = sparse.csc_matrix((np.ones(r), (d, d)), shape=(k + r, k + r))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.direct_solve_method = "qdldl"
    settings.max_iter = CLARABEL_ITERATIONS
    settings.time_limit = solver_seconds()
    out = clarabel.DefaultSolver(P, np.zeros(k + r), M, b, cones, settings).solve()
    if str(out.status) not in ("Solved", "AlmostSolved"):
        log.debug("the least-energy optimum: Clarabel %s", out.status)
        return None
    x = np.asarray(out.x)[:k]
    return (problem.a0 + R @ x).reshape(-1, 6)
