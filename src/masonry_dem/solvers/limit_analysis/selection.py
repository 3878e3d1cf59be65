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

import numpy as np
from scipy import sparse

from .formulation import Solution

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
