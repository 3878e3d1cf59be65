"""Rigid-block limit analysis of a :class:`~masonry_dem.model.Model`: the collapse multiplier
and mechanism in one convex solve (associative), or by a sequence of them (non-associative).

Statics. Each interface carries point forces at a grid of ``n x n`` contact points (the
Gauss-Lobatto points of the rectangle, corners included). Point k carries
``(t1, t2, n) = (0, 0, ft_k) + compression`` where ``ft_k`` is its share of the interface's
tensile force (tensile strength x area, Lobatto weights) and the compression lies in the
friction cone ``|t| <= mu c``, ``n = ft_k - c``, ``c >= 0``: no tension beyond ``ft``, Coulomb
friction with the cohesion ``mu ft`` of the DEM's law (``fsu = mu (ft - fn)``), and rocking and
torsion that follow the interface's real area. The point forces reduce to the interface
actions ``[f1, f2, fn, m1, m2, m3]`` about its centre (``m = y x p``), which are work-conjugate
to the rows of the compatibility matrix H of Eqs. (A1)-(A3); equilibrium of the free DOFs is
``H^T a = F_dead + lambda F_live``.

Cones. ``backend="highs"``: a pyramid of ``friction_sides`` faces, in generator form (the
compression is a non-negative combination of the pyramid's edges, ``(mu rho e_d, -1)``), so
the LP has only equality rows and sign bounds; ``"circumscribed"`` (default) contains the
circular cone of the DEM, so the DEM's strength domain lies inside the LA's and Radenkovic's
theorem makes the associative multiplier an upper bound of the pushover's;
``"inscribed"`` lies inside it. ``backend="clarabel"``: the exact circular cone (SOCP).

Why the associative answer needs only the corners. The kinematic (dual) problem asks, at
each point y of the grid, ``v_n(y) >= mu max_d e_d . v_t(y)`` (or ``>= mu |v_t(y)|``), where
the relative velocity v(y) is affine in y (a rigid relative motion). The right side is
convex in y, the left side affine, so the set of points where it holds is convex: if it
holds at the four corners it holds on the whole rectangle. The tensile part enters the
objective only through the resultant ``ft``. Hence any grid that contains the corners (and
the continuum interface itself) gives the same associative multiplier as the four corners:
the default ``grid`` of the associative problem is 2, and a finer grid only costs time
(``tests/solvers/test_limit_analysis.py`` checks 2 against 6). The same argument shows why
four corner contacts carry a torsion of ``mu N R`` (R the half diagonal), 1.7 to 1.9 times
the ``cT mu N`` of uniform pressure: the rigid-plastic interface may put its compression in
the corners.

Non-associative (zero dilatancy). The scheme of Gilbert, Casapulla & Ahmed (2006), "Limit
analysis of masonry block structures with non-associative frictional joints using linear
programming", Computers & Structures 84, 873-887: the friction capacity of each interface
is frozen at the normal actions of the previous solve (a cohesive, Tresca-like capacity,
which sliding does not dilate), the LP is solved again, and the capacities are updated
(under-relaxed) until lambda and the normal actions settle. The frozen capacity is spread
as the DEM spreads it (Figure 10): a uniform compression ``ft - fn`` on the reduced rectangle
``l1 - 2|m2|/(ft - fn)`` x ``l2 - 2|m1|/(ft - fn)`` centred on the resultant, integrated at its
``n x n`` Lobatto points, so the frozen torsion capacity is the DEM's ``cT mu (ft - fn)`` to
within the quadrature error (the default n is the smallest even n for which it is within
1 % of the closed form on rectangles up to 4:1, ``benchmarks/bench_limit_analysis.py
--grid-study``). The normal forces stay at the four corners (no tension beyond ft, free
rocking). Convergence: none is proved (the non-associative problem is not convex and its
solution need not be unique, and its LPs are degenerate, so the actions may jump between
equivalent vertices); the iteration stops when its last three lambdas lie within
``tolerance`` (relative) of each other. Where lambda turns back (it oscillates between
degenerate LP vertices), the relaxation is halved, down to 1/64, a damping that lets the
frozen actions settle; the iteration reports ``failed`` with the last lambdas when ``max_iterations`` pass without it.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy import sparse

from masonry_dem.assembly.compatibility import compatibility_matrix
from masonry_dem.model import Model

log = logging.getLogger(__name__)

BACKENDS = ("highs", "clarabel")
#: the non-associative iteration halves its relaxation each time lambda turns back, down to
_SMALLEST_RELAXATION = 1.0 / 64
PYRAMIDS = ("circumscribed", "inscribed")
STATUSES = ("collapse", "no collapse", "failed")
#: grid of the associative problem: the corners are exact (module docstring)
ASSOCIATIVE_GRID = 2
#: grid of the non-associative problem's frozen capacities: the smallest even n whose
#: Lobatto quadrature of the uniform-pressure torsion is within 1 % of cT on rectangles
#: of aspect 1 to 4 (benchmarks/bench_limit_analysis.py --grid-study: 0.64 % at 4:1)
NON_ASSOCIATIVE_GRID = 8


@dataclass(frozen=True)
class LimitAnalysisResult:
    """Outcome of :func:`limit_analysis`.

    status: "collapse", "no collapse" (no mechanism is possible: the LP is unbounded, or
        lambda reaches ``LAMBDA_CAP`` x max(1, |dead| / |live|)) or
        "failed" (``reason`` says why, with the solver's own status).
    load_factor: the collapse multiplier (nan unless "collapse").
    block_velocities: (n, 6) the collapse mechanism (zeros unless "collapse"), scaled so
        that the largest translation is 1 and the live load does positive work.
    interface_actions: (m, 6) local actions [f1, f2, fn, m1, m2, m3] at collapse.
    """

    status: str
    load_factor: float
    reason: str
    block_velocities: np.ndarray
    interface_actions: np.ndarray
    method: str  # "associative" or "non-associative"
    grid: int
    backend: str
    seconds: float
    cone: str = "circumscribed"
    friction_sides: int = 8
    iterations: int = 1
    load_factors: tuple[float, ...] = ()  # one per solve (the non-associative iterations)
    variables: int = 0
    constraints: int = 0
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def bound(self) -> str:
        """What the multiplier is to the DEM's: an "upper" bound (associative, with a cone
        that contains the DEM's) or an "estimate" (non-associative, or an inscribed cone)."""
        upper = self.method == "associative" and self.cone in ("circumscribed", "exact")
        return "upper" if upper else "estimate"

    def summary(self) -> dict[str, Any]:
        lam = self.load_factor if np.isfinite(self.load_factor) else None
        return {
            "status": self.status,
            "reason": self.reason,
            "lambda": lam,
            "method": self.method,
            "bound": self.bound,
            "grid": self.grid,
            "backend": self.backend,
            "cone": self.cone,
            "friction_sides": self.friction_sides,
            "iterations": self.iterations,
            "load_factors": [float(x) for x in self.load_factors],
            "variables": self.variables,
            "constraints": self.constraints,
            "seconds": round(self.seconds, 4),
        }


# --------------------------------------------------------------------------- geometry
def lobatto_rule(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Lobatto points and weights on [-1, 1] (n >= 2; the ends included)."""
    if isinstance(n, bool) or int(n) != n or n < 2:
        raise ValueError(f"grid must be an integer >= 2 (points along each side), got {n!r}")
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


def _directions(sides: int, pyramid: str) -> np.ndarray:
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


def _resultant_columns(
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


# --------------------------------------------------------------------------- the problem
@dataclass
class _Problem:
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
    def of(cls, model: Model) -> _Problem:
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


def _associative_columns(
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
            _resultant_columns(
                np.repeat(yk, D, axis=0), force.reshape(-1, 3), np.repeat(iface, D), m
            ),
            K,
        )
    # Clarabel: per point the compression c and the shear (t1, t2), in this order
    eye = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    force = np.broadcast_to(eye, (m * K, 3, 3)).reshape(-1, 3)
    return _resultant_columns(np.repeat(yk, 3, axis=0), force, np.repeat(iface, 3), m), K


# --------------------------------------------------------------------------- backends
@dataclass
class _Solution:
    status: str  # "optimal", "unbounded", "infeasible", or the solver's own word
    lam: float = float("nan")
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    duals: np.ndarray = field(default_factory=lambda: np.zeros(0))
    detail: str = ""


#: lambda is capped at this multiple of max(1, |dead| / |live|): reaching the cap is "no
#: collapse" (no mechanism below it)
LAMBDA_CAP = 1.0e4


def _lambda_cap(live: np.ndarray, rhs: np.ndarray) -> float:
    ratio = float(np.linalg.norm(rhs)) / max(float(np.linalg.norm(live)), 1e-300)
    return LAMBDA_CAP * max(1.0, ratio)


def _solve_highs(
    E: sparse.csc_matrix,
    live: np.ndarray,
    rhs: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    ineq: tuple[sparse.csc_matrix, np.ndarray] | None = None,
) -> _Solution:
    """max lambda s.t. E x - lambda live = rhs, [C x <= d], lower <= x <= upper, by HiGHS's
    interior point method (scipy's ``linprog``; the simplex methods were 2-8 times slower on
    these degenerate LPs, benchmarks/bench_limit_analysis.py). First with lambda = 0 (is
    there an equilibrium under the dead load?), then free."""
    from scipy.optimize import linprog

    n_eq, k = E.shape
    A = sparse.hstack([E, sparse.csc_matrix(-live.reshape(-1, 1))], format="csc")
    A_ub = b_ub = None
    if ineq is not None:
        C, d = ineq
        A_ub = sparse.hstack([C, sparse.csc_matrix((C.shape[0], 1))], format="csc")
        b_ub = d
    bounds = np.column_stack([np.concatenate([lower, [0.0]]), np.concatenate([upper, [0.0]])])
    words = {2: "infeasible", 3: "unbounded", 1: "iteration limit", 4: "numerical difficulties"}
    c = np.zeros(k + 1)
    res = linprog(c, A_ub, b_ub, A, rhs, bounds=bounds, method="highs-ipm")
    if res.status == 2:
        return _Solution("dead load", detail=f"HiGHS: {res.message} (at lambda = 0)")
    if res.status != 0:
        return _Solution(
            "error", detail=f"HiGHS: {words.get(res.status, res.status)}: {res.message}"
        )
    cap = _lambda_cap(live, rhs)
    bounds[k] = (0.0, cap)
    c[k] = -1.0
    res = linprog(c, A_ub, b_ub, A, rhs, bounds=bounds, method="highs-ipm")
    if res.status == 3:
        return _Solution("unbounded", detail=f"HiGHS: {res.message}")
    if res.status != 0:
        return _Solution(
            "error", detail=f"HiGHS: {words.get(res.status, res.status)}: {res.message}"
        )
    x = np.asarray(res.x)
    if x[k] >= cap * (1 - 1e-3):
        return _Solution("unbounded", detail=f"HiGHS: lambda reached its cap {cap:.3g}")
    return _Solution(
        "optimal", float(x[k]), x[:k], np.asarray(res.eqlin.marginals), "HiGHS: optimal"
    )


def _solve_clarabel(
    E: sparse.csc_matrix,
    live: np.ndarray,
    rhs: np.ndarray,
    n_points: int,
    mu: np.ndarray,
    capacity: np.ndarray | None,
    n_normal: int = 0,
    fix_lambda: bool = False,
) -> _Solution:
    """max lambda s.t. E x - lambda live = rhs with, per point, x = (c, t1, t2):
    ``|t| <= mu c``, ``c >= 0`` (``capacity`` None), or ``|t| <= mu capacity`` and then
    ``n_normal`` leading columns of compressions >= 0."""
    try:
        import clarabel
    except ImportError as exc:  # pragma: no cover - declared dependency
        return _Solution("error", detail=f"clarabel is not installed ({exc})")
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
        b.append(np.zeros(3 * n_points))
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
        bb[3 * p] = mu * capacity
        rows.append(G)
        b.append(bb)
        cones += [clarabel.SecondOrderConeT(3)] * n_points
    cap = _lambda_cap(live, rhs)
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
    q[k] = 0.0 if fix_lambda else -1.0
    P = sparse.csc_matrix((nvar, nvar))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solver = clarabel.DefaultSolver(P, q, A, np.concatenate(b), cones, settings)
    sol = solver.solve()
    word = str(sol.status)
    if "DualInfeasible" in word:
        return _Solution("unbounded", detail=f"Clarabel: {word}")
    if "PrimalInfeasible" in word:
        return _Solution("infeasible", detail=f"Clarabel: {word}")
    if word not in ("Solved", "AlmostSolved"):
        return _Solution("error", detail=f"Clarabel: {word}")
    x = np.asarray(sol.x)
    if not fix_lambda and x[k] >= cap * (1 - 1e-3):
        return _Solution("unbounded", detail=f"Clarabel: lambda reached its cap {cap:.3g}")
    z = np.asarray(sol.z)[:n_eq]
    return _Solution("optimal", float(x[k]), x[:k], -z, f"Clarabel: {word}")


def _dead_load_stands_clarabel(
    problem: _Problem, E: sparse.csc_matrix, solve_args: tuple, capacity: np.ndarray | None
) -> _Solution | None:
    """None if the dead load alone (lambda = 0) is in equilibrium, else why not (Clarabel has
    no warm start: a feasibility problem of its own)."""
    n_points, mu, n_normal = solve_args
    sol = _solve_clarabel(
        E, problem.live, problem.rhs, n_points, mu, capacity, n_normal, fix_lambda=True
    )
    if sol.status == "optimal":
        return None
    if sol.status == "infeasible":
        return _Solution("dead load", detail=f"{sol.detail} at lambda = 0")
    return _Solution("error", detail=f"{sol.detail} at lambda = 0")


#: largest violation of the kinematic admissibility of a returned mechanism, relative to its
#: largest relative velocity (interior point solutions are accurate to about 1e-8)
_ADMISSIBILITY_TOLERANCE = 1e-5


def mechanism_violation(model: Model, velocities: np.ndarray, dirs: np.ndarray | None) -> float:
    """How far a mechanism is from kinematically admissible for the associative problem:
    the largest ``mu g(v_t) - v_n`` over the corners of every interface (g: the pyramid's
    gauge, or |v_t| for the exact cone, ``dirs`` None), divided by the largest relative
    velocity; 0 when admissible. The corners suffice (module docstring). An independent
    check of the solver's dual: on a 3 053-block wall Clarabel reported "Solved" with a
    mechanism 0.7 off."""
    its = model.interfaces
    if its.count == 0:
        return 0.0
    H = compatibility_matrix(model.blocks, its)
    d = (H @ np.asarray(velocities, dtype=float).reshape(-1)).reshape(-1, 6)
    scale = float(np.abs(d).max(initial=0.0))
    if scale == 0:
        return 0.0
    y, _ = grid_points(its.l1, its.l2, 2)
    vt1 = d[:, None, 0] - d[:, None, 5] * y[:, :, 1]
    vt2 = d[:, None, 1] + d[:, None, 5] * y[:, :, 0]
    vn = d[:, None, 2] + d[:, None, 3] * y[:, :, 1] - d[:, None, 4] * y[:, :, 0]
    if dirs is None:
        gauge = np.hypot(vt1, vt2)
    else:
        gauge = (vt1[..., None] * dirs[:, 0] + vt2[..., None] * dirs[:, 1]).max(axis=-1)
    gap = model.friction[:, None] * gauge - vn
    return max(float(gap.max()) / scale, 0.0)


# --------------------------------------------------------------------------- public entry
def limit_analysis(
    model: Model,
    *,
    associative: bool = True,
    grid: int | None = None,
    backend: str = "highs",
    cone: str | None = None,
    friction_sides: int = 8,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    relaxation: float = 0.5,
) -> LimitAnalysisResult:
    """The collapse multiplier of ``model``'s live load over its dead load, and the mechanism.

    Args:
        associative: True: the classical (associative) multiplier, an upper bound of the
            DEM's with the default cone; False: zero dilatancy (Gilbert et al. 2006).
        grid: contact points per side of each interface (n x n, >= 2). None: 2 for the
            associative problem (exact, see the module docstring) and
            ``NON_ASSOCIATIVE_GRID`` for the frozen capacities of the non-associative one.
        backend: "highs" (LP, friction pyramid) or "clarabel" (SOCP, the exact cone).
        cone: "circumscribed" (default) or "inscribed" pyramid with "highs"; "exact" (the
            only one) with "clarabel".
        friction_sides: faces of the pyramid (>= 3). 8 by default: on the bundled wall
            (out of plane, held on one edge) the circumscribed pyramid of 4, 8 and 16 faces
            gives 0.587, 0.447 and 0.434 against 0.429 with the exact cone, in 0.7, 1.2
            and 2.4 s (docs/limit_analysis.md).
        tolerance, max_iterations, relaxation: the non-associative iteration (the last
            three lambdas within ``tolerance``, relative; the starting under-relaxation of
            the frozen actions between solves, halved where lambda turns back).

    Returns a :class:`LimitAnalysisResult`; solver trouble is a status, never an exception
    (bad arguments raise ValueError naming the argument).
    """
    t0 = time.perf_counter()
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if backend == "clarabel":
        if cone not in (None, "exact"):
            raise ValueError(f"cone must be 'exact' with backend 'clarabel', got {cone!r}")
        cone = "exact"
        dirs = None
    else:
        cone = "circumscribed" if cone is None else cone
        dirs = _directions(friction_sides, cone)
    if grid is None:
        grid = ASSOCIATIVE_GRID if associative else NON_ASSOCIATIVE_GRID
    lobatto_rule(grid)  # validates grid
    grid = int(grid)
    if not (isinstance(tolerance, (int, float)) and 0 < tolerance < 1):
        raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
    if (
        isinstance(max_iterations, bool)
        or int(max_iterations) != max_iterations
        or max_iterations < 1
    ):
        raise ValueError(f"max_iterations must be an integer >= 1, got {max_iterations!r}")
    if not (isinstance(relaxation, (int, float)) and 0 < relaxation <= 1):
        raise ValueError(f"relaxation must be in (0, 1], got {relaxation!r}")
    method = "associative" if associative else "non-associative"
    n, m = model.blocks.count, model.interfaces.count

    def result(status: str, lam: float, reason: str, **kw: Any) -> LimitAnalysisResult:
        kw.setdefault("block_velocities", np.zeros((n, 6)))
        kw.setdefault("interface_actions", np.zeros((m, 6)))
        out = LimitAnalysisResult(
            status,
            lam if status == "collapse" else float("nan"),
            reason,
            method=method,
            grid=grid,
            backend=backend,
            seconds=time.perf_counter() - t0,
            cone=str(cone),
            friction_sides=int(friction_sides) if backend == "highs" else 0,
            **kw,
        )
        log.info("%s limit analysis of %s: %s (%s)", method, model.name, status, reason)
        return out

    problem = _Problem.of(model)
    if not np.any(problem.live):
        return result("failed", float("nan"), "no live load: there is no multiplier to find")
    if associative:
        sol, size = _associative(problem, grid, dirs)
        out = _finish(problem, sol, size, result, iterations=1, load_factors=(sol.lam,))
        if out.status == "collapse":
            violation = mechanism_violation(model, out.block_velocities, dirs)
            if violation > _ADMISSIBILITY_TOLERANCE:
                return replace(
                    out,
                    status="failed",
                    load_factor=float("nan"),
                    reason=(
                        f"the solver's mechanism is not kinematically admissible (a corner "
                        f"closes or slides without dilating by {violation:.3g} of the largest "
                        f"relative velocity; {sol.detail}): lambda {sol.lam:.6g} is only "
                        "statically admissible, a lower bound of the multiplier"
                    ),
                )
        return out
    return _non_associative(
        problem, grid, dirs, tolerance, int(max_iterations), float(relaxation), result
    )


def _finish(problem: _Problem, sol: _Solution, size: tuple[int, int], result, **kw):
    variables, constraints = size
    kw = dict(kw, variables=variables, constraints=constraints)
    if sol.status == "unbounded":
        return result(
            "no collapse",
            float("nan"),
            f"no mechanism: the equilibrium holds for any lambda ({sol.detail})",
            **kw,
        )
    if sol.status == "dead load":
        return result(
            "failed",
            float("nan"),
            f"no equilibrium under the dead load ({sol.detail})",
            **kw,
        )
    if sol.status != "optimal":
        return result("failed", float("nan"), f"solver trouble: {sol.detail}", **kw)
    actions = sol.info_actions if hasattr(sol, "info_actions") else None
    return result(
        "collapse",
        sol.lam,
        f"collapse mechanism at lambda = {sol.lam:.6g} ({sol.detail})",
        block_velocities=problem.velocities(sol.duals),
        interface_actions=actions,
        **kw,
    )


def _associative(
    problem: _Problem, grid: int, dirs: np.ndarray | None
) -> tuple[_Solution, tuple[int, int]]:
    model = problem.model
    R, K = _associative_columns(model, grid, dirs)
    E = (problem.H_T @ R).tocsc()
    size = (E.shape[1] + 1, E.shape[0])
    if dirs is not None:
        k = E.shape[1]
        sol = _solve_highs(E, problem.live, problem.rhs, np.zeros(k), np.full(k, np.inf))
    else:
        n_points = model.interfaces.count * K
        mu = np.repeat(model.friction, K)
        dead = _dead_load_stands_clarabel(problem, E, (n_points, mu, 0), None)
        if dead is not None:
            return dead, size
        sol = _solve_clarabel(E, problem.live, problem.rhs, n_points, mu, None)
        if sol.status == "infeasible":  # stood at lambda = 0, so not expected
            sol = _Solution("error", detail=sol.detail)
    if sol.status == "optimal":
        sol.info_actions = (problem.a0 + R @ sol.x).reshape(-1, 6)  # type: ignore[attr-defined]
    return sol, size


# --------------------------------------------------------------------------- non-associative
def _frozen_layout(model: Model, actions: np.ndarray, grid: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (m, K, 2) and frozen compressions (m, K) of the DEM's reading of the
    actions: ``ft - fn`` spread uniformly over the reduced rectangle centred on the
    resultant (Figure 10)."""
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
    return pts, cap[:, None] * share


def _non_associative(
    problem: _Problem,
    grid: int,
    dirs: np.ndarray | None,
    tolerance: float,
    max_iterations: int,
    relaxation: float,
    result,
) -> LimitAnalysisResult:
    model = problem.model
    m = model.interfaces.count
    start, size = _associative(problem, ASSOCIATIVE_GRID, dirs)
    if start.status != "optimal":
        return _finish(problem, start, size, result, iterations=1, load_factors=())
    actions = start.info_actions  # type: ignore[attr-defined]
    # the normal forces at the corners (rocking, tension) stay associative
    corners, _ = grid_points(model.interfaces.l1, model.interfaces.l2, 2)
    iface4 = np.repeat(np.arange(m), 4)
    normal = np.zeros((4 * m, 3))
    normal[:, 2] = -1.0
    R_n = _resultant_columns(corners.reshape(-1, 2), normal, iface4, m)
    lams: list[float] = []
    sol = start
    for it in range(1, max_iterations + 1):
        pts, cap = _frozen_layout(model, actions, grid)
        K = pts.shape[1]
        iface = np.repeat(np.arange(m), K)
        yk = pts.reshape(-1, 2)
        mu = np.repeat(model.friction, K)
        capk = cap.ravel()
        if dirs is None:
            shear = np.zeros((m * K, 2, 3))
            shear[:, 0, 0] = 1.0
            shear[:, 1, 1] = 1.0
            R_s = _resultant_columns(
                np.repeat(yk, 2, axis=0), shear.reshape(-1, 3), np.repeat(iface, 2), m
            )
            R = sparse.hstack([R_n, R_s], format="csc")
            E = (problem.H_T @ R).tocsc()
            sol = _solve_clarabel(E, problem.live, problem.rhs, m * K, mu, capk, 4 * m)
            if sol.status == "infeasible":
                sol = _Solution("dead load", detail=f"{sol.detail} (frozen capacities)")
        else:
            D = dirs.shape[0]
            force = np.zeros((m * K, D, 3))
            force[:, :, :2] = mu[:, None, None] * dirs[None, :, :]
            R_s = _resultant_columns(
                np.repeat(yk, D, axis=0), force.reshape(-1, 3), np.repeat(iface, D), m
            )
            R = sparse.hstack([R_n, R_s], format="csc")
            E = (problem.H_T @ R).tocsc()
            k = E.shape[1]
            # per point, the edge multipliers share its frozen compression: sum_d g_d <= cap
            npts = m * K
            C = sparse.csc_matrix(
                (np.ones(npts * D), (np.repeat(np.arange(npts), D), 4 * m + np.arange(npts * D))),
                shape=(npts, k),
            )
            sol = _solve_highs(
                E, problem.live, problem.rhs, np.zeros(k), np.full(k, np.inf), (C, capk)
            )
        size = (E.shape[1] + 1, E.shape[0] + (m * K if dirs is not None else 0))
        if sol.status != "optimal":
            return _finish(problem, sol, size, result, iterations=it, load_factors=tuple(lams))
        new = (problem.a0 + R @ sol.x).reshape(-1, 6)
        sol.info_actions = new  # type: ignore[attr-defined]
        lams.append(sol.lam)
        # the LPs are degenerate: the actions may jump between equivalent vertices while
        # lambda settles, so the test is on lambda (its last three values)
        last = lams[-3:]
        settled = len(last) == 3 and max(last) - min(last) <= tolerance * max(abs(last[-1]), 1e-12)
        log.debug("non-associative iteration %d: lambda = %.6g", it, sol.lam)
        if settled:
            return _finish(problem, sol, size, result, iterations=it, load_factors=tuple(lams))
        if len(lams) > 2 and (lams[-1] - lams[-2]) * (lams[-2] - lams[-3]) < 0:
            relaxation = max(relaxation / 2, _SMALLEST_RELAXATION)  # it oscillates: damp it
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
    )


__all__ = [
    "ASSOCIATIVE_GRID",
    "BACKENDS",
    "NON_ASSOCIATIVE_GRID",
    "LimitAnalysisResult",
    "grid_points",
    "limit_analysis",
    "lobatto_rule",
    "mechanism_violation",
    "torsion_quadrature",
]
