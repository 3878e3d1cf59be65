"""The frozen-capacity LP of the non-associative iteration by column generation
(Dantzig-Wolfe): the same optimum as the full LP, on a master of a few thousand columns.

The full LP (``backends.solve_highs`` with the capacity rows) carries, at each of the K grid
points p of each interface, D pyramid edge multipliers ``g_pd >= 0`` with ``sum_d g_pd <=
cap_p``: K x D columns and K capacity rows an interface. The point's
shear lies in ``cap_p conv{0, e_1 .. e_D}``, so the friction an interface can carry is the
Minkowski sum of these polytopes over its points, whose vertices are the *patterns*: one
choice per point, an edge d_p or none, carrying ``sum_p cap_p E_{p d_p}``. Every point
of that sum is a convex combination of patterns, so the LP

    max lambda  s.t.  E_n c + sum_q theta_q P_q - lambda live = rhs,
                      sum_{q of interface i} theta_q <= 1,  c, theta >= 0

(``E_n`` the corner compressions, ``P_q`` the columns of the patterns) has the full LP's
optimum once it holds every pattern; it has one row an interface besides equilibrium. Only a few patterns
are needed, and the duals ``y`` of the equilibrium rows and ``w`` of the convexity rows find
the missing ones: the best pattern of interface i under ``y`` takes at each point the edge of
largest ``v_pd = y . E_pd`` if positive (none otherwise); its reduced cost (minimisation)
is ``-gain_i - w_i`` with ``gain_i = sum_p cap_p max(0, max_d v_pd)``, all interfaces
priced in one sparse product ``E_s^T y``. The restricted master's optimum is a lower bound
of the full LP's, and since each interface's thetas sum to at most one, the Lagrangian
bound ``lambda_full <= lambda + sum_i max(0, gain_i + w_i) / scale`` (``scale`` the
objective's coefficient of lambda) is an upper one: the rounds stop when that gap is
below ``rtol`` lambda (``STALL_RTOL`` where nothing new prices out), so the answer is the
full LP's to that relative tolerance, certified by the duals, not assumed.

The master is kept in one ``highspy`` model, so each round's primal simplex starts from the
previous round's basis (scipy's ``linprog`` has no warm start; it is the fallback where
highspy is missing). Where the master has no equilibrium (the
starting patterns cannot carry the dead load) or the rounds run out, the full LP is solved
instead, so the status is always the full LP's.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy import sparse

from .backends import solve_highs
from .budget import HIGHS_IPM_ITERATIONS, HIGHS_SIMPLEX_ITERATIONS, solver_seconds
from .formulation import Solution, lambda_cap, objective_scale

log = logging.getLogger(__name__)

#: the rounds stop when the certified gap of lambda is below this fraction of lambda. Not
#: smaller: HiGHS's duals are accurate to its dual feasibility tolerance (1e-7 on its scaled
#: problem), and below it the gap stalls while each round adds patterns that differ only at
#: points of near-zero slip (docs/limit_analysis.md)
PRICING_RTOL = 1e-7
#: rounds of pricing before the full LP is solved instead (several times the rounds the
#: LPs measured took)
MAX_ROUNDS = 100
#: the gap accepted when every pattern that prices out is in the master already: HiGHS
#: then holds its basis optimal to its own tolerances, and more rounds add the same
#: patterns again. 100x below the non-associative iteration's own tolerance (1e-3);
#: larger, the full LP
STALL_RTOL = 1e-5


@dataclass
class FrozenFriction:
    """The frozen friction of one iteration: ``E_s`` (n_eq, m K D) the equilibrium columns
    of the pyramid edges (unit multiplier) at the K points of each of the m interfaces,
    point-major then edge, and ``cap`` (m K,) the points' frozen compressions."""

    E_s: sparse.csc_matrix
    cap: np.ndarray
    m: int
    K: int
    D: int

    def columns(self, choice: np.ndarray, owner: np.ndarray) -> sparse.csc_matrix:
        """The master's columns of the patterns ``choice`` (q, K), an edge or -1 per point,
        of interfaces ``owner`` (q,)."""
        q, K, D = choice.shape[0], self.K, self.D
        points = owner[:, None] * K + np.arange(K)[None, :]
        on = choice >= 0
        rows = (points * D + np.where(on, choice, 0))[on]
        cols = np.broadcast_to(np.arange(q)[:, None], (q, K))[on]
        S = sparse.csc_matrix((self.cap[points[on]], (rows, cols)), shape=(self.E_s.shape[1], q))
        return (self.E_s @ S).tocsc()

    def best(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The best pattern of every interface under the duals ``y``: (m, K) edges (-1 where
        no edge does positive work) and (m,) its gain ``sum_p cap_p max(0, max_d v_pd)``."""
        v = (self.E_s.T @ y).reshape(self.m, self.K, self.D)
        edge = np.argmax(v, axis=2)
        top = np.take_along_axis(v, edge[..., None], axis=2)[..., 0]
        gain = (np.maximum(top, 0.0) * self.cap.reshape(self.m, self.K)).sum(axis=1)
        return np.where(top > 0, edge, -1), gain

    def translations(self) -> tuple[np.ndarray, np.ndarray]:
        """Patterns that slide each interface along each edge at every point: (m D, K), and
        their interfaces (m D,). They carry any shear the pyramid carries, so the first
        master has the dead load's equilibrium wherever it needs no torsion."""
        choice = np.repeat(np.tile(np.arange(self.D), self.m)[:, None], self.K, axis=1)
        return choice, np.repeat(np.arange(self.m), self.D)


@dataclass
class Patterns:
    """A working set carried from one iteration to the next: the patterns (q, K) and their
    interfaces (q,); re-evaluated on the next iteration's points and capacities."""

    choice: np.ndarray
    owner: np.ndarray


@dataclass
class ColumnStats:
    """What the column generation did in one LP: pricing ``rounds``, ``columns`` of the
    master at the end (patterns), and whether it fell back on the ``full`` LP."""

    rounds: int = 0
    columns: int = 0
    full: bool = False


def solve_frozen_columns(
    E_n: sparse.csc_matrix,
    friction: FrozenFriction,
    live: np.ndarray,
    rhs: np.ndarray,
    start: Patterns | None,
    duals: np.ndarray | None,
    rtol: float = PRICING_RTOL,
    max_rounds: int = MAX_ROUNDS,
) -> tuple[Solution, Patterns, ColumnStats]:
    """max lambda of the frozen-capacity LP: ``E_n`` the corner compressions' columns,
    ``friction`` the pyramid edges at the points. The first master holds the translations,
    the patterns ``start`` (the previous iteration's) and the best patterns under ``duals``
    (the previous solve's). Returns the solution in the full LP's variables (corner
    compressions, then ``g_pd``), the patterns used (for the next iteration) and the counts."""
    n_eq, nn = E_n.shape
    m = friction.m
    choice, owner = friction.translations()
    if start is not None:
        choice, owner = np.vstack([choice, start.choice]), np.concatenate([owner, start.owner])
    if duals is not None and len(duals) == n_eq:
        best, _ = friction.best(duals)
        choice, owner = np.vstack([choice, best]), np.concatenate([owner, np.arange(m)])
    scale = objective_scale(live)
    cap = lambda_cap(live, rhs)
    master = _master(E_n, live, rhs, m, scale, cap)
    master.add(friction.columns(choice, owner), owner)
    master_keys = _keys(choice, owner)
    stats = ColumnStats()
    for _ in range(max_rounds):
        q = choice.shape[0]
        solved = master.solve()
        stats.columns = q
        if solved is None:  # no equilibrium with these patterns, or trouble: the full LP
            log.debug("column generation: the master failed, the full LP instead")
            break
        x_n, lam, theta, y, w = solved
        if lam >= cap * (1 - 1e-3):  # a lower bound of the full LP's lambda: it is capped too
            return (
                Solution("unbounded", detail=f"HiGHS: lambda reached its cap {cap:.3g}"),
                Patterns(choice, owner),
                stats,
            )
        best, gain = friction.best(y)
        excess = np.maximum(gain + w, 0.0)
        gap = float(excess.sum()) / scale
        log.debug(
            "column generation round %d: lambda %.10g, gap %.3g, %d patterns, %d priced out",
            stats.rounds,
            lam,
            gap,
            q,
            int(np.count_nonzero(excess)),
        )
        priced = np.nonzero(excess > 0)[0]
        keys = _keys(best[priced], priced)
        new = priced[~np.isin(keys, master_keys)]
        size = max(abs(lam), 1e-12)
        if gap <= rtol * size or (new.size == 0 and gap <= STALL_RTOL * size):
            x = np.concatenate([x_n, edge_multipliers(friction, choice, owner, theta)])
            used = theta > 0
            return (
                Solution(
                    "optimal",
                    lam,
                    x,
                    y,
                    f"HiGHS: optimal, column generation ({stats.rounds} rounds, {q} patterns, "
                    f"gap {gap:.2g})",
                ),
                Patterns(choice[used], owner[used]),
                stats,
            )
        if new.size == 0:  # the master cannot use them: trouble, the full LP
            log.debug("column generation: a gap of %.3g with nothing new to add", gap)
            break
        choice = np.vstack([choice, best[new]])
        owner = np.concatenate([owner, new])
        master_keys = np.concatenate([master_keys, _keys(best[new], new)])
        master.add(friction.columns(best[new], new), new)
        stats.rounds += 1
    else:
        log.debug("column generation: %d rounds without closing the gap", max_rounds)
    stats.full = True
    if start is not None:
        choice, owner = start.choice, start.owner
    return solve_frozen_full(E_n, friction, live, rhs), Patterns(choice, owner), stats


def solve_frozen_full(
    E_n: sparse.csc_matrix, friction: FrozenFriction, live: np.ndarray, rhs: np.ndarray
) -> Solution:
    """The full frozen-capacity LP (HiGHS's interior point): every edge of every point a
    column, and per point ``sum_d g_pd <= cap_p``; no lambda = 0 solve first (the
    associative start checked the dead load, and the frozen capacities are those of the
    collapse, not of the dead load's equilibrium)."""
    E, C = full_lp(E_n, friction)
    k = E.shape[1]
    return solve_highs(E, live, rhs, np.zeros(k), np.full(k, np.inf), (C, friction.cap), False)


def full_lp(
    E_n: sparse.csc_matrix, friction: FrozenFriction
) -> tuple[sparse.csc_matrix, sparse.csc_matrix]:
    """The full frozen-capacity LP's equilibrium columns (corner compressions, then every
    edge of every point) and its capacity rows ``C`` (``C x <= friction.cap``)."""
    nn = E_n.shape[1]
    k = nn + friction.E_s.shape[1]
    E = sparse.hstack([E_n, friction.E_s], format="csc")
    npts, D = friction.m * friction.K, friction.D
    C = sparse.csc_matrix(
        (np.ones(npts * D), (np.repeat(np.arange(npts), D), nn + np.arange(npts * D))),
        shape=(npts, k),
    )
    return E, C


class _HighsMaster:
    """The master LP kept in one ``highspy.Highs``: columns added to it are priced from the
    previous round's basis (a hot start of the simplex), where scipy's ``linprog`` starts
    each round from scratch. Columns: the corner compressions, lambda, then the patterns;
    rows: equilibrium, then one convexity row per interface."""

    def __init__(self, E_n, live, rhs, m: int, scale: float, cap: float) -> None:
        import highspy

        # the bare binding where the package exposes it: the public class's callback layer
        # prints HiGHS's banner on stdout once per process, before any option can be set
        self.h = h = getattr(highspy, "_Highs", highspy.Highs)()
        h.setOptionValue("output_flag", False)
        h.setOptionValue("solver", "simplex")
        # the primal simplex: added columns leave the basis primal feasible, so each round
        # goes on from the last vertex (3-5x faster than HiGHS's default, the dual
        # simplex, on the walls measured in docs/limit_analysis.md)
        h.setOptionValue("simplex_strategy", 4)
        h.setOptionValue("simplex_iteration_limit", HIGHS_SIMPLEX_ITERATIONS)
        self.optimal = highspy.HighsModelStatus.kOptimal
        n_eq, nn = E_n.shape
        self.n_eq, self.nn, self.m = n_eq, nn, m
        inf = highspy.kHighsInf
        lower = np.concatenate([rhs, np.full(m, -inf)])
        upper = np.concatenate([rhs, np.ones(m)])
        h.addRows(n_eq + m, lower, upper, 0, np.zeros(0, np.int32), np.zeros(0, np.int32), [])
        A = sparse.vstack(
            [
                sparse.hstack([E_n, sparse.csc_matrix(-live.reshape(-1, 1))]),
                sparse.csc_matrix((m, nn + 1)),
            ],
            format="csc",
        )
        cost = np.zeros(nn + 1)
        cost[-1] = -scale
        upper_x = np.full(nn + 1, inf)
        upper_x[-1] = cap
        self._add(A, cost, upper_x)

    def _add(self, A: sparse.csc_matrix, cost: np.ndarray, upper: np.ndarray) -> None:
        n = A.shape[1]
        self.h.addCols(
            n,
            cost,
            np.zeros(n),
            upper,
            A.nnz,
            A.indptr[:-1].astype(np.int32),
            A.indices.astype(np.int32),
            A.data,
        )

    def add(self, P: sparse.csc_matrix, owner: np.ndarray) -> None:
        q = P.shape[1]
        convex = sparse.csc_matrix((np.ones(q), (owner, np.arange(q))), shape=(self.m, q))
        self._add(sparse.vstack([P, convex], format="csc"), np.zeros(q), np.full(q, np.inf))

    def solve(self):
        """(corner compressions, lambda, thetas, equilibrium duals, convexity duals), or None
        where the master has no optimum (its time or iteration limit among the reasons)."""
        self.h.setOptionValue("time_limit", solver_seconds())
        self.h.run()
        if self.h.getModelStatus() != self.optimal:
            return None
        sol = self.h.getSolution()
        x = np.asarray(sol.col_value)
        row = np.asarray(sol.row_dual)
        nn = self.nn
        return x[:nn], float(x[nn]), x[nn + 1 :], row[: self.n_eq], row[self.n_eq :]


class _LinprogMaster:
    """The master by scipy's ``linprog`` (HiGHS's dual simplex from scratch each round),
    where ``highspy`` is not installed."""

    def __init__(self, E_n, live, rhs, m: int, scale: float, cap: float) -> None:
        self.E_n, self.live, self.rhs, self.m = E_n, live, rhs, m
        self.scale, self.cap = scale, cap
        self.P = sparse.csc_matrix((E_n.shape[0], 0))
        self.owner = np.zeros(0, dtype=np.int64)

    def add(self, P: sparse.csc_matrix, owner: np.ndarray) -> None:
        self.P = sparse.hstack([self.P, P], format="csc")
        self.owner = np.concatenate([self.owner, owner])

    def solve(self):
        from scipy.optimize import linprog

        nn, q, m = self.E_n.shape[1], self.P.shape[1], self.m
        live = self.live.reshape(-1, 1)
        A = sparse.hstack([self.E_n, self.P, sparse.csc_matrix(-live)], format="csc")
        convex = sparse.csc_matrix(
            (np.ones(q), (self.owner, nn + np.arange(q))), shape=(m, nn + q + 1)
        )
        c = np.zeros(nn + q + 1)
        c[-1] = -self.scale
        bounds = np.zeros((nn + q + 1, 2))
        bounds[:, 1] = np.inf
        bounds[-1, 1] = self.cap
        options = {"time_limit": solver_seconds(), "maxiter": HIGHS_IPM_ITERATIONS}
        res = linprog(
            c, convex, np.ones(m), A, self.rhs, bounds=bounds, method="highs-ds", options=options
        )
        if res.status != 0:
            return None
        x = np.asarray(res.x)
        duals = np.asarray(res.eqlin.marginals), np.asarray(res.ineqlin.marginals)
        return (x[:nn], float(x[-1]), x[nn:-1], *duals)


def _master(E_n, live, rhs, m: int, scale: float, cap: float):
    """The master LP: kept in highspy (hot starts) where it is installed."""
    try:
        import highspy  # noqa: F401
    except ImportError:  # pragma: no cover - declared dependency
        return _LinprogMaster(E_n, live, rhs, m, scale, cap)
    return _HighsMaster(E_n, live, rhs, m, scale, cap)


def _keys(choice: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """A number per pattern (its edges and its interface), equal for equal patterns: a dot
    product with fixed random weights, computed the same way for every row."""
    K = choice.shape[1]
    weights = np.random.default_rng(20261125).random(K + 1)
    return (choice + 1.0) @ weights[:K] + owner * weights[K]


def edge_multipliers(
    friction: FrozenFriction, choice: np.ndarray, owner: np.ndarray, theta: np.ndarray
) -> np.ndarray:
    """``g_pd`` (m K D,) of the patterns' combination ``theta``."""
    K, D = friction.K, friction.D
    points = owner[:, None] * K + np.arange(K)[None, :]
    on = choice >= 0
    index = (points * D + np.where(on, choice, 0))[on]
    weight = (theta[:, None] * friction.cap[points])[on]
    return np.bincount(index, weights=weight, minlength=friction.E_s.shape[1])
