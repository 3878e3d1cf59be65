"""The convex problem of a model: the equilibrium rows of its free DOFs, scaled, the columns of
the contact forces, and the cap on lambda that turns an unbounded problem into "no collapse"."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import sparse

from masonry_dem.assembly.compatibility import compatibility_matrix
from masonry_dem.model import Model

from .interface import NON_ASSOCIATIVE_GRID, grid_points, resultant_columns


# --------------------------------------------------------------------------- the problem
@dataclass
class Problem:
    """The equilibrium of the free DOFs: ``E @ x - lambda * live = rhs`` with the interface
    actions ``a = a0 + R @ x`` (6m,); rows scaled (rotations by 1/length)."""

    model: Model
    H_T: sparse.csr_matrix  # (6n_free, 6m) scaled rows
    live: np.ndarray
    rhs: np.ndarray
    a0: np.ndarray
    row_scale: np.ndarray
    free: np.ndarray

    @classmethod
    def of(cls, model: Model) -> Problem:
        H = compatibility_matrix(model.blocks, model.interfaces)
        free = model.free
        length = float(np.median(model.blocks.sizes))
        row_scale = np.tile([1.0, 1.0, 1.0, 1 / length, 1 / length, 1 / length], model.blocks.count)
        row_scale = row_scale[free]
        H_T = sparse.diags(row_scale) @ H.T.tocsr()[free]
        H_T = H_T.tocsr()
        m = model.interfaces.count
        a06 = np.zeros((m, 6))
        a06[:, 2] = model.tensile_strength * model.interfaces.area  # ft at every point
        a0 = a06.ravel()
        dead = model.dead.reshape(-1)[free] * row_scale
        live = model.live.reshape(-1)[free] * row_scale
        return cls(model, H_T, live, dead - H_T @ a0, a0, row_scale, free)

    def velocities(self, duals: np.ndarray) -> np.ndarray:
        """(n, 6) block velocities from the duals of the scaled equilibrium rows, oriented so
        that the live load does positive work, largest translation 1."""
        q = np.zeros(self.model.n_dofs)
        q[self.free] = duals * self.row_scale
        work = float(self.model.live.reshape(-1) @ q)
        if work < 0:
            q = -q
        v = q.reshape(-1, 6)
        peak = float(np.abs(v[:, :3]).max(initial=0.0))
        return v / peak if peak > 0 else v


def cohesive_grid(grid: int) -> int:
    """The grid of the cohesion's dissipation ``(c - mu ft) |v_t(y)|``, at least
    ``NON_ASSOCIATIVE_GRID``, whatever the friction's (the corners are exact for the
    friction, ``interface``): it is integrated by the grid's Lobatto rule, exact for a
    translation (v_t constant), but a twist's ``|v_t|`` grows with the distance from its
    centre, and the corners would take it at the corner distance (0.71 l on a square,
    against the mean 0.38 l: 85 % over); the 8 x 8 rule is within 1 % of it, above, on
    rectangles of aspect 1 to 4 (``torsion_quadrature``)."""
    return max(int(grid), NON_ASSOCIATIVE_GRID)


def cohesive_offsets(model: Model, grid: int) -> np.ndarray:
    """(m K,) the shear every contact point of the n x n grid carries at its tension cap:
    ``(c - mu ft) A_k`` (N), A_k the point's Lobatto area weight. The point's cone is
    ``|t| <= mu c_k + (c - mu ft) A_k`` with ``c_k >= 0`` its compression beyond the cap, so
    that ``|t| <= mu N + c A_k`` in the compression ``N = c_k - ft A_k`` >= -ft A_k. Zeros
    (bit for bit the paper's cone) where the cohesion is the paper's mu ft."""
    its = model.interfaces
    _, w = grid_points(its.l1, its.l2, grid)
    return (model.cohesion_beyond_friction[:, None] * w).ravel()


def cohesive_points(model: Model, grid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The points that carry a cohesive shear on the ``cohesive_grid`` of ``grid``: their
    indices among the m n^2 points (interface-major), their local positions (p, 2) and
    offsets (p,) (``cohesive_offsets``)."""
    g = cohesive_grid(grid)
    its = model.interfaces
    offset = cohesive_offsets(model, g)
    points = np.flatnonzero(offset > 0)
    y, _ = grid_points(its.l1, its.l2, g)
    return points, y.reshape(-1, 2)[points], offset[points]


def slip_columns(model: Model, grid: int) -> sparse.csc_matrix | None:
    """(6m, 2p) the actions of unit shears (t1, t2) at the cohesive points
    (``cohesive_points``), the layout of the kinematic form's cohesive statics; None
    without a cohesion of its own."""
    points, y, _ = cohesive_points(model, grid)
    if points.size == 0:
        return None
    K = cohesive_grid(grid) ** 2
    shear = np.tile(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), (points.size, 1))
    iface = np.repeat(points // K, 2)
    return resultant_columns(np.repeat(y, 2, axis=0), shear, iface, model.interfaces.count)


def cohesive_columns(
    model: Model, grid: int, dirs: np.ndarray
) -> tuple[sparse.csc_matrix, sparse.csr_matrix] | None:
    """The cohesive shear of the pyramid (HiGHS), None where no joint has one: at every
    cohesive point (``cohesive_points``: the ``cohesive_grid``, not the friction's) D
    columns, the pyramid's section scaled by its offset o_k (forces ``o_k e_d``, no normal),
    and the rows ``sum_d w_kd <= 1`` (their convex hull, with 0), (R_c (6m, p D), C (p, p D)).
    With the friction edges ``mu e_d`` per unit compression, the shear spans ``mu c_k``
    times the pyramid's section plus ``o_k`` times it: the friction's polygon grown by
    the cohesion."""
    points, y, offset = cohesive_points(model, grid)
    if points.size == 0:
        return None
    K = cohesive_grid(grid) ** 2
    D = dirs.shape[0]
    force = np.zeros((points.size, D, 3))
    force[:, :, :2] = offset[:, None, None] * dirs[None, :, :]
    R = resultant_columns(
        np.repeat(y, D, axis=0),
        force.reshape(-1, 3),
        np.repeat(points // K, D),
        model.interfaces.count,
    )
    p = points.size
    C = sparse.csr_matrix(
        (np.ones(p * D), (np.repeat(np.arange(p), D), np.arange(p * D))), shape=(p, p * D)
    )
    return R, C


def associative_columns(
    model: Model, grid: int, mu_dirs: np.ndarray | None
) -> tuple[sparse.csc_matrix, int]:
    """R (6m, k): the actions of the pyramid edges at every grid point (HiGHS), or of the
    point forces (c, t1, t2) per point (Clarabel: ``mu_dirs`` None)."""
    its = model.interfaces
    m = its.count
    y, _ = grid_points(its.l1, its.l2, grid)
    K = y.shape[1]
    iface = np.repeat(np.arange(m), K)
    yk = y.reshape(-1, 2)
    mu = np.repeat(model.friction, K)
    if mu_dirs is not None:
        D = mu_dirs.shape[0]
        force = np.empty((m * K, D, 3))
        force[:, :, :2] = mu[:, None, None] * mu_dirs[None, :, :]
        force[:, :, 2] = -1.0
        return (
            resultant_columns(
                np.repeat(yk, D, axis=0), force.reshape(-1, 3), np.repeat(iface, D), m
            ),
            K,
        )
    # Clarabel: per point the compression c and the shear (t1, t2), in this order
    eye = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    force = np.broadcast_to(eye, (m * K, 3, 3)).reshape(-1, 3)
    return resultant_columns(np.repeat(yk, 3, axis=0), force, np.repeat(iface, 3), m), K


# --------------------------------------------------------------------------- backends
@dataclass
class Solution:
    status: str  # "optimal", "unbounded", "infeasible", or the solver's own word
    lam: float = float("nan")
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    duals: np.ndarray = field(default_factory=lambda: np.zeros(0))
    detail: str = ""
    iterations: int = 0  # the solver's own (interior point iterations)
    setup_seconds: float = 0.0  # CPU seconds of the solver's setup (before its iterations)
    #: (lower, upper): a certified bracket of lambda (``normal_ipm``), None where not certified
    bracket: tuple[float, float] | None = None


#: lambda is capped at this multiple of max(1, |dead| / |live|): reaching the cap is "no
#: collapse" (no mechanism below it)
LAMBDA_CAP = 1.0e4


def lambda_cap(live: np.ndarray, rhs: np.ndarray) -> float:
    ratio = float(np.linalg.norm(rhs)) / max(float(np.linalg.norm(live)), 1e-300)
    return LAMBDA_CAP * max(1.0, ratio)


def objective_scale(live: np.ndarray) -> float:
    """The objective is lambda |F_live| (the live load at collapse, in the units of the
    equilibrium rows), not lambda: the solvers' dual tolerances are absolute, and the duals
    (the mechanism) scale as 1 / the objective's coefficient. With a coefficient of 1 and
    loads in newtons, Clarabel stopped "Solved" at 0.449 on a 298-block wall whose multiplier
    is 0.4657 (HiGHS, and Clarabel with this scale), its mechanism 0.7 % off admissible; on
    a 1 041-block wall 0.282 against 0.4167."""
    return max(float(np.linalg.norm(live)), 1e-300)
