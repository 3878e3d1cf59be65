"""Multifrontal LU without pivoting, for the tangent stiffness of the static solver.

The tangent of an assembly keeps one sparsity pattern for a whole analysis, is structurally
symmetric and is factorized with diagonal pivots (SuperLU's ``diag_pivot_thresh=0``): so the
elimination tree, the fronts and where every entry goes are worked out once
(:class:`Symbolic`), and each factorization only adds numbers into dense fronts, eliminates
their pivot columns and passes the Schur complement to the parent front, the bulk of it in
one matrix product (BLAS dgemm, in place). On the validation walls this is 1.4-2.4x faster
than SuperLU (which runs these small block-sparse matrices at about 1 GFlop/s); the answers
agree to the rounding of the arithmetic.

The fronts of two sets of whole subtrees of the elimination tree, of about equal work, are
factorized side by side on two threads (numba's ``prange``), then the fronts above them: a
front only reads the complements of its own children, so the factors are the same bits on
any number of threads, 1.6-1.9x faster on two cores than on one.

A zero or non-finite pivot raises :class:`ZeroPivot`: the caller then factorizes with
SuperLU, which pivots.
"""

from __future__ import annotations

import llvmlite.binding as llvm
import numba
import numpy as np
from numba import types
from numba.extending import get_cython_function_address
from scipy import sparse

_jit = numba.njit(cache=True)

# BLAS dgemm (scipy's, 32-bit integers) called from compiled code by symbol name, so that the
# compiled functions can be cached on disk (a ctypes pointer cannot be)
llvm.add_symbol(
    "masonry_dem_dgemm", get_cython_function_address("scipy.linalg.cython_blas", "dgemm")
)
_dgemm = types.ExternalFunction("masonry_dem_dgemm", types.void(*[types.voidptr] * 13))
_NO_TRANSPOSE = np.array([ord("N")], np.uint8)
_MINUS_ONE_ONE = np.array([-1.0, 1.0])


class ZeroPivot(RuntimeError):
    """A pivot of the factorization without pivoting is zero (or not finite)."""


@_jit
def _elimination_tree(n, indptr, indices):
    """Parent of each column in the elimination tree of a structurally symmetric pattern
    (Liu's algorithm with path compression; -1 for a root)."""
    parent = np.full(n, -1, np.int64)
    ancestor = np.full(n, -1, np.int64)
    for j in range(n):
        for t in range(indptr[j], indptr[j + 1]):
            i = indices[t]
            while i != -1 and i < j:
                nxt = ancestor[i]
                ancestor[i] = j
                if nxt == -1:
                    parent[i] = j
                i = nxt
    return parent


@_jit
def _gather_below(j, source, start, stop, mark, found, count):
    """Append to ``found[:count]`` the rows of ``source[start:stop]`` below ``j`` not yet
    marked for column j; returns the new count."""
    for t in range(start, stop):
        i = source[t]
        if i > j and mark[i] != j:
            mark[i] = j
            found[count] = i
            count += 1
    return count


@_jit
def _row_structure(n, indptr, indices, parent):
    """Rows below the diagonal of each column j of L, sorted: ``rows[ptr[j] : ptr[j + 1]]``,
    the rows of A's column j below j and those of j's children in the elimination tree."""
    head = np.full(n, -1, np.int64)  # children as linked lists
    sibling = np.full(n, -1, np.int64)
    for j in range(n - 1, -1, -1):
        if parent[j] >= 0:
            sibling[j] = head[parent[j]]
            head[parent[j]] = j
    mark = np.full(n, -1, np.int64)
    ptr = np.zeros(n + 1, np.int64)
    rows = np.empty(max(indices.size, 16), np.int64)
    found = np.empty(n, np.int64)
    for j in range(n):
        count = _gather_below(j, indices, indptr[j], indptr[j + 1], mark, found, 0)
        c = head[j]
        while c >= 0:
            count = _gather_below(j, rows, ptr[c], ptr[c + 1], mark, found, count)
            c = sibling[c]
        if ptr[j] + count > rows.size:  # grow the store
            bigger = np.empty(2 * (ptr[j] + count), np.int64)
            for a in range(ptr[j]):
                bigger[a] = rows[a]
            rows = bigger
        for a in range(1, count):  # insertion sort: short lists, and no sort to compile
            value = found[a]
            b = a - 1
            while b >= 0 and found[b] > value:
                found[b + 1] = found[b]
                b -= 1
            found[b + 1] = value
        for a in range(count):
            rows[ptr[j] + a] = found[a]
        ptr[j + 1] = ptr[j] + count
    out = np.empty(ptr[n], np.int64)
    for a in range(ptr[n]):
        out[a] = rows[a]
    return ptr, out


class Symbolic:
    """Fronts of the multifrontal factorization of matrices with the pattern of ``A``
    (square CSC, structurally symmetric, rows and columns in elimination order)."""

    def __init__(self, A: sparse.csc_matrix) -> None:
        A = sparse.csc_matrix(A)
        if A.shape[0] != A.shape[1]:
            raise ValueError(f"the matrix must be square, got shape {A.shape}")
        A.sort_indices()
        n = A.shape[0]
        indptr = A.indptr.astype(np.int64)
        indices = A.indices.astype(np.int64)
        parent = _elimination_tree(n, indptr, indices)
        # rows below the diagonal of each column of L (its own, and its children's)
        below_ptr, below_rows = _row_structure(n, indptr, indices, parent)
        count = np.diff(below_ptr)
        # supernodes: consecutive columns with nested structures share one front
        nested = (parent[:-1] == np.arange(1, n)) & (count[1:] == count[:-1] - 1)
        starts = [0] + (np.flatnonzero(~nested) + 1).tolist()
        first = np.array(starts + [n], dtype=np.int64)
        ns = first.size - 1
        pivots = np.diff(first)
        owner_of_column = np.repeat(np.arange(ns), pivots)
        fronts = [
            np.concatenate(
                [
                    np.arange(first[s], first[s + 1]),
                    below_rows[below_ptr[first[s + 1] - 1] : below_ptr[first[s + 1]]],
                ]
            )
            for s in range(ns)
        ]
        updates = np.array([f.size for f in fronts], dtype=np.int64) - pivots
        front_parent = np.array(
            [
                owner_of_column[f[p]] if f.size > p else -1
                for f, p in zip(fronts, pivots, strict=True)
            ],
            dtype=np.int64,
        )
        # where each stored entry of A is added: the front of its first eliminated index
        cols = np.repeat(np.arange(n), np.diff(indptr))
        owner = owner_of_column[np.minimum(indices, cols)]
        entry = np.argsort(owner, kind="stable").astype(np.int64)
        entry_ptr = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=ns))])
        where = np.empty(entry.size, np.int64)
        for s in range(ns):
            sl = entry[entry_ptr[s] : entry_ptr[s + 1]]
            local_row = np.searchsorted(fronts[s], indices[sl])
            local_col = np.searchsorted(fronts[s], cols[sl])
            where[entry_ptr[s] : entry_ptr[s + 1]] = local_row * fronts[s].size + local_col
        # each front's Schur complement goes to its parent front: its rows there
        kids: list[list[int]] = [[] for _ in range(ns)]
        for s in np.flatnonzero(front_parent >= 0).tolist():
            kids[front_parent[s]].append(s)
        kid_ptr = np.concatenate([[0], np.cumsum([len(k) for k in kids])])
        kid = np.array([c for k in kids for c in k], dtype=np.int64)
        rel_ptr = np.concatenate([[0], np.cumsum(updates)])
        rel = np.zeros(rel_ptr[-1], np.int64)
        for s in np.flatnonzero(front_parent >= 0).tolist():
            rows = fronts[s][pivots[s] :]
            rel[rel_ptr[s] : rel_ptr[s + 1]] = np.searchsorted(fronts[front_parent[s]], rows)
        sizes = pivots + updates
        self.n = n
        self.fronts = ns
        self.pattern = (indptr, indices)
        self.arrays = (
            pivots.astype(np.int64),
            updates,
            entry_ptr.astype(np.int64),
            entry,
            where,
            kid_ptr.astype(np.int64),
            kid,
            rel_ptr.astype(np.int64),
            rel,
            np.concatenate([[0], np.cumsum(updates**2)]).astype(np.int64),
            np.concatenate([[0], np.cumsum(sizes**2 - updates**2)]).astype(np.int64),
        )
        #: floating-point operations of each front, and of one factorization
        self.front_flops = 2 * updates**2 * pivots + 2 * updates * pivots**2 + 2 * pivots**3 / 3
        self.flops = float(self.front_flops.sum())
        # the work of a front: its operations and the extend-add of its complement
        self.tasks, self.task_ptr = _split_in_two(self.front_flops + updates**2, front_parent)
        self.front_rows = np.concatenate(fronts).astype(np.int64)
        self.front_ptr = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)

    def factorize(self, A: sparse.csc_matrix) -> LU:
        """LU factors of ``A`` (the pattern this was built for, indices sorted)."""
        if A.shape != (self.n, self.n) or not (
            np.array_equal(A.indptr, self.pattern[0]) and np.array_equal(A.indices, self.pattern[1])
        ):
            raise ValueError("the matrix does not have the pattern of the symbolic factorization")
        return self.factorize_entries(np.asarray(A.data, dtype=float))

    def factorize_entries(self, data: np.ndarray) -> LU:
        """LU factors of the matrix of this pattern whose stored entries (CSC order, indices
        sorted) are ``data``: :meth:`factorize` without building or checking a matrix."""
        if data.shape != self.pattern[1].shape:
            raise ValueError(
                f"the entries must have shape {self.pattern[1].shape}, got {data.shape}"
            )
        factors, failed = _factorize(data, self.tasks, self.task_ptr, *self.arrays)
        if failed >= 0:
            raise ZeroPivot(f"zero or non-finite pivot in front {failed} of {self.fronts}")
        return LU(self, factors)


class LU:
    """Factors of one matrix; :meth:`solve` solves A x = b."""

    def __init__(self, symbolic: Symbolic, factors: np.ndarray) -> None:
        self.symbolic = symbolic
        self.factors = factors

    def solve(self, b: np.ndarray) -> np.ndarray:
        sym = self.symbolic
        b = np.asarray(b, dtype=float)
        if b.shape != (sym.n,):
            raise ValueError(f"the right-hand side must have shape ({sym.n},), got {b.shape}")
        pivots, updates = sym.arrays[0], sym.arrays[1]
        return _solve(
            self.factors, b, pivots, updates, sym.arrays[10], sym.front_rows, sym.front_ptr
        )


def _split_in_two(work: np.ndarray, parent: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fronts in three lists, in elimination order: two sets of whole subtrees of about equal
    work, which are factorized side by side, and the fronts above them (``tasks[ptr[i] :
    ptr[i + 1]]``, i = 0, 1, 2). A subtree that holds more than half the work of those left
    is split: its root goes to the top and its children take its place."""
    n = work.size
    total = work.copy()
    for s in range(n):  # children come before their parents
        if parent[s] >= 0:
            total[parent[s]] += total[s]
    children: list[list[int]] = [[] for _ in range(n)]
    for s in range(n):
        if parent[s] >= 0:
            children[parent[s]].append(s)
    pool = [s for s in range(n) if parent[s] < 0]
    in_top = np.zeros(n, dtype=bool)
    while pool:
        big = max(pool, key=lambda t: total[t])
        if total[big] <= 0.5 * sum(total[t] for t in pool):
            break
        pool.remove(big)
        in_top[big] = True
        pool.extend(children[big])
    bins: list[list[int]] = [[], []]
    load = [0.0, 0.0]
    for root in sorted(pool, key=lambda t: -total[t]):  # largest first, to the lighter bin
        b = 0 if load[0] <= load[1] else 1
        bins[b].append(root)
        load[b] += total[root]
    owner = np.full(n, -1, np.int64)  # the bin of each front, -1: the top
    for b, roots in enumerate(bins):
        owner[roots] = b
    for s in range(n - 1, -1, -1):  # parents come after their children
        if owner[s] < 0 and not in_top[s]:
            owner[s] = owner[parent[s]]
    owner[in_top] = 2
    order = np.argsort(owner, kind="stable").astype(np.int64)
    ptr = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=3))]).astype(np.int64)
    return order, ptr


@_jit
def _front(
    s,
    data,
    schur,
    factors,
    pivots,
    updates,
    entry_ptr,
    entry,
    where,
    kid_ptr,
    kid,
    rel_ptr,
    rel,
    upd_ptr,
    fac_ptr,
):
    """Factorize front ``s`` into ``factors`` and its Schur complement into ``schur``; False
    if a pivot is zero (or not finite)."""
    p = pivots[s]
    u = updates[s]
    f = p + u
    F = np.zeros((f, f))
    flat = F.reshape(-1)
    for t in range(entry_ptr[s], entry_ptr[s + 1]):
        flat[where[t]] += data[entry[t]]
    for kk in range(kid_ptr[s], kid_ptr[s + 1]):  # extend-add the children's complements
        c = kid[kk]
        uc = updates[c]
        o = upd_ptr[c]
        r0 = rel_ptr[c]
        for a in range(uc):
            ra = rel[r0 + a]
            for b in range(uc):
                F[ra, rel[r0 + b]] += schur[o + a * uc + b]
    inverse = np.empty(p)
    for k in range(p):  # the pivot rows: L11 and U11, U12
        piv = F[k, k]
        if piv == 0.0 or not np.isfinite(piv):
            return False
        inv = 1.0 / piv
        inverse[k] = inv
        for i in range(k + 1, p):
            F[i, k] *= inv
            lik = F[i, k]
            if lik != 0.0:
                for m in range(k + 1, f):
                    F[i, m] -= lik * F[k, m]
    # L21 = F21 U11^-1 row by row (each row stays in cache while its p columns are done;
    # every entry sees the same operations in the same order as column by column); the
    # complement waits for the product below
    for i in range(p, f):
        for k in range(p):
            F[i, k] *= inverse[k]
            lik = F[i, k]
            if lik != 0.0:
                for m in range(k + 1, p):
                    F[i, m] -= lik * F[k, m]
    if u > 0:
        # the complement in place: F22 -= L21 U12 by BLAS (row-major F seen column-major:
        # F22^T -= U12^T L21^T), without the temporaries of a product and a difference
        ints = np.empty(3, np.int32)
        ints[0] = u
        ints[1] = p
        ints[2] = f
        base = F.ctypes.data
        _dgemm(
            _NO_TRANSPOSE.ctypes,
            _NO_TRANSPOSE.ctypes,
            ints[0:].ctypes,
            ints[0:].ctypes,
            ints[1:].ctypes,
            _MINUS_ONE_ONE[0:].ctypes,
            base + 8 * p,
            ints[2:].ctypes,
            base + 8 * p * f,
            ints[2:].ctypes,
            _MINUS_ONE_ONE[1:].ctypes,
            base + 8 * (p * f + p),
            ints[2:].ctypes,
        )
        o = upd_ptr[s]
        for a in range(u):
            for b in range(u):
                schur[o + a * u + b] = F[p + a, p + b]
    o = fac_ptr[s]
    for a in range(p * f):  # (loops rather than slices: nothing shape-checked to compile)
        factors[o + a] = flat[a]
    o += p * f
    for a in range(p, f):
        for b in range(p):
            factors[o] = F[a, b]
            o += 1
    return True


@_jit
def _front_list(
    first, last, tasks, data, schur, factors, pivots, updates, entry_ptr, entry, where,
    kid_ptr, kid, rel_ptr, rel, upd_ptr, fac_ptr,
):  # fmt: skip
    """Fronts ``tasks[first:last]`` in that order; -1, or the first whose pivot was zero."""
    for t in range(first, last):
        ok = _front(
            tasks[t], data, schur, factors, pivots, updates, entry_ptr, entry, where,
            kid_ptr, kid, rel_ptr, rel, upd_ptr, fac_ptr,
        )  # fmt: skip
        if not ok:
            return tasks[t]
    return -1


@numba.njit(cache=True, parallel=True)
def _factorize(
    data, tasks, task_ptr, pivots, updates, entry_ptr, entry, where, kid_ptr, kid, rel_ptr,
    rel, upd_ptr, fac_ptr,
):  # fmt: skip
    """Fronts in elimination order (children before parents): the two sets of subtrees of
    ``tasks`` side by side, then the top. Returns the factors, front by front: the p pivot
    rows (U11 with L11 below its diagonal, then U12; p x f), then L21 (u x p); and -1, or a
    front whose pivot was zero."""
    schur = np.empty(upd_ptr[-1])
    factors = np.empty(fac_ptr[-1])
    failed = np.full(2, -1, np.int64)
    for part in numba.prange(2):  # the two halves side by side, then the top
        failed[part] = _front_list(
            task_ptr[part], task_ptr[part + 1], tasks, data, schur, factors, pivots, updates,
            entry_ptr, entry, where, kid_ptr, kid, rel_ptr, rel, upd_ptr, fac_ptr,
        )  # fmt: skip
    for part in range(2):
        if failed[part] >= 0:
            return factors, failed[part]
    top = _front_list(
        task_ptr[2], task_ptr[3], tasks, data, schur, factors, pivots, updates, entry_ptr,
        entry, where, kid_ptr, kid, rel_ptr, rel, upd_ptr, fac_ptr,
    )  # fmt: skip
    return factors, top


@_jit
def _solve(factors, b, pivots, updates, fac_ptr, front_rows, front_ptr):
    x = b.copy()
    for s in range(pivots.size):  # L y = b
        p = pivots[s]
        f = p + updates[s]
        o = fac_ptr[s]
        rows = front_rows[front_ptr[s] : front_ptr[s + 1]]
        for k in range(p):
            acc = x[rows[k]]
            for m in range(k):
                acc -= factors[o + k * f + m] * x[rows[m]]
            x[rows[k]] = acc
        o += p * f
        for a in range(f - p):
            acc = 0.0
            for m in range(p):
                acc += factors[o + a * p + m] * x[rows[m]]
            x[rows[p + a]] -= acc
    for s in range(pivots.size - 1, -1, -1):  # U x = y
        p = pivots[s]
        f = p + updates[s]
        o = fac_ptr[s]
        rows = front_rows[front_ptr[s] : front_ptr[s + 1]]
        for k in range(p - 1, -1, -1):
            acc = x[rows[k]]
            for m in range(k + 1, f):
                acc -= factors[o + k * f + m] * x[rows[m]]
            x[rows[k]] = acc / factors[o + k * f + k]
    return x
