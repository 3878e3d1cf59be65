"""The non-associative iteration's frozen-capacity LP by column generation (``columns``):
the full LP's lambda on closed forms and on a wall whose first master is not optimal."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse

from helpers.walls import on_base
from masonry_dem.geometry.builders import single_block
from masonry_dem.geometry.plans import l_wall
from masonry_dem.solvers.limit_analysis import columns, limit_analysis
from masonry_dem.solvers.limit_analysis import non_associative as na

GAMMA = 2.0e4


@pytest.mark.parametrize("column_generation", [True, False])
def test_sliding_block_at_mu_by_columns_and_in_full(column_generation):
    """mu = 0.2 < s/a = 0.25: the block slides without dilating when lambda W = mu W, so
    lambda = 0.2 and the mechanism does not rise (u2 = 0), whichever way the LP is solved."""
    model = on_base(single_block(0.4, 0.3, 0.1, GAMMA), 0.2)
    r = limit_analysis(model, associative=False, column_generation=column_generation)
    assert r.status == "collapse", r.reason
    assert r.load_factor == pytest.approx(0.2, rel=1e-6)
    assert abs(r.block_velocities[0, 1]) < 1e-6
    assert ("pricing_rounds" in r.info) == column_generation


@pytest.mark.parametrize("column_generation", [True, False])
def test_tilting_block_at_s_over_a_by_columns_and_in_full(column_generation):
    """mu = 0.6 > s/a = 0.25: the block turns about its front edge at lambda = s/a (moments
    about that edge: lambda W a/2 = W s/2), with no sliding to price."""
    a, s = 0.4, 0.1
    model = on_base(single_block(a, 0.3, s, GAMMA), 0.6)
    r = limit_analysis(model, associative=False, column_generation=column_generation)
    assert r.status == "collapse", r.reason
    assert r.load_factor == pytest.approx(s / a, rel=1e-6)
    assert r.block_velocities[0, 1] == pytest.approx(s / a, rel=1e-5)


@pytest.fixture(scope="module")
def l_wall_lp():
    """The first frozen-capacity LP of a small L wall (a 3-block facade, a 2-block return,
    2 courses: 22 interfaces, 1 408 points, 11 264 edge columns), tilted out of plane: its
    corner turns and twists, so the bed joints carry torsion, which no translation pattern
    gives."""
    wall = l_wall(3, 2, 0.081, 0.21, 0.07, GAMMA, return_blocks=2)
    model = on_base(wall, 0.7)
    got = []
    real = na.solve_frozen_columns

    def capture(E_n, friction, live, rhs, start, duals):
        got.append((E_n, friction, live, rhs))
        return real(E_n, friction, live, rhs, start, duals)

    na.solve_frozen_columns = capture
    try:
        limit_analysis(model, associative=False, max_iterations=1)
    finally:
        na.solve_frozen_columns = real
    E_n, friction, live, rhs = got[0]
    return E_n, friction, live, rhs, columns.solve_frozen_full(E_n, friction, live, rhs)


def test_pricing_adds_the_missing_patterns_and_reaches_the_full_lp(l_wall_lp):
    """From the translations alone (no start, no duals) the first master is not optimal:
    pricing must add patterns (rounds and patterns counted) and stop at the full LP's
    lambda (HiGHS's interior point on all 11 264 columns) to its certified 1e-7."""
    E_n, friction, live, rhs, full = l_wall_lp
    assert full.status == "optimal"
    sol, patterns, stats = columns.solve_frozen_columns(E_n, friction, live, rhs, None, None)
    assert sol.status == "optimal", sol.detail
    assert not stats.full
    assert stats.rounds >= 2
    translations = friction.m * friction.D
    assert stats.columns > translations  # patterns were added
    assert stats.columns < friction.E_s.shape[1] / 10
    assert sol.lam == pytest.approx(full.lam, rel=1e-7)
    # the patterns in use seed the next iteration
    assert 0 < patterns.choice.shape[0] <= stats.columns


def test_the_edge_multipliers_are_a_solution_of_the_full_lp(l_wall_lp):
    """The master's thetas, spread back to the edges ``g_pd``, satisfy the full LP's rows:
    equilibrium ``E x - lambda live = rhs``, ``g >= 0`` and ``sum_d g_pd <= cap_p`` at
    every point, so the actions the next iteration freezes are the full LP's kind."""
    E_n, friction, live, rhs, _ = l_wall_lp
    sol, _, _ = columns.solve_frozen_columns(E_n, friction, live, rhs, None, None)
    E = sparse.hstack([E_n, friction.E_s], format="csc")
    residual = E @ sol.x - sol.lam * live - rhs
    assert np.abs(residual).max() <= 1e-7 * np.abs(rhs).max()
    g = sol.x[E_n.shape[1] :].reshape(-1, friction.D)
    assert g.min() >= 0
    assert (g.sum(axis=1) - friction.cap).max() <= 1e-9 * friction.cap.max()


def test_a_master_out_of_rounds_falls_back_on_the_full_lp(l_wall_lp):
    """One round is not enough from the translations: the full LP is solved instead, and
    its lambda returned."""
    E_n, friction, live, rhs, full = l_wall_lp
    sol, _, stats = columns.solve_frozen_columns(E_n, friction, live, rhs, None, None, max_rounds=1)
    assert stats.full
    assert sol.lam == full.lam


def test_the_master_without_highspy_gives_the_same_lambda(l_wall_lp, monkeypatch):
    """Where highspy is missing the master is re-solved by scipy's linprog each round (no
    hot start): the same rounds of pricing reach the full LP's lambda."""
    E_n, friction, live, rhs, full = l_wall_lp
    monkeypatch.setattr(columns, "_master", columns._LinprogMaster)
    sol, _, stats = columns.solve_frozen_columns(E_n, friction, live, rhs, None, None)
    assert not stats.full and stats.rounds >= 2
    assert sol.lam == pytest.approx(full.lam, rel=1e-7)
