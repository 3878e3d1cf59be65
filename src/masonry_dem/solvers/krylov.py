"""A linear solve by GMRES preconditioned with the factors of a nearby matrix.

Between two Newton iterations the tangent changes only in the joints whose state changed: a
change of low rank against the whole matrix. With the LU factors P of an earlier tangent as
preconditioner, K P^-1 is the identity plus that change, and GMRES converges in about as many
iterations as the change has rank (exactly so in exact arithmetic). Each iteration costs one
solve with P and one product with K, far less than a factorization of K on all but the
smallest walls (``docs/solvers.md``, "Cheaper linear solves").
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.linalg import solve_triangular

from masonry_dem.solvers.factorization import Factors


def gmres(
    product: Callable[[np.ndarray], np.ndarray],
    preconditioner: Factors,
    b: np.ndarray,
    weight: np.ndarray,
    iterations: int,
    tolerance: float,
) -> tuple[np.ndarray | None, int]:
    """(x, iterations) with |W (b - K x)| <= ``tolerance`` |W b|, K x = ``product(x)``, by
    right-preconditioned GMRES (no restart) on W K P^-1 W^-1 u = W b, x = P^-1 W^-1 u, in at
    most ``iterations`` iterations; x is None when it does not get there. W = diag(``weight``)
    is the norm of the residual (moments as forces), so the tolerance is measured as the
    Newton iterations measure their residual. The Arnoldi basis is orthogonalised twice
    (classical Gram-Schmidt, each pass one matrix product) and the small least-squares
    problem reduced by Givens rotations as it grows (Saad, Iterative Methods for Sparse
    Linear Systems, 6.5.3), so its residual is known at each iteration without a solve."""
    rhs = weight * b
    beta = math.sqrt(float(rhs @ rhs))
    n = b.size
    if beta == 0.0:
        return np.zeros(n), 0
    if not math.isfinite(beta):
        return None, 0
    V = np.empty((iterations + 1, n))  # the Arnoldi basis, one vector a row
    Z = np.empty((iterations, n))  # P^-1 W^-1 of each basis vector: x = Z^T y
    R = np.zeros((iterations, iterations))  # the Hessenberg matrix reduced by the rotations
    cos = np.zeros(iterations)
    sin = np.zeros(iterations)
    g = np.zeros(iterations + 1)  # the rotated right-hand side beta e1
    g[0] = beta
    V[0] = rhs / beta
    goal = tolerance * beta
    for j in range(iterations):
        Z[j] = preconditioner.solve(V[j] / weight)
        w = weight * product(Z[j])
        basis = V[: j + 1]
        h = basis @ w
        w -= h @ basis
        again = basis @ w  # the second pass restores the orthogonality round-off took
        w -= again @ basis
        h += again
        below = math.sqrt(float(w @ w))
        if not (math.isfinite(below) and np.all(np.isfinite(h))):
            return None, j + 1
        for i in range(j):  # the earlier rotations, on the new column
            h[i], h[i + 1] = cos[i] * h[i] + sin[i] * h[i + 1], cos[i] * h[i + 1] - sin[i] * h[i]
        rho = math.hypot(h[j], below)
        if rho == 0.0:
            return None, j + 1
        cos[j], sin[j] = h[j] / rho, below / rho
        h[j] = rho
        R[: j + 1, j] = h
        g[j + 1] = -sin[j] * g[j]
        g[j] *= cos[j]
        # |g[j + 1]| is the residual of the least-squares solution in the first j + 1 vectors;
        # a zero ``below`` (breakdown) makes it exact
        if abs(g[j + 1]) <= goal or below <= 1e-14 * beta:
            y = solve_triangular(R[: j + 1, : j + 1], g[: j + 1])
            return y @ Z[: j + 1], j + 1
        V[j + 1] = w / below
    return None, iterations
