"""The interface of the limit analysis: its grid of contact points (Gauss-Lobatto, corners
included), the friction pyramid, and the actions of point forces about the interface centre.

Why the associative answer needs only the corners. The kinematic (dual) problem asks, at
each point y of the grid, ``v_n(y) >= mu max_d e_d . v_t(y)`` (or ``>= mu |v_t(y)|``), where
the relative velocity v(y) is affine in y (a rigid relative motion). The right side is
convex in y, the left side affine, so the set of points where it holds is convex: if it
holds at the four corners it holds on the whole rectangle. The tensile part enters the
objective only through the resultant ``ft``. Hence any grid that contains the corners (and
the continuum interface itself) gives the same associative multiplier as the four corners.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from masonry_dem._validation import GRID_MOST, plain

PYRAMIDS = ("circumscribed", "inscribed")
STATUSES = ("collapse", "no collapse", "failed")
#: grid of the associative problem: the corners are exact (module docstring)
ASSOCIATIVE_GRID = 2
#: grid of the non-associative problem's frozen capacities: the smallest even n whose
#: Lobatto quadrature of the uniform-pressure torsion is within 1 % of cT on rectangles
#: of aspect 1 to 4 (benchmarks/bench_limit_analysis.py --grid-study: 0.64 % at 4:1)
NON_ASSOCIATIVE_GRID = 8


# --------------------------------------------------------------------------- geometry
def lobatto_rule(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Lobatto points and weights on [-1, 1] (n >= 2; the ends included)."""
    if isinstance(n, (bool, str, bytes)) or int(n) != n or not 2 <= n <= GRID_MOST:
        raise ValueError(
            f"grid must be a whole number from 2 to {GRID_MOST} (contact points along each "
            f"side of an interface), got {plain(n)}"
        )
    n = int(n)
    if n == 2:
        return np.array([-1.0, 1.0]), np.array([1.0, 1.0])
    from numpy.polynomial import legendre as leg

    c = np.zeros(n)
    c[-1] = 1.0
    inner = np.sort(np.real(leg.legroots(leg.legder(c))))
    x = np.concatenate([[-1.0], inner, [1.0]])
    w = 2.0 / (n * (n - 1) * leg.legval(x, c) ** 2)
    return x, w


def grid_points(
    l1: np.ndarray, l2: np.ndarray, n: int, centre: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(m, n*n, 2) local points (y1, y2) of an n x n Lobatto grid on each l1 x l2 rectangle
    (centred on ``centre`` (m, 2), default the origin), and (m, n*n) area weights."""
    x, w = lobatto_rule(n)
    a, b = np.meshgrid(x, x, indexing="ij")
    wa = np.outer(w, w).ravel() / 4.0
    pts = np.stack(
        [0.5 * l1[:, None] * a.ravel()[None, :], 0.5 * l2[:, None] * b.ravel()[None, :]], axis=2
    )
    if centre is not None:
        pts = pts + centre[:, None, :]
    return pts, (l1 * l2)[:, None] * wa[None, :]


def torsion_quadrature(l1: float, l2: float, n: int) -> float:
    """Mean distance from the centre of an l1 x l2 rectangle by the n x n Lobatto grid: the
    torsion capacity per unit mu (ft - fn) of a uniform pressure at the grid points, which
    converges to the closed-form cT (``constitutive.torsion_constant``)."""
    pts, w = grid_points(np.array([float(l1)]), np.array([float(l2)]), n)
    return float((w[0] * np.hypot(pts[0, :, 0], pts[0, :, 1])).sum() / (l1 * l2))


def pyramid_edges(sides: int, pyramid: str) -> np.ndarray:
    """(D, 2) edges of the friction pyramid's section at unit compression, per unit mu."""
    if isinstance(sides, bool) or int(sides) != sides or sides < 3:
        raise ValueError(f"friction_sides must be an integer >= 3, got {sides!r}")
    if pyramid not in PYRAMIDS:
        raise ValueError(f"cone must be one of {PYRAMIDS} with backend 'highs', got {pyramid!r}")
    d = int(sides)
    if pyramid == "circumscribed":  # faces tangent to the circle, a face normal on each axis
        theta = (np.arange(d) + 0.5) * 2 * np.pi / d
        rho = 1.0 / np.cos(np.pi / d)
    else:  # vertices on the circle, one on each axis
        theta = np.arange(d) * 2 * np.pi / d
        rho = 1.0
    return rho * np.stack([np.cos(theta), np.sin(theta)], axis=1)


def resultant_columns(
    y: np.ndarray, force: np.ndarray, interface: np.ndarray, m: int
) -> sparse.csc_matrix:
    """(6m, k) interface actions [f1, f2, fn, m1, m2, m3] of k point forces ``force`` (k, 3)
    = (t1, t2, n) at local points ``y`` (k, 2) of interfaces ``interface`` (k,): m = y x p."""
    t1, t2, fn = force.T
    y1, y2 = y.T
    vals = np.stack([t1, t2, fn, y2 * fn, -y1 * fn, y1 * t2 - y2 * t1], axis=1)
    k = y.shape[0]
    rows = 6 * interface[:, None] + np.arange(6)[None, :]
    cols = np.repeat(np.arange(k), 6).reshape(k, 6)
    return sparse.csc_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(6 * m, k))
