"""The sparse LU backends of the static solver (solvers/factorization.py): every installed
backend against a dense solve, on random structurally symmetric (numerically unsymmetric)
patterns and on assembly tangents of a wall with random per-interface tangents; the same
collapse multiplier of a block on its base (s / a) through the solver with each; a stale
factorization and a singular matrix refused with clear errors; the choice of backend.

Backends whose library is not installed are skipped (they are optional extras)."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import sparse

from helpers.walls import A, B, S, on_base
from masonry_dem.geometry import builders
from masonry_dem.solvers import factorization as fz
from masonry_dem.solvers.incremental import StaticSolver

INSTALLED = fz.installed()
EVERY = [
    pytest.param(
        name,
        marks=pytest.mark.skipif(name not in INSTALLED, reason=f"{name} is not installed"),
    )
    for name in fz.BACKENDS
]


def random_matrix(n: int, density: float, seed: int) -> sparse.csc_matrix:
    """Structurally symmetric, numerically unsymmetric, diagonally dominant, every diagonal
    entry stored, indices sorted (the form of the solver's tangents)."""
    rng = np.random.default_rng(seed)
    mask = sparse.random(n, n, density=density, rng=rng, format="csc")
    pattern = (mask + mask.T + sparse.identity(n)).tocoo()
    values = rng.uniform(-1.0, 1.0, pattern.nnz)  # a different value on each side
    M = sparse.csc_matrix((values, (pattern.row, pattern.col)), shape=(n, n))
    M = sparse.csc_matrix(M + sparse.diags(np.abs(M).sum(axis=1).A1 + 1.0))
    M.sort_indices()
    return M


def assert_solves(factorizer, M: sparse.csc_matrix, seed: int) -> None:
    b = np.random.default_rng(seed).uniform(-1.0, 1.0, M.shape[0])
    x = factorizer.factor(M.data).solve(b)
    reference = np.linalg.solve(M.toarray(), b)
    assert x.shape == b.shape
    np.testing.assert_allclose(x, reference, rtol=1e-9, atol=1e-11 * np.abs(reference).max())


@pytest.mark.parametrize("backend", EVERY)
@settings(max_examples=15, deadline=None)
@given(n=st.integers(1, 60), density=st.floats(0.0, 0.3), seed=st.integers(0, 2**31 - 1))
def test_random_patterns_solve_as_a_dense_solve(backend, n, density, seed):
    M = random_matrix(n, density, seed)
    factorizer = fz.analyse(M.indptr, M.indices, n, backend)
    assert factorizer.name == backend
    assert_solves(factorizer, M, seed)
    # new values of the same pattern: the analysis is reused
    M2 = M.copy()
    M2.data = M.data * np.random.default_rng(seed + 1).uniform(0.5, 2.0, M.nnz)
    M2 = sparse.csc_matrix(M2 + sparse.diags(np.abs(M2).sum(axis=1).A1))
    M2.sort_indices()
    assert np.array_equal(M2.indices, M.indices)
    assert_solves(factorizer, M2, seed + 2)


def wall_tangents(seed: int):
    """The free-DOF tangent assembler of a 4 x 5 running-bond wall on a base (held on its
    left column) and entries for random per-interface 6x6 tangents: a symmetric positive
    part (the elastic stiffness of each joint) plus an unsymmetric coupling (a yielded
    joint's)."""
    wall = builders.running_bond_wall(4, 5, A, B, S, 20e3)
    model = on_base(wall, left=["u1", "u3"])
    solver = StaticSolver(model)
    rng = np.random.default_rng(seed)
    m = model.interfaces.count
    G = rng.normal(size=(m, 6, 6))
    T = np.einsum("mij,mkj->mik", G, G) + 6.0 * np.eye(6)
    T += 0.5 * rng.normal(size=(m, 6, 6))  # unsymmetric
    T *= 1e9
    return solver.problem.tangent_assembler, T


@pytest.mark.parametrize("backend", EVERY)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_assembly_tangents_solve_as_a_dense_solve(backend, seed):
    tangents, T = wall_tangents(seed)
    factorizer = fz.analyse(tangents.indptr, tangents.indices, tangents.n, backend)
    for k in range(2):  # two tangents of the one pattern
        K = tangents.matrix(T * (1.0 + k))
        assert abs(K - K.T).max() > 1e-3 * abs(K).max()  # unsymmetric, as intended
        b = np.random.default_rng(seed + k).uniform(-1.0, 1.0, K.shape[0])
        x = factorizer.factor(K.data).solve(b)
        reference = np.linalg.solve(K.toarray(), b)
        np.testing.assert_allclose(x, reference, rtol=1e-8, atol=1e-10 * np.abs(reference).max())


@pytest.mark.parametrize("backend", EVERY)
def test_entries_assembled_in_the_backends_order_are_the_same_bits(backend):
    """The assembler writes the entries where the backend stores them (``layout``: PARDISO's
    CSR order) instead of the backend gathering them at each matrix: the same bits as the
    CSC entries gathered, and the same solution as a dense solve."""
    tangents, T = wall_tangents(3)
    factorizer = fz.analyse(tangents.indptr, tangents.indices, tangents.n, backend)
    data = tangents.data(T)
    layout = factorizer.layout
    values = tangents.data(T, layout)
    expected = data if layout is None else data[layout]
    assert np.array_equal(values, expected)
    if layout is not None:  # the layout's terms are kept: a second matrix too
        assert np.array_equal(tangents.data(2.0 * T, layout), tangents.data(2.0 * T)[layout])
    b = np.random.default_rng(3).uniform(-1.0, 1.0, tangents.n)
    x = factorizer.factor_laid_out(values).solve(b)
    reference = np.linalg.solve(tangents.matrix(T).toarray(), b)
    np.testing.assert_allclose(x, reference, rtol=1e-8, atol=1e-10 * np.abs(reference).max())


@pytest.mark.parametrize("backend", EVERY)
def test_a_tangent_updated_from_the_last_one_is_the_same_bits(backend):
    """``update`` works out again only the joints whose tangent changed since its last
    matrix and the entries they add to: every entry the same number as a whole assembly
    (``data``), in the backend's layout, whether no joint, a few or all of them changed; a
    change of layout starts anew, and the entries returned are a copy (a caller that
    writes into them leaves the next update alone)."""
    tangents, T = wall_tangents(4)
    layout = fz.analyse(tangents.indptr, tangents.indices, tangents.n, backend).layout
    rng = np.random.default_rng(5)

    def whole(T):
        data = tangents.data(T)
        return data if layout is None else data[layout]

    T = T.copy()
    first = tangents.update(T, layout)
    assert np.array_equal(first, whole(T))
    first[:] = np.nan  # a copy: the kept entries are untouched
    assert np.array_equal(tangents.update(T, layout), whole(T))  # no joint changed
    for changed in (1, 3, T.shape[0]):
        joints = rng.choice(T.shape[0], changed, replace=False)
        T[joints] *= rng.uniform(0.5, 2.0, size=(changed, 6, 6))
        assert np.array_equal(tangents.update(T, layout), whole(T))
    other = None if layout is not None else np.arange(tangents.nnz)[::-1].copy()
    assert np.array_equal(tangents.update(T, other), tangents.data(T, other))
    T[0, 2, 2] *= 3.0  # back to the first layout after the other: anew, the same bits
    assert np.array_equal(tangents.update(T, layout), whole(T))


@pytest.mark.parametrize("backend", EVERY)
def test_a_block_on_its_base_tilts_at_s_over_a_with_every_backend(backend, monkeypatch):
    """The rigid block of width s and height a on a fixed base, tilted: it overturns at
    lambda = s / a (moment balance about the toe) whichever library factorizes."""
    monkeypatch.setenv(fz.ENVIRONMENT, backend)
    hist = StaticSolver(on_base(builders.single_block(A, B, S, 20e3))).run()
    assert hist.status == "collapse"
    assert hist.collapse_multiplier == pytest.approx(S / A, rel=0.005)


@pytest.mark.parametrize("backend", [b for b in ("pardiso", "mumps") if b in INSTALLED])
def test_factors_replaced_by_a_later_factorization_refuse_to_solve(backend):
    M = random_matrix(20, 0.2, 3)
    factorizer = fz.analyse(M.indptr, M.indices, 20, backend)
    first = factorizer.factor(M.data)
    factorizer.factor(2.0 * M.data)
    with pytest.raises(fz.StaleFactors, match="replaced by a later factorization"):
        first.solve(np.ones(20))


@pytest.mark.parametrize("backend", [b for b in ("superlu", "umfpack") if b in INSTALLED])
def test_a_singular_matrix_raises_singular_matrix(backend):
    """A zero column: no pivot exists (SuperLU, UMFPACK report it; PARDISO and MUMPS perturb
    tiny pivots instead, so the Newton step that follows is judged by its residual)."""
    M = sparse.csc_matrix(np.array([[1.0, 1.0], [1.0, 1.0]]))
    M.sort_indices()
    with pytest.raises(fz.SingularMatrix, match=backend):
        fz.analyse(M.indptr, M.indices, 2, backend).factor(M.data)


def test_the_choice_follows_the_size_and_what_is_installed(monkeypatch):
    monkeypatch.delenv(fz.ENVIRONMENT, raising=False)
    assert fz.choose(10) == "superlu"
    large = fz.choose(10 * fz.SMALL)
    assert large in INSTALLED
    assert large == next(b for b in fz._PREFERENCE if b in INSTALLED)
    monkeypatch.setattr(fz, "installed", lambda: ["superlu"])
    assert fz.choose(10 * fz.SMALL) == "superlu"  # the always-present default
    with pytest.raises(ValueError, match="pardiso.*not installed"):
        fz.choose(10, "pardiso")
    with pytest.raises(ValueError, match=r"one of \['superlu'"):
        fz.choose(10, "lapack")
    monkeypatch.setenv(fz.ENVIRONMENT, "bogus")
    with pytest.raises(ValueError, match=f"{fz.ENVIRONMENT}.*got 'bogus'"):
        fz.choose(10)


def test_a_pattern_of_the_wrong_size_is_refused():
    M = random_matrix(5, 0.3, 0)
    with pytest.raises(ValueError, match="n \\+ 1 = 7 column pointers"):
        fz.analyse(M.indptr, M.indices, 6, "superlu")


@pytest.mark.parametrize("backend", EVERY)
def test_elastic_factors_stay_valid_after_tangent_factorizations(backend, monkeypatch):
    """The bonded assembly's elastic factors are kept for the whole run (the robust re-try,
    the certificate's elastic slope) while tangents are factorized in between: they must
    still solve K_el x = b exactly (a backend with one factorization per handle would
    otherwise hand back stale factors)."""
    monkeypatch.setenv(fz.ENVIRONMENT, backend)
    wall = builders.running_bond_wall(4, 5, A, B, S, 20e3)
    solver = StaticSolver(on_base(wall, left=["u1", "u3"]))
    problem = solver.problem
    elastic = problem.elastic_factor()
    _, _, response = solver.residual(solver.q, 0.0)
    problem.factor(response)
    problem.factor(response)
    idx = np.arange(6)
    T = np.zeros((solver.model.interfaces.count, 6, 6))
    T[:, idx, idx] = problem.law.kbar
    K = problem.tangent_assembler.matrix(T)
    b = np.random.default_rng(3).uniform(-1.0, 1.0, K.shape[0])
    reference = np.linalg.solve(K.toarray(), b)
    np.testing.assert_allclose(
        elastic.solve(b), reference, rtol=1e-8, atol=1e-10 * np.abs(reference).max()
    )


@pytest.mark.parametrize("backend", EVERY)
def test_solutions_are_the_callers_and_many_right_hand_sides_solve_column_by_column(backend):
    """A solution is not overwritten by a later solve (PARDISO solves into a buffer of its
    handle), and (n, k) right-hand sides give the k solutions of their columns."""
    M = random_matrix(40, 0.1, 7)
    factors = fz.analyse(M.indptr, M.indices, 40, backend).factor(M.data)
    rng = np.random.default_rng(8)
    b1, b2 = rng.uniform(-1, 1, 40), rng.uniform(-1, 1, 40)
    x1 = factors.solve(b1)
    kept = x1.copy()
    factors.solve(b2)
    assert np.array_equal(x1, kept)
    B = rng.uniform(-1, 1, (40, 3))
    X = factors.solve(B)
    assert X.shape == (40, 3)
    reference = np.linalg.solve(M.toarray(), B)
    np.testing.assert_allclose(X, reference, rtol=1e-9, atol=1e-11 * np.abs(reference).max())


@pytest.mark.skipif("pardiso" not in INSTALLED, reason="pardiso is not installed")
@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two kernel threads")
def test_a_pardiso_handle_keeps_the_threads_of_its_analysis(monkeypatch):
    """PARDISO sizes its work space for the threads of its analysis; the numba thread count
    that sets them may change between calls (``kernel_threads_for`` runs small models on one
    thread). A handle analysed on two threads and factorized again on one crashed the
    process (segmentation fault) before each handle kept its analysis' count; now it solves
    as a dense solve. ``PARALLEL_FROM`` lowered so that a small matrix takes two threads."""
    monkeypatch.setattr(fz, "PARALLEL_FROM", 1)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(2)
        M = random_matrix(400, 0.02, 7)
        factorizer = fz.analyse(M.indptr, M.indices, 400, "pardiso")
        assert factorizer.threads == 2
        assert_solves(factorizer, M, 1)
        numba.set_num_threads(1)
        for seed in (2, 3):
            N = random_matrix(400, 0.02, 7)  # the same pattern, new values
            N.data *= np.random.default_rng(seed).uniform(0.5, 2.0, N.nnz)
            N = sparse.csc_matrix(N + sparse.diags(np.abs(N).sum(axis=1).A1))
            assert np.array_equal(N.indices, M.indices) and np.array_equal(N.indptr, M.indptr)
            assert_solves(factorizer, N, seed)
    finally:
        numba.set_num_threads(before)


@pytest.mark.skipif("pardiso" not in INSTALLED, reason="pardiso is not installed")
def test_pardiso_takes_one_thread_below_parallel_from():
    M = random_matrix(50, 0.1, 3)
    assert fz.analyse(M.indptr, M.indices, 50, "pardiso").threads == 1


@pytest.mark.parametrize("backend", EVERY)
@pytest.mark.parametrize(("seed", "fraction"), [(0, 0.9), (1, 1.0)])
def test_tangents_with_joints_left_only_their_normal_stiffness_solve_as_a_dense_solve(
    backend, seed, fraction
):
    """Joints of no strength at zero compression keep only their normal stiffness and a
    floor of 1e-9 x kbar on the other diagonal terms (``DiscreteProblem._zero_capacity_
    tangent``). With most joints so (a dry wall under its own weight), shear and rotation of
    the blocks are held by the floor alone: a tangent whose condition number is about 1e12,
    whose diagonal entries span nine orders, the case PARDISO's weighted matching was for;
    since session 15 it pivots on the diagonal. Each backend must leave a backward error
    |K x - b| / (|K| |x|) of round-off (1e-14; a bad pivot leaves orders more) and agree
    with a dense solve as far as the conditioning allows (1e-4 of the largest entry)."""
    tangents, T = wall_tangents(seed)
    rng = np.random.default_rng(seed)
    reduced = rng.random(T.shape[0]) < fraction
    normal = T[reduced, 2, 2].copy()
    T[reduced] = 0.0
    T[reduced, np.arange(6)[:, None], np.arange(6)[:, None]] = 1e-9 * 1e9
    T[reduced, 2, 2] = normal
    K = tangents.matrix(T)
    factorizer = fz.analyse(tangents.indptr, tangents.indices, tangents.n, backend)
    b = rng.uniform(-1.0, 1.0, tangents.n)
    x = factorizer.factor(K.data).solve(b)
    reference = np.linalg.solve(K.toarray(), b)
    assert np.linalg.cond(K.toarray()) > 1e11  # as ill conditioned as intended
    assert np.abs(K @ x - b).max() <= 1e-14 * np.abs(K).max() * np.abs(x).max()
    np.testing.assert_allclose(x, reference, rtol=0, atol=1e-4 * np.abs(reference).max())


@pytest.mark.skipif("pardiso" not in INSTALLED, reason="pardiso is not installed")
def test_one_pardiso_handle_serves_cholesky_and_ldlt_of_the_upper_triangle():
    """``PardisoHandle`` with the normal matrix's options (the limit analysis's interior
    point: METIS, no refinement): Cholesky (mtype 2) of a symmetric positive definite
    matrix's upper triangle solves as a dense solve, one right-hand side or two columns; on
    an indefinite matrix it refuses a pivot with ``SingularMatrix`` (the interior point
    then goes over to LDL^T), and LDL^T with perturbed pivots (mtype -2) solves that one."""
    rng = np.random.default_rng(7)
    n = 40
    G = sparse.random(3 * n, n, density=0.1, rng=rng) + sparse.eye(3 * n, n)
    spd = (G.T @ G + 0.1 * sparse.identity(n)).toarray()
    indefinite = spd - 1.5 * np.eye(n) * np.abs(np.linalg.eigvalsh(spd)).max() / 2.0
    b = rng.uniform(-1.0, 1.0, (n, 2))
    for mtype, M, refuses in ((2, spd, False), (2, indefinite, True), (-2, indefinite, False)):
        upper = sparse.csr_matrix(np.triu(M))
        upper.sort_indices()
        options = {2: 2, 8: 0, **({10: 8} if mtype == -2 else {})}
        handle = fz.PardisoHandle(upper.indptr, upper.indices, n, mtype, options)
        np.copyto(handle.values, upper.data)
        handle.call(11)
        if refuses:
            with pytest.raises(fz.SingularMatrix, match="phase 22"):
                handle.call(22)
            handle.release()
            assert not handle.analysed
            continue
        handle.call(22)
        reference = np.linalg.solve(M, b)
        np.testing.assert_allclose(handle.call(33, b[:, 0]), reference[:, 0], rtol=1e-8)
        np.testing.assert_allclose(handle.call(33, b), reference, rtol=1e-8)
        handle.release()
