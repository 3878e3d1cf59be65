"""The discrete problem of a static analysis: the residual R(q, lambda) = F_D + lambda F_L -
H^T f(Hq) of a Model under its interface law, and the factorized consistent tangent
dR/dq, assembled into a sparse matrix of fixed pattern.

Every solver of the package answers this problem: the static corrector (Newton), the
damped motion of the reference analysis, and dynamic relaxation (which relaxes the same residual, with the
same loads and the same displacement limit). The factorization sits behind one method,
:meth:`DiscreteProblem.factor`, so that the sparse direct solver can be swapped in one place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from scipy import sparse

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive.law import CONTACT_BAND, InterfaceLaw, LawResponse, Memory, Tension
from masonry_dem.jit import kernel
from masonry_dem.model import Model
from masonry_dem.solvers.factorization import (
    Factorizer,
    Factors,
    SignedFactorizer,
    SingularMatrix,
    analyse,
    signed_factorizer,
)


@numba.njit(fastmath={"contract"})
def _joint_block(H_loc: np.ndarray, T: np.ndarray, i: int, B: np.ndarray) -> None:
    """B[i] = H_loc[i]^T T[i] H_loc[i], the 12 x 12 block of joint i, as sequential fused
    multiply-adds (compiled into its callers). The zeros of H_loc (three quarters of it: the
    unit translations and the lever arms of a rigid block) are skipped: each sum keeps its
    order over k, and a term h x t with h = 0 adds nothing to it (t is finite), so the
    entries are the same numbers."""
    A = np.zeros((12, 6))
    for r in range(12):
        for k in range(6):
            h = H_loc[i, k, r]
            if h != 0.0:
                for c in range(6):
                    A[r, c] += h * T[i, k, c]
    for r in range(12):
        for c in range(12):
            B[i, r, c] = 0.0
    for c in range(12):
        for k in range(6):
            h = H_loc[i, k, c]
            if h != 0.0:
                for r in range(12):
                    B[i, r, c] += A[r, k] * h


@kernel(parallel=True, fastmath={"contract"})
def _assemble_tangent(H_loc: np.ndarray, T: np.ndarray, terms: np.ndarray, ptr: np.ndarray):
    """The stored entries of K = sum over interfaces of H_loc^T T H_loc (12 x 12 each):
    ``out[j] = sum(B.flat[terms[ptr[j] : ptr[j + 1]]])``, added in that order from 0. The
    products run as sequential fused multiply-adds, which is what the batched BLAS products
    of numpy gave here, bit for bit; the interfaces, then the entries, are shared among the
    threads."""
    m = H_loc.shape[0]
    B = np.empty((m, 12, 12))
    for i in numba.prange(m):
        _joint_block(H_loc, T, i, B)
    flat = B.reshape(-1)
    out = np.empty(ptr.size - 1)
    for j in numba.prange(ptr.size - 1):
        total = 0.0
        for t in range(ptr[j], ptr[j + 1]):
            total += flat[terms[t]]
        out[j] = total
    return out


@kernel(parallel=True, fastmath={"contract"})
def _update_tangent(
    H_loc: np.ndarray,
    T: np.ndarray,
    T_kept: np.ndarray,
    B: np.ndarray,
    terms: np.ndarray,
    ptr: np.ndarray,
    joint_ptr: np.ndarray,
    joint_entries: np.ndarray,
    out: np.ndarray,
    everything: bool,
) -> int:
    """:func:`_assemble_tangent` of the tangents T, in place in ``out``, where ``out`` holds
    the entries of the tangents ``T_kept`` and ``B`` their blocks: only the blocks of the
    joints whose tangent changed (any of its 36 numbers) and the entries they add to
    (``joint_entries[joint_ptr[i] : joint_ptr[i + 1]]``) are worked out again, by the same
    products and sums in the same order, so every entry is the same number as a full
    assembly's (``everything``: all of them, the first matrix). ``T_kept`` and ``B`` are
    then those of T. Returns the number of joints whose tangent changed."""
    m = H_loc.shape[0]
    changed = np.zeros(m, dtype=np.bool_)
    for i in numba.prange(m):
        same = not everything
        if same:
            for k in range(6):
                for c in range(6):
                    if T[i, k, c] != T_kept[i, k, c]:
                        same = False
        if same:
            continue
        changed[i] = True
        for k in range(6):
            for c in range(6):
                T_kept[i, k, c] = T[i, k, c]
        _joint_block(H_loc, T, i, B)  # the products of _assemble_tangent
    dirty = np.zeros(out.size, dtype=np.bool_)
    count = 0
    for i in range(m):
        if changed[i]:
            count += 1
            for e in range(joint_ptr[i], joint_ptr[i + 1]):
                dirty[joint_entries[e]] = True
    flat = B.reshape(-1)
    for j in numba.prange(ptr.size - 1):
        if everything or dirty[j]:
            total = 0.0
            for t in range(ptr[j], ptr[j + 1]):
                total += flat[terms[t]]
            out[j] = total
    return count


@kernel()
def _entry_terms(pair, r, c, ptr, pair_start, record_order):
    """The terms of each stored entry (pair, r, c): the B.flat index 144 i + 12 (6 side(I) +
    r) + 6 side(J) + c of each interface i of its block pair, in the order of the
    interfaces. The records 4 i + 2 side(I) + side(J) are sorted stably by pair
    (``record_order``), those of a pair from ``pair_start[pair]`` on."""
    terms = np.empty(ptr[-1], dtype=np.int64)
    for e in range(pair.size):
        start = ptr[e]
        for t in range(ptr[e + 1] - start):
            record = record_order[pair_start[pair[e]] + t]
            i, sides = divmod(record, 4)
            side_i, side_j = divmod(sides, 2)
            terms[start + t] = 144 * i + 12 * (6 * side_i + r[e]) + 6 * side_j + c[e]
    return terms


@kernel()
def _reduce_zero_capacity(T, trial, strength, kbar, floor, contact_band):
    """In place, the joints of :meth:`DiscreteProblem._zero_capacity_tangent`: no strength
    at zero compression (``strength``: the tensile force, plus the cohesive force beyond mu
    ft where there is one) and a trial normal force within ``contact_band`` x the largest of
    zero keep only their normal stiffness, with ``floor`` x kbar on the other diagonal
    terms. One compiled pass: on the small validation walls the dozen numpy calls of the
    same selection cost more than the law's tangent itself."""
    m = trial.shape[0]
    largest = 0.0
    for i in range(m):
        largest = max(largest, abs(trial[i, 2]))
    band = contact_band * largest
    if band == 0.0:  # the undeformed start: every joint at zero, none decided by round-off
        return
    for i in range(m):
        if strength[i] <= 0.0 and abs(trial[i, 2]) <= band:
            normal = T[i, 2, 2]
            for r in range(6):
                for c in range(6):
                    T[i, r, c] = 0.0
                T[i, r, r] = floor * kbar[i, r]
            T[i, 2, 2] = normal


@dataclass
class _Kept:
    """What :meth:`TangentAssembler.update` keeps from the last matrix it assembled."""

    layout: np.ndarray | None
    T: np.ndarray  # (m, 6, 6) the joints' tangents
    B: np.ndarray  # (m, 12, 12) their blocks H_loc^T T H_loc
    values: np.ndarray  # the entries, in the layout's order
    joint_ptr: np.ndarray  # the entries joint i adds to: joint_entries[joint_ptr[i]:...]
    joint_entries: np.ndarray


class TangentAssembler:
    """K_ff = H_f^T T H_f for per-interface 6x6 tangents T, with the sparsity pattern built
    once: each interface adds B = H_loc^T T H_loc (12 x 12, the DOFs of its two blocks) and
    the blocks are summed into a fixed CSC structure (compiled kernel, :meth:`data`).

    The pattern is worked out on the blocks, not on the 144 entries of each interface: one
    stable sort of the 4 block pairs of each interface (its two blocks, either way round)
    gives each block column's neighbour blocks in order; the 36 entries of a block pair then
    sit at known offsets of their columns, and the terms of an entry are the interfaces of
    its pair, in the order of the interfaces (the order a sum over the interfaces adds
    them). Fixed DOFs are dropped from the full pattern by a mask."""

    def __init__(self, asm: Assembly, model: Model) -> None:
        its = model.interfaces
        m = its.count
        H = asm.H.tocoo()
        k = H.row // 6
        blk = H.col // 6
        side = (blk == its.block_j[k]).astype(np.int64)
        self.H_loc = np.zeros((m, 6, 12))
        self.H_loc[k, H.row % 6, 6 * side + H.col % 6] = H.data
        nb = model.blocks.count
        position = np.full(model.n_dofs, -1, dtype=np.int64)
        position[asm.free_index] = np.arange(asm.n_free)  # increasing: CSC order kept
        # the 4 block pairs (row block I, column block J) of each interface, record
        # 4 i + 2 side(I) + side(J)
        ends = np.stack([its.block_i, its.block_j], axis=1).astype(np.int64)  # (m, 2)
        row_block = np.repeat(ends, 2, axis=1).ravel()  # I: i, i, j, j
        col_block = np.tile(ends, (1, 2)).ravel()  # J: i, j, i, j
        record_order = np.argsort(col_block * nb + row_block, kind="stable")
        sorted_key = (col_block * nb + row_block)[record_order]
        first = np.flatnonzero(np.r_[True, sorted_key[1:] != sorted_key[:-1]])
        n_terms = np.diff(np.r_[first, sorted_key.size])  # interfaces of each block pair
        pair_I = row_block[record_order[first]]
        pair_J = col_block[record_order[first]]
        pairs = first.size
        per_column = np.bincount(pair_J, minlength=nb)  # neighbour blocks of each block
        column_start = np.r_[0, np.cumsum(per_column)[:-1]]  # first pair of each column
        rank = np.arange(pairs) - column_start[pair_J]
        # the full (all DOFs) CSC position of entry (pair, r, c): its column 6 J + c holds
        # the 6 rows of each neighbour block of J in turn
        r = np.arange(6)[None, :, None]
        c = np.arange(6)[None, None, :]
        full = (
            36 * column_start[pair_J][:, None, None]
            + c * 6 * per_column[pair_J][:, None, None]
            + 6 * rank[:, None, None]
            + r
        )  # (pairs, 6, 6)
        entry = np.empty(36 * pairs, dtype=np.int64)  # the flat (pair, r, c) at each position
        entry[full.ravel()] = np.arange(36 * pairs)
        e_pair, e_rc = np.divmod(entry, 36)
        e_r, e_c = np.divmod(e_rc, 6)
        row = position[6 * pair_I[e_pair] + e_r]
        col = position[6 * pair_J[e_pair] + e_c]
        kept = np.flatnonzero((row >= 0) & (col >= 0))
        nf = asm.n_free
        self.indices = row[kept].astype(np.int32)
        counts = np.bincount(col[kept], minlength=nf)
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        k_pair = e_pair[kept]
        self.term_ptr = np.concatenate([[0], np.cumsum(n_terms[k_pair])]).astype(np.int64)
        self.terms = _entry_terms(k_pair, e_r[kept], e_c[kept], self.term_ptr, first, record_order)
        self.nnz = kept.size
        self.n = nf
        self._layout: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        #: what :meth:`update` keeps from its last matrix: its layout, its joint tangents,
        #: their 12 x 12 blocks, its entries, and the entries each joint adds to
        self._kept: _Kept | None = None

    def data(self, T: np.ndarray, layout: np.ndarray | None = None) -> np.ndarray:
        """The stored entries of :meth:`matrix`, in its CSC order, or in the order
        ``layout`` (``data(T)[layout]``, the same bits: each entry is the same sum, written
        where a backend stores it, which saves the backend its gather at each matrix)."""
        terms, ptr = (self.terms, self.term_ptr) if layout is None else self._laid_out(layout)
        assemble = _assemble_tangent.for_rows(self.H_loc.shape[0])
        return assemble(self.H_loc, np.ascontiguousarray(T), terms, ptr)

    def update(self, T: np.ndarray, layout: np.ndarray | None = None) -> np.ndarray:
        """:meth:`data` of the tangents T (a copy: the same bits), worked out from the last
        matrix :meth:`update` assembled in the same ``layout``: only the joints whose tangent
        changed since, and the entries they add to. Between two factorized tangents of a
        path most joints (the elastic ones) keep theirs, so their products and the sums of
        the entries they alone add to are not worked out again (measured in
        docs/history/solvers_record.md, "Where the 909-block pushover's seconds go"). It keeps the
        joints' tangents and 12 x 12 blocks and the entries
        (``resources.KEPT_BYTES_PER_INTERFACE``)."""
        kept = self._kept
        everything = kept is None or kept.layout is not layout
        if kept is None or kept.layout is not layout:
            kept = self._kept = self._keep(layout)
        terms, ptr = (self.terms, self.term_ptr) if layout is None else self._laid_out(layout)
        update = _update_tangent.for_rows(self.H_loc.shape[0])
        update(
            self.H_loc,
            np.ascontiguousarray(T),
            kept.T,
            kept.B,
            terms,
            ptr,
            kept.joint_ptr,
            kept.joint_entries,
            kept.values,
            everything,
        )
        return kept.values.copy()

    def _keep(self, layout: np.ndarray | None) -> _Kept:
        """The store of :meth:`update` for ``layout``: which entries each joint adds to."""
        terms, ptr = (self.terms, self.term_ptr) if layout is None else self._laid_out(layout)
        m = self.H_loc.shape[0]
        joint = terms // 144  # the joint of each term (terms are indices of B.flat)
        entry = np.repeat(np.arange(ptr.size - 1, dtype=np.int64), np.diff(ptr))
        order = np.argsort(joint, kind="stable")
        joint_ptr = np.concatenate([[0], np.cumsum(np.bincount(joint, minlength=m))])
        index = np.int32 if ptr.size < 2**31 else np.int64
        return _Kept(
            layout,
            np.zeros((m, 6, 6)),
            np.zeros((m, 12, 12)),
            np.zeros(ptr.size - 1),
            joint_ptr.astype(np.int64),
            entry[order].astype(index),
        )

    def _laid_out(self, layout: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(terms, pointers) of the entries in the order ``layout``, worked out once per
        layout (the last one is kept)."""
        if self._layout is None or self._layout[0] is not layout:
            counts = np.diff(self.term_ptr)[layout]
            ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
            # term t of entry k is term t - ptr[k] of entry layout[k]
            start = np.repeat(self.term_ptr[layout] - ptr[:-1], counts)
            terms = self.terms[start + np.arange(ptr[-1])]
            self._layout = (layout, terms, ptr)
        return self._layout[1], self._layout[2]

    def matrix(self, T: np.ndarray, data: np.ndarray | None = None) -> sparse.csc_matrix:
        """K_ff for the tangents T (or for entries ``data`` assembled already)."""
        if data is None:
            data = self.data(T)
        return sparse.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def symbolic(self) -> Factorizer:
        """A factorizer of :meth:`matrix`'s pattern (the backend: factorization.choose)."""
        return analyse(self.indptr, self.indices, self.n)


class DiscreteProblem:
    """Loads, assembly, law and tangent of one model, with no state of a path: the state
    (q, the plastic part and the cracked joints) is handed to each call."""

    def __init__(
        self,
        model: Model,
        *,
        tension: Tension | None = None,
        memory: Memory | None = None,
        tangent: str = "analytic",
        residual_stiffness: float = 1e-9,
        displacement_limit: float | None = None,
    ) -> None:
        self.model = model
        self.asm = Assembly.of(model)
        self.law = InterfaceLaw.of(model, self.asm.kbar, tension, memory)
        self.tangent_method = tangent
        self.residual_stiffness = residual_stiffness
        self._assembler: TangentAssembler | None = None  # built on the first factorization
        free = self.asm.free_index
        self.free = free
        self.F_dead = model.dead.reshape(-1)[free]
        self.F_live = model.live.reshape(-1)[free]
        dead_norm = float(np.linalg.norm(self.F_dead))
        live_norm = float(np.linalg.norm(self.F_live))
        #: lambda of a live load as large as the dead load (1 for a tilt table)
        self.load_scale = dead_norm / live_norm if live_norm > 0 and dead_norm > 0 else 1.0
        #: largest translation still in the small-displacement range [m]
        self.limit = (
            displacement_limit
            if displacement_limit is not None
            else 0.5 * model.smallest_moving_size
        )
        # residual norm: moments as forces at the median block size
        length = float(np.median(model.blocks.sizes))
        self.weight = np.where(free % 6 < 3, 1.0, 1.0 / length)
        #: a correction's norm: rotations as displacements at the median block size
        self.displacement_weight = np.where(free % 6 < 3, 1.0, length)
        self.translation = (free % 6) < 3  # among the free DOFs
        self.moving_translations = free[self.translation]  # DOF numbers
        self.factorizations = 0
        self._fronts: Factorizer | None = None  # the tangent's pattern, analysed once
        #: SuperLU on the same pattern, whose factors give the sign of det K_t
        self._signs: SignedFactorizer | None = None
        self._elastic: Factors | None = None
        self._scale: float | None = None
        #: (lambda, dead factor), F_ext and its weighted norm of the last residual
        self._load: tuple[tuple[float, float], np.ndarray, float] | None = None

    @property
    def displacement_scale(self) -> float:
        """The wall's own elastic unit of displacement [m]: the largest translation of the
        bonded assembly under the dead load (under the live load at the load scale when
        there is no dead load). The model is geometrically linear, so with kn and kt scaled
        together by f every displacement of the path scales by 1 / f, and so does this:
        search lengths measured in it make the solver's iterates the same on both walls
        (docs/history/solvers_record.md, "Invariance"). Falls back to 1e-3 x the displacement limit
        when the bonded assembly is itself a mechanism."""
        if self._scale is None:
            load = self.F_dead if np.any(self.F_dead) else self.load_scale * self.F_live
            size = self.elastic_displacement(load) if np.any(load) else 0.0
            self._scale = size if math.isfinite(size) and size > 0 else 1e-3 * self.limit
        return self._scale

    # ------------------------------------------------------------------ residual
    def residual(
        self,
        q: np.ndarray,
        lam: float,
        plastic: np.ndarray,
        cracked: np.ndarray,
        dead_factor: float = 1.0,
    ) -> tuple[np.ndarray, float, LawResponse]:
        """(R on the free DOFs, |R| / |F| in the weighted norm, the law's response)."""
        _, response, internal = self.law.forces(self.asm.H, q, plastic, cracked, self.asm.H_free_T)
        residual = self._external(lam, dead_factor)[0] - internal
        return residual, self.relative_norm(residual, lam, dead_factor), response

    def relative_norm(self, force: np.ndarray, lam: float, dead_factor: float = 1.0) -> float:
        """|force| / |F_D + lambda F_L| (free DOFs), in the residual's weighted norm."""
        weighted = self.weight * force
        return math.sqrt(float(weighted @ weighted)) / self._external(lam, dead_factor)[1]

    def _external(self, lam: float, dead_factor: float) -> tuple[np.ndarray, float]:
        """(F_ext on the free DOFs, its weighted norm) at (lambda, dead_factor), kept for
        the last pair: a search evaluates many residuals at one lambda."""
        key = (lam, dead_factor)
        if self._load is None or self._load[0] != key:
            F_ext = dead_factor * self.F_dead + lam * self.F_live
            # sqrt(x.x) is what np.linalg.norm computes for a real vector, the same bits
            # without its dispatch
            weighted = self.weight * F_ext
            scale = max(math.sqrt(float(weighted @ weighted)), 1e-30)
            self._load = (key, F_ext, scale)
        return self._load[1], self._load[2]

    # ------------------------------------------------------------------ tangent
    @property
    def _tangents(self) -> TangentAssembler:
        """The assembler of the tangent's fixed pattern (dynamic relaxation never needs it)."""
        if self._assembler is None:
            self._assembler = TangentAssembler(self.asm, self.model)
        return self._assembler

    @property
    def tangent_assembler(self) -> TangentAssembler:
        """The fixed-pattern assembler of the tangent (its pattern: ``indptr``, ``indices``)."""
        return self._tangents

    def factor(self, response: LawResponse, floor: float | None = None) -> Factors:
        """LU of the consistent tangent at ``response`` (with ``floor`` x the elastic
        stiffness kept on the diagonal of every joint). The tangent is structurally symmetric
        with a regular diagonal (the residual stiffness); its pattern never changes, so it is
        analysed once (:func:`masonry_dem.solvers.factorization.analyse`: the ordering and
        symbolic factorization of the backend chosen for its size) and each tangent's
        entries go straight to a numeric factorization."""
        if floor is None:
            floor = self.residual_stiffness
        T = self.joint_tangents(response, floor)
        fronts = self._factorizer()
        values = self._tangents.update(T, fronts.layout)  # in the backend's own order
        self.factorizations += 1
        try:
            return fronts.factor_laid_out(values)
        except SingularMatrix:  # exactly singular: stiffen the floor
            idx = np.arange(6)
            T[:, idx, idx] += 1e-6 * self.law.kbar
            return fronts.factor_laid_out(self._tangents.data(T, fronts.layout))

    def determinant_sign(self, response: LawResponse) -> int:
        """The sign of det K_t at ``response`` (the tangent :meth:`factor` factorizes; 0:
        singular), from a SuperLU factorization of its own: its pivots and permutations are
        known, where PARDISO permutes rows inside its supernodes and tells neither. A state
        of the path where it is negative has crossed a limit or bifurcation point: an
        unstable equilibrium (Crisfield 1997, *Non-linear Finite Element Analysis of Solids
        and Structures*, vol. 2, 16.5; Wriggers 2008, *Nonlinear Finite Element Methods*,
        7.4)."""
        if self._signs is None:
            pattern = self._tangents
            self._signs = signed_factorizer(pattern.indptr, pattern.indices, pattern.n)
        T = self.joint_tangents(response, self.residual_stiffness)
        self.factorizations += 1
        try:
            factors = self._signs.factor(self._tangents.data(T))
        except SingularMatrix:
            return 0
        return factors.determinant_sign()

    def relative(self, dq: np.ndarray) -> np.ndarray:
        """(m, 6) relative displacements of the joints for an increment ``dq`` of the free
        DOFs."""
        return np.asarray(self.asm.H_free @ dq).reshape(-1, 6)

    def joint_tangents(self, response: LawResponse, floor: float | None = None) -> np.ndarray:
        """(m, 6, 6) tangents of the joints at ``response``, as :meth:`factor` assembles them:
        the law's consistent tangent with ``floor`` x kbar on the diagonal, and joints of no
        strength at zero compression reduced to their normal stiffness (their state is set
        by round-off, :meth:`_zero_capacity_tangent`). With kn and kt scaled together by f,
        these scale by f exactly, whatever round-off put those joints on either side."""
        if floor is None:
            floor = self.residual_stiffness
        T = self.law.tangent(response, floor, self.tangent_method)
        self._zero_capacity_tangent(T, response, floor)
        return T

    def _zero_capacity_tangent(self, T: np.ndarray, response: LawResponse, floor: float) -> None:
        """Joints of no strength at zero compression (no tensile strength, trial normal force
        within the law's contact band of zero: the head joints of a dry wall under its own
        weight) keep only their normal stiffness, with ``floor`` on the other diagonal
        terms. Their trial actions are round-off, so the law's flags (elastic, sliding,
        rocking or detached) are set by it, and an elastic shear or bending stiffness tells
        Newton they carry what they cannot: along that direction hundreds of such joints
        change state at any step length and the residual rises (docs/history/solvers_record.md, "Why
        Newton stalls from the dead-load state"). The residual is unchanged, so a
        converged state is still an exact equilibrium of the law. A joint with a cohesion
        beyond mu ft keeps a shear strength at zero compression: it is not one of them."""
        strength = response.strength_at_zero
        _reduce_zero_capacity(
            T, response.trial, strength, self.law.kbar, float(floor), CONTACT_BAND
        )

    def _factorizer(self) -> Factorizer:
        if self._fronts is None:
            self._fronts = self._tangents.symbolic()
        return self._fronts

    def elastic_factor(self) -> Factors:
        """LU of the elastic stiffness of the bonded assembly (every joint at its elastic
        stiffness, in tension too), factorized once per problem. It has a factorizer of its
        own: a backend keeps one numeric factorization per handle (PARDISO, MUMPS), so
        factors shared with the tangent's handle would go stale at the next tangent."""
        if self._elastic is None:
            T = self.elastic_tangents()
            self.factorizations += 1
            self._elastic = self._tangents.symbolic().factor(self._tangents.data(T))
        return self._elastic

    def elastic_tangents(self) -> np.ndarray:
        """(m, 6, 6) the joints' elastic stiffness, in tension too (the bonded assembly)."""
        T = np.zeros((self.model.interfaces.count, 6, 6))
        T[:, np.arange(6), np.arange(6)] = self.law.kbar
        return T

    def elastic_displacement(self, load: np.ndarray) -> float:
        """Largest translation of the bonded assembly under ``load`` (free DOFs); inf when
        the bonded assembly is itself a mechanism (nothing holds some block)."""
        try:
            x = self.elastic_factor().solve(load)
        except RuntimeError:
            return math.inf
        size = float(np.abs(x[self.translation]).max(initial=0.0))
        return size if math.isfinite(size) else math.inf
