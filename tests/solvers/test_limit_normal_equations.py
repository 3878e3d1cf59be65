"""The interior point method on the normal equations (``limit_analysis.normal_ipm``), its cone
kernels and the mirror reduction: closed forms, Clarabel's answers, and the certified bracket."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.geometry.builders import add_base, running_bond_wall, single_block
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.limit_analysis import cones, formulation, limit_analysis, normal_ipm
from masonry_dem.solvers.limit_analysis.dem_domain import dem_friction_scale
from masonry_dem.solvers.limit_analysis.kinematic import solve_kinematic_clarabel
from masonry_dem.solvers.limit_analysis.mirror import mirror_dofs
from masonry_dem.solvers.limit_analysis.result import mechanism_violation

GAMMA = 2.0e4


def _on_base(blocks, mu: float, direction=(0.0, 0.0, 1.0)) -> Model:
    blocks, base = add_base(blocks)
    return Model.build(
        blocks,
        InterfaceMaterial(kn=1e9, kt=1e9, friction=mu),
        [Support([base])],
        [SelfWeight(), WeightProportional(direction)],
    )


def _ladder_wall(side: int) -> Model:
    """The size ladder's wall: side x side courses of 0.4 x 0.2 x 0.2 m running bond, mu 0.6,
    on a slab, tilted in plane."""
    wall = running_bond_wall(side, side, a=0.2, b=0.4, s=0.2, unit_weight=2000 * 9.81)
    return _on_base(wall, 0.6, direction=(1.0, 0.0, 0.0))


def _pardiso() -> None:
    """The normal equations need PARDISO (``pypardiso``, a test dependency on x86-64)."""
    pytest.importorskip("pypardiso")


def _interior(rng, p: int) -> np.ndarray:
    x = rng.standard_normal((p, 3))
    x[:, 0] = np.hypot(x[:, 1], x[:, 2]) + rng.uniform(1e-3, 2.0, p)
    return x


def test_cone_kernels_against_their_definitions():
    """The Nesterov-Todd scaling maps s and z to one point, ``W s = W^-1 z = lam`` (its
    definition), W^2 is W applied twice, the Jordan solve inverts the Jordan product, and the
    largest step lands on the boundary (det = 0) with the point inside just before it."""
    rng = np.random.default_rng(3)
    s, z = _interior(rng, 50), _interior(rng, 50)
    w, beta, lam = cones.nt_scaling(s, z)
    out = np.empty_like(s)
    cones.apply_w(w, beta, z, -1, out)
    assert np.allclose(out, lam, rtol=1e-12, atol=1e-12)
    once, twice = np.empty_like(s), np.empty_like(s)
    cones.apply_w(w, beta, s, 1, once)
    cones.apply_w(w, beta, once, 1, twice)
    cones.apply_w(w, beta, s, 2, out)
    assert np.allclose(out, twice, rtol=1e-12, atol=1e-12)
    r = rng.standard_normal((50, 3))
    assert np.allclose(cones.jordan(lam, cones.jordan_solve(lam, r)), r, atol=1e-10)
    for k in range(5):
        d = rng.standard_normal((1, 3)) * 3
        alpha = cones.max_step(s[k : k + 1], d)
        if np.isfinite(alpha):
            edge = s[k] + alpha * d[0]
            assert edge[0] ** 2 - edge[1] ** 2 - edge[2] ** 2 == pytest.approx(0.0, abs=1e-9)
            inside = s[k] + 0.999 * alpha * d[0]
            assert inside[0] > np.hypot(inside[1], inside[2])


def test_centrality_correction_is_the_clipped_spectral_product():
    """Gondzio's correction of a cone: the scaled product v = (W s_t) o (W^-1 z_t) at the
    trial point has spectral values v0 +- |v1|; the correction moves each into [lo, hi]
    (a decrease capped at -hi) in v's own frame, so v + t has its spectral values there."""
    rng = np.random.default_rng(5)
    s, z = _interior(rng, 200), _interior(rng, 200)
    ds, dz = 0.3 * rng.standard_normal((200, 3)), 0.3 * rng.standard_normal((200, 3))
    w, beta, _ = cones.nt_scaling(s, z)
    alpha, lo, hi = 0.6, 0.5, 3.0
    ws, wz = np.empty_like(s), np.empty_like(s)
    cones.apply_w(w, beta, s + alpha * ds, 1, ws)
    cones.apply_w(w, beta, z + alpha * dz, -1, wz)
    v = cones.jordan(ws, wz)
    t = cones.centrality_correction(w, beta, s, z, ds, dz, alpha, lo, hi)

    def spectral(x: np.ndarray) -> np.ndarray:  # (p, 2): v0 + |v1|, v0 - |v1|
        norm = np.hypot(x[:, 1], x[:, 2])
        return np.column_stack([x[:, 0] + norm, x[:, 0] - norm])

    before = spectral(v)
    assert np.allclose(spectral(v + t), np.maximum(np.clip(before, lo, hi), before - hi))
    assert (before < lo).any() and (before > hi).any()  # both sides were clipped
    # the frame kept: v1 + t1 parallel to v1
    cross = (v + t)[:, 1] * v[:, 2] - (v + t)[:, 2] * v[:, 1]
    assert np.allclose(cross, 0.0, atol=1e-12)


def test_normal_matrix_is_g_transpose_s_g():
    """The compiled pattern of the normal matrix (no sort: a block's columns are contiguous)
    and its entries: ``N x = G^T W^2 G x`` on a wall with a partly held column, on every DOF
    and on the mirror-symmetric ones; every row starts on its diagonal."""
    from scipy import sparse

    from masonry_dem.solvers.limit_analysis.kinematic import corner_velocity_rows

    wall = running_bond_wall(5, 6, a=0.1, b=0.25, s=0.12, unit_weight=GAMMA)
    placed, base = add_base(wall)
    held = [0, 5, 10]
    model = Model.build(
        placed,
        InterfaceMaterial(kn=1e9, kt=4e8, friction=0.6),
        [Support([base]), Support(held, ["u1", "u3"])],
        [SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
    )
    problem = formulation.Problem.of(model)
    G_all = corner_velocity_rows(problem, 2).tocsr()
    free = np.flatnonzero(problem.free)
    rng = np.random.default_rng(7)
    for drop in (None, mirror_dofs(model)):
        keep = np.ones(free.size, dtype=bool) if drop is None else ~drop[free]
        G = G_all[:, keep].tocsr()
        index = np.full(model.n_dofs, -1)
        index[free[keep]] = np.arange(int(keep.sum()))
        normal = normal_ipm._NormalMatrix(G, model, index, 4)
        p = G.shape[0] // 3
        s, z = _interior(rng, p), _interior(rng, p)
        w, beta, _ = cones.nt_scaling(s, z)
        N = normal.assemble(w, beta, 0.0)
        assert np.array_equal(N.indices[N.indptr[:-1]], np.arange(N.shape[0]))
        full = N + sparse.triu(N, 1).T
        x = rng.standard_normal(G.shape[1])
        sgx = np.empty((p, 3))
        cones.apply_w(w, beta, np.ascontiguousarray((G @ x).reshape(-1, 3)), 2, sgx)
        expected = G.T @ sgx.ravel()
        assert np.allclose(full @ x, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    assert drop is not None  # loaded in its plane: the mirror plane was tried too


def test_early_iterates_past_the_cap_are_not_no_collapse(monkeypatch):
    """The first iterates are far from any mechanism, and their ``c . u`` passes lambda's cap
    on large walls (7 000 at 3 x 10^4 blocks): at 10^5 that sent the wall to Clarabel, which
    filled the memory. Here, with the cap at 50 and the 298-block wall (c . u 110 at its
    third iterate, lambda 0.4657), the normal equations still certify the multiplier; the cap
    counts only once the iterate is nearly a mechanism."""
    _pardiso()
    problem = formulation.Problem.of(_ladder_wall(17))
    monkeypatch.setattr(formulation, "LAMBDA_CAP", 50.0)
    assert formulation.lambda_cap(problem.live, problem.rhs) < 100
    out = normal_ipm.solve_kinematic_normal(problem, 2)
    assert out is not None
    bracket = out[3]
    assert bracket.lower - 1e-6 <= 0.465658 <= bracket.upper + 1e-6


def test_a_reflection_that_swaps_blocks_halves_the_velocities(monkeypatch):
    """A wall on a base pushed out of its plane is symmetric about the vertical plane across
    its middle, which swaps its blocks in pairs (``mirror_pairs``; no plane holds every block,
    so ``mirror_dofs`` finds none): the normal equations on its symmetric mechanisms give the
    bracket of every DOF, which holds the closed form of the wall tipping about its base edge
    as one body, lambda = s / H; the wall held at its left edge only has no such plane."""
    from masonry_dem.geometry import selectors as select
    from masonry_dem.solvers.limit_analysis.mirror import mirror_pairs, symmetric_basis

    _pardiso()
    a, b, s = 0.081, 0.210, 0.070
    wall = running_bond_wall(14, 14, a=a, b=b, s=s, unit_weight=GAMMA)
    placed, base = add_base(wall)

    def model(held: list[int]) -> Model:
        supports = [Support([base])] + ([Support(held, ["u1", "u3"])] if held else [])
        return Model.build(
            placed,
            InterfaceMaterial(kn=1e9, kt=4e8, friction=0.7),
            supports,
            [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        )

    free = model([])
    assert mirror_dofs(free) is None
    problem = formulation.Problem.of(free)
    pairs = mirror_pairs(problem)
    assert pairs is not None
    perm, signs, _ = pairs
    swapped = perm != np.arange(free.blocks.count)
    assert swapped.sum() >= free.blocks.count - 14 and np.array_equal(
        perm[perm], np.arange(perm.size)
    )
    P, kept, _ = symmetric_basis(problem, pairs)
    assert P.shape[1] < 0.55 * P.shape[0]  # about half the velocities
    whole = normal_ipm.solve_kinematic_normal(problem, 2)
    half = normal_ipm.solve_kinematic_normal(problem, 2, pairs=pairs)
    assert whole is not None and half is not None
    closed = s / (14 * a)
    for out in (whole, half):
        bracket = out[3]
        assert bracket.width <= normal_ipm.BRACKET
        assert bracket.lower - 1e-8 <= closed <= bracket.upper + 1e-8
    u = half[1]
    assert mechanism_violation(free, problem.velocities(u), None) < 1e-8
    R = formulation.associative_columns(free, 2, None)[0]
    residual = problem.H_T @ (R @ half[0].x) - half[3].lower * problem.live - problem.rhs
    assert np.abs(residual).max() < 1e-7 * np.abs(problem.rhs).max()
    r = limit_analysis(free)
    assert "swaps blocks in pairs" in r.reason and r.bracket is not None
    held = select.column(placed, "left", among=list(range(wall.count)))
    assert mirror_pairs(formulation.Problem.of(model(list(held)))) is None
    # corners that do not pair: every DOF, not Clarabel (whose memory at 10^5 blocks is
    # the machine's)
    monkeypatch.setattr(normal_ipm, "_mirror_cones", lambda *args: None)
    again = normal_ipm.solve_kinematic_normal(problem, 2, pairs=pairs)
    assert again is not None and "swaps" not in again[0].detail
    assert again[3].upper == whole[3].upper


def test_centrality_correctors_save_iterations():
    """Gondzio's correctors (``CORRECTORS``, one solve each with the factorization at hand)
    on the 298-block ladder wall, every DOF: the same certified bracket in fewer iterations
    than Mehrotra's predictor-corrector alone (20 against 22 when measured)."""
    _pardiso()
    problem = formulation.Problem.of(_ladder_wall(17))
    iterations = {}
    for correctors in (0, normal_ipm.CORRECTORS):
        normal_ipm.CORRECTORS, saved = correctors, normal_ipm.CORRECTORS
        try:
            out = normal_ipm.solve_kinematic_normal(problem, 2)
        finally:
            normal_ipm.CORRECTORS = saved
        assert out is not None
        sol, _, _, bracket = out
        assert bracket.width <= normal_ipm.BRACKET
        assert bracket.lower - 1e-6 <= 0.465658 <= bracket.upper + 1e-6
        iterations[correctors] = sol.iterations
    assert normal_ipm.CORRECTORS >= 1
    assert iterations[normal_ipm.CORRECTORS] < iterations[0], iterations


def test_single_block_tilts_inside_the_bracket():
    """A block a high and s thick on a rigid base tilts out of plane at lambda = s/a (its
    weight's lever s/2 against the push's a/2; friction 0.6 > s/a): the certified bracket
    holds s/a (to the 1e-8 to which its mechanism and forces are admissible) and is within
    ``BRACKET``."""
    _pardiso()
    a, s = 0.4, 0.1
    problem = formulation.Problem.of(_on_base(single_block(a, 0.3, s, GAMMA), 0.6))
    out = normal_ipm.solve_kinematic_normal(problem, 2)
    assert out is not None
    sol, u, K, bracket = out
    assert bracket.lower - 1e-8 <= s / a <= bracket.upper + 1e-8
    assert bracket.violation <= normal_ipm.ADMISSIBLE
    assert bracket.width <= normal_ipm.BRACKET
    assert sol.lam == bracket.upper and sol.bracket == (bracket.lower, bracket.upper)


def test_mirror_plane_of_a_wall_in_its_plane():
    """A wall of one leaf pushed in its plane (e1-e2, thickness along e3) is its own mirror
    image through its mid-plane: the symmetric mechanisms have u3 = w1 = w2 = 0. Pushed out
    of plane it is not (the load is on u3)."""
    drop = mirror_dofs(_ladder_wall(4))
    assert drop is not None
    assert drop.reshape(-1, 6).all(axis=0).tolist() == [False, False, True, True, True, False]
    wall = running_bond_wall(4, 4, a=0.2, b=0.4, s=0.2, unit_weight=GAMMA)
    assert mirror_dofs(_on_base(wall, 0.6, direction=(0.0, 0.0, 1.0))) is None


def test_ladder_wall_bracket_holds_clarabels_multiplier():
    """The 298-block ladder wall, whose multiplier 0.465658 is the 4-face LP's (exact in plane,
    ``test_limit_analysis``): the normal equations on every DOF and on the mirror-symmetric
    ones give brackets within ``BRACKET`` that hold Clarabel's multiplier (to its 1e-8
    tolerance); the mechanism is admissible, and the certified forces balance every free DOF
    (the out-of-plane ones too) at the bracket's lower end."""
    _pardiso()
    model = _ladder_wall(17)
    problem = formulation.Problem.of(model)
    reference, _, _ = solve_kinematic_clarabel(problem, 2)
    assert reference.lam == pytest.approx(0.465658, rel=1e-5)
    drop = mirror_dofs(model)
    for reduce in (None, drop):
        out = normal_ipm.solve_kinematic_normal(problem, 2, drop=reduce)
        assert out is not None
        sol, u, K, bracket = out
        assert bracket.width <= normal_ipm.BRACKET
        assert bracket.lower - 1e-8 <= reference.lam <= bracket.upper + 1e-8
        assert mechanism_violation(model, problem.velocities(u), None) < 1e-8
        R = formulation.associative_columns(model, 2, None)[0]
        residual = problem.H_T @ (R @ sol.x) - bracket.lower * problem.live - problem.rhs
        assert np.abs(residual).max() < 1e-7 * np.abs(problem.rhs).max()


def test_out_of_plane_wall_agrees_with_clarabel():
    """A wall pushed out of plane (no mirror plane: every DOF is solved for) against
    Clarabel's kinematic SOCP on the same problem."""
    _pardiso()
    wall = running_bond_wall(6, 8, a=0.1, b=0.25, s=0.12, unit_weight=GAMMA)
    model = _on_base(wall, 0.6, direction=(0.0, 0.0, 1.0))
    problem = formulation.Problem.of(model)
    reference, _, _ = solve_kinematic_clarabel(problem, 2)
    out = normal_ipm.solve_kinematic_normal(problem, 2, drop=mirror_dofs(model))
    assert out is not None
    bracket = out[3]
    assert bracket.lower - 1e-8 <= reference.lam <= bracket.upper + 1e-8


def test_entry_point_reports_the_bracket_and_falls_back_without_pardiso(monkeypatch):
    """From ``NORMAL_EQUATIONS_FROM`` velocities the exact cone is solved on the normal
    equations and the result carries the bracket; without pypardiso the same call is
    Clarabel's, with no bracket and the same multiplier."""
    _pardiso()
    model = _ladder_wall(17)
    assert 6 * (model.blocks.count - 1) >= normal_ipm.NORMAL_EQUATIONS_FROM
    r = limit_analysis(model, backend="clarabel")
    assert r.bracket is not None and "normal-equation" in r.reason
    assert r.summary()["lambda_bracket"] == [r.bracket[0], r.bracket[1]]
    monkeypatch.setitem(__import__("sys").modules, "pypardiso", None)
    plain = limit_analysis(model, backend="clarabel")
    assert plain.bracket is None and "Clarabel" in plain.reason
    assert plain.load_factor == pytest.approx(r.load_factor, rel=1e-6)


def test_friction_scale_of_many_interfaces_is_that_of_their_alphas():
    """kappa over an array is the largest kappa of its distinct values (one per interface in
    a model: the same answer as the scalars)."""
    alphas = np.array([1.5] * 50_000 + [2.0] * 3)
    assert dem_friction_scale(alphas) == dem_friction_scale(2.0)
    assert dem_friction_scale(2.0) == pytest.approx(np.sqrt(5) / 2, rel=1e-8)


def test_the_single_block_bracket_does_not_depend_on_what_ran_before():
    """The same block after a pushover of it: on a948e3a the pushover's round-off left the
    IPM a full step onto the cones' boundary (mu 7e-18), the next scaling 0 / 0 and every
    iterate after it NaN, so no bracket; a step is now always a fraction of the way to the
    boundary, and a step that is not finite ends the iteration."""
    import masonry_dem as md

    _pardiso()
    a, s = 0.4, 0.1
    model = _on_base(single_block(a, 0.3, s, GAMMA), 0.6)
    assert md.pushover(model).collapse_multiplier == pytest.approx(s / a, rel=1e-6)
    out = normal_ipm.solve_kinematic_normal(formulation.Problem.of(model), 2)
    assert out is not None
    bracket = out[3]
    assert bracket.lower - 1e-8 <= s / a <= bracket.upper + 1e-8
    assert bracket.width <= normal_ipm.BRACKET
