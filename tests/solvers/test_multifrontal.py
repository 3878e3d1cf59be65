"""The multifrontal LU of the static solver's tangent: exact solves against dense LU on
random structurally symmetric (numerically unsymmetric) patterns and on a real tangent, a
clear error for a zero pivot (the solver then falls back to SuperLU) and for a matrix of
another pattern."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import sparse
from scipy.sparse.linalg import splu
from test_stability import A, B, S, on_base

from masonry_dem.geometry import builders
from masonry_dem.solvers.incremental import StaticSolver
from masonry_dem.solvers.multifrontal import Symbolic, ZeroPivot


def random_matrix(n: int, density: float, seed: int) -> sparse.csc_matrix:
    """Structurally symmetric, numerically unsymmetric, diagonally dominant."""
    rng = np.random.default_rng(seed)
    mask = sparse.random(n, n, density=density, random_state=rng, format="csc")
    pattern = (mask + mask.T).tocoo()
    values = rng.uniform(-1.0, 1.0, pattern.nnz)  # a different value on each side
    M = sparse.csc_matrix((values, (pattern.row, pattern.col)), shape=(n, n))
    M = M + sparse.diags(np.abs(M).sum(axis=1).A1 + 1.0)
    M = sparse.csc_matrix(M)
    M.sort_indices()
    return M


@settings(max_examples=25, deadline=None)
@given(
    n=st.integers(1, 60),
    density=st.floats(0.0, 0.3),
    seed=st.integers(0, 2**31 - 1),
)
def test_solves_agree_with_dense_lu_and_the_halves_are_whole_subtrees(n, density, seed):
    M = random_matrix(n, density, seed)
    b = np.random.default_rng(seed + 1).uniform(-1.0, 1.0, n)
    symbolic = Symbolic(M)
    x = symbolic.factorize(M).solve(b)
    np.testing.assert_allclose(x, np.linalg.solve(M.toarray(), b), rtol=1e-10, atol=1e-12)
    check_split(symbolic)  # the fronts factorized side by side (see below)


def test_a_tangent_of_a_validation_wall_solves_as_superlu_does():
    """A tangent with yielded joints (unsymmetric) in the solver's kept ordering."""
    from masonry_dem.cases.paper import build_case

    case = build_case("S15")
    solver = StaticSolver(case.model, case.settings)
    out = solver.equilibrate(0.0, radius=solver.limit, damped=True)
    solver.accept(out, 0, 0.0)
    out = solver.equilibrate(0.1)  # past the first yielding of S15's joints
    assert out.ok and np.any(out.response.state > 0)
    solver.problem.factor(out.response)  # the first factorization fixes the ordering
    T = solver.law.tangent(out.response, solver.settings.residual_stiffness)
    K = solver.problem._tangents.matrix(T)
    assert abs(K - K.T).max() > 1e-6 * abs(K).max()  # unsymmetric, as intended
    b = np.random.default_rng(0).uniform(-1.0, 1.0, K.shape[0])
    x = solver.problem._fronts.factorize(K).solve(b)
    reference = splu(K, permc_spec="NATURAL", diag_pivot_thresh=0.0).solve(b)
    np.testing.assert_allclose(x, reference, rtol=1e-8, atol=1e-12 * np.abs(reference).max())
    assert np.linalg.norm(K @ x - b) <= 1e-10 * np.linalg.norm(b)


def test_zero_pivot_is_reported_and_the_solver_falls_back_to_superlu(monkeypatch):
    swap = sparse.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0]]))
    with pytest.raises(ZeroPivot, match="zero or non-finite pivot"):
        Symbolic(swap).factorize(swap)

    calls = []

    def zero_pivot(self, entries):
        calls.append(entries.shape)
        raise ZeroPivot("forced")

    monkeypatch.setattr(Symbolic, "factorize_entries", zero_pivot)
    model = on_base(builders.single_block(A, B, S, 20e3))
    hist = StaticSolver(model).run()
    assert calls  # the multifrontal LU was asked, and SuperLU took over
    assert hist.status == "collapse"
    assert hist.collapse_multiplier == pytest.approx(S / A, rel=0.005)


def test_a_matrix_of_another_pattern_is_refused():
    M = random_matrix(10, 0.2, 1)
    symbolic = Symbolic(M)
    with pytest.raises(ValueError, match="pattern"):
        symbolic.factorize(sparse.csc_matrix(sparse.identity(10)))
    with pytest.raises(ValueError, match="right-hand side must have shape"):
        symbolic.factorize(M).solve(np.ones(9))
    with pytest.raises(ValueError, match="entries must have shape"):
        symbolic.factorize_entries(np.ones(M.nnz + 1))
    b = np.arange(10.0)  # the entries alone give the matrix's factors
    assert np.array_equal(
        symbolic.factorize_entries(M.data).solve(b), symbolic.factorize(M).solve(b)
    )


def check_split(symbolic: Symbolic) -> tuple[float, float, float]:
    """The fronts of the two halves (factorized side by side) and of the top: every front once,
    children before parents in each list, and no front of a half whose parent lies in the
    other half. Returns the work of the halves and of the top."""
    tasks, ptr = symbolic.tasks, symbolic.task_ptr
    n = symbolic.fronts
    assert np.array_equal(np.sort(tasks), np.arange(n))
    part = np.empty(n, dtype=np.int64)
    for i in range(3):
        fronts = tasks[ptr[i] : ptr[i + 1]]
        assert np.all(np.diff(fronts) > 0)  # in elimination order
        part[fronts] = i
    parent = np.full(n, -1, dtype=np.int64)
    kid_ptr, kid = symbolic.arrays[5], symbolic.arrays[6]
    for s in range(n):
        parent[kid[kid_ptr[s] : kid_ptr[s + 1]]] = s
    for s in range(n):
        if part[s] < 2 and parent[s] >= 0:
            assert part[parent[s]] in (part[s], 2), "a subtree is cut between the halves"
        if part[s] == 2 and parent[s] >= 0:
            assert part[parent[s]] == 2, "a front of the top has its parent in a half"
    work = symbolic.front_flops
    return tuple(float(work[part == i].sum()) for i in range(3))  # type: ignore[return-value]


def test_a_wall_splits_into_halves_of_equal_work_and_gives_the_same_bits_on_one_thread():
    from masonry_dem.cases.paper import build_case

    case = build_case("S12")
    solver = StaticSolver(case.model, case.settings)
    out = solver.equilibrate(0.0, radius=solver.limit, damped=True)
    solver.problem.factor(out.response)  # the first factorization fixes the ordering
    half_a, half_b, top = check_split(solver.problem._fronts)
    assert min(half_a, half_b) >= 0.8 * max(half_a, half_b)
    assert top <= 0.5 * (half_a + half_b + top)  # so that two threads gain at least 1.33x
    K = solver.problem._tangents.matrix(solver.law.tangent(out.response, 1e-9))
    two = solver.problem._fronts.factorize(K).factors
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        one = solver.problem._fronts.factorize(K).factors
    finally:
        numba.set_num_threads(threads)
    assert np.array_equal(one, two)


def test_the_kernel_threads_wait_passively_unless_the_user_says_otherwise():
    """Spinning OpenMP threads took a core from the serial work between the parallel loops
    (a 20 x 40 wall 1.8x slower): importing the package asks for passive waiting, and keeps
    a policy the user set."""
    import os
    import subprocess
    import sys

    code = "import os, masonry_dem; print(os.environ['OMP_WAIT_POLICY'])"
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.stdout.strip() == "PASSIVE", out.stderr
    env["OMP_WAIT_POLICY"] = "ACTIVE"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.stdout.strip() == "ACTIVE", out.stderr
