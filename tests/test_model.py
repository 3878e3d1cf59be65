"""The frozen Model: supports, loads, materials, and refusal of bad input by field name.

Proves: DOF masks and supports fix exactly the chosen DOFs; each load pattern gives its exact
generalised forces (self-weight, weight-proportional tilt pattern, face pressure, point loads
with their moment); dead and live loads are kept apart; interfaces between two fully fixed
blocks are dropped; material overrides reach the right joints; NaN or non-positive parameters
fail with a ValueError naming the field; an unsupported wall, a detached floating block or
supports that leave a rigid-body motion free are refused as mechanisms before any solve.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import add_base, boxes, running_bond_wall, stack_bond_column
from masonry_dem.geometry.selectors import column
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    PointLoad,
    Pressure,
    SelfWeight,
    Support,
    WeightProportional,
    dof_mask,
)

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0
MAT = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)


@pytest.fixture(scope="module")
def wall():
    return add_base(running_bond_wall(4, 3, A, B, S, GAMMA))


# ------------------------------------------------------------------------------- DOFs
def test_dof_masks():
    np.testing.assert_array_equal(dof_mask("all"), [1] * 6)
    np.testing.assert_array_equal(dof_mask("translations"), [1, 1, 1, 0, 0, 0])
    np.testing.assert_array_equal(dof_mask("rotations"), [0, 0, 0, 1, 1, 1])
    np.testing.assert_array_equal(dof_mask("in_plane"), [1, 1, 0, 0, 0, 1])
    np.testing.assert_array_equal(dof_mask("out_of_plane"), [0, 0, 1, 1, 1, 0])
    np.testing.assert_array_equal(dof_mask(["u3", "w2"]), [0, 0, 1, 0, 1, 0])
    with pytest.raises(ValueError, match=r"^dofs must name a group .* got 'u4'"):
        dof_mask(["u1", "u4"])


def test_supports_fix_exactly_the_chosen_dofs(wall):
    blocks, ib = wall
    left = column(blocks, "left", among=np.arange(blocks.count) != ib)
    model = Model.build(blocks, MAT, [Support([ib]), Support(left, ["u3"])])
    expect = np.zeros((blocks.count, 6), bool)
    expect[ib] = True
    expect[left, 2] = True
    np.testing.assert_array_equal(model.fixed, expect)
    np.testing.assert_array_equal(model.free, ~expect.ravel())
    assert model.n_dofs == 6 * blocks.count
    with pytest.raises(ValueError, match=rf"Support.blocks: block index {blocks.count} is out"):
        Support([blocks.count]).mask(blocks.count)
    with pytest.raises(ValueError, match="Support.blocks: the selection is empty"):
        Support([]).mask(blocks.count)


def test_api_refuses_block_selections_it_cannot_read_plainly(wall):
    """A boolean mask read as indices fixed blocks 0 and 1 (issue 24); 15.7 was read as 15."""
    blocks, ib = wall
    mask = np.zeros(blocks.count, dtype=bool)
    mask[[ib]] = True
    with pytest.raises(ValueError, match="Support.blocks: got a boolean mask of"):
        Support(mask).mask(blocks.count)
    with pytest.raises(
        ValueError, match=r"Support.blocks: block indices must be whole numbers, got 15.7"
    ):
        Support([15.7]).mask(blocks.count)
    with pytest.raises(ValueError, match="PointLoad.blocks: got a boolean mask"):
        PointLoad(mask, (0.0, -1.0, 0.0)).vector(blocks)
    with pytest.raises(ValueError, match="WeightProportional.blocks: block indices must be whole"):
        WeightProportional(blocks=[0.5]).vector(blocks)
    with pytest.raises(ValueError, match="Pressure.blocks: block index -1 is out of range"):
        Pressure(1.0, blocks=[-1]).vector(blocks)
    with pytest.raises(ValueError, match="kn must be a number, got the boolean true"):
        InterfaceMaterial(kn=True, kt=1e9, friction=0.7)
    model = Model.build(blocks, MAT, [Support([ib])])
    for bad in (True, 1.5, "3"):
        with pytest.raises(ValueError, match="block must be a whole block index"):
            model.dof_index(bad, "u3")  # type: ignore[arg-type]
    assert model.dof_index(np.int64(1), "u3") == 8
    # whole numbers stored as floats are read plainly
    np.testing.assert_array_equal(
        Support([float(ib)]).mask(blocks.count), Support([ib]).mask(blocks.count)
    )


# ------------------------------------------------------------------------------ loads
def test_self_weight(wall):
    blocks, _ = wall
    F = SelfWeight().vector(blocks)
    np.testing.assert_allclose(F[:, 1], -blocks.volumes * blocks.unit_weight, rtol=1e-15)
    assert not np.delete(F, 1, axis=1).any()


def test_weight_proportional_pattern_is_normalised(wall):
    blocks, _ = wall
    F = WeightProportional(direction=(3.0, 0.0, 4.0)).vector(blocks)
    np.testing.assert_allclose(F[:, 0], 0.6 * blocks.weights, rtol=1e-15)
    np.testing.assert_allclose(F[:, 2], 0.8 * blocks.weights, rtol=1e-15)
    assert not F[:, [1, 3, 4, 5]].any()
    sub = WeightProportional(blocks=[0, 2]).vector(blocks)
    assert np.count_nonzero(sub[:, 2]) == 2
    with pytest.raises(ValueError, match="direction must be a non-zero vector"):
        WeightProportional(direction=(0, 0, 0)).vector(blocks)
    with pytest.raises(ValueError, match=r"^direction contains a non-finite"):
        WeightProportional(direction=(0, np.nan, 1)).vector(blocks)


def test_pressure_on_a_face(wall):
    blocks, ib = wall
    F = Pressure(1000.0, axis=2, sign=-1).vector(blocks)
    np.testing.assert_allclose(F[:, 2], -1000.0 * blocks.sizes[:, 0] * blocks.sizes[:, 1])
    assert not np.delete(F, 2, axis=1).any()
    F0 = Pressure(50.0, axis=0, blocks=[1]).vector(blocks)
    assert F0[1, 0] == pytest.approx(50.0 * A * S) and np.count_nonzero(F0) == 1
    with pytest.raises(ValueError, match=r"^pressure contains a non-finite"):
        Pressure(np.nan).vector(blocks)
    with pytest.raises(ValueError, match="pressure axis"):
        Pressure(1.0, axis=3).vector(blocks)
    with pytest.raises(ValueError, match="pressure sign"):
        Pressure(1.0, sign=0).vector(blocks)


def test_point_load_with_offset_gives_its_moment(wall):
    blocks, _ = wall
    f, r = np.array([10.0, -20.0, 5.0]), np.array([0.1, 0.02, -0.03])
    F = PointLoad([3, 3, 5], f, offset=r).vector(blocks)  # block 3 twice: loads add up
    np.testing.assert_allclose(F[3, :3], 2 * f)
    np.testing.assert_allclose(F[3, 3:], 2 * np.cross(r, f))
    np.testing.assert_allclose(F[5], np.concatenate([f, np.cross(r, f)]))
    with pytest.raises(ValueError, match=r"^force contains a non-finite"):
        PointLoad([0], (np.nan, 0, 0)).vector(blocks)
    with pytest.raises(ValueError, match=r"^offset must have shape"):
        PointLoad([0], (1, 0, 0), offset=(0, 0)).vector(blocks)


def test_dead_and_live_loads_are_kept_apart(wall):
    blocks, ib = wall
    loads = [SelfWeight(), WeightProportional((0, 0, 1)), PointLoad([2], (0, -5.0, 0))]
    model = Model.build(blocks, MAT, [Support([ib])], loads=loads)
    np.testing.assert_allclose(
        model.dead, SelfWeight().vector(blocks) + loads[2].vector(blocks), rtol=1e-15
    )
    np.testing.assert_allclose(model.live, loads[1].vector(blocks), rtol=1e-15)
    live_weight = Model.build(blocks, MAT, [Support([ib])], loads=[SelfWeight(live=True)])
    assert not live_weight.dead.any() and live_weight.live[:, 1].sum() < 0


# --------------------------------------------------------------------------- building
def test_interfaces_between_fixed_blocks_are_dropped(wall):
    blocks, ib = wall
    bottom = np.flatnonzero(np.isclose(blocks.centres[:, 1], A / 2))
    full = Model.build(blocks, MAT, [Support([ib])])
    fewer = Model.build(blocks, MAT, [Support([ib]), Support(bottom)])
    both_fixed = np.isin(full.interfaces.block_i, [ib, *bottom]) & np.isin(
        full.interfaces.block_j, [ib, *bottom]
    )
    assert fewer.interfaces.count == full.interfaces.count - both_fixed.sum() > 0
    assert fewer.kn.shape == (fewer.interfaces.count,)


def test_material_arrays_and_default_alpha(wall):
    blocks, ib = wall
    mortar = InterfaceMaterial(kn=1e9, kt=4e8, friction=0.6, tensile_strength=1e5, alpha=1.43)
    model = Model.build(blocks, MAT, [Support([ib])], material_overrides=[([ib], mortar)])
    on_base = model.interfaces.block_i == ib
    np.testing.assert_allclose(model.alpha[~on_base], 1.5)  # the paper's value by default
    np.testing.assert_allclose(model.alpha[on_base], 1.43)
    np.testing.assert_allclose(model.tensile_strength[on_base], 1e5)
    np.testing.assert_allclose(model.friction[~on_base], 0.7)
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.name = "x"


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"kn": np.nan}, "kn"),
        ({"kn": 0.0}, "kn"),
        ({"kt": -1.0}, "kt"),
        ({"kt": np.inf}, "kt"),
        ({"friction": np.nan}, "friction"),
        ({"friction": -0.1}, "friction"),
        ({"tensile_strength": np.nan}, "tensile_strength"),
        ({"alpha": 0.0}, "alpha"),
        ({"alpha": np.nan}, "alpha"),
    ],
)
def test_material_rejects_bad_values_by_name(kwargs, field):
    args = {"kn": 1e9, "kt": 1e9, "friction": 0.6} | kwargs
    with pytest.raises(ValueError, match=rf"^{field}\b"):
        InterfaceMaterial(**args)


# -------------------------------------------------------------------------- mechanisms
def test_a_wall_with_no_support_is_a_mechanism(wall):
    blocks, _ = wall
    with pytest.raises(ValueError, match=r"no DOF is fixed.*mechanism"):
        Model.build(blocks, MAT, [])


def test_a_detached_floating_block_is_a_mechanism():
    blocks, ib = add_base(running_bond_wall(3, 2, A, B, S, GAMMA))
    floating = boxes([[5.0, 5.0, 0.0]], [[5.0 + B, 5.0 + A, S]], GAMMA)
    all_blocks = Blocks.concatenate(blocks, floating)
    lone = all_blocks.count - 1
    with pytest.raises(
        ValueError, match=rf"1 block\(s\) touch no support.*block {lone}.*mechanism"
    ):
        Model.build(all_blocks, MAT, [Support([ib])])


@pytest.mark.parametrize(
    "dofs",
    [
        "translations",  # the base can rotate, the whole wall with it
        ["u1", "u2", "w1", "w2", "w3"],  # nothing stops a slide along e3
        "in_plane",
    ],
)
def test_supports_that_leave_a_rigid_motion_free_are_a_mechanism(wall, dofs):
    blocks, ib = wall
    with pytest.raises(ValueError, match=r"leave \d rigid-body motion.*mechanism"):
        Model.build(blocks, MAT, [Support([ib], dofs)])


def test_translations_of_collinear_blocks_leave_the_torsion_free():
    col = stack_bond_column(4, A, B, S, GAMMA)
    with pytest.raises(ValueError, match=r"leave 1 rigid-body motion.*mechanism"):
        Model.build(col, MAT, [Support(np.arange(4), "translations")])


def test_enough_partial_supports_are_accepted():
    # the paper's restraint: translations of the left column only (not collinear centres)
    w = running_bond_wall(6, 8, A, B, S, GAMMA)
    model = Model.build(w, MAT, [Support(column(w, "left"), "translations")])
    assert model.fixed.sum() == 3 * column(w, "left").size


def test_overlapping_blocks_are_refused_when_building():
    lo = np.array([[0.0, 0.0, 0.0], [0.1, 0.5, 0.0]])
    blocks = boxes(lo, lo + [B, A * 6, S], GAMMA)
    with pytest.raises(ValueError, match="blocks overlap"):
        Model.build(blocks, MAT, [Support([0])])
