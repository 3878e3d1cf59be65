"""The discrete problem of a static analysis: the residual R(q, lambda) = F_D + lambda F_L -
H^T f(Hq) of a Model under its interface law, and the factorized consistent tangent
dR/dq, assembled into a sparse matrix of fixed pattern.

Every solver of the package answers this problem: the static corrector (Newton), the
pseudo-transient step, and dynamic relaxation (which relaxes the same residual, with the
same loads and the same displacement limit). The factorization sits behind one method,
:meth:`DiscreteProblem.factor`, so that the sparse direct solver can be swapped in one place.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy import sparse

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive.law import InterfaceLaw, LawResponse
from masonry_dem.jit import kernel
from masonry_dem.model import Model
from masonry_dem.solvers.factorization import Factorizer, Factors, SingularMatrix, analyse


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


class TangentAssembler:
    """K_ff = H_f^T T H_f for per-interface 6x6 tangents T, with the sparsity pattern built
    once: each interface adds B = H_loc^T T H_loc (12 x 12, the DOFs of its two blocks) and
    the blocks are summed into a fixed CSC structure with one bincount."""

    def __init__(self, asm: Assembly, model: Model) -> None:
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
        position[asm.free_index] = np.arange(asm.n_free)
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
        assemble = _assemble_tangent.for_rows(self.H_loc.shape[0])
        return assemble(self.H_loc, np.ascontiguousarray(T), self.terms, self.term_ptr)

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
        tension: str | None = None,
        memory: str | None = None,
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
        self.translation = (free % 6) < 3  # among the free DOFs
        self.moving_translations = free[self.translation]  # DOF numbers
        self.factorizations = 0
        self._fronts: Factorizer | None = None  # the tangent's pattern, analysed once
        self._elastic: Factors | None = None

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
        F_ext = dead_factor * self.F_dead + lam * self.F_live
        residual = F_ext - internal
        scale = max(float(np.linalg.norm(self.weight * F_ext)), 1e-30)
        return residual, float(np.linalg.norm(self.weight * residual)) / scale, response

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
        T = self.law.tangent(response, floor, self.tangent_method)
        data = self._tangents.data(T)
        self.factorizations += 1
        fronts = self._factorizer()
        try:
            return fronts.factor(data)
        except SingularMatrix:  # exactly singular: stiffen the floor
            idx = np.arange(6)
            T[:, idx, idx] += 1e-6 * self.law.kbar
            return fronts.factor(self._tangents.data(T))

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
            idx = np.arange(6)
            T = np.zeros((self.model.interfaces.count, 6, 6))
            T[:, idx, idx] = self.law.kbar
            self.factorizations += 1
            self._elastic = self._tangents.symbolic().factor(self._tangents.data(T))
        return self._elastic

    def elastic_displacement(self, load: np.ndarray) -> float:
        """Largest translation of the bonded assembly under ``load`` (free DOFs); inf when
        the bonded assembly is itself a mechanism (nothing holds some block)."""
        try:
            x = self.elastic_factor().solve(load)
        except RuntimeError:
            return math.inf
        size = float(np.abs(x[self.translation]).max(initial=0.0))
        return size if math.isfinite(size) else math.inf
