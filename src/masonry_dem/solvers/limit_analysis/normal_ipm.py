"""The kinematic SOCP by a primal-dual interior point method on the normal equations, stopped
at a certified bracket of lambda.

The problem is ``kinematic``'s: ``min c . u`` s.t. ``l . u = 1`` and ``s = G u`` in a product
of p cones SOC(3) (the corner velocities ``(v_n, mu v_t1, mu v_t2)``), with ``c = -rhs / |live|``
and ``l = live / |live|``; its dual is ``max y`` s.t. ``G^T z + l y = c``, z in the cones (the
point forces). Clarabel factorizes the whole KKT system, 3 rows per cone and 6 per block (41
rows a block); here the cones are eliminated through their Nesterov-Todd scalings, which leaves
the normal matrix ``N = G^T W^2 G`` on the velocities (6 rows a block, 6 x 6 blocks on the block
adjacency graph), summed from one 12 x 12 matrix per interface and factorized by PARDISO
(Cholesky, METIS ordering, analysed once). The live-work row is a border, solved by a Schur
complement (one more right-hand side per iteration). Mehrotra's predictor-corrector, as in
CVXOPT's ``coneqp`` and Clarabel (without the homogeneous embedding: problems with no
mechanism or no statics are left to Clarabel, which certifies infeasibility).

Why a bracket, and not a gap of 1e-8: the corners that stay shut in the mechanism (most of a
wall) have ``s -> 0``, so their scaling ``W^2 ~ z / s`` grows without bound and the normal
matrix loses accuracy near the optimum; the iteration then stalls at relative gaps of about
1e-7 to 1e-6. What it has by then is enough to certify lambda both ways:

* **upper bound** (kinematic theorem): the iterate's own mechanism u, rescaled to
  ``l . u = 1``, is admissible if ``G u`` lies in the cones; lambda_up = ``c . u``. Its
  largest cone violation, relative to the largest corner velocity, must be under
  ``ADMISSIBLE`` (1e-8, Clarabel's feasibility tolerance: the bound holds to that order).
* **lower bound** (static theorem): the iterate's forces z miss equilibrium by ``r = c - l y
  - G^T z``; the correction of least norm in the scaling's metric, ``z + W^2 G N^-1 r``,
  restores it, and if it stays in the cones (checked corner by corner) the corrected forces
  are statically admissible and lambda_low = y.

The iteration stops when both hold and ``lambda_up - lambda_low <= BRACKET * lambda_up``.
Where it cannot (too many iterations, a step that stalls, PARDISO missing or failing), it
returns None and the caller solves with Clarabel.
"""

from __future__ import annotations

import itertools
import logging
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy import sparse

from masonry_dem.model import Model

from . import cones
from .budget import spent
from .formulation import Problem, Solution, lambda_cap
from .kinematic import corner_velocity_rows
from .progress import report

if TYPE_CHECKING:
    from masonry_dem.solvers.factorization import PardisoHandle

log = logging.getLogger(__name__)

#: the certified bracket's relative width at which the iteration stops: lambda is then known
#: to 6 digits, as the ladder's and the validation tables' values are given
BRACKET = 1e-6
#: largest cone violation of an accepted mechanism, relative to its largest corner velocity:
#: Clarabel's feasibility tolerance (the upper bound is exact for a mechanism admissible to
#: this; ``result.mechanism_violation`` checks every mechanism again at 1e-5)
ADMISSIBLE = 1e-8
#: largest equilibrium residual of accepted forces, relative to |c| (Clarabel's feasibility
#: tolerance)
EQUILIBRIUM = 1e-8
#: the iteration gives up (and the caller falls back on Clarabel) after this many steps. The
#: iterations grow with the wall: 35, 52 and 70 at 10^3, 10^4 and 3 x 10^4 blocks in plane
#: (one corrector); 80 would leave a 10^5-block wall to Clarabel, whose memory there is the
#: machine's. A stalled step, lambda's cap and the time budget end a stuck iteration sooner
MAX_ITERATIONS = 150
#: the exact cone takes this solver from this many velocities (6 per free block): on every
#: DOF it took Clarabel's CPU time at 636 velocities (106 blocks) and 0.57x at 1 788 (298
#: blocks); below, Clarabel's answers and its infeasibility certificates come at no cost
#: (``python benchmarks/bench_limit_analysis.py --speed``, docs/limit_analysis.md "Speed")
NORMAL_EQUATIONS_FROM = 1_000
#: PARDISO's threads: one; two cost more CPU and wall time on a shared 2-core machine, as
#: faer's did for Clarabel (``kinematic.clarabel_options``; docs/limit_analysis.md, "Speed")
THREADS = 1
#: fraction of the step to the cones' boundary, a full step included: an iterate never
#: lands on the boundary, where the scaling of the next iteration is 0 / 0 (on a single
#: block a full step left mu at 7e-18, then NaN, as round-off decided)
STEP_FRACTION = 0.99


@dataclass
class Bracket:
    """A certified bracket of the associative multiplier: ``lower`` from statically
    admissible forces (their equilibrium residual, relative to |c|, is ``residual``),
    ``upper`` from a mechanism whose cone violation is ``violation``."""

    lower: float
    upper: float
    violation: float
    residual: float
    forces: np.ndarray  # (p, 3) the statically admissible cone duals of the lower bound

    @property
    def width(self) -> float:
        return (self.upper - self.lower) / max(abs(self.upper), 1e-300)


# --------------------------------------------------------------------------- the cones
def _cone_margin(x: np.ndarray) -> np.ndarray:
    """x0 - |x1| per cone (>= 0 inside)."""
    return x[:, 0] - np.hypot(x[:, 1], x[:, 2])


# --------------------------------------------------------------------------- the normal matrix
class _NormalMatrix:
    """``N = G^T S G`` (S block diagonal, 3 x 3 per cone) summed from one C x C matrix per
    interface (its corners couple the C <= 12 solved velocities of its two blocks) into a fixed
    upper-triangular CSR pattern, and its Cholesky factors (PARDISO)."""

    def __init__(
        self,
        G: sparse.csr_matrix,
        model: Model,
        index: np.ndarray,
        K: int,
        dof_columns: np.ndarray | None = None,
    ) -> None:
        """``index``: the DOF of the model each column of G is (``index[dof]`` = column, -1
        for the DOFs not solved for); ``dof_columns``: the column every DOF moves with (a
        block's mirror image shares its columns: ``mirror.symmetric_basis``), ``index`` by
        default."""
        its = model.interfaces
        m, n = its.count, G.shape[1]
        self.m, self.K, self.n = m, K, n
        dofs = np.concatenate(
            [6 * its.block_i[:, None] + np.arange(6), 6 * its.block_j[:, None] + np.arange(6)],
            axis=1,
        )
        cols = (index if dof_columns is None else dof_columns)[dofs]  # (m, 12), -1: none
        # each column once (an interface between a block and its mirror image meets the same
        # columns from both sides), the solved columns first, and only as many as the widest
        # interface has (6 of 12 on the mirror-symmetric mechanisms)
        cols = np.sort(cols, axis=1)
        cols[:, 1:][cols[:, 1:] == cols[:, :-1]] = -1
        cols = np.take_along_axis(cols, np.argsort(cols < 0, axis=1, kind="stable"), axis=1)
        C = max(int((cols >= 0).sum(axis=1).max(initial=1)), 1)
        cols = np.ascontiguousarray(cols[:, :C])
        G = G.tocsr()
        G.sort_indices()
        local = cones.local_rows(G.indptr, G.indices, G.data, cols, 3 * K)
        self.local = local.reshape(m, K, 3, C)
        # the pattern (compiled, no sort: 0.5 s of numpy's unique at 10^4 blocks): the
        # columns of a block are contiguous and increase with the block (``index`` counts
        # the solved DOFs in order)
        solved = np.flatnonzero(index >= 0)
        assert np.array_equal(index[solved], np.arange(n)), "the solved DOFs counted in order"
        col_block = np.empty(n, dtype=np.int64)
        col_block[index[solved]] = solved // 6
        nb = model.blocks.count
        count = np.bincount(col_block, minlength=nb).astype(np.int64)
        start = np.zeros(nb, dtype=np.int64)
        first = np.flatnonzero(count)
        start[first] = np.searchsorted(col_block, first)
        blocks = np.where(cols >= 0, col_block[np.maximum(cols, 0)], -1)
        b_lo = np.where(blocks < 0, nb, blocks).min(axis=1)
        b_hi = blocks.max(axis=1)
        pair = (b_lo < b_hi) & (b_lo < nb)
        keys = np.unique(b_lo[pair] * nb + b_hi[pair])
        bptr = np.searchsorted(keys // nb, np.arange(nb + 1)).astype(np.int64)
        bnbr = (keys % nb).astype(np.int64)
        indptr, indices, self.slot = cones.normal_pattern(
            np.ascontiguousarray(cols, dtype=np.int64), col_block, start, count, bptr, bnbr
        )
        self.indptr = indptr.astype(np.int32)
        self.indices = indices
        self.diagonal = indptr[:-1].copy()  # each row starts on its diagonal
        self.nnz = int(indptr[-1])
        self._handle: PardisoHandle | None = None  # of the last matrix factorized
        #: seconds of the numeric factorizations and of the solves
        self.seconds = [0.0, 0.0]

    def assemble(self, w: np.ndarray, beta: np.ndarray, shift: float) -> sparse.csr_matrix:
        """The upper triangle of ``G^T W^2 G + shift I`` (W: the scalings, ``cones``)."""
        data = cones.normal_entries(self.local, w, beta, self.slot, self.nnz)
        data[self.diagonal] += shift
        return sparse.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def factor(self, N: sparse.csr_matrix, threads: int) -> None:
        """Cholesky (PARDISO's mtype 2), and from its first refused pivot on, LDL^T with
        perturbed pivots (mtype -2): near the optimum the stuck corners make N positive
        definite in exact arithmetic only. Cholesky is tried first because it is the cheaper
        factorization and solve (docs/limit_analysis.md, "Speed")."""
        from masonry_dem.solvers.factorization import SingularMatrix

        if self._handle is None:
            self._open(2, N, threads)
        assert self._handle is not None
        self._handle.threads = threads
        t0 = time.perf_counter()
        try:
            np.copyto(self._handle.values, N.data)
            self._handle.call(22)
        except SingularMatrix:
            if self._handle.mtype != 2:
                raise
            log.debug("normal-equation IPM: Cholesky refused a pivot; LDL^T from here on")
            self.release()
            self._open(-2, N, threads)
            np.copyto(self._handle.values, N.data)
            self._handle.call(22)
        self.seconds[0] += time.perf_counter() - t0

    def _open(self, mtype: int, N: sparse.csr_matrix, threads: int) -> None:
        """A PARDISO handle of ``mtype`` on N's pattern and its analysis (METIS, phase 11),
        with no refinement inside PARDISO (ours is on N) and, for LDL^T, pivots perturbed
        by 1e-8."""
        from masonry_dem.solvers.factorization import PardisoHandle

        options = {2: 2, 8: 0, **({10: 8} if mtype == -2 else {})}
        self._handle = PardisoHandle(self.indptr, self.indices, self.n, mtype, options, threads)
        np.copyto(self._handle.values, N.data)
        self._handle.call(11)

    def solve(self, b: np.ndarray) -> np.ndarray:
        assert self._handle is not None
        t0 = time.perf_counter()
        try:
            return np.ascontiguousarray(self._handle.call(33, b)).reshape(b.shape)
        finally:
            self.seconds[1] += time.perf_counter() - t0

    def release(self) -> None:
        if self._handle is not None:
            self._handle.release()
            self._handle = None


# --------------------------------------------------------------------------- the iteration
def _w(w: np.ndarray, beta: np.ndarray, x: np.ndarray, power: int) -> np.ndarray:
    """W^power x per cone (x: (p, 3))."""
    out = np.empty_like(x)
    cones.apply_w(w, beta, np.ascontiguousarray(x), power, out)
    return out


@dataclass
class _Dropped:
    """The equilibrium rows of the DOFs held at zero (``drop``): ``GT`` (their rows of
    G^T), and their entries of l and c. The certified forces must balance there too."""

    GT: sparse.csr_matrix
    ell: np.ndarray
    c: np.ndarray
    lift: np.ndarray  # the solved cone of every cone (``_distinct_cones``)
    share: np.ndarray  # the share of that cone's force each carries
    #: a reflection that swaps blocks (``pairs``): the image of every solved cone and the
    #: signs (1, +-1, +-1) its components take there; None otherwise
    image: tuple[np.ndarray, np.ndarray] | None = None

    def spread(self, z: np.ndarray) -> np.ndarray:
        """The forces of every cone from those of the solved ones."""
        return z[self.lift] * self.share[:, None]

    def symmetric(self, z: np.ndarray) -> np.ndarray:
        """The mean of the forces and their mirror image: the reduced equilibrium is kept,
        and forces symmetric in a symmetric model balance every DOF (``mirror``)."""
        if self.image is None:
            return z
        cone, sign = self.image
        return 0.5 * (z + z[cone] * sign)


@dataclass
class _Kinematic:
    """The problem in the iteration's terms: ``min c . u`` s.t. ``l . u = 1``, ``G u`` in
    the cones, and its normal matrix."""

    G: sparse.csr_matrix
    GT: sparse.csr_matrix
    ell: np.ndarray
    c: np.ndarray

    normal: _NormalMatrix
    shift: float
    threads: int
    dropped: _Dropped

    @property
    def cones(self) -> int:
        return self.G.shape[0] // 3


#: a direction (du, dy, ds, dz)
_Step = tuple[np.ndarray, float, np.ndarray, np.ndarray]


@dataclass
class _Point:
    """An iterate: the mechanism u, the dual y of the live-work row, the cone slacks s
    (``= G u`` at convergence) and the cone duals z (the point forces)."""

    u: np.ndarray
    y: float
    s: np.ndarray
    z: np.ndarray

    def moved(self, step: _Step, alpha: float) -> _Point:
        du, dy, ds, dz = step
        return _Point(
            self.u + alpha * du, self.y + alpha * dy, self.s + alpha * ds, self.z + alpha * dz
        )


def solve_kinematic_normal(
    problem: Problem,
    grid: int,
    threads: int = THREADS,
    max_iterations: int = MAX_ITERATIONS,
    drop: np.ndarray | None = None,
    pairs: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> tuple[Solution, np.ndarray, int, Bracket] | None:
    """The kinematic SOCP of ``problem`` on the normal equations; None where it does not
    reach a certified bracket (the caller then solves with Clarabel). ``drop`` (6n,) bool:
    DOFs held at zero velocity (``mirror.mirror_dofs``); ``pairs``: a reflection that swaps
    blocks (``mirror.mirror_pairs``), the mechanism sought among its symmetric ones
    (``mirror.symmetric_basis``); either way the bracket is still certified on the whole
    problem. Returns the solution in ``kinematic.solve_kinematic_clarabel``'s layout, the
    mechanism u (every free DOF), the points per interface and the bracket."""
    try:
        import pypardiso  # noqa: F401
    except ImportError:
        return None
    t0 = time.process_time()
    model = problem.model
    G_all = corner_velocity_rows(problem, grid).tocsr()
    free = np.flatnonzero(problem.free)
    K_all = G_all.shape[0] // 3 // max(model.interfaces.count, 1)
    norm = max(float(np.linalg.norm(problem.live)), 1e-300)
    ell_all, c_all = problem.live / norm, -problem.rhs / norm
    index = np.full(model.n_dofs, -1)
    P = None
    dof_columns = None
    keep = np.ones(free.size, dtype=bool) if drop is None else ~drop[free]
    if pairs is None:
        G_keep = G_all[:, keep].tocsr()
        index[free[keep]] = np.arange(int(keep.sum()))
        ell, c = ell_all[keep], c_all[keep]
        rest = (G_all[:, ~keep].T.tocsr(), ell_all[~keep], c_all[~keep])
    else:
        from .mirror import symmetric_basis

        P, kept_dofs, dof_columns = symmetric_basis(problem, pairs)
        G_keep = (G_all @ P).tocsr()
        # every cone kept, each paired with its mirror image for the certificate
        image = _mirror_cones(G_keep, pairs[2], K_all)
        if image is None:  # a corner with no image: every DOF instead (never Clarabel's
            # memory for want of a pairing)
            log.info("normal-equation IPM: the mirror's corners do not pair; every DOF")
            return solve_kinematic_normal(problem, grid, threads, max_iterations, drop, None)
        index[kept_dofs] = np.arange(kept_dofs.size)
        ell, c = P.T @ ell_all, P.T @ c_all
        rest = (G_all.T.tocsr(), ell_all, c_all)  # the equilibrium of every free DOF
    if pairs is None:
        kept, lift, share, K = _distinct_cones(G_keep, model.interfaces.count, K_all)
        image = None
    else:
        kept = lift = np.arange(G_keep.shape[0] // 3)
        share, K = np.ones(kept.size), K_all
    G = G_keep[(3 * kept[:, None] + np.arange(3)).ravel()].tocsr()
    p = G.shape[0] // 3
    normal = _NormalMatrix(G, model, index, K, dof_columns)
    identity = (np.tile([1.0, 0.0, 0.0], (p, 1)), np.ones(p))  # W = I
    # a shift at rounding size keeps N definite where a DOF meets no corner
    shift = 1e-12 * float(normal.assemble(*identity, 0.0).diagonal().max(initial=1.0))
    dropped = _Dropped(*rest, lift, share, image)
    kin = _Kinematic(G, G.T.tocsr(), ell, c, normal, shift, threads, dropped)
    try:
        out = _iterate(kin, max_iterations, lambda_cap(problem.live, problem.rhs))
    except Exception as exc:  # noqa: BLE001 (PARDISO's errors are plain exceptions)
        log.info("normal-equation IPM: %s; Clarabel instead", exc)
        return None
    finally:
        log.debug("PARDISO: factorizations %.2f s, solves %.2f s", *normal.seconds)
        normal.release()
    if out is None:
        return None
    bracket, point, iterations = out
    if bracket.upper < 0 or bracket.upper >= lambda_cap(problem.live, problem.rhs) * (1 - 1e-3):
        return None  # no statics under the dead load, or no mechanism: Clarabel's words
    seconds = time.process_time() - t0
    u = np.zeros(free.size)
    if P is None:
        u[keep] = point.u / float(kin.ell @ point.u)
    else:
        u = P @ (point.u / float(kin.ell @ point.u))
    mu_f = np.repeat(model.friction, K_all)
    z = dropped.spread(bracket.forces)
    x = np.column_stack([norm * z[:, 0], -norm * mu_f * z[:, 1], -norm * mu_f * z[:, 2]]).ravel()
    detail = (
        f"normal-equation IPM{_reduction_words(drop, pairs)}: "
        f"lambda in [{bracket.lower:.9g}, {bracket.upper:.9g}] "
        f"({iterations} iterations, {seconds:.2f} s CPU)"
    )
    sol = Solution(
        "optimal", bracket.upper, x, u, detail, iterations, 0.0, (bracket.lower, bracket.upper)
    )
    return sol, u, K_all, bracket


def _mirror_cones(
    G: sparse.csr_matrix, interface_image: np.ndarray, K: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """The image of every cone under a reflection that swaps blocks, and its signs: on the
    symmetric mechanisms (``G`` = the corner rows times the symmetric basis) the rows of a
    corner's image are its own rows with the tangential ones' signs flipped as the
    reflection flips the interface's axes. Found among the image interface's K corners by
    the rows' products with a random vector; None where some corner has no image."""
    p = G.shape[0] // 3
    m = p // K
    if K > 4:  # the associative problem's 2 x 2 corners; finer grids are not paired here
        return None
    h = (G @ np.random.default_rng(1).standard_normal(G.shape[1])).reshape(m, K, 3)
    hi = h[interface_image]  # (m, K, 3): the image interface's corners
    diff = np.abs(np.abs(h[:, :, None, :]) - np.abs(hi[:, None, :, :])).sum(axis=3)
    diff += np.abs(h[:, :, None, 0] - hi[:, None, :, 0])  # the normal row keeps its sign
    # one permutation of the K corners an interface (corners with equal rows tie: the one
    # that is its own inverse where the interface is its own image, the inverse of its
    # image's where the two differ)
    perms = np.array(list(itertools.permutations(range(K))))
    cost = diff[:, np.arange(K)[None, :], perms].sum(axis=2)  # (m, K!)
    itself = interface_image == np.arange(m)
    involutive = np.all(perms[np.arange(len(perms))[:, None], perms] == np.arange(K), axis=1)
    cost[np.ix_(itself, ~involutive)] = np.inf
    choice = np.argmin(cost, axis=1)
    best = perms[choice]  # (m, K)
    later = interface_image < np.arange(m)  # take the inverse of the first of each pair
    inverse = np.argsort(best[interface_image[later]], axis=1)
    best[later] = inverse
    scale = max(float(np.abs(h).max(initial=0.0)), 1e-300)
    worst = float(np.take_along_axis(diff, best[:, :, None], axis=2).max(initial=0.0))
    if worst > 1e-9 * scale:
        return None
    cone = (interface_image[:, None] * K + best).ravel()
    matched = hi[np.arange(m)[:, None], best]  # (m, K, 3)
    sign = np.where(h * matched < 0, -1.0, 1.0).reshape(p, 3)
    sign[:, 0] = 1.0
    if not np.array_equal(cone[cone], np.arange(p)):
        return None
    return cone, sign


def _reduction_words(drop: np.ndarray | None, pairs: tuple | None) -> str:
    if pairs is not None:
        return " on the mechanisms symmetric about a plane that swaps blocks in pairs"
    return "" if drop is None else " on the mirror-symmetric mechanisms"


def _distinct_cones(
    G: sparse.csr_matrix, m: int, K: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The cones of G that differ, when every interface has the same number K' of them (the
    corners on either side of a mirror plane move alike): (kept cones, the kept cone of
    every cone, the share of its force each carries, K'). Equal rows are told apart by
    their product with a random vector (equal rows give equal products to the bit)."""
    p = G.shape[0] // 3
    every = np.arange(p)
    same = (every, every, np.ones(p), K)
    if m == 0 or p != m * K:
        return same
    h = (G @ np.random.default_rng(0).standard_normal(G.shape[1])).reshape(p, 3)
    keys = np.column_stack([np.repeat(np.arange(m), K).astype(float), h])
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    per = np.bincount(np.repeat(np.arange(m), K)[first], minlength=m)
    if first.size == p or np.any(per != per[0]):
        return same
    order = np.argsort(first)
    position = np.empty(first.size, dtype=np.int64)
    position[order] = np.arange(first.size)
    lift = position[inverse]
    share = 1.0 / np.bincount(inverse)[inverse]
    return first[order], lift, share, int(per[0])


def _start(kin: _Kinematic) -> _Point:
    """Clarabel's start: the least-squares u with ``l . u = 1`` and the least-norm z, each
    shifted into the cones."""
    p = kin.cones
    kin.normal.factor(
        kin.normal.assemble(np.tile([1.0, 0.0, 0.0], (p, 1)), np.ones(p), kin.shift), kin.threads
    )
    w = kin.normal.solve(np.column_stack([kin.ell, kin.c]))
    u = w[:, 0] / (kin.ell @ w[:, 0])
    y = float(kin.ell @ w[:, 1]) / float(kin.ell @ w[:, 0])
    s = (kin.G @ u).reshape(-1, 3)
    z = (kin.G @ (w[:, 1] - y * w[:, 0])).reshape(-1, 3)
    for x in (s, z):
        gap = float(-_cone_margin(x).min())
        if gap >= 0:
            x[:, 0] += 1.0 + gap
    return _Point(u, y, s, z)


@dataclass
class _Newton:
    """The Newton system of one iterate, its normal matrix factorized: the cone scalings
    (``w, beta``, and the scaled point ``lam``), the residuals and ``N^-1 l``."""

    kin: _Kinematic
    w: np.ndarray
    beta: np.ndarray
    lam: np.ndarray
    r_d: np.ndarray  # c - l y - G^T z
    r_e: float  # 1 - l . u
    r_p: np.ndarray  # G u - s
    ninv_l: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def rhs(self, r_c: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray]:
        """(W d_c, b) for the complementarity target r_c (``lam o (W ds + W^-1 dz) = r_c``)
        and the residuals times ``scale``: ``N du - l dy = b``."""
        w, beta, GT = self.w, self.beta, self.kin.GT
        Wd = _w(w, beta, cones.jordan_solve(self.lam, r_c), 1)
        if scale == 0:  # a corrector: the complementarity alone
            return Wd, GT @ Wd.ravel()
        Sr_p = _w(w, beta, self.r_p.reshape(-1, 3), 2).ravel()
        return Wd, GT @ (Wd.ravel() - scale * Sr_p) - scale * self.r_d

    def step(self, Wd: np.ndarray, x: np.ndarray, scale: float) -> _Step:
        """The direction from ``x = N^-1 b``: the border's dy by its Schur complement, then
        ``ds = G du + r_p`` and ``dz = W d_c - W^2 ds``."""
        ell = self.kin.ell
        dy = (scale * self.r_e - ell @ x) / (ell @ self.ninv_l)
        du = x + dy * self.ninv_l
        ds = self.kin.G @ du
        if scale != 0:
            ds += scale * self.r_p
        ds = ds.reshape(-1, 3)
        return du, float(dy), ds, Wd - _w(self.w, self.beta, ds, 2)


def _iterate(kin: _Kinematic, max_iterations: int, cap: float):
    """Mehrotra's predictor-corrector from Clarabel's start; (bracket, iterate, iterations)
    of the first iterate whose certified bracket is within ``BRACKET``, or None."""
    G, GT, ell, c, normal = kin.G, kin.GT, kin.ell, kin.c, kin.normal
    p = kin.cones
    pt = _start(kin)
    start_residual = max(float(np.abs(G @ pt.u - pt.s.ravel()).max(initial=0.0)), 1e-300)
    e = np.zeros((p, 3))
    e[:, 0] = 1.0
    for it in range(1, max_iterations + 1):
        if spent():  # the analysis's time budget (``budget``)
            log.info("normal-equation IPM: the time budget ran out at iteration %d", it)
            return None
        mu = float(np.einsum("ij,ij->", pt.s, pt.z)) / p
        w, beta, lam = cones.nt_scaling(pt.s, pt.z)
        newton = _Newton(
            kin,
            w,
            beta,
            lam,
            c - ell * pt.y - GT @ pt.z.ravel(),
            1.0 - float(ell @ pt.u),
            (G @ pt.u) - pt.s.ravel(),
        )
        normal.factor(normal.assemble(w, beta, kin.shift), kin.threads)
        upper, lower = float(c @ pt.u), pt.y
        report("interior point", it, lower, upper)
        if abs(upper - lower) <= 1e-5 * max(abs(upper), 1e-3):
            bracket = _certify(kin, w, beta, pt)
            if bracket is not None and bracket.width <= BRACKET:
                return bracket, pt, it
        lam_lam = cones.jordan(lam, lam)
        Wd, b = newton.rhs(-lam_lam, 1.0)  # predictor (affine scaling)
        both = normal.solve(np.column_stack([ell, b]))
        newton.ninv_l = both[:, 0]
        aff = newton.step(Wd, both[:, 1], 1.0)
        alpha = min(1.0, cones.max_step(pt.s, aff[2]), cones.max_step(pt.z, aff[3]))
        sigma = float(np.einsum("ij,ij->", pt.s + alpha * aff[2], pt.z + alpha * aff[3])) / p / mu
        sigma = min(max(sigma, 0.0), 1.0) ** 3
        # Mehrotra's corrector
        second = cones.jordan(_w(w, beta, aff[2], 1), _w(w, beta, aff[3], -1))
        Wd, b = newton.rhs(-lam_lam - second + sigma * mu * e, 1.0 - sigma)
        d = newton.step(Wd, normal.solve(b), 1.0 - sigma)
        alpha = STEP_FRACTION * min(1.0, cones.max_step(pt.s, d[2]), cones.max_step(pt.z, d[3]))
        d, alpha = _centrality_correctors(newton, pt, d, alpha, sigma * mu)
        log.debug(
            "IPM %d: c.u %.9g y %.9g mu %.2e |r_d| %.2e |r_p| %.2e sigma %.3f alpha %.3f",
            it,
            upper,
            lower,
            mu,
            float(np.abs(newton.r_d).max()),
            float(np.abs(newton.r_p).max()),
            sigma,
            alpha,
        )
        if not (np.isfinite(alpha) and all(np.all(np.isfinite(x)) for x in d)) or alpha < 1e-8:
            log.info("normal-equation IPM: the step stalled at iteration %d", it)
            return None
        pt = pt.moved(d, alpha)
        # past the cap: no mechanism below it (Clarabel certifies it) - once the iterate is
        # nearly a mechanism: the infeasible early iterates of large walls pass it on their
        # way (c . u 3 500 at 10^4 blocks, 7 000 at 3 x 10^4; at 10^5 it sent the wall to
        # Clarabel, which filled the memory)
        near = newton_residual(newton) <= FEASIBLE * start_residual
        if (abs(float(c @ pt.u)) > cap and near) or pt.y > cap:  # statics past the cap too
            return None
    log.info("normal-equation IPM: no certified bracket within %.0e in %d steps", BRACKET, it)
    return None


#: Gondzio's multiple centrality correctors (Gondzio 1996, as HiGHS's and MOSEK's interior
#: point methods use them), each one more solve with the factorization at hand: at most this
#: many an iteration. Measured (``python benchmarks/bench_limit_analysis.py --scale``, one
#: run, one thread): 10^4 blocks out of plane 46 -> 35 iterations, 14.2 -> 12.5 s; in plane
#: 62 -> 52, 4.6 -> 4.2 s; two or three save one or two iterations more and cost as much in
#: solves (docs/limit_analysis.md, "Speed")
CORRECTORS = 1
#: a corrector aims at the step ``1.5 alpha + 0.1`` and moves the scaled products of that
#: trial point into [BETA_MIN, BETA_MAX] times the centring target sigma mu
_BETA_MIN, _BETA_MAX = 0.1, 10.0


def _centrality_correctors(
    newton: _Newton, pt: _Point, d: _Step, alpha: float, target: float
) -> tuple[_Step, float]:
    """Gondzio's multiple centrality correctors on Mehrotra's direction ``d`` (its step
    ``alpha``): each aims at a longer step, clips the scaled complementarity products of
    the trial point into a box about ``target`` (the centring mu), and is kept if the step
    grows enough. One solve each with the factorization at hand."""
    w, beta = newton.w, newton.beta
    for _ in range(CORRECTORS):
        if alpha >= STEP_FRACTION * 0.999:
            break
        trial = min(1.0, 1.5 * alpha + 0.1)
        t = cones.centrality_correction(
            w, beta, pt.s, pt.z, d[2], d[3], trial, _BETA_MIN * target, _BETA_MAX * target
        )
        Wd, b = newton.rhs(t, 0.0)
        c = newton.step(Wd, newton.kin.normal.solve(b), 0.0)
        d2 = (d[0] + c[0], d[1] + c[1], d[2] + c[2], d[3] + c[3])
        alpha2 = STEP_FRACTION * min(1.0, cones.max_step(pt.s, d2[2]), cones.max_step(pt.z, d2[3]))
        if alpha2 < alpha + 0.1 * (trial - alpha):
            break
        d, alpha = d2, alpha2
    return d, alpha


#: the primal residual (``G u - s``), relative to the start's, below which an iterate's
#: ``c . u`` above the cap of lambda means no mechanism
FEASIBLE = 1e-6


def newton_residual(newton: _Newton) -> float:
    """The largest primal residual ``|G u - s|`` of the iterate the Newton system was made at."""
    return float(np.abs(newton.r_p).max(initial=0.0))


def _certify(kin: _Kinematic, w: np.ndarray, beta: np.ndarray, pt: _Point) -> Bracket | None:
    """The bracket of the iterate ``pt`` (module docstring), or None where either bound
    fails its check. ``w, beta``: the scalings of ``pt``, whose normal matrix is factorized."""
    G, GT, ell, c = kin.G, kin.GT, kin.ell, kin.c
    lu = float(ell @ pt.u)
    if lu <= 0:
        return None
    v = (G @ pt.u).reshape(-1, 3) / lu
    scale = float(np.abs(v).max(initial=0.0))
    violation = max(0.0, -float(_cone_margin(v).min())) / max(scale, 1e-300)
    r = c - ell * pt.y - GT @ pt.z.ravel()
    v_w = np.zeros_like(r)
    for _ in range(2):  # the correction, refined once on the unshifted N = G^T S G
        v_w += kin.normal.solve(r - GT @ _w(w, beta, (G @ v_w).reshape(-1, 3), 2).ravel())
    z2 = pt.z + _w(w, beta, (G @ v_w).reshape(-1, 3), 2)
    out = kin.dropped
    z2 = out.symmetric(z2)
    rest = np.concatenate(
        [c - ell * pt.y - GT @ z2.ravel(), out.c - out.ell * pt.y - out.GT @ out.spread(z2).ravel()]
    )
    residual = float(np.linalg.norm(rest)) / max(
        float(np.hypot(np.linalg.norm(c), np.linalg.norm(out.c))), 1e-300
    )
    # inside the cones to rounding (forces on a cone's edge are admissible)
    inside = float(_cone_margin(z2).min()) >= -1e-12 * float(np.abs(z2).max(initial=0.0))
    upper = float(c @ pt.u) / lu
    log.debug(
        "certificate: upper %.9g (violation %.1e), lower %.9g (residual %.1e, inside %s)",
        upper,
        violation,
        pt.y,
        residual,
        inside,
    )
    if violation > ADMISSIBLE or residual > EQUILIBRIUM or not inside:
        return None
    return Bracket(pt.y, upper, violation, residual, z2)
