"""Linear elastic solve of block assemblies against closed-form answers.

Proves: stacked blocks in compression carry the exact normal force and shorten by exactly
N / (kn A) per joint (and an eccentric load rotates the block by M / (kn I)); a stack-bond
column under a tip load matches the closed-form deflection of a chain of rigid blocks with
elastic joints, in plane and out of plane; reactions equilibrate the loads (forces and
moments); a symmetric wall under a symmetric load has mirror-symmetric displacements and an
in-plane load moves nothing out of plane; the answer does not depend on the block numbering.
"""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import add_base, running_bond_wall, stack_bond_column
from masonry_dem.geometry.selectors import column, where
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    PointLoad,
    Pressure,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.solvers.linear import solve_linear

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0
KN, KT = 2.4e9, 1.0e9
MAT = InterfaceMaterial(kn=KN, kt=KT, friction=0.7)
RTOL = 1e-9


def _column_on_base(k: int, a=A, b=B, s=S, gamma=GAMMA) -> tuple[Blocks, int]:
    return add_base(stack_bond_column(k, a, b, s, gamma))


# ---------------------------------------------------------------- blocks in compression
def test_block_on_a_base_under_self_weight():
    blocks, ib = _column_on_base(1)
    model = Model.build(blocks, MAT, [Support([ib])], loads=[SelfWeight()])
    sol = solve_linear(model)
    W = GAMMA * A * B * S
    area = B * S
    assert model.interfaces.count == 1
    assert sol.actions[0, 2] == pytest.approx(-W, rel=RTOL)  # compression negative
    assert sol.relative[0, 2] == pytest.approx(-W / (KN * area), rel=RTOL)
    expect_q = np.zeros(6)
    expect_q[1] = -W / (KN * area)
    np.testing.assert_allclose(sol.q[0], expect_q, rtol=RTOL, atol=1e-12 * W / (KN * area))
    assert not np.delete(sol.actions[0], 2).any()
    # the base reacts with W upwards
    np.testing.assert_allclose(sol.reactions[ib], [0, W, 0, 0, 0, 0], atol=1e-9 * W)
    assert not sol.reactions[0].any()


def test_two_stacked_blocks_in_compression():
    """Two blocks of weights W1 (bottom) and W2 (top, twice as dense) on a fixed base: the
    joints carry N0 = W1 + W2 and N1 = W2 and shorten by N / (kn b s) each."""
    lower = np.array([[0.0, 0.0, 0.0], [0.0, A, 0.0]])
    two = Blocks.from_boxes(lower, lower + [B, A, S], [GAMMA, 2 * GAMMA])
    blocks, ib = add_base(two)
    model = Model.build(blocks, MAT, [Support([ib])], loads=[SelfWeight()])
    sol = solve_linear(model)
    W1, W2 = GAMMA * A * B * S, 2 * GAMMA * A * B * S
    its = model.interfaces
    base_joint = np.flatnonzero(its.block_i == ib)[0]
    mid_joint = np.flatnonzero((its.block_i == 0) & (its.block_j == 1))[0]
    assert sol.actions[base_joint, 2] == pytest.approx(-(W1 + W2), rel=RTOL)
    assert sol.actions[mid_joint, 2] == pytest.approx(-W2, rel=RTOL)
    kA = KN * B * S
    assert sol.q[0, 1] == pytest.approx(-(W1 + W2) / kA, rel=RTOL)
    assert sol.q[1, 1] == pytest.approx(-(W1 + W2) / kA - W2 / kA, rel=RTOL)
    others = np.abs(np.delete(sol.q[:2], 1, axis=1)).max()
    assert others <= 1e-12 * abs(sol.q[1, 1])


def test_eccentric_load_on_a_block_rotates_it_by_M_over_kn_I():
    """Point load P down at eccentricity e along e1 from the centre of a block on a fixed
    base: N = -P, M3 = -e P, w3 = M3 / (kn s b^3 / 12), and no slip at the joint, so the
    centre (a/2 above the joint) moves by u1 = -w3 a / 2."""
    blocks, ib = _column_on_base(1)
    P, e = 1000.0, 0.04
    load = PointLoad([0], (0.0, -P, 0.0), offset=(e, 0.0, 0.0))
    model = Model.build(blocks, MAT, [Support([ib])], loads=[load])
    sol = solve_linear(model)
    I3 = S * B**3 / 12
    w3 = -e * P / (KN * I3)
    expect = np.array([-w3 * A / 2, -P / (KN * B * S), 0.0, 0.0, 0.0, w3])
    np.testing.assert_allclose(sol.q[0], expect, rtol=RTOL, atol=1e-12 * abs(w3))
    # local order of a bed joint: y1 = e3, y2 = e1, so m1 is the moment about e3
    np.testing.assert_allclose(
        sol.actions[0], [0, 0, -P, -e * P, 0, 0], rtol=RTOL, atol=1e-9 * P * e
    )


# ------------------------------------------------------------ stack-bond column, tip load
def column_tip_closed_form(k: int, F: float, bending_inertia: float) -> tuple[float, float]:
    r"""Tip translation and rotation of k rigid blocks (height a) on a fixed base, elastic
    joints, under a lateral force F at the centre of the top block.

    Derivation. Joint j (j = 0 at the base, j = 1..k-1 between blocks j-1 and j) lies at
    height y_j = j a; the load acts at y_F = (k - 1/2) a. The chain is statically
    determinate: every joint carries the shear V = F and the bending moment
    M_j = F (y_F - y_j) = F h_j, h_j = (k - j - 1/2) a. With rigid blocks the joint is the
    only compliance: it slips by s_j = F / (kt A) (A = b s) and rotates by
    theta_j = M_j / (kn I) (I the second moment about the bending axis). Each joint moves
    everything above it rigidly, so the load point (the top block centre) translates by
        u = sum_j [ s_j + theta_j h_j ] = k F / (kt A) + F / (kn I) sum_j h_j^2
    and rotates by
        theta = sum_j theta_j = F / (kn I) sum_j h_j,
    with sum_j h_j = a k^2 / 2 and sum_j h_j^2 = a^2 sum_{m=1}^{k} (m - 1/2)^2
    = a^2 k (4 k^2 - 1) / 12. Block m (centre at y_m = (m + 1/2) a) translates by
    sum_{j <= m} [ s_j + theta_j (y_m - y_j) ] (checked block by block below).
    In plane (F along e1) I = s b^3 / 12 (about e3); out of plane (F along e3)
    I = b s^3 / 12 (about e1); A = b s in both.
    """
    shear = k * F / (KT * B * S)
    bending = F / (KN * bending_inertia) * A**2 * k * (4 * k**2 - 1) / 12
    rotation = F / (KN * bending_inertia) * A * k**2 / 2
    return shear + bending, rotation


@pytest.mark.parametrize("k", [1, 2, 5, 12])
@pytest.mark.parametrize("direction", ["in_plane", "out_of_plane"])
def test_stack_column_tip_load_matches_the_rigid_chain(k, direction):
    blocks, ib = _column_on_base(k)
    F = 350.0
    top = k - 1
    if direction == "in_plane":
        force, comp, rot, inertia, rot_sign = (F, 0, 0), 0, 5, S * B**3 / 12, -1.0
    else:
        force, comp, rot, inertia, rot_sign = (0, 0, F), 2, 3, B * S**3 / 12, 1.0
    model = Model.build(blocks, MAT, [Support([ib])], loads=[PointLoad([top], force)])
    sol = solve_linear(model)
    u_tip, theta_tip = column_tip_closed_form(k, F, inertia)
    # F e1 at height h turns about -e3 (clockwise seen from +e3); F e3 turns about +e1
    assert sol.q[top, comp] == pytest.approx(u_tip, rel=RTOL)
    assert sol.q[top, rot] == pytest.approx(rot_sign * theta_tip, rel=RTOL)
    # every block of the chain
    y_joint = np.arange(k) * A
    h = (k - np.arange(k) - 0.5) * A
    theta_j = F * h / (KN * inertia)
    for m in range(k):
        y_m = (m + 0.5) * A
        u_m = np.sum(F / (KT * B * S) + theta_j[: m + 1] * (y_m - y_joint[: m + 1]))
        assert sol.q[m, comp] == pytest.approx(u_m, rel=RTOL)
        assert sol.q[m, rot] == pytest.approx(rot_sign * theta_j[: m + 1].sum(), rel=RTOL)
    # no vertical motion, no motion in the other plane
    other = [c for c in range(6) if c not in (comp, rot)]
    assert np.abs(sol.q[:k, other]).max() <= 1e-12 * u_tip
    # joint actions: shear F and moment F h_j at every joint, nothing else
    its = model.interfaces
    order = np.argsort(its.centre[:, 1])
    act = sol.actions[order]
    # bed joints: local y1 = e3, y2 = e1; shear along e1 is f2, along e3 is f1; the moment
    # about e3 is m1, about e1 is m2
    shear_col, moment_col = (1, 3) if direction == "in_plane" else (0, 4)
    np.testing.assert_allclose(np.abs(act[:, shear_col]), F, rtol=RTOL)
    np.testing.assert_allclose(np.abs(act[:, moment_col]), F * h, rtol=RTOL)
    rest = np.delete(act, [shear_col, moment_col], axis=1)
    assert np.abs(rest).max() <= 1e-9 * F * A


# -------------------------------------------------------------------------- equilibrium
def _wall_model(**kw) -> Model:
    blocks, ib = add_base(running_bond_wall(5, 6, A, B, S, GAMMA))
    loads = [SelfWeight(), WeightProportional((0.3, 0.0, 1.0)), PointLoad([7], (0, -300.0, 40.0))]
    return Model.build(blocks, MAT, [Support([ib])], loads=loads, **kw)


def test_reactions_balance_the_loads():
    model = _wall_model()
    lam = 0.37
    sol = solve_linear(model, lam)
    F = model.dead + lam * model.live
    total = F + sol.reactions
    c = model.blocks.centres
    force = total[:, :3].sum(axis=0)
    moment = (total[:, 3:] + np.cross(c, total[:, :3])).sum(axis=0)
    scale = np.abs(F[:, :3]).sum()
    np.testing.assert_allclose(force, 0.0, atol=1e-9 * scale)
    np.testing.assert_allclose(moment, 0.0, atol=1e-9 * scale * c.max())
    # reactions only at fixed DOFs; equilibrium of every free DOF
    assert not sol.reactions.reshape(-1)[model.free].any()
    asm = Assembly.of(model)
    resid = asm.internal_forces(sol.actions)[model.free] - F.reshape(-1)[model.free]
    assert np.abs(resid).max() <= 1e-9 * np.abs(F).max()
    # actions are Kbar times the relative displacements
    np.testing.assert_allclose(sol.actions, asm.kbar * sol.relative, rtol=1e-15)


def test_load_factor_scales_the_live_load_only():
    model = _wall_model()
    q0 = solve_linear(model, 0.0).q
    q1 = solve_linear(model, 1.0).q
    q2 = solve_linear(model, 2.5).q
    np.testing.assert_allclose(q2 - q0, 2.5 * (q1 - q0), rtol=1e-9, atol=1e-12 * np.abs(q1).max())


def test_singular_stiffness_is_reported_as_a_mechanism():
    # Model.build refuses mechanisms up front; the solver guards the rest with its own error
    blocks, ib = _column_on_base(1)
    model = Model.build(blocks, MAT, [Support([ib])])
    asm = Assembly.of(model)
    zero = Assembly(asm.H, asm.H_free, asm.free_index, np.zeros_like(asm.kbar))
    with pytest.raises(ValueError, match="mechanism"):
        solve_linear(model, assembly=zero)


# ----------------------------------------------------------------------------- symmetry
def _mirror_index(centres: np.ndarray, axis: int) -> np.ndarray:
    """Index of each block's mirror image through the mid-plane normal to ``axis``."""
    mid = (centres[:, axis].min() + centres[:, axis].max()) / 2
    image = centres.copy()
    image[:, axis] = 2 * mid - image[:, axis]
    d = np.abs(image[:, None, :] - centres[None, :, :]).sum(-1)
    idx = d.argmin(axis=1)
    assert np.all(d[np.arange(len(idx)), idx] < 1e-9)
    return idx


# reflection x -> -x along e1 maps displacements u -> (-u1, u2, u3) and rotations (axial
# vectors) w -> (w1, -w2, -w3)
MIRROR_E1 = np.array([-1, 1, 1, 1, -1, -1])
# reflection along e3 (through the wall's mid-plane): u -> (u1, u2, -u3), w -> (-w1, -w2, w3)
MIRROR_E3 = np.array([1, 1, -1, -1, -1, 1])


@pytest.mark.parametrize("with_base", [False, True])
def test_symmetric_wall_gives_mirror_symmetric_displacements(with_base):
    wall = running_bond_wall(6, 7, A, B, S, GAMMA)  # symmetric about x = 3 b
    blocks, ib = add_base(wall) if with_base else (wall, None)
    supports = [Support(column(wall, "left")), Support(column(wall, "right"))]
    if with_base:
        supports.append(Support([ib]))
    loads = [SelfWeight(), Pressure(2000.0, axis=2, sign=1)]
    model = Model.build(blocks, MAT, supports, loads=loads)
    q = solve_linear(model).q
    mirror = _mirror_index(blocks.centres, 0)
    assert np.any(mirror != np.arange(blocks.count))
    scale = np.abs(q).max()
    assert scale > 0
    np.testing.assert_allclose(q[mirror] * MIRROR_E1, q, rtol=0, atol=1e-9 * scale)
    # the out-of-plane response is not trivially zero
    assert np.abs(q[:, 2]).max() > 0.1 * scale


def test_in_plane_load_moves_nothing_out_of_plane():
    blocks, ib = add_base(running_bond_wall(5, 6, A, B, S, GAMMA))
    loads = [SelfWeight(), WeightProportional((1.0, 0.0, 0.0))]
    model = Model.build(blocks, MAT, [Support([ib])], loads=loads)
    q = solve_linear(model).q
    scale = np.abs(q).max()
    # every block is its own image through the mid-plane z = s/2: symmetric answer
    np.testing.assert_allclose(q * MIRROR_E3, q, rtol=0, atol=1e-12 * scale)
    assert np.abs(q[:, [2, 3, 4]]).max() <= 1e-12 * scale
    assert np.abs(q[:, [0, 1, 5]]).max() > 0


# ------------------------------------------------------------------ numbering invariance
def test_answer_is_independent_of_block_numbering():
    wall = running_bond_wall(5, 6, A, B, S, GAMMA)
    blocks, _ = add_base(wall)

    def build(bl: Blocks) -> Model:
        base = where(bl, lambda c: c[:, 1] < 0, name="base")
        top_right = where(bl, lambda c: (c[:, 1] > 5 * A) & (c[:, 0] > 4 * B), name="corner")
        left = column(bl, "left", among=bl.centres[:, 1] > 0)
        loads = [
            SelfWeight(),
            WeightProportional((0.2, 0.0, 1.0)),
            PointLoad(top_right, (-50.0, -100.0, 30.0), offset=(0.01, 0.02, 0.0)),
        ]
        sup = [Support(base), Support(left, ["u3"])]
        return Model.build(bl, MAT, sup, loads=loads)

    ref_model = build(blocks)
    ref = solve_linear(ref_model, 0.8)
    order = np.random.default_rng(42).permutation(blocks.count)
    perm_model = build(blocks.permuted(order))
    sol = solve_linear(perm_model, 0.8)
    scale = np.abs(ref.q).max()
    # new block k is old block order[k]
    np.testing.assert_allclose(sol.q, ref.q[order], rtol=0, atol=1e-9 * scale)
    r_scale = np.abs(ref.reactions).max()
    np.testing.assert_allclose(sol.reactions, ref.reactions[order], rtol=0, atol=1e-9 * r_scale)

    def by_pair(model: Model, actions: np.ndarray, ids: np.ndarray) -> dict:
        its = model.interfaces
        return {
            (int(ids[i]), int(ids[j])): a
            for i, j, a in zip(its.block_i, its.block_j, actions, strict=True)
        }

    a_ref = by_pair(ref_model, ref.actions, np.arange(blocks.count))
    a_perm = by_pair(perm_model, sol.actions, order)
    assert a_ref.keys() == a_perm.keys()
    f_scale = np.abs(ref.actions).max()
    for key, val in a_ref.items():
        np.testing.assert_allclose(a_perm[key], val, rtol=0, atol=1e-9 * f_scale)
