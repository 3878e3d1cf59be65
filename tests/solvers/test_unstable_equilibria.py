"""The stability test along the path (docs/solvers.md, "The stability test"): the sign of
det K_t from a SuperLU factorization, exact whatever pivots it took, and the instability
rule run where a converged state of the path has det K_t < 0.

Proves:

- the sign of the determinant equals numpy's (``slogdet``) on random structurally symmetric,
  numerically unsymmetric matrices with weak, negative or zero diagonals (the last factorized
  with partial pivoting, whose row permutation counts), and the parity of a permutation is
  that of its transpositions;
- a wall that stands under its weight is stable (det K_t > 0), and along its pushover the
  sign at each state the test is asked about is numpy's;
- on a generated wall whose path passes unstable equilibria (w092: det K_t < 0 from lambda
  0.320 to 0.332, 0.497 to 0.503 and 0.565 to 0.579 along the path of work control), the
  pushover agrees with the reference quasi-static analysis within 2 %; without the test
  it followed the unstable branch to 0.5986, 12 % above the reference's 0.5344.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import sparse

import masonry_dem as md
from helpers.walls import A, B, S, on_base
from masonry_dem.geometry import builders
from masonry_dem.solvers import factorization as fz
from masonry_dem.solvers.incremental import StaticSolver
from masonry_dem.solvers.static import paths
from masonry_dem.studies.corpus import random_wall
from masonry_dem.studies.judge import reference_within_range


def weak_matrix(n: int, density: float, seed: int, zero_diagonal: bool) -> sparse.csc_matrix:
    """Structurally symmetric, numerically unsymmetric, with a diagonal of either sign no
    larger than the off-diagonal entries (pivots of both signs); ``zero_diagonal``: its
    first diagonal entry stored as 0 (diagonal pivots fail: partial pivoting)."""
    rng = np.random.default_rng(seed)
    mask = sparse.random(n, n, density=density, rng=rng, format="csc")
    pattern = mask + mask.T + sparse.identity(n) + sparse.eye(n, k=1) + sparse.eye(n, k=-1)
    pattern = pattern.tocoo()
    values = rng.uniform(-1.0, 1.0, pattern.nnz)
    values[pattern.row == pattern.col] *= 0.5
    if zero_diagonal:
        values[(pattern.row == 0) & (pattern.col == 0)] = 0.0
    M = sparse.csc_matrix((values, (pattern.row, pattern.col)), shape=(n, n))
    M.sort_indices()
    return M


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(2, 40),
    density=st.floats(0.0, 0.3),
    seed=st.integers(0, 2**31 - 1),
    zero_diagonal=st.booleans(),
)
def test_the_determinant_sign_is_numpys(n, density, seed, zero_diagonal):
    M = weak_matrix(n, density, seed, zero_diagonal)
    sign, logdet = np.linalg.slogdet(M.toarray())
    if sign != 0 and logdet < np.log(1e-12) + np.log(np.abs(M).max()) * n:
        return  # too close to singular for either to tell the sign
    factors = fz.signed_factorizer(M.indptr, M.indices, n).factor(M.data)
    assert factors.determinant_sign() == int(sign)


@pytest.mark.parametrize(
    "dense",
    [
        [[0.0, 2.0], [3.0, 0.0]],  # det -6
        [[0.0, 2.0, 0.0], [3.0, 0.0, 1.0], [0.0, 1.0, 1.0]],  # det -6
        [[0.0, 1.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 0.0]],  # singular
        [[-1.0, 0.5], [0.5, -2.0]],  # det 1.75, both pivots negative
    ],
)
def test_zero_and_negative_pivots_give_the_sign_of_the_determinant(dense):
    D = np.array(dense)
    n = D.shape[0]
    # every diagonal entry stored, zeros too (the pattern of the solver's tangents)
    pattern = sparse.csc_matrix((D != 0.0) | np.eye(n, dtype=bool), dtype=float)
    pattern.sort_indices()
    columns = np.repeat(np.arange(n), np.diff(pattern.indptr))
    values = D[pattern.indices, columns]
    expected = int(np.sign(round(float(np.linalg.det(D)), 9)))
    factorizer = fz.signed_factorizer(pattern.indptr, pattern.indices, n)
    try:
        sign = factorizer.factor(values).determinant_sign()
    except fz.SingularMatrix:
        sign = 0
    assert sign == expected


@settings(max_examples=40, deadline=None)
@given(perm=st.permutations(list(range(12))))
def test_the_parity_of_a_permutation_is_that_of_its_transpositions(perm):
    p = np.array(perm)
    swaps, q = 0, p.copy()
    for i in range(q.size):  # selection by transpositions
        j = int(np.flatnonzero(q == i)[0])
        if j != i:
            q[[i, j]] = q[[j, i]]
            swaps += 1
    assert fz.permutation_parity(p) == (-1) ** swaps


def test_the_sign_on_a_walls_tangents_is_numpys_and_positive_under_the_dead_load(monkeypatch):
    """A 4 x 5 running-bond wall on a base, held on its left column, tilted out of plane:
    det K_t > 0 under its weight (a wall that stands is stable), and at every state the
    stability test is asked about along its pushover, yielded joints and all, the sign is
    numpy's."""
    wall = builders.running_bond_wall(4, 5, A, B, S, 20e3)
    model = on_base(wall, left=["u1", "u3"])
    solver = StaticSolver(model)
    problem = solver.problem
    dead = solver.dead_load()
    assert dead.ok
    assert problem.determinant_sign(dead.response) == 1

    asked: list[int] = []
    test = paths.unstable

    def checked(solver_, out):
        own = solver_.problem
        K = own.tangent_assembler.matrix(own.joint_tangents(out.response))
        sign = int(np.linalg.slogdet(K.toarray())[0])
        assert own.determinant_sign(out.response) == sign, out.load_factor
        asked.append(sign)
        return test(solver_, out)

    monkeypatch.setattr(paths, "unstable", checked)
    hist = StaticSolver(model).run()
    assert hist.status == "collapse", hist.reason
    assert len(asked) >= 5


@pytest.mark.slow
def test_the_pushover_leaves_unstable_equilibria_as_the_reference_does():
    model = random_wall(92).build()
    reference, _ = reference_within_range(model)
    assert reference.status == "collapse", reference.reason
    hist = md.pushover(model)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(reference.collapse_multiplier, rel=0.02)
