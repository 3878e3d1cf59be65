"""A factorization reused across Newton iterations (solvers/krylov.py and
``DiscreteProblem.tangent_solver``): GMRES preconditioned with the factors of a nearby matrix
converges in rank + 1 iterations for a change of that rank (Saad, Iterative Methods for
Sparse Linear Systems, prop. 6.12 applied to K P^-1 = I + low rank), and gives up when its
budget is shorter; a pushover whose Newton iterations reuse factorizations reaches the
same equilibria as one that factorizes every tangent; the settings refuse bad values."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.linalg import splu

from helpers.walls import on_base
from masonry_dem.geometry import builders
from masonry_dem.solvers import factorization as fz
from masonry_dem.solvers.incremental import StaticSettings, StaticSolver
from masonry_dem.solvers.krylov import gmres


def _matrix_and_change(n: int, rank: int, seed: int):
    """A diagonally dominant sparse matrix P, P + U V^T of the given rank, b and weights."""
    rng = np.random.default_rng(seed)
    P = sparse.csc_matrix(sparse.random(n, n, density=0.05, rng=rng) + 5.0 * sparse.eye(n))
    U = rng.standard_normal((n, rank))
    V = rng.standard_normal((n, rank))
    K = sparse.csc_matrix(P + sparse.csc_matrix(0.1 * U @ V.T))
    return P, K, rng.standard_normal(n), rng.uniform(0.5, 2.0, n)


@pytest.mark.parametrize("rank", [0, 1, 3, 6])
def test_a_change_of_rank_r_converges_in_r_plus_one_iterations(rank):
    """K P^-1 = I + (K - P) P^-1 has at most rank + 1 distinct eigenvalues' worth of Krylov
    space: GMRES is exact after rank + 1 iterations (round-off aside), with the residual in
    the weighted norm at the tolerance."""
    P, K, b, w = _matrix_and_change(120, rank, seed=rank)
    x, spent = gmres(K.__matmul__, splu(P), b, w, 20, 1e-10)
    assert x is not None
    assert spent <= rank + 1
    assert np.linalg.norm(w * (K @ x - b)) <= 1e-9 * np.linalg.norm(w * b)
    np.testing.assert_allclose(x, np.linalg.solve(K.toarray(), b), rtol=1e-7, atol=1e-9)


def test_a_budget_shorter_than_the_rank_gives_up():
    P, K, b, w = _matrix_and_change(120, 6, seed=7)
    x, spent = gmres(K.__matmul__, splu(P), b, w, 3, 1e-10)
    assert x is None and spent == 3


def test_a_zero_right_hand_side_is_solved_at_once():
    P, K, _, w = _matrix_and_change(30, 2, seed=1)
    x, spent = gmres(K.__matmul__, splu(P), np.zeros(30), w, 5, 1e-10)
    assert spent == 0 and x is not None and not x.any()


def _wall():
    """A 4 x 6 running-bond wall on a base, held on its left column and tilted out of
    plane: its joints open and slide one after another on the way to collapse."""
    wall = builders.running_bond_wall(4, 6, 0.2, 0.3, 0.1, 20e3)
    return on_base(wall, left=["u1", "u3"])


@pytest.mark.parametrize("backend", ["superlu", "pardiso"])
def test_reused_factorizations_reach_the_same_equilibria(backend, monkeypatch):
    """The same pushover with a factorization per tangent and with GMRES on the newest
    factors (to 1e-10): the same path (steps and their load factors within 1e-7, the
    displacements of every step within 1e-6 of the largest) and the same collapse
    multiplier within 1e-7, with fewer factorizations."""
    if backend not in fz.installed():
        pytest.skip(f"{backend} is not installed")
    monkeypatch.setenv(fz.ENVIRONMENT, backend)
    runs = []
    for iterations in (0, 12):
        solver = StaticSolver(
            _wall(), StaticSettings(krylov_iterations=iterations, krylov_tolerance=1e-10)
        )
        runs.append((solver, solver.run()))
    (fresh, h0), (reused, h1) = runs
    assert h0.status == h1.status == "collapse"
    assert h1.collapse_multiplier == pytest.approx(h0.collapse_multiplier, rel=1e-7)
    assert len(h1.steps) == len(h0.steps)
    for a, b in zip(h0.steps, h1.steps, strict=True):
        assert b.load_factor == pytest.approx(a.load_factor, rel=1e-7, abs=1e-12)
        scale = max(np.abs(a.q).max(), 1e-30)
        np.testing.assert_allclose(b.q, a.q, rtol=0, atol=1e-6 * scale)
    assert reused.problem.krylov_solves > 0  # the reuse did take place
    assert reused.factorizations < fresh.factorizations


@pytest.mark.parametrize(
    ("field", "value", "words"),
    [
        ("krylov_iterations", -1, "an integer >= 0"),
        ("krylov_iterations", 2.5, "an integer >= 0"),
        ("krylov_tolerance", 0.0, "a number between 0 and 1"),
        ("krylov_tolerance", 1.0, "a number between 0 and 1"),
        ("krylov_tolerance", float("nan"), "a number between 0 and 1"),
    ],
)
def test_bad_krylov_settings_are_refused_by_name(field, value, words):
    with pytest.raises(ValueError, match=rf"{field} must be {words}, got"):
        StaticSettings(**{field: value})
