"""Static incremental analysis (Section 2.3 of the paper): the stiffness of the assembly is
updated as interfaces yield, interface actions are corrected onto the strength domain and the
residual is iterated away in every step.

Loads are F = F_D + lambda F_L: the dead load first, then lambda raised step by step (load
control) or one DOF driven while lambda follows (displacement control, which passes the peak).

Each equilibrium is found by Newton's method on the corrected actions, with the consistent
tangent of the interface law (:meth:`InterfaceLaw.tangent`: the paper's damaged stiffness of
Eqs. 13-14 plus the couplings that make a yielded joint's capacity grow with its compression),
safeguarded by a trust region on the displacement increment and a backtracking line search.
Newton converges in a few iterations when an equilibrium exists, so the tolerance can be tight
(1e-8 of the applied load) and a step that fails is one with no equilibrium near the last
converged state: the search runs out of descent directions (the tangent of the yielded
assembly is singular along a mechanism that the load drives), or the displacements leave the
small-displacement range. The collapse multiplier is then bracketed: [last converged, first
failed], the step is halved from the last converged state until the bracket is narrower than
``bracket_tolerance`` x lambda, and the first failure is re-tried from the end of the bracket,
so a failure caused only by a long step does not stop the analysis.

Load control cannot pass a limit point, and near a plastic plateau it creeps; so from its
first failure the curve is followed with the work-conjugate displacement of the live load
prescribed and lambda free (``continuation="work"``) until it is flat. The bracket is then
refined only if work control finds nothing above the last load step: refining it first
cost a third of the validation time in failing steps for the same peak. Newton still stops
where the path folds at a kink of the law (a joint changing state turns the path back, or
leaves a block with almost no stiffness along a mode the load does not drive), for any
increment; there work control takes a pseudo-transient step (implicit overdamped relaxation
to a slightly higher lambda, ``transient_steps``) and goes on from where it comes to rest, so
that the answer is the peak of the curve and does not move with the steps taken
(docs/solvers.md). ``rescue_time_steps`` lets dynamic relaxation take failed load steps.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numba
import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from masonry_dem._threads import kernel_threads_for
from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive.law import (
    MEMORY,
    TANGENT_METHODS,
    TENSION,
    InterfaceLaw,
    LawResponse,
)
from masonry_dem.model import Model
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.factorization import Factorizer, SingularMatrix, analyse

if TYPE_CHECKING:
    from masonry_dem.solvers.dynamic_relaxation import DynamicRelaxation

log = logging.getLogger(__name__)

#: Newton converges fast when an equilibrium is near: a search that has not halved the
#: residual in _STALL_WINDOW iterations either sits at a local minimum of |R| away from
#: equilibrium or drifts along a mechanism (equal corrections at a nearly constant residual,
#: the displacements growing without bound): no equilibrium near the last converged state
_STALL_WINDOW = 8
_STALL_DECREASE = 0.5
#: largest tangent floor (fraction of the elastic stiffness) of the Levenberg-Marquardt fallback
_MAX_FLOOR = 1e-3
#: a factorized tangent is reused for the next correction while each full step divides the
#: residual by at least 1 / _CHORD_RATIO (modified Newton: a solve instead of a factorization)
_CHORD_RATIO = 0.25
#: a step shorter than this fraction of the Newton correction, with no joint changing state,
#: leaves the tangent as it was: the factorization is kept. Where the trust region creeps
#: along a fold (steps of 1e-10 of the correction), refactoring after each step had been a
#: sixth of all factorizations
_CREEP = 1e-3
#: a search gives up after this many cuts of its trust radius (each cut: no step along the
#: Newton direction lowered the residual, a kink of the law in the way). Over the 647
#: searches of the 18 validation cases that converged, none took more than 6 (a step of
#: 8^-6 of the correction that crosses the kink, then fast convergence with the new
#: tangent), while failing ones crept on with steps of 1e-7..1e-13 of the correction, each
#: search cutting 10-14 times before the radius fell below 1e-12 of the displacement limit
_SEARCH_CUTS = 7
#: the robust re-try of a failed load step mixes the last _ANDERSON corrections, and stops when
#: the residual has not fallen by x10 in _DIVERGENCE_WINDOW iterations with corrections that do
#: not shrink. Over all validation cases it succeeds in 4 of 114 calls, all four with this
#: window; 60 only made the failures twice as long (11 % of the validation time), 15 loses
#: two of the successes
_ANDERSON = 5
_DIVERGENCE_WINDOW = 30
CONTINUATION = ("work", "bracket")
#: a controlled displacement is reached when within this fraction of the step asked for (each
#: converged state is an exact equilibrium at its own lambda whatever the tolerance); relative
#: to the step, not to the block size, so that stiff joints (tiny displacements) are followed
#: as closely as soft ones
_CONTROL_TOLERANCE = 1e-6
#: work control gives up after this many halvings of its step in a row
_MAX_CUTS = 10
#: a work step whose iterations pass the displacement limit finds a mechanism only when it
#: does so again after this many halvings in a row: from the state where load control first
#: failed, a first step as long as the last load step may let Newton run off along a mode the
#: load does not yet drive (S13 stopped at 0.149 instead of 0.172)
_LIMIT_CUTS = 2
#: a step that converges in at most this many iterations is easy: the steps grow after it.
#: (Starting the next step from its last factorization saved 8 % of the validation time but
#: doubled the iterations of the 12 x 26 in-plane shear wall, and slowed OL1 and S15: dropped.)
_EASY_STEP = 6
#: a step whose d(lambda)/dw is below this fraction of the elastic one gains nothing
_FLAT_SLOPE = 1e-3
#: pseudo-transient step (see StaticSolver._pseudo_transient): tried once work control has
#: halved its step _TRANSIENT_AFTER times in a row (after one has failed: only where work
#: control would stop), once from each state; the first pseudo time step is
#: 1 / _TRANSIENT_START (the floor of the tangent, in units of the elastic stiffness), divided
#: by _TRANSIENT_SHRINK beyond the residual ratio after a step that lowers the residual; it
#: gives up when the residual has not halved in _TRANSIENT_WINDOW steps
_TRANSIENT_AFTER = 2
#: the pseudo-transient step relaxes to lambda x (1 + _TRANSIENT_RISE): far enough to leave
#: the fold, near enough not to jump past the peak (the bracket tolerance is no measure of
#: that: at 1e-4 the step does not leave the fold, at 2 % it passes the peak)
_TRANSIENT_RISE = 0.005
#: two failed work steps whose searches stop at lambdas this close (relative) stop at one fold
_FOLD_MATCH = 1e-3
#: after a pseudo-transient (or dynamic-relaxation) step has moved the state past a fold, work
#: control goes on with this fraction of its first step (or the present step if longer): the
#: full first step right after a fold failed 3 times in 4 on S15 (each failure ~20 iterations);
#: half of it saves 3 % of the factorizations and 10 % of the iterations of the validation set
#: (no step kept at its halved length: S34 stops 0.6 % lower, after a longer search)
_RESUME_STEP = 0.5
_TRANSIENT_START = 1e-3
_TRANSIENT_SHRINK = 0.25
_TRANSIENT_WINDOW = 30


@dataclass(frozen=True)
class StaticSettings:
    """Knobs of the static solver. Step sizes are in units of the load scale |F_D| / |F_L|
    (1 for a tilt table, where the live load is the weight turned horizontal).

    initial_step, max_step, growth: lambda increments in units of the load scale
        |F_D| / |F_L| (1 when both loads are weights; the weight per unit of a pressure),
        grown by ``growth`` after easy steps. ``max_step`` 1.0: a pressure wall collapses at
        7-26 load scales and took 60-140 steps at the former cap of 0.2.
    bracket_tolerance: collapse bracket width, relative to lambda.
    tolerance: force residual |R| / |F_D + lambda F_L| (moments measured as forces at the
        median block size) below which a state is in equilibrium.
    max_iterations: Newton iterations per attempt.
    displacement_limit: largest translation [m] still in the small-displacement range
        (None: half the smallest dimension of the blocks that can move); beyond it the step
        has found a mechanism.
    tension, memory: interface law options (see :mod:`masonry_dem.constitutive.law`).
    residual_stiffness: fraction of the elastic stiffness kept on the diagonal of the tangent.
    tangent: how the tangent of yielded joints is computed (see
        :meth:`~masonry_dem.constitutive.law.InterfaceLaw.tangent`): ``"analytic"``
        (default; the closed-form derivative of the return, 1.4x faster on S15 than
        ``"difference"``, the forward difference of every yielded joint, with the same
        lambdas to 1e-6).
    robust_iterations: budget of the second strategy (initial-stiffness iterations with
        Anderson acceleration) that re-tries a load step Newton could not solve; 0 (default)
        disables it. Since work control takes over at the first failure it changes no
        validation lambda by more than 0.2 % and costs 11 % of the time; it can help
        ``continuation="bracket"``.
    continuation: what follows the first failure of load control. ``"work"`` (default): go
        on from the last converged state under control of the work-conjugate displacement of
        the live load (lambda free), which passes limit points and long plastic plateaus,
        until the pushover curve is flat or no equilibrium is found for tiny increments; the
        collapse multiplier is the peak of the curve (if it finds nothing above the last load
        step, the load-control bracket is refined from there). ``"bracket"``: refine the
        load-control bracket and stop there.
    rescue_time_steps: budget of a dynamic relaxation of a load step that Newton could not
        solve (then polished by Newton); 0 (default) disables it. It finds equilibria Newton
        misses at kinks of the interface law, at about the cost of dynamic relaxation.
    transient_steps: budget of the pseudo-transient step that work control takes where
        Newton stops at a fold of the path (see ``StaticSolver._pseudo_transient``): lambda
        raised by 0.5 % and the state relaxed by implicit, overdamped pseudo
        time steps; 0 disables it (work control then stops there).
    stop_check_time_steps: budget of the dynamic relaxation that checks a stop of work
        control where neither Newton nor the pseudo-transient step finds an equilibrium: it
        relaxes from the last state to lambda x 1.005 and, if it comes to rest (polished by
        Newton to the static tolerance), the path goes on from there; 0 disables it. Without
        it a wall with openings (S34 with 10-course windows) stopped at lambda 0.040, below
        the overturning of the whole wall as one block (s/H = 0.067); dynamic relaxation
        finds 0.118 and the checked static path 0.147.
    """

    initial_step: float = 0.02
    max_step: float = 1.0
    growth: float = 1.5
    bracket_tolerance: float = 0.005
    refine: bool = True
    tolerance: float = 1e-8
    max_iterations: int = 40
    max_steps: int = 1000
    max_load_factor: float = math.inf
    displacement_limit: float | None = None
    tension: str = "brittle"
    memory: str = "none"
    residual_stiffness: float = 1e-9
    tangent: str = "analytic"
    robust_iterations: int = 0
    continuation: str = "work"
    rescue_time_steps: int = 0
    transient_steps: int = 100
    stop_check_time_steps: int = 4000

    def __post_init__(self) -> None:
        for name in (
            "initial_step",
            "max_step",
            "bracket_tolerance",
            "tolerance",
            "residual_stiffness",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        if self.growth < 1:
            raise ValueError(f"growth must be >= 1, got {self.growth!r}")
        if self.rescue_time_steps < 0:
            raise ValueError(f"rescue_time_steps must be >= 0, got {self.rescue_time_steps!r}")
        if self.transient_steps < 0:
            raise ValueError(f"transient_steps must be >= 0, got {self.transient_steps!r}")
        if self.stop_check_time_steps < 0:
            raise ValueError(
                f"stop_check_time_steps must be >= 0, got {self.stop_check_time_steps!r}"
            )
        if self.robust_iterations < 0:
            raise ValueError(f"robust_iterations must be >= 0, got {self.robust_iterations!r}")
        if self.max_iterations < 1 or self.max_steps < 1:
            raise ValueError("max_iterations and max_steps must be at least 1")
        if self.displacement_limit is not None and not self.displacement_limit > 0:
            raise ValueError(
                f"displacement_limit must be positive or None, got {self.displacement_limit!r}"
            )
        if self.tension not in TENSION:
            raise ValueError(f"tension must be one of {TENSION}, got {self.tension!r}")
        if self.memory not in MEMORY:
            raise ValueError(f"memory must be one of {MEMORY}, got {self.memory!r}")
        if self.tangent not in TANGENT_METHODS:
            raise ValueError(f"tangent must be one of {TANGENT_METHODS}, got {self.tangent!r}")
        if self.continuation not in CONTINUATION:
            raise ValueError(
                f"continuation must be one of {CONTINUATION}, got {self.continuation!r}"
            )


@dataclass(frozen=True)
class DisplacementControl:
    """Drive DOF ``dof`` (name, e.g. ``u3``) of ``block`` to ``target`` in ``steps`` steps."""

    block: int
    dof: str
    target: float
    steps: int = 50


@dataclass
class _Outcome:
    ok: bool
    q: np.ndarray
    load_factor: float
    response: LawResponse
    iterations: int
    reason: str = ""


@numba.njit(cache=True, parallel=True, fastmath={"contract"})
def _assemble_tangent(H_loc: np.ndarray, T: np.ndarray, terms: np.ndarray, ptr: np.ndarray):
    """The stored entries of K = sum over interfaces of H_loc^T T H_loc (12 x 12 each):
    ``out[j] = sum(B.flat[terms[ptr[j] : ptr[j + 1]]])``, added in that order from 0. The
    products run as sequential fused multiply-adds, which is what the batched BLAS products
    of numpy gave here, bit for bit; the interfaces, then the entries, are shared among the
    threads."""
    m = H_loc.shape[0]
    B = np.empty((m, 12, 12))
    for i in numba.prange(m):
        A = np.empty((12, 6))
        for r in range(12):
            for c in range(6):
                total = 0.0
                for k in range(6):
                    total += H_loc[i, k, r] * T[i, k, c]
                A[r, c] = total
        for r in range(12):
            for c in range(12):
                total = 0.0
                for k in range(6):
                    total += A[r, k] * H_loc[i, k, c]
                B[i, r, c] = total
    flat = B.reshape(-1)
    out = np.empty(ptr.size - 1)
    for j in numba.prange(ptr.size - 1):
        total = 0.0
        for t in range(ptr[j], ptr[j + 1]):
            total += flat[terms[t]]
        out[j] = total
    return out


class _TangentAssembler:
    """K_ff = H_f^T T H_f for per-interface 6x6 tangents T, with the sparsity pattern built
    once: each interface adds B = H_loc^T T H_loc (12 x 12, the DOFs of its two blocks) and
    the blocks are summed into a fixed CSC structure with one bincount."""

    def __init__(self, asm: Assembly, model: Model, order: np.ndarray | None = None) -> None:
        """``order[d]``: the row and column of free DOF d in the matrix (None: as numbered)."""
        its = model.interfaces
        m = its.count
        H = asm.H.tocoo()
        k = H.row // 6
        blk = H.col // 6
        side = (blk == its.block_j[k]).astype(np.int64)
        self.H_loc = np.zeros((m, 6, 12))
        self.H_loc[k, H.row % 6, 6 * side + H.col % 6] = H.data
        dofs = np.concatenate(
            [6 * its.block_i[:, None] + np.arange(6), 6 * its.block_j[:, None] + np.arange(6)],
            axis=1,
        )  # (m, 12)
        position = np.full(model.n_dofs, -1, dtype=np.int64)
        position[asm.free_index] = np.arange(asm.n_free) if order is None else order
        self.order = order
        self._numbering = None if order is None else np.argsort(order)
        pos = position[dofs]
        rows = np.broadcast_to(pos[:, :, None], (m, 12, 12)).ravel()
        cols = np.broadcast_to(pos[:, None, :], (m, 12, 12)).ravel()
        self.keep = np.flatnonzero((rows >= 0) & (cols >= 0))
        nf = asm.n_free
        key = cols[self.keep] * nf + rows[self.keep]  # column-major
        unique, inverse = np.unique(key, return_inverse=True)
        # the terms of each stored entry, in the order np.bincount would add them
        by_entry = np.argsort(inverse, kind="stable")
        self.terms = self.keep[by_entry]
        self.term_ptr = np.concatenate([[0], np.cumsum(np.bincount(inverse))]).astype(np.int64)
        self.indices = (unique % nf).astype(np.int32)
        counts = np.bincount(unique // nf, minlength=nf)
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        self.nnz = unique.size
        self.n = nf

    def data(self, T: np.ndarray) -> np.ndarray:
        """The stored entries of :meth:`matrix`, in its CSC order."""
        return _assemble_tangent(self.H_loc, np.ascontiguousarray(T), self.terms, self.term_ptr)

    def matrix(self, T: np.ndarray, data: np.ndarray | None = None) -> sparse.csc_matrix:
        """K_ff for the tangents T (or for entries ``data`` assembled already)."""
        if data is None:
            data = self.data(T)
        return sparse.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def symbolic(self) -> Factorizer:
        """A factorizer of :meth:`matrix`'s pattern (the backend: factorization.choose)."""
        return analyse(self.indptr, self.indices, self.n)

    def factorized(self, lu) -> _Factorized:
        """A factorization of :meth:`matrix` that solves in the DOF numbering."""
        return _Factorized(lu, self._numbering)


class _Factorized:
    """LU factors of a symmetrically permuted matrix, solving in the original numbering."""

    def __init__(self, lu, numbering: np.ndarray | None) -> None:
        self.lu = lu
        self.numbering = numbering  # numbering[i]: the DOF in row i of the factorized matrix

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.numbering is None:
            return self.lu.solve(b)
        x = np.empty_like(b)
        x[self.numbering] = self.lu.solve(b[self.numbering])
        return x


class StaticSolver:
    """Incremental-iterative solver for one model (keeps the assembly and the state)."""

    def __init__(self, model: Model, settings: StaticSettings | None = None) -> None:
        self.model = model
        self.settings = settings or StaticSettings()
        s = self.settings
        self.asm = Assembly.of(model)
        self.law = InterfaceLaw.of(model, self.asm.kbar, s.tension, s.memory)
        self._tangents = _TangentAssembler(self.asm, model)
        free = self.asm.free_index
        self.F_dead = model.dead.reshape(-1)[free]
        self.F_live = model.live.reshape(-1)[free]
        dead_norm = float(np.linalg.norm(self.F_dead))
        live_norm = float(np.linalg.norm(self.F_live))
        self.load_scale = dead_norm / live_norm if live_norm > 0 and dead_norm > 0 else 1.0
        blocks = model.blocks
        self.limit = (
            s.displacement_limit
            if s.displacement_limit is not None
            else 0.5 * model.smallest_moving_size
        )
        # residual norm: moments as forces at the median block size
        length = float(np.median(blocks.sizes))
        self._weight = np.where(free % 6 < 3, 1.0, 1.0 / length)
        self._translation = (free % 6) < 3
        self._moving_translations = free[self._translation]  # DOF numbers
        m = model.interfaces.count
        self.plastic = np.zeros((m, 6))
        self.cracked = np.zeros(m, dtype=bool)
        self.q = np.zeros(model.n_dofs)
        self.factorizations = 0
        self.iterations = 0
        self._last_increment = 0.0
        self._elastic_lu: _Factorized | None = None
        self._dr: DynamicRelaxation | None = None
        self._fronts: Factorizer | None = None  # the tangent's pattern analysed

    # ------------------------------------------------------------------ one equilibrium
    def _increment(self, q: np.ndarray) -> float:
        """Largest translation of ``q`` away from the last converged state."""
        idx = self._moving_translations
        return float(np.abs(q[idx] - self.q[idx]).max(initial=0.0))

    def _residual(self, q: np.ndarray, lam: float, dead_factor: float = 1.0):
        _, response, internal = self.law.forces(
            self.asm.H, q, self.plastic, self.cracked, self.asm.H_free_T
        )
        F_ext = dead_factor * self.F_dead + lam * self.F_live
        residual = F_ext - internal
        scale = max(float(np.linalg.norm(self._weight * F_ext)), 1e-30)
        return residual, float(np.linalg.norm(self._weight * residual)) / scale, response

    def _factor(self, response: LawResponse, floor: float | None = None) -> _Factorized:
        """LU of the tangent. The tangent is structurally symmetric with a regular diagonal
        (the residual stiffness); its pattern never changes, so it is analysed once
        (:func:`masonry_dem.solvers.factorization.analyse`: the ordering and symbolic
        factorization of the backend chosen for its size) and each tangent's entries go
        straight to a numeric factorization."""
        if floor is None:
            floor = self.settings.residual_stiffness
        T = self.law.tangent(response, floor, self.settings.tangent)
        data = self._tangents.data(T)
        self.factorizations += 1
        if self._fronts is None:
            self._fronts = self._tangents.symbolic()
        try:
            return self._tangents.factorized(self._fronts.factor(data))
        except SingularMatrix:  # exactly singular: stiffen the floor
            idx = np.arange(6)
            T[:, idx, idx] += 1e-6 * self.law.kbar
            return self._tangents.factorized(self._fronts.factor(self._tangents.data(T)))

    def _equilibrate(
        self,
        load_factor: float,
        dead_factor: float = 1.0,
        control: tuple[np.ndarray, float, float] | None = None,
        radius: float | None = None,
        damped: bool = False,
        start: np.ndarray | None = None,
    ) -> _Outcome:
        """Newton iterations from the last converged state to equilibrium at ``load_factor``
        (load control) or with the generalised displacement ``control[0] . q_free`` at
        ``control[1]`` (lambda free: displacement control of one DOF, or of the work-conjugate
        displacement of the live load), reached within ``_CONTROL_TOLERANCE`` x ``control[2]``
        (the size of the step asked for).

        Safeguards: the translation part of each correction is held within a trust radius
        (grown after full steps, cut by 8 when no step along the direction lowers the
        residual), and the step is backtracked until the residual decreases.
        """
        s = self.settings
        free = self.asm.free_index
        q = (self.q if start is None else start).copy()
        lam = load_factor
        if radius is None:
            radius = max(4.0 * self._last_increment, 1e-4 * self.limit)
        residual, rnorm, response = self._residual(q, lam, dead_factor)
        floor = s.residual_stiffness
        lu = None  # the factorized tangent, kept while it converges fast (chord steps)
        here = False  # lu was factorized at the current state
        history: list[tuple[float, float]]  # (merit, trust radius) of the iterates; set below
        budget: int
        cuts: int

        def regularise() -> bool:
            """Levenberg-Marquardt fallback: stiffen the tangent's floor (x1000, up to
            _MAX_FLOOR x kbar). A near-mechanism of the yielded assembly (a joint at zero gap
            beside a sliding one) leaves the tangent almost singular along a direction the
            residual needs; the undamped Newton step along it is huge, the trust region cuts
            it to nothing and the search stalls far from an equilibrium that exists. The
            floor changes only the search direction, never the residual, so a converged
            state is still an exact equilibrium of the law."""
            nonlocal floor, history, budget, lu, cuts
            if not damped or floor >= _MAX_FLOOR:
                return False
            assert radius is not None  # set above when not given
            floor = min(floor * 1e3, _MAX_FLOOR)
            lu = None
            cuts = 0
            history = [(rnorm + constraint_error(q), radius)]
            budget = it + s.max_iterations  # a fresh budget for the damped search
            return True

        def constraint_error(qq: np.ndarray) -> float:
            if control is None:
                return 0.0
            return abs(float(control[0] @ qq[free]) - control[1]) / max(control[2], 1e-300)

        # the merit of the start includes the control's error: a controlled step starts at
        # an equilibrium (tiny residual) one whole step away from its goal
        history = [(rnorm + constraint_error(q), radius)]
        budget = s.max_iterations
        it = 0
        cuts = 0  # cuts of the trust radius in this search
        cut = False  # the last iteration cut the radius
        direction = (np.zeros(0), 0.0)  # (dq, dlam) of the search that was cut
        live_solved: tuple[_Factorized | None, np.ndarray] = (None, np.zeros(0))  # K^-1 F_live
        cerr = constraint_error(q)  # of the present iterate q, kept with it
        while it < budget:
            it += 1
            if rnorm <= s.tolerance and cerr <= _CONTROL_TOLERANCE:
                self._last_increment = self._increment(q)
                return _Outcome(True, q, lam, response, it - 1)
            self.iterations += 1
            fresh = lu is None
            if lu is None:
                lu = self._factor(response, floor)
                here = True  # the tangent of this state (False once a step is taken with it)
            repeat = cut and not fresh  # same state, same tangent: the same direction
            cut = False
            if repeat:
                dq, dlam = direction
            else:
                dq = lu.solve(residual)
                dlam = 0.0
            if control is not None and not repeat:
                c = control[0]
                if live_solved[0] is not lu:  # once per factorization: chord steps reuse it
                    live_solved = (lu, lu.solve(self.F_live))
                a = live_solved[1]
                ca = float(c @ a)
                if abs(ca) < 1e-300:
                    return _Outcome(
                        False,
                        q,
                        lam,
                        response,
                        it,
                        "the controlled displacement does not move under the live load",
                    )
                dlam = (control[1] - float(c @ q[free]) - float(c @ dq)) / ca
                dq = dq + dlam * a
            if not np.all(np.isfinite(dq)):
                return _Outcome(False, q, lam, response, it, "singular tangent stiffness")
            size = float(np.abs(dq[self._translation]).max(initial=0.0))
            shrink = min(1.0, radius / size) if size > 0 else 1.0
            merit = rnorm + cerr
            accepted = None
            # after a cut the full step is the last backtrack of the search before it (x 1/8)
            for step in (0.5, 0.25, 0.125) if repeat else (1.0, 0.5, 0.25, 0.125):
                f = shrink * step
                q_try = q.copy()
                q_try[free] += f * dq
                lam_try = lam + f * dlam
                r_try, n_try, resp_try = self._residual(q_try, lam_try, dead_factor)
                c_try = constraint_error(q_try)
                if n_try + c_try < (1.0 - 1e-4 * f) * merit:
                    accepted = (q_try, lam_try, r_try, n_try, resp_try, c_try)
                    break
            if accepted is None and not here:  # a stale tangent: refactor before cutting
                lu = None
                continue
            if accepted is None:
                if not fresh:
                    # a search after a cut, with the tangent of this state: refactoring here
                    # would give the same matrix and the same failed search, so the radius is
                    # cut at once; that repeat still counts against the budget, which thus
                    # ends the same searches (a cut costs two iterations of it)
                    if it >= budget:
                        break
                    it += 1
                radius = min(radius, shrink * size) / 8.0
                cuts += 1
                exhausted = radius < 1e-12 * self.limit or cuts >= _SEARCH_CUTS
                if exhausted and regularise():
                    radius = max(4.0 * self._last_increment, 1e-4 * self.limit)
                    continue
                if exhausted:
                    return _Outcome(
                        False,
                        q,
                        lam,
                        response,
                        it,
                        f"no equilibrium found: no correction lowers the residual {rnorm:.2e}",
                    )
                cut, direction = True, (dq, dlam)
                continue
            if step == 1.0 and shrink < 1.0:
                radius *= 2.0
            # keep the factorization (modified Newton) while a full step divides the residual
            # by _CHORD_RATIO or more, and after a creep (a step too short to change the
            # tangent: under _CREEP of the correction, no joint changing state); otherwise the
            # next iteration refactors
            crept = shrink * step < _CREEP and np.array_equal(
                accepted[4].flags, response.flags
            )  # the same flags: the same states
            if not (
                crept or (step == 1.0 and shrink == 1.0 and accepted[3] < _CHORD_RATIO * rnorm)
            ):
                lu = None
            q, lam, residual, rnorm, response, cerr = accepted
            here = here and crept
            umax = self._increment(q)
            if not math.isfinite(umax) or umax > self.limit:
                return _Outcome(
                    False,
                    q,
                    lam,
                    response,
                    it,
                    f"displacements exceed the limit {self.limit:.3g} m (a mechanism)",
                )
            history.append((rnorm + cerr, radius))
            if len(history) > _STALL_WINDOW:
                window = history[-1 - _STALL_WINDOW :]
                steady = all(rad >= window[0][1] for _, rad in window)  # no cut in the window
                stalled = steady and history[-1][0] > (1.0 - _STALL_DECREASE) * window[0][0]
            if len(history) > _STALL_WINDOW and stalled and regularise():
                continue
            if len(history) > _STALL_WINDOW and stalled:
                return _Outcome(
                    False,
                    q,
                    lam,
                    response,
                    it,
                    f"no equilibrium found: the residual stalls at {rnorm:.2e} "
                    f"(displacement increment {umax:.2e} m)",
                )
        if rnorm <= s.tolerance and constraint_error(q) <= _CONTROL_TOLERANCE:
            self._last_increment = self._increment(q)
            return _Outcome(True, q, lam, response, it)
        return _Outcome(
            False,
            q,
            lam,
            response,
            it,
            f"no convergence in {it} iterations (residual {rnorm:.2e})",
        )

    def _robust(self, load_factor: float, start: np.ndarray | None = None) -> _Outcome:
        """Second strategy for a load step Newton could not solve: initial-stiffness
        iterations (the elastic matrix of the assembly, factorized once per analysis) with
        Anderson acceleration over the last _ANDERSON corrections, no line search.

        Newton stalls where the yielded tangent is nearly singular or flips between contact
        states of zero-gap joints; the fixed point of q <- q + K0^-1 R(q) does not depend on
        the tangent, so it converges (slowly, hence the larger budget) wherever an equilibrium
        is near. It gives up when the displacements pass the limit (a mechanism) or when the
        residual has not decreased by a tenth over _DIVERGENCE_WINDOW iterations while the
        corrections do not shrink (the iterates drift: no equilibrium)."""
        s = self.settings
        free = self.asm.free_index
        if self._elastic_lu is None:
            idx = np.arange(6)
            m = self.model.interfaces.count
            T = np.zeros((m, 6, 6))
            T[:, idx, idx] = self.law.kbar
            self.factorizations += 1
            self._elastic_lu = self._tangents.factorized(
                splu(self._tangents.matrix(T), permc_spec="COLAMD")
            )
        lu = self._elastic_lu
        x = (self.q if start is None else start)[free].copy()
        q = self.q.copy()

        def g(xx):
            q[free] = xx
            r, n, resp = self._residual(q, load_factor)
            return lu.solve(r), n, resp

        f, rnorm, response = g(x)
        xs, fs = [x.copy()], [f.copy()]
        best = (rnorm, x.copy(), response)
        hist: list[tuple[float, float]] = []
        for it in range(1, s.robust_iterations + 1):
            self.iterations += 1
            if len(xs) > 1:
                dX = np.diff(np.array(xs), axis=0).T
                dF = np.diff(np.array(fs), axis=0).T
                gamma = np.linalg.lstsq(dF, f, rcond=1e-10)[0]
                x_new = x + f - (dX + dF) @ gamma
            else:
                x_new = x + f
            if not np.all(np.isfinite(x_new)):
                xs, fs = [x.copy()], [f.copy()]
                x_new = x + f
            x = x_new
            f, rnorm, response = g(x)
            xs.append(x.copy())
            fs.append(f.copy())
            if len(xs) > _ANDERSON + 1:
                xs.pop(0)
                fs.pop(0)
            if rnorm < best[0]:
                best = (rnorm, x.copy(), response)
            q_now = self.q.copy()
            q_now[free] = x
            umax = self._increment(q_now)
            if rnorm <= s.tolerance:
                self._last_increment = umax
                return _Outcome(True, q_now, load_factor, response, it)
            if not math.isfinite(umax) or umax > self.limit:
                return _Outcome(
                    False,
                    q_now,
                    load_factor,
                    response,
                    it,
                    f"displacements exceed the limit {self.limit:.3g} m (a mechanism)",
                )
            step = float(np.abs(f[self._translation]).max(initial=0.0))
            hist.append((rnorm, step))
            if len(hist) > _DIVERGENCE_WINDOW:
                r0, s0 = hist[-1 - _DIVERGENCE_WINDOW]
                if best[0] > 0.1 * r0 and step >= s0:
                    return _Outcome(
                        False,
                        q_now,
                        load_factor,
                        response,
                        it,
                        f"no equilibrium found: the robust iterations drift (residual "
                        f"{rnorm:.2e}, correction {step:.2e} m not shrinking)",
                    )
        q_best = self.q.copy()
        q_best[free] = best[1]
        return _Outcome(
            False,
            q_best,
            load_factor,
            best[2],
            s.robust_iterations,
            f"no convergence in {s.robust_iterations} robust iterations (residual {best[0]:.2e})",
        )

    def _pseudo_transient(self, target: float, start: np.ndarray | None = None) -> _Outcome:
        """Pseudo-transient continuation to equilibrium at ``target`` from the last converged
        state (or from ``start``; displacements are measured from the last converged state): backward-Euler steps of the overdamped motion D dq/dt = R(q), with D the
        elastic stiffness of the joints (the floor of the tangent),

            (K_t + D / dt) dq = R(q),

        the pseudo time step dt grown as the residual falls (switched evolution relaxation,
        dt ~ 1 / |R|, grown faster while the residual falls) until the steps are Newton's.
        There is no line search: the residual may rise on the way.

        Work control stops where the equilibrium path folds at a kink of the law (a joint that
        changes state turns the path back in w, or a block between two sliding joints is left
        with almost no stiffness along a mode the load does not drive): no Newton correction
        lowers the residual from the last state, for any step. A damped motion goes round
        such a fold as dynamic relaxation does, to a stable equilibrium at the higher load,
        with few steps since each is implicit. Every accepted state meets the static
        tolerance on the exact residual. It fails when the displacements pass the limit
        (a mechanism), or the residual has not halved in _TRANSIENT_WINDOW steps, or the
        budget ``transient_steps`` runs out."""
        s = self.settings
        free = self.asm.free_index
        q = (self.q if start is None else start).copy()
        residual, rnorm, response = self._residual(q, target)
        floor = _TRANSIENT_START
        best = [rnorm]
        for it in range(1, s.transient_steps + 1):
            if rnorm <= s.tolerance:
                self._last_increment = self._increment(q)
                return _Outcome(True, q, target, response, it - 1)
            self.iterations += 1
            dq = self._factor(response, floor).solve(residual)
            if not np.all(np.isfinite(dq)):
                floor = min(10.0 * floor, 1.0)
                continue
            size = float(np.abs(dq[self._translation]).max(initial=0.0))
            if size > 0.1 * self.limit:  # no pseudo time step moves a block that far
                dq *= 0.1 * self.limit / size
            q_new = q.copy()
            q_new[free] += dq
            r_new, n_new, resp_new = self._residual(q_new, target)
            if not n_new < 10.0 * rnorm:  # too long a time step: repeat it shorter
                floor = min(10.0 * floor, 1.0)
                continue
            ratio = n_new / rnorm
            q, residual, rnorm, response = q_new, r_new, n_new, resp_new
            if ratio < 1.0:
                ratio *= _TRANSIENT_SHRINK
            floor = min(max(floor * ratio, s.residual_stiffness), 1.0)
            umax = self._increment(q)
            if umax > self.limit:
                return _Outcome(
                    False,
                    q,
                    target,
                    response,
                    it,
                    f"displacements exceed the limit {self.limit:.3g} m (a mechanism)",
                )
            best.append(min(best[-1], rnorm))
            if len(best) > _TRANSIENT_WINDOW and best[-1] > 0.5 * best[-1 - _TRANSIENT_WINDOW]:
                return _Outcome(
                    False,
                    q,
                    target,
                    response,
                    it,
                    f"no rest: the residual {rnorm:.2e} has not halved in "
                    f"{_TRANSIENT_WINDOW} pseudo time steps",
                )
        if rnorm <= s.tolerance:
            return _Outcome(True, q, target, response, s.transient_steps)
        return _Outcome(
            False,
            q,
            target,
            response,
            s.transient_steps,
            f"no rest in {s.transient_steps} pseudo time steps (residual {rnorm:.2e})",
        )

    def _dynamic_rescue(
        self, target: float, last: float, budget: int | None = None
    ) -> _Outcome | None:
        """Dynamic relaxation of a load step Newton could not solve, from the last converged
        state, then Newton from where it came to rest (so an accepted state meets the static
        tolerance). Newton stops at kinks of the projection (joints on the edge between two
        states) where no correction lowers the residual; the damped motion goes round them."""
        from masonry_dem.solvers.dynamic_relaxation import (
            DRSettings,
            DynamicRelaxation,
            _State,
        )

        s = self.settings
        free = self.asm.free_index
        budget = s.rescue_time_steps if budget is None else budget
        if self._dr is None or self._dr.settings.max_cycles != budget:
            self._dr = DynamicRelaxation(
                self.model,
                DRSettings(
                    tension=s.tension,
                    memory=s.memory,
                    tolerance=1e-6,
                    max_cycles=budget,
                    min_stall_window=budget // 4,
                    displacement_limit=self.limit,
                ),
            )
        start = _State(
            self.q[free].copy(),
            self.plastic.copy(),
            self.cracked.copy(),
            last,
            np.ones((self.model.interfaces.count, 6)),
        )
        relaxed = self._dr._relax_with_cuts(start, target, None)
        self.iterations += relaxed.cycles
        if not relaxed.ok:
            log.debug("dynamic rescue at lambda=%.6g failed: %s", target, relaxed.reason)
            return None
        q = self.q.copy()
        q[free] = relaxed.x
        polished = self._equilibrate(target, start=q)
        log.debug(
            "dynamic rescue at lambda=%.6g: %d time steps, Newton %s",
            target,
            relaxed.cycles,
            "ok" if polished.ok else polished.reason,
        )
        return polished if polished.ok else None

    def _accept(self, out: _Outcome, step: int, control_value: float) -> StepResult:
        rel = self.asm.relative_displacements(out.q)
        resp = out.response
        self.plastic = self.law.plastic_part(rel, resp.actions)
        self.cracked = self.law.cracked_after(self.cracked, resp)
        self.q = out.q
        return StepResult(
            step=step,
            load_factor=float(out.load_factor),
            q=out.q.reshape(-1, 6).copy(),
            actions=resp.actions.copy(),
            state=resp.state.astype(np.int32),
            utilisation=np.minimum(self.law.utilisation(resp), 1.0),
            flags=resp.flags.astype(np.int32),
            control_displacement=float(control_value),
            iterations=out.iterations,
        )

    def _control_value(self, q: np.ndarray, control_dof: int | None) -> float:
        if control_dof is None:
            return float(np.abs(q.reshape(-1, 6)[:, :3]).max(initial=0.0))
        return float(q[control_dof])

    # ------------------------------------------------------------------ analyses
    def run(
        self,
        control: DisplacementControl | None = None,
        callback: Callable[[StepResult], None] | None = None,
        monitor: tuple[int, str] | None = None,
    ) -> History:
        """Dead load, then lambda raised (load control) or a DOF driven (displacement control).

        ``monitor`` = (block, dof name) picks the displacement stored on the pushover curve
        (default: the largest block translation).
        """
        with kernel_threads_for(self.model.interfaces.count):
            return self._run(control, callback, monitor)

    def _run(
        self,
        control: DisplacementControl | None,
        callback: Callable[[StepResult], None] | None,
        monitor: tuple[int, str] | None,
    ) -> History:
        t0 = time.perf_counter()
        hist = History()
        monitor_dof = None
        if monitor is not None:
            monitor_dof = self._global_dof(*monitor)
        if control is not None:
            monitor_dof = self._global_dof(control.block, control.dof)

        def record(out: _Outcome) -> None:
            sr = self._accept(out, len(hist.steps), self._control_value(out.q, monitor_dof))
            hist.steps.append(sr)
            if callback is not None:
                callback(sr)

        # the dead-load state exists (the specimens stood): the damped fallback may be used
        dead = self._equilibrate(0.0, 1.0, radius=self.limit, damped=True)
        if not dead.ok and self.settings.transient_steps > 0 and "exceed" not in dead.reason:
            # where the damped Newton search stalls (a wall with openings, blocks settling
            # on their neighbours), an overdamped relaxation may still come to rest: from
            # where Newton stopped (often a few pseudo time steps away), else from the start
            settled = None
            if np.all(np.isfinite(dead.q)):
                settled = self._pseudo_transient(0.0, start=dead.q)
            if settled is None or not settled.ok:
                settled = self._pseudo_transient(0.0)
            log.debug(
                "dead load: Newton %s; pseudo-transient: %s",
                dead.reason,
                "ok" if settled.ok else settled.reason,
            )
            dead = (
                settled
                if settled.ok
                else replace(dead, reason=f"{dead.reason}; pseudo-transient: {settled.reason}")
            )
        if not dead.ok:
            reason = f"no equilibrium under the dead load: {dead.reason}"
            zero = self._residual(np.zeros_like(self.q), 0.0, 0.0)[2]
            record(_Outcome(True, np.zeros_like(self.q), 0.0, zero, dead.iterations))
            return self._finish(hist, "failed", reason, t0)
        record(dead)
        if not np.any(self.F_live):
            return self._finish(
                hist, "completed", "no live load: the dead-load state is the answer", t0
            )
        if control is None:
            self._load_control(hist, record)
        else:
            assert monitor_dof is not None  # the control DOF, set above
            self._displacement_control(hist, record, control, monitor_dof)
        return self._finish(hist, hist.status, hist.reason, t0)

    def _load_control(self, hist: History, record) -> None:
        s = self.settings
        lam = 0.0
        dlam = s.initial_step * self.load_scale
        max_dlam = s.max_step * self.load_scale
        lam_fail = math.inf
        failed_step = dlam
        last_reason = ""
        verified = False  # the first failure was re-tried from the end of the bracket
        hand_over = True  # work control takes over at the first failure (continuation="work")
        work_reason: str | None = None
        for _ in range(s.max_steps):
            target = min(lam + dlam, s.max_load_factor)
            out = self._equilibrate(target)
            robust_ok = False
            if not out.ok and s.rescue_time_steps > 0 and "exceed the limit" not in out.reason:
                rescued = self._dynamic_rescue(target, lam)
                if rescued is not None:
                    out, robust_ok = rescued, True
            if not out.ok and s.robust_iterations > 0 and "exceed the limit" not in out.reason:
                second = self._robust(target)
                log.debug(
                    "Newton failed at lambda=%.6g (%s); robust: %s",
                    target,
                    out.reason,
                    "ok" if second.ok else second.reason,
                )
                if second.ok:
                    out, robust_ok = second, True
                else:
                    out = replace(out, reason=f"{out.reason}; {second.reason}")
            if out.ok:
                record(out)
                lam = target
                if lam >= s.max_load_factor:
                    hist.status, hist.reason = "completed", f"reached max_load_factor {lam:.6g}"
                    return
                if lam >= lam_fail:  # the earlier failure came from a long step only
                    log.debug("lambda=%.6g passed after an earlier failure", lam)
                    lam_fail, verified = math.inf, False
                    # the bracket's halvings came from a long step only: resume with half
                    # the step that failed instead of creeping on at the bracket width
                    dlam = max(dlam, min(failed_step / 2, max_dlam))
                if math.isfinite(lam_fail):
                    dlam = (lam_fail - lam) / 2
                elif out.iterations <= _EASY_STEP or robust_ok:
                    # the robust strategy copes with long steps: grow them after it too
                    dlam = min(dlam * s.growth, max_dlam)
            else:
                last_reason = out.reason
                log.debug("step to lambda=%.6g failed: %s", target, out.reason)
                if target < lam_fail:
                    if not math.isfinite(lam_fail):  # the step that opened this bracket
                        failed_step = target - lam
                    lam_fail, verified = target, False
                elif target == lam_fail:
                    verified = True
                if not s.refine:
                    break
                if hand_over and s.continuation == "work" and len(hist.steps) > 2:
                    # work control follows the curve from here past any limit point, so
                    # refining this bracket would only cost failing steps; if it finds
                    # nothing higher, the bracket is refined after all (below)
                    hand_over = False
                    kept = (
                        self.q.copy(),
                        self.plastic.copy(),
                        self.cracked.copy(),
                        self._last_increment,
                    )
                    hist.collapse_bracket = (lam, lam_fail)
                    work_reason = self._work_control(hist, record, first_failure=out.reason)
                    if work_reason is None:
                        return
                    log.debug(
                        "work control found nothing above lambda=%.6g (%s): refining "
                        "the load-control bracket",
                        lam,
                        work_reason,
                    )
                    self.q, self.plastic, self.cracked, self._last_increment = kept
                    hist.collapse_bracket = None
                dlam = (lam_fail - lam) / 2
            if math.isfinite(lam_fail) and lam_fail - lam <= s.bracket_tolerance * max(
                abs(lam), 1e-12 * self.load_scale
            ):
                if verified:
                    break
                dlam = lam_fail - lam  # re-try the first failure from the bracket's end
        else:
            hist.status = "failed"
            hist.reason = f"max_steps={s.max_steps} reached at lambda={lam:.6g}"
            return
        hist.collapse_bracket = (lam, lam_fail)
        hist.status = "collapse"
        hist.reason = (
            f"no equilibrium beyond lambda={lam:.6g} (first failure at {lam_fail:.6g}: "
            f"{last_reason})"
        )
        if not s.refine:  # a long step may fail where a shorter one would not
            hist.reason += "; refine=False: the failed step was not cut, so this is an upper "
            hist.reason += "bracket of the first failure only, not a refined collapse load"
        if hand_over and s.continuation == "work" and len(hist.steps) > 2:
            work_reason = self._work_control(hist, record, first_failure=last_reason)
        if work_reason is not None:
            hist.reason += f"; work control found no higher equilibrium ({work_reason})"

    def _control_radius(self, c: np.ndarray, dw: float) -> float:
        """Trust radius for a controlled step: room for the requested increment."""
        return max(
            4.0 * self._last_increment,
            1e-4 * self.limit,
            4.0 * abs(dw) / max(float(np.abs(c).max()), 1e-300),
        )

    def _work_control(self, hist: History, record, first_failure: str) -> str | None:
        """Continue past the first failure of load control with lambda free and the
        work-conjugate displacement w = c . q (c = F_L / |F_L|) prescribed, from the last
        converged state. Returns None when the run is decided (a peak above the last
        load-control state, or ``max_steps`` / ``max_load_factor``), else why nothing
        higher was found (load control then refines its bracket).

        Load control fails where the pushover curve turns flat (a plastic plateau or a
        limit point); under work control the same equilibria are found with bounded
        increments. The curve is followed until one of: lambda at w has risen less than
        ``bracket_tolerance`` x lambda since w / 2 (w measured from the dead-load state);
        three steps in a row gain less than ``_FLAT_SLOPE`` of the elastic d(lambda)/dw (a
        formed mechanism, or creeping steps when Newton stalls at a kink); the step has been
        halved ``_MAX_CUTS`` times or below what the control tolerance can resolve, and a
        pseudo-transient step to lambda x (1 + _TRANSIENT_RISE) finds no rest either
        (one is tried as soon as the step has been halved ``_TRANSIENT_AFTER`` times in a
        row: a fold of the path, which no shorter step passes); the displacements pass the
        limit. The collapse multiplier is the highest lambda on the
        path."""
        s = self.settings
        free = self.asm.free_index
        c = self.F_live / float(np.linalg.norm(self.F_live))
        q0 = hist.steps[0].q.reshape(-1)[free]
        path_w = [float(c @ (st.q.reshape(-1)[free] - q0)) for st in hist.steps]
        path_lam = [float(st.load_factor) for st in hist.steps]
        w = path_w[-1]
        dw = max(w - path_w[-2], 1e-3 * abs(w), 1e-12 * self.limit)
        lam = path_lam[-1]
        first_lambda = hist.collapse_bracket[1] if hist.collapse_bracket else lam
        peak = max(path_lam)
        # the first live-load step is elastic for walls that stand: its secant is the scale
        elastic_slope = (path_lam[1] - path_lam[0]) / max(path_w[1] - path_w[0], 1e-300)
        flat_steps = 0
        cuts = 0
        first_dw = dw
        transient_from = -1  # the step from which the last pseudo-transient step started
        transient_failed = False
        reason = ""
        checked_from = -1  # the step from which the last dynamic-relaxation check started
        last_fold: float | None = None  # lambda where the last failed search stopped
        fold_failed = False  # a pseudo-transient step past a fold found no rest

        def transient(why: str, above: float | None = None) -> bool:
            """A pseudo-transient step to a lambda a little higher (and past ``above``),
            once from each state."""
            nonlocal transient_from
            transient_from = len(hist.steps)
            target = lam + _TRANSIENT_RISE * abs(lam)
            if above is not None:  # just past a fold known to within _FOLD_MATCH
                target = max(target, above + _FOLD_MATCH * abs(above))
            moved = self._pseudo_transient(target)
            log.debug(
                "work control stuck at lambda=%.6g (%s); pseudo-transient step to %.6g: %s",
                lam,
                why,
                target,
                f"ok in {moved.iterations}" if moved.ok else moved.reason,
            )
            if moved.ok:
                accept_moved(moved)
            return moved.ok

        def accept_moved(moved: _Outcome) -> None:
            """Go on from a state found at a higher lambda (not by a work step)."""
            nonlocal lam, w, peak, dw, cuts, flat_steps
            record(moved)
            lam = float(moved.load_factor)
            w = float(c @ (moved.q[free] - q0))
            path_w.append(w)
            path_lam.append(lam)
            peak = max(peak, lam)
            dw, cuts, flat_steps = max(dw, first_dw * _RESUME_STEP), 0, 0

        while len(hist.steps) < s.max_steps:
            goal = w + dw
            out = self._equilibrate(
                lam,
                control=(c, goal + float(c @ q0), dw),
                radius=self._control_radius(c, dw),
            )
            if not out.ok and "exceed the limit" not in out.reason:
                # on a plateau the search may meet equilibria short of the goal (lambda is
                # free, so any converged state on the way is a point of the curve)
                reached = float(c @ (out.q[free] - q0))
                _, rnorm, response = self._residual(out.q, out.load_factor)
                if rnorm <= s.tolerance and reached > w + 0.1 * dw:
                    out = replace(out, ok=True, response=response)
                    goal = reached
            if not out.ok:
                log.debug("work step to w=%.6g failed: %s", goal, out.reason)
                if "exceed the limit" in out.reason and cuts >= _LIMIT_CUTS:
                    reason = f"a mechanism at lambda={peak:.6g}: {out.reason}"
                    break
                cuts += 1
                dw /= 2
                # a step below this cannot be told from no step (the control tolerance)
                tiny = 1e-4 * max(abs(w), path_w[1] - path_w[0], 1e-8 * self.limit)
                stuck = cuts > _MAX_CUTS or dw < tiny
                # the search stops where the one before it stopped: a fold of the path that
                # halved steps only close in on (each half converges, the next full step
                # fails there again), so the pseudo-transient step goes past it at once
                fold = float(out.load_factor)
                refold = (
                    last_fold is not None
                    and abs(fold - last_fold) <= _FOLD_MATCH * abs(lam)
                    and not fold_failed
                )
                last_fold = fold
                if (
                    (stuck or refold or (cuts == _TRANSIENT_AFTER and not transient_failed))
                    and s.transient_steps > 0
                    and transient_from != len(hist.steps)
                ):
                    # Newton stops at a fold of the path
                    if transient(out.reason, above=fold if refold else None):
                        continue
                    if refold:
                        fold_failed = True
                    else:
                        transient_failed = True
                if stuck and s.stop_check_time_steps > 0 and checked_from != len(hist.steps):
                    # neither Newton nor the pseudo-transient step passes: before calling
                    # this a collapse, let dynamic relaxation look for rest a little higher
                    checked_from = len(hist.steps)
                    target = lam + _TRANSIENT_RISE * abs(lam)
                    rescued = self._dynamic_rescue(target, lam, s.stop_check_time_steps)
                    log.debug(
                        "work control stuck at lambda=%.6g; dynamic relaxation to %.6g: %s",
                        lam,
                        target,
                        "ok" if rescued else "no rest",
                    )
                    if rescued is not None:
                        accept_moved(rescued)
                        transient_failed = False
                        continue
                if stuck:
                    reason = (
                        f"no equilibrium beyond lambda={lam:.6g} under work control ({out.reason})"
                    )
                    break
                continue
            record(out)
            w, lam = goal, float(out.load_factor)
            path_w.append(w)
            path_lam.append(lam)
            peak = max(peak, lam)
            if lam >= s.max_load_factor:
                hist.status, hist.reason = "completed", f"reached max_load_factor {lam:.6g}"
                return None
            total = float(
                np.abs(out.q - hist.steps[0].q.reshape(-1))[free][self._translation].max()
            )
            if total > self.limit:
                reason = (
                    f"a mechanism: displacements {total:.3g} m exceed the limit "
                    f"{self.limit:.3g} m at lambda={lam:.6g}"
                )
                break
            half = float(np.interp(w / 2, path_w, path_lam))
            if w > 0 and lam - half <= s.bracket_tolerance * abs(peak) and lam < peak + 1e-12:
                reason = (
                    f"the pushover curve is flat: lambda rose {lam - half:.3g} while the "
                    f"work-conjugate displacement doubled to {w:.3g} m (peak {peak:.6g})"
                )
                break
            # a formed mechanism: the last steps gained (almost) nothing for their
            # displacement, compared with the elastic stiffness of the live load
            slope = (path_lam[-1] - path_lam[-2]) / max(path_w[-1] - path_w[-2], 1e-300)
            flat_steps = flat_steps + 1 if slope < _FLAT_SLOPE * elastic_slope else 0
            if flat_steps >= 3:
                tiny = path_w[-1] - path_w[-4] < 1e-3 * w
                reason = (
                    f"no equilibrium beyond lambda={peak:.6g}: work control creeps "
                    f"(w {path_w[-4]:.6g} -> {w:.6g} m in 3 steps)"
                    if tiny
                    else f"a mechanism: lambda gains {slope / elastic_slope:.1e} of the "
                    f"elastic stiffness per unit displacement over 3 steps (peak {peak:.6g})"
                )
                break
            if cuts == 0 and out.iterations <= _EASY_STEP:
                dw *= s.growth
            cuts = 0
        else:
            hist.status = "failed"
            hist.reason = f"max_steps={s.max_steps} reached at lambda={lam:.6g}"
            return None
        assert hist.collapse_bracket is not None  # set by the caller
        if peak <= hist.collapse_bracket[0]:
            return reason
        hist.collapse_bracket = (peak, peak)
        hist.status = "collapse"
        hist.reason = f"{reason}; load control first failed at {first_lambda:.6g} ({first_failure})"
        return None

    def _displacement_control(
        self, hist: History, record, control: DisplacementControl, dof: int
    ) -> None:
        s = self.settings
        position = np.flatnonzero(self.asm.free_index == dof)
        if position.size == 0:
            raise ValueError(f"control dof {control.dof} of block {control.block} is fixed")
        k = int(position[0])
        if control.steps < 1:
            raise ValueError(f"control steps must be at least 1, got {control.steps!r}")
        unit = np.zeros(self.asm.n_free)
        unit[k] = 1.0
        du_nominal = control.target / control.steps
        du = du_nominal
        lam = 0.0
        u = float(self.q[dof])
        cuts = 0
        while (
            abs(u - control.target) > 1e-12 * abs(control.target) and len(hist.steps) < s.max_steps
        ):
            goal = u + du
            if (goal - control.target) * np.sign(du_nominal) > 0:
                goal = control.target
            out = self._equilibrate(
                lam,
                control=(unit, goal, abs(goal - u)),
                radius=self._control_radius(unit, goal - u),
            )
            if out.ok:
                record(out)
                lam, u = out.load_factor, goal
                du = min(abs(du) * s.growth, abs(du_nominal)) * np.sign(du_nominal)
                cuts = 0
            else:
                du /= 2
                cuts += 1
                if cuts > 12:
                    hist.status = "failed"
                    hist.reason = f"displacement control stuck at {u:.4g}: {out.reason}"
                    break
        else:
            hist.status, hist.reason = "completed", f"control displacement reached {u:.6g}"
        lams = hist.load_factors
        peak = int(np.argmax(lams))
        hist.collapse_bracket = (float(lams[peak]), float(lams[peak]))

    def _global_dof(self, block: int, dof: str) -> int:
        return self.model.dof_index(block, dof)

    def _finish(self, hist: History, status: str, reason: str, t0: float) -> History:
        hist.status, hist.reason = status, reason
        hist.seconds = time.perf_counter() - t0
        hist.iterations = self.iterations
        hist.factorizations = self.factorizations
        log.info("%s: %s after %d steps (%s)", self.model.name, status, len(hist.steps), reason)
        return hist


def pushover(
    model: Model,
    settings: StaticSettings | None = None,
    control: DisplacementControl | None = None,
    out=None,
    monitor: tuple[int, str] | None = None,
    write_every: int = 1,
    callback: Callable[[StepResult], None] | None = None,
) -> History:
    """Run the static incremental analysis; with ``out`` write VTU/PVD, pushover.csv and
    summary.json to that folder as the steps converge. ``callback(step)`` is called after
    each converged step (e.g. a progress bar)."""
    writer = None
    if out is not None:
        from masonry_dem.export.writer import ResultsWriter

        writer = ResultsWriter(out, model, every=write_every, background=True)

    def on_step(step: StepResult) -> None:
        if writer is not None:
            writer(step)
        if callback is not None:
            callback(step)

    solver = StaticSolver(model, settings)
    with writer or nullcontext():  # the steps handed to the writer reach the disk
        history = solver.run(control=control, callback=on_step, monitor=monitor)
    if writer is not None:
        writer.finish(history)
    return history


__all__ = ["DisplacementControl", "StaticSettings", "StaticSolver", "pushover", "replace"]
