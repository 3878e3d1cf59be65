"""Sparse LU of matrices of one fixed pattern, from well-kept libraries.

The static solver factorizes hundreds of tangents of one sparsity pattern per analysis. A
:class:`Factorizer` works the pattern out once (:func:`analyse`: the fill-reducing ordering,
the symbolic factorization) and then factorizes new values of it many times
(:meth:`Factorizer.factor`), each :class:`Factors` solving A x = b.

Backends (``BACKENDS``), each an ordinary library:

* ``"superlu"`` (scipy, always present): the minimum-degree ordering of A^T + A worked out
  once, later matrices permuted by one gather of their entries and factorized with diagonal
  pivots (SuperLU's symmetric mode); partial pivoting (COLAMD) where a diagonal pivot is zero.
* ``"pardiso"`` (Intel MKL PARDISO through ``pypardiso``; x86-64): the analysis (minimum
  degree ordering, symbolic factorization) with the first matrix, then a
  numeric factorization per matrix, on one MKL thread below ``PARALLEL_FROM`` unknowns and
  on ``numba.get_num_threads()`` from it (so one knob, ``NUMBA_NUM_THREADS``, sets the
  threads of every kernel), fixed for the handle at its analysis (PARDISO sizes its work
  space for the threads of the analysis: a later factorization on more threads crashed).
  Its handle (:class:`PardisoHandle`: a matrix type, a fixed pattern, options, the call's
  arguments made once) also serves the limit analysis's normal matrix (Cholesky or LDL^T).
* ``"umfpack"`` (SuiteSparse UMFPACK through ``kvxopt``) and ``"mumps"`` (MUMPS through
  ``python-mumps``): the symbolic analysis with the first matrix, a numeric factorization per
  matrix.

:func:`choose` picks the backend for a size from those installed, by the rule measured with
``python benchmarks/bench_scale.py`` (see ``docs/history/solvers_record.md``, "Scale"). The
environment variable ``MASONRY_DEM_FACTORIZER`` (one of ``BACKENDS``) overrides the choice, so that
a whole analysis or benchmark can be run with one backend.

Only the newest :class:`Factors` of a :class:`Factorizer` solves (PARDISO and MUMPS keep one
factorization per handle); an older one raises :class:`StaleFactors` rather than solving with
the wrong matrix.
"""

from __future__ import annotations

import ctypes
import glob
import importlib
import importlib.util
import logging
import os
import sys
from collections.abc import Callable
from typing import Any, Protocol

import numba
import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

log = logging.getLogger(__name__)

BACKENDS = ("superlu", "pardiso", "umfpack", "mumps")
#: the module that must be importable for each backend
_MODULES = {"superlu": "scipy", "pardiso": "pypardiso", "umfpack": "kvxopt", "mumps": "mumps"}
ENVIRONMENT = "MASONRY_DEM_FACTORIZER"
#: ``"auto"``: below this many unknowns SuperLU (one call into scipy, no library to load)
#: factorizes as fast as the others or faster (6-60 DOFs: PARDISO 1.0-1.3x SuperLU's time);
#: from about 100 DOFs PARDISO is the fastest: 0.92x at 102 DOFs, 0.65-0.70x at 216, 0.53-0.72x
#: at 2 460, on 1 and 2 threads (factorization and solve, medians of 100 in one process:
#: ``python benchmarks/bench_scale.py --small``), and at 6 000 and 60 000 DOFs
#: (docs/history/solvers_record.md "Scale"). The validation walls (244-6 000 DOFs) all take PARDISO.
SMALL = 100
#: the order of preference from ``SMALL`` unknowns, fastest first (bench_scale.py: MUMPS
#: before UMFPACK at 6 000 and 60 000 DOFs)
_PREFERENCE = ("pardiso", "mumps", "umfpack", "superlu")
#: PARDISO factorizes on one thread below this many unknowns, on ``numba.get_num_threads()``
#: from it: a front this small gives the threads too little work between their
#: synchronisations (measured by ``python benchmarks/bench_factorization.py``;
#: docs/history/solvers_record.md, "Scale")
PARALLEL_FROM = 2_000


#: PARDISO's error code for "not enough memory" (MKL's documentation of pardiso, "error")
PARDISO_OUT_OF_MEMORY = -2


class SingularMatrix(RuntimeError):
    """The matrix is singular to working precision (no backend pivot found)."""


class StaleFactors(RuntimeError):
    """The factors were replaced by a later factorization of the same factorizer."""


class Factors(Protocol):
    """The factors of one matrix."""

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x with A x = b (b of shape (n,))."""
        ...


class Factorizer(Protocol):
    """A sparsity pattern analysed once; :meth:`factor` factorizes new values of it."""

    name: str
    n: int
    #: the backend's own order of the entries: it stores ``data[layout]`` (None: CSC order),
    #: so that an assembler can write them in that order (:meth:`factor_laid_out`)
    layout: np.ndarray | None

    def factor(self, data: np.ndarray) -> Factors:
        """LU factors of the matrix whose stored entries (CSC order of the pattern) are
        ``data``; raises :class:`SingularMatrix` when it is singular."""
        ...

    def factor_laid_out(self, values: np.ndarray) -> Factors:
        """:meth:`factor` of the entries given in ``layout`` order (``data[layout]``)."""
        ...


def installed() -> list[str]:
    """The backends whose library can be imported here (SuperLU always)."""
    return [b for b in BACKENDS if importlib.util.find_spec(_MODULES[b]) is not None]


def choose(n: int, backend: str = "auto") -> str:
    """The backend for a matrix of ``n`` unknowns: ``backend`` if named (it must be installed),
    else ``MASONRY_DEM_FACTORIZER`` if set, else SuperLU below ``SMALL`` unknowns and the
    fastest installed library above (``_PREFERENCE``)."""
    if backend == "auto":
        backend = os.environ.get(ENVIRONMENT, "auto") or "auto"
        source = f"the environment variable {ENVIRONMENT}"
    else:
        source = "backend"
    if backend != "auto":
        if backend not in BACKENDS:
            raise ValueError(f"{source} must be 'auto' or one of {list(BACKENDS)}, got {backend!r}")
        if backend not in installed():
            raise ValueError(
                f"{source} = {backend!r}: its library ({_MODULES[backend]}) is not installed; "
                f"installed: {installed()} (pip install 'masonry_dem[{backend}]')"
            )
        return backend
    if n < SMALL:
        return "superlu"
    have = installed()
    return next(b for b in _PREFERENCE if b in have)


def analyse(indptr: np.ndarray, indices: np.ndarray, n: int, backend: str = "auto") -> Factorizer:
    """A factorizer of the n x n pattern (CSC ``indptr``, ``indices``, sorted within each
    column, every diagonal entry stored) by ``backend`` (``"auto"``: :func:`choose`)."""
    indptr = np.asarray(indptr)
    indices = np.asarray(indices)
    if indptr.shape != (n + 1,) or indptr[-1] != indices.size:
        raise ValueError(
            f"the pattern must have n + 1 = {n + 1} column pointers ending at its "
            f"{indices.size} entries, got {indptr.shape[0]} ending at {indptr[-1]}"
        )
    name = choose(n, backend)
    cls: dict[str, Callable[[np.ndarray, np.ndarray, int], Factorizer]] = {
        "superlu": _SuperLU,
        "pardiso": _Pardiso,
        "umfpack": _Umfpack,
        "mumps": _Mumps,
    }
    return cls[name](indptr, indices, n)


class _Generation:
    """Counts the factorizations of a handle that holds one at a time."""

    def __init__(self) -> None:
        self.current = 0

    def next(self) -> int:
        self.current += 1
        return self.current

    def check(self, generation: int, name: str) -> None:
        if generation != self.current:
            raise StaleFactors(f"{name}: these factors were replaced by a later factorization")


class _HeldFactors:
    """The factors of a handle that holds one factorization at a time (PARDISO, MUMPS): they
    solve with it until the handle factorizes again, then refuse (:class:`StaleFactors`)."""

    def __init__(
        self, name: str, generations: _Generation, solve: Callable[[np.ndarray], np.ndarray]
    ) -> None:
        self.name = name
        self.generations = generations
        self.generation = generations.next()
        self._solve = solve

    def solve(self, b: np.ndarray) -> np.ndarray:
        self.generations.check(self.generation, self.name)
        return self._solve(b)


# --------------------------------------------------------------------------- SuperLU
class _CSCOrder:
    """A backend that stores the entries in the pattern's CSC order: the laid-out entries
    are the CSC entries."""

    layout: np.ndarray | None = None

    def factor(self, data: np.ndarray) -> Factors:
        raise NotImplementedError

    def factor_laid_out(self, values: np.ndarray) -> Factors:
        return self.factor(values)


def permutation_parity(perm: np.ndarray) -> int:
    """+1 for an even permutation, -1 for an odd one: (-1)^(n - its cycles), the cycles
    counted as the connected components of the graph i -> perm[i]."""
    n = perm.size
    graph = sparse.csr_matrix((np.ones(n), (np.arange(n), perm)), shape=(n, n))
    cycles = connected_components(graph, directed=True, connection="weak")[0]
    return 1 if (n - cycles) % 2 == 0 else -1


class _SuperLUFactors:
    def __init__(self, lu, numbering: np.ndarray | None) -> None:
        self.lu = lu
        self.numbering = numbering  # numbering[k]: the unknown in row k of the permuted matrix

    def determinant_sign(self) -> int:
        """The sign of det A (0: singular): the product of the signs of U's diagonal and of
        the parities of the row and column permutations (L has a unit diagonal; the
        symmetric permutation by ``numbering`` leaves det A as it is)."""
        diagonal = self.lu.U.diagonal()
        if not np.all(diagonal):
            return 0
        negative = int(np.count_nonzero(diagonal < 0))
        sign = -1 if negative % 2 else 1
        return sign * permutation_parity(self.lu.perm_r) * permutation_parity(self.lu.perm_c)

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.numbering is None:
            return self.lu.solve(b)
        x = np.empty_like(b)
        x[self.numbering] = self.lu.solve(b[self.numbering])
        return x


class _SuperLU(_CSCOrder):
    """SuperLU with the ordering worked out once: the minimum degree of A^T + A (SuperLU's
    symmetric mode) on the pattern; each matrix is permuted symmetrically by a gather of its
    entries and factorized in that order with diagonal pivots (``relax=1``: no relaxed
    supernodes, about twice as fast on these small block-sparse matrices)."""

    name = "superlu"

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, n: int) -> None:
        self.n = n
        self.pattern = (indptr, indices)
        # the ordering depends on the pattern only: take it from a diagonally dominant matrix
        # of the pattern (one factorization, once)
        counts = np.diff(indptr)
        cols = np.repeat(np.arange(n), counts)
        probe = np.where(indices == cols, float(counts.max(initial=1) + 1), 1.0)
        lu = splu(
            sparse.csc_matrix((probe, indices, indptr), shape=(n, n)),
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=0.0,
            relax=1,
            options={"SymmetricMode": True},
        )
        self.numbering = np.argsort(lu.perm_c)
        # where each entry of the permuted matrix comes from
        ids = sparse.csc_matrix(
            (np.arange(1, indices.size + 1, dtype=float), indices, indptr), shape=(n, n)
        )
        permuted = sparse.csc_matrix(ids[self.numbering][:, self.numbering])
        permuted.sort_indices()
        self.gather = permuted.data.astype(np.int64) - 1
        self.permuted = (permuted.indptr, permuted.indices)

    def factor(self, data: np.ndarray) -> _SuperLUFactors:
        indptr, indices = self.permuted
        A = sparse.csc_matrix((data[self.gather], indices, indptr), shape=(self.n,) * 2)
        try:
            lu = splu(
                A,
                permc_spec="NATURAL",
                diag_pivot_thresh=0.0,
                relax=1,
                options={"SymmetricMode": True},
            )
            return _SuperLUFactors(lu, self.numbering)
        except RuntimeError:  # a zero diagonal pivot: partial pivoting
            pass
        K = sparse.csc_matrix((data, self.pattern[1], self.pattern[0]), shape=(self.n,) * 2)
        try:
            return _SuperLUFactors(splu(K, permc_spec="COLAMD"), None)
        except RuntimeError as exc:
            raise SingularMatrix(f"superlu: {exc}") from exc


#: the factorizer whose factors also give the sign of the determinant
SignedFactorizer = _SuperLU


def signed_factorizer(indptr: np.ndarray, indices: np.ndarray, n: int) -> SignedFactorizer:
    """SuperLU on the pattern (as :func:`analyse` with ``"superlu"``), whose factors also
    give the sign of the determinant (``determinant_sign``)."""
    return _SuperLU(np.asarray(indptr), np.asarray(indices), n)


# --------------------------------------------------------------------------- PARDISO
def _transpose_gather(
    indptr: np.ndarray, indices: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR of the matrix of CSC pattern (indptr, indices): its row pointers, column indices
    and where each of its entries sits in the CSC entries."""
    ids = sparse.csc_matrix(
        (np.arange(1, indices.size + 1, dtype=float), indices, indptr), shape=(n, n)
    ).tocsr()
    ids.sort_indices()
    return ids.indptr, ids.indices, ids.data.astype(np.int64) - 1


def _point_pypardiso_at_mkl() -> None:
    """Name MKL's runtime library for pypardiso (``PYPARDISO_MKL_RT``) when it sits where the
    ``mkl`` wheel puts it: pypardiso otherwise searches every folder of the environment for it,
    on import and again for each solver (1-3 s)."""
    if "PYPARDISO_MKL_RT" in os.environ:
        return
    for folder in ("lib", "Library/bin"):
        found = sorted(glob.glob(os.path.join(sys.prefix, folder, "*mkl_rt*")))
        if found:
            os.environ["PYPARDISO_MKL_RT"] = found[0]
            return


class PardisoHandle:
    """One MKL PARDISO handle: a matrix type (``mtype``), a fixed CSR pattern (made 1-based
    once) and its options (``iparm``, numbered from 1 as in MKL's manual and in pypardiso's
    ``set_iparm``), the values in place (:attr:`values`: write them, then :meth:`call`), on
    ``threads`` MKL threads. Both PARDISO users of the package run through it: the tangent's
    LU (:class:`_Pardiso`, real unsymmetric, mtype 11) and the normal matrix of the limit
    analysis's interior-point method (Cholesky, mtype 2, or LDL^T, -2:
    ``limit_analysis.normal_ipm``). The arguments of every call but the phase and the
    right-hand sides are made once: on the validation walls (250-6 000 DOFs) building the
    16 ctypes arguments at each call cost about as much as PARDISO's own factorization."""

    def __init__(
        self,
        indptr: np.ndarray,
        indices: np.ndarray,
        n: int,
        mtype: int,
        iparm: dict[int, int],
        threads: int = 1,
    ) -> None:
        _point_pypardiso_at_mkl()
        from pypardiso import PyPardisoSolver

        self.n = n
        self.mtype = mtype
        #: MKL threads of every call (PARDISO sizes its work space for those of the analysis:
        #: a later factorization on more threads crashed)
        self.threads = threads
        self.solver = PyPardisoSolver(mtype=mtype)  # its pt, iparm, perm and MKL library
        self.solver.set_iparm(1, 1)  # iparm given (not the defaults)
        for i, value in iparm.items():
            self.solver.set_iparm(i, value)
        self.ia = (np.asarray(indptr) + 1).astype(np.int32)
        self.ja = (np.asarray(indices) + 1).astype(np.int32)
        self.values = np.ones(self.ja.size)
        self.analysed = False  # a phase that analyses has run (its memory is held)
        int_p = ctypes.POINTER(ctypes.c_int32)
        double_p = ctypes.POINTER(ctypes.c_double)
        s = self.solver
        self._phase = ctypes.c_int32(0)
        self._nrhs = ctypes.c_int32(1)
        self._error = ctypes.c_int32(0)
        self._b = np.zeros(n)  # one right-hand side and its solution, in place
        self._x = np.zeros(n)
        self._head = (
            s.pt.ctypes.data_as(ctypes.POINTER(s._pt_type[0])),
            ctypes.byref(ctypes.c_int32(1)),  # maxfct
            ctypes.byref(ctypes.c_int32(1)),  # mnum
            ctypes.byref(ctypes.c_int32(mtype)),
            ctypes.byref(self._phase),
            ctypes.byref(ctypes.c_int32(n)),
            self.values.ctypes.data_as(double_p),
            self.ia.ctypes.data_as(int_p),
            self.ja.ctypes.data_as(int_p),
            s.perm.ctypes.data_as(int_p),
            ctypes.byref(self._nrhs),
            s.iparm.ctypes.data_as(int_p),
            ctypes.byref(ctypes.c_int32(0)),  # no messages
        )
        self._one = (self._b.ctypes.data_as(double_p), self._x.ctypes.data_as(double_p))

    def call(self, phase: int, b: np.ndarray | None = None) -> np.ndarray:
        """One call of MKL's pardiso on this handle (phase 11, 12, 22, 33 or -1) with
        :attr:`values`; x for b (one right-hand side, or one a column; None: none). A
        PARDISO error raises :class:`SingularMatrix` (a zero or refused pivot: the caller's
        matrix is the cause), but its lack of memory a MemoryError (the machine is)."""
        s = self.solver
        # the C entry point (the lower-case name is the Fortran one, which takes a pointer)
        s.libmkl.MKL_Set_Num_Threads_Local(ctypes.c_int(self.threads))
        self._phase.value = phase
        self._error.value = 0
        if b is None or b.ndim == 1:
            if b is not None:
                self._b[:] = b
            self._nrhs.value = 1
            s._mkl_pardiso(*self._head, *self._one, ctypes.byref(self._error))
            x = self._x.copy()
        else:
            double_p = ctypes.POINTER(ctypes.c_double)
            b = np.asfortranarray(b, dtype=float)
            x = np.zeros_like(b)
            self._nrhs.value = b.shape[1]
            s._mkl_pardiso(
                *self._head,
                b.ctypes.data_as(double_p),
                x.ctypes.data_as(double_p),
                ctypes.byref(self._error),
            )
        if phase == -1:
            self.analysed = False
        if self._error.value == PARDISO_OUT_OF_MEMORY:  # no property of the matrix
            raise MemoryError(f"pardiso: not enough memory for the factorization (phase {phase})")
        if self._error.value != 0:
            raise SingularMatrix(f"pardiso: error {self._error.value} in phase {phase}")
        if phase in (11, 12, 13):
            self.analysed = True
        return x

    def release(self) -> None:
        """PARDISO's memory of this handle is the library's: released (phase -1)."""
        if self.analysed:
            self.call(-1)

    def __del__(self) -> None:
        try:
            self.release()
        except Exception:  # noqa: BLE001 (at interpreter exit the library may be gone)
            pass


class _Pardiso:
    """MKL PARDISO, real unsymmetric (mtype 11: minimum-degree ordering, diagonal pivots
    perturbed rather than refused, iterative refinement after a perturbed pivot). The
    analysis runs once, with the first matrix's factorization (phase 12)."""

    name = "pardiso"

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, n: int) -> None:
        self.n = n
        ia, ja, self.gather = _transpose_gather(indptr, indices, n)
        self.layout: np.ndarray | None = self.gather  # PARDISO stores the CSR order
        #: MKL threads of every call, fixed at the analysis
        self.threads = 1 if n < PARALLEL_FROM else max(1, numba.get_num_threads())
        # the minimum-degree ordering, refinement only after a perturbed pivot, perturbation
        # 1e-13, no scaling, no matching, 1-based indices. The tangent is structurally
        # symmetric with a regular diagonal (the residual stiffness), so its diagonal pivots
        # serve, as in SuperLU's symmetric mode; minimum degree fills less than METIS on
        # these tangents (docs/history/solvers_record.md, "Cheaper linear solves").
        options = {2: 0, 8: 0, 10: 13, 11: 0, 13: 0, 35: 0}
        self.handle = PardisoHandle(ia, ja, n, 11, options, self.threads)
        self.solver = self.handle.solver  # its iparm: options set and counts read by benchmarks
        self.values = self.handle.values
        self.generations = _Generation()

    @property
    def analysed(self) -> bool:
        return self.handle.analysed

    def _call(self, phase: int, b: np.ndarray | None = None) -> np.ndarray:
        return self.handle.call(phase, b)

    def factor(self, data: np.ndarray) -> Factors:
        # in place: the pointer handed to PARDISO stays valid
        np.take(data, self.gather, out=self.values)
        return self._factor()

    def factor_laid_out(self, values: np.ndarray) -> Factors:
        np.copyto(self.values, values)  # a contiguous copy instead of the gather
        return self._factor()

    def _factor(self) -> Factors:
        # phase 12 (analysis and factorization) for the first matrix, 22 after it
        self._call(22 if self.analysed else 12)
        return _HeldFactors("pardiso", self.generations, self.solve)

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._call(33, b).reshape(b.shape)


# --------------------------------------------------------------------------- UMFPACK
def _kvxopt() -> tuple[Any, Any]:
    """kvxopt and its UMFPACK module (untyped: kvxopt's partial stubs do not cover the
    buffer-protocol constructors used here)."""
    return importlib.import_module("kvxopt"), importlib.import_module("kvxopt.umfpack")


class _UmfpackFactors:
    def __init__(self, owner: _Umfpack, numeric) -> None:
        self.owner = owner
        self.numeric = numeric

    def solve(self, b: np.ndarray) -> np.ndarray:
        kvxopt, umfpack = _kvxopt()
        x = kvxopt.matrix(np.array(b, dtype=float))
        umfpack.solve(self.owner.matrix, self.numeric, x)
        return np.array(x).reshape(b.shape)


class _Umfpack(_CSCOrder):
    """SuiteSparse UMFPACK (kvxopt): the symbolic analysis (its ordering and strategy) of
    the first matrix, a numeric factorization per matrix."""

    name = "umfpack"

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, n: int) -> None:
        kvxopt, _ = _kvxopt()
        self.n = n
        cols = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
        # built from triplets in CSC order, so its values are ours in the same order
        self.matrix = kvxopt.spmatrix(
            kvxopt.matrix(np.ones(indices.size)),
            kvxopt.matrix(np.asarray(indices, dtype=np.int64)),
            kvxopt.matrix(cols),
            (n, n),
        )
        if len(self.matrix.V) != indices.size:
            raise ValueError("the pattern holds repeated entries")
        self.symbolic = None  # of the first matrix (its values choose UMFPACK's strategy)

    def factor(self, data: np.ndarray) -> Factors:
        kvxopt, umfpack = _kvxopt()
        self.matrix.V = kvxopt.matrix(np.ascontiguousarray(data, dtype=float))
        try:
            if self.symbolic is None:
                self.symbolic = umfpack.symbolic(self.matrix)
            numeric = umfpack.numeric(self.matrix, self.symbolic)
        except ArithmeticError as exc:  # kvxopt: "singular matrix"
            raise SingularMatrix(f"umfpack: {exc}") from exc
        return _UmfpackFactors(self, numeric)


# --------------------------------------------------------------------------- MUMPS
class _Mumps(_CSCOrder):
    """MUMPS (sequential, python-mumps): the analysis (its automatic ordering) with the
    first matrix, a factorization per matrix."""

    name = "mumps"

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, n: int) -> None:
        import mumps

        self.n = n
        self.rows = np.asarray(indices, dtype=np.int64)
        self.cols = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
        self.context = mumps.Context()
        self.analysed = False  # with the first matrix (its matching and scaling use values)
        self.generations = _Generation()

    def _coo(self, data: np.ndarray) -> sparse.coo_array:
        return sparse.coo_array((data, (self.rows, self.cols)), shape=(self.n, self.n))

    def factor(self, data: np.ndarray) -> Factors:
        import mumps

        try:
            self.context.factor(
                self._coo(np.asarray(data, dtype=float)), reuse_analysis=self.analysed
            )
            self.analysed = True
        except mumps.MUMPSError as exc:
            raise SingularMatrix(f"mumps: {exc}") from exc
        return _HeldFactors("mumps", self.generations, self._solve)

    def _solve(self, b: np.ndarray) -> np.ndarray:
        return np.asarray(self.context.solve(np.array(b, dtype=float))).reshape(b.shape)
