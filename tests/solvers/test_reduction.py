"""The in-plane reduction: when it applies, that it is exact, and what the model costs."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.geometry import builders
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    PointLoad,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.solvers import reduction
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation
from masonry_dem.solvers.incremental import StaticSolver

DRY = InterfaceMaterial(2.4e9, 1.0e9, 0.7)


def shear_wall(nx=3, nc=3, direction=(1.0, 0.0, 0.0), material=DRY, extra=()) -> Model:
    wall = builders.running_bond_wall(nx, nc, 0.081, 0.21, 0.07, 20e3)
    blocks, base = builders.add_base(wall)
    return Model.build(
        blocks,
        material,
        [Support(np.array([base]))],
        [SelfWeight(), WeightProportional(direction), *extra],
        name="shear wall",
    )


@pytest.fixture(scope="module")
def wall() -> Model:
    return shear_wall()


# ---------------------------------------------------------------------------- the check
def test_in_plane_scene_is_recognised(wall):
    check = reduction.in_plane_check(wall)
    assert check.in_plane, check.reason


def test_out_of_plane_load_is_not_in_plane():
    check = reduction.in_plane_check(shear_wall(direction=(0.0, 0.0, 1.0)))
    assert not check.in_plane
    assert "live load" in check.reason and "out-of-plane" in check.reason


def test_eccentric_dead_load_is_not_in_plane():
    """A point load off the mid-plane puts a moment about e1 on its block."""
    load = PointLoad(np.array([0]), (0.0, -10.0, 0.0), offset=(0.0, 0.0, 0.02))
    check = reduction.in_plane_check(shear_wall(extra=(load,)))
    assert not check.in_plane and "dead load" in check.reason


def test_blocks_of_different_thickness_are_not_in_plane():
    lower = np.array([[0.0, 0.0, 0.0], [0.0, 0.1, 0.0]])
    upper = np.array([[0.2, 0.1, 0.1], [0.2, 0.2, 0.06]])
    blocks = Blocks.from_boxes(lower, upper, 20e3)
    model = Model.build(
        blocks, DRY, [Support(np.array([0]))], [SelfWeight(), WeightProportional((1, 0, 0))]
    )
    check = reduction.in_plane_check(model)
    assert not check.in_plane and "mid-plane" in check.reason


def test_contact_normal_to_e3_is_not_in_plane():
    lower = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.1]])
    upper = np.array([[0.2, 0.1, 0.1], [0.2, 0.1, 0.2]])
    blocks = Blocks.from_boxes(lower, upper, 20e3)
    model = Model.build(
        blocks, DRY, [Support(np.array([0]))], [SelfWeight(), WeightProportional((1, 0, 0))]
    )
    check = reduction.in_plane_check(model)
    assert not check.in_plane and "e3" in check.reason


def test_refused_reduction_names_the_reason():
    with pytest.raises(ValueError, match="out-of-plane"):
        reduction.in_plane_model(shear_wall(direction=(0.0, 0.0, 1.0)))


# ---------------------------------------------------------------------------- the model
def test_reduced_model_keeps_three_dofs_per_free_block(wall):
    reduced = reduction.in_plane_model(wall)
    free_blocks = (~wall.fixed.all(axis=1)).sum()
    assert reduced.free.sum() == 3 * free_blocks
    assert np.all(reduced.fixed[:, [2, 3, 4]])
    assert reduced.meta["reduction"] == "in_plane"
    assert reduction.in_plane_model(reduced) is reduced  # idempotent
    # the reduced stiffness is the in-plane block of the full one
    full = Assembly.of(wall)
    red = Assembly.of(reduced)
    pos = np.searchsorted(full.free_index, red.free_index)
    K = full.stiffness().toarray()
    assert np.allclose(K[np.ix_(pos, pos)], red.stiffness().toarray())
    out = np.setdiff1d(np.arange(full.n_free), pos)
    assert np.all(K[np.ix_(pos, out)] == 0)  # no coupling to the out-of-plane DOFs


def test_cheapest_model_picks_the_reduction_only_when_exact(wall):
    model, why = reduction.cheapest_model(wall)
    assert model.meta.get("reduction") == "in_plane" and "in-plane" in why
    tilt = shear_wall(direction=(0.0, 0.0, 1.0))
    model, why = reduction.cheapest_model(tilt)
    assert model is tilt and "full 6-DOF" in why


@pytest.mark.parametrize("tensile_strength", [0.0, 0.1e6], ids=["dry", "mortar"])
def test_same_lambda_as_the_full_model(tensile_strength):
    material = InterfaceMaterial(2.4e9, 1.0e9, 0.7, tensile_strength)
    model = shear_wall(4, 4, material=material)
    full = StaticSolver(model).run()
    red = StaticSolver(reduction.in_plane_model(model)).run()
    assert full.status == red.status == "collapse"
    assert red.collapse_multiplier == pytest.approx(full.collapse_multiplier, rel=1e-3)
    # the out-of-plane DOFs of the full model never move
    assert np.abs(full.last.q[:, [2, 3, 4]]).max() == 0.0


def test_dynamic_relaxation_on_the_reduced_model(wall):
    settings = DRSettings(bracket_tolerance=0.01)
    full = DynamicRelaxation(wall, settings).run()
    red = DynamicRelaxation(reduction.in_plane_model(wall), settings).run()
    assert red.status == full.status == "collapse"
    assert red.collapse_multiplier == pytest.approx(full.collapse_multiplier, rel=0.01)


# ---------------------------------------------------------------------------- costs
def test_model_cost_counts_the_assembled_dofs(wall):
    cost = reduction.model_cost(wall)
    assert cost["free_dofs"] == cost["dofs"] - cost["fixed_dofs"]
    assert cost["fully_fixed_blocks"] == 1  # the base
    red = reduction.model_cost(reduction.in_plane_model(wall))
    assert red["free_dofs"] * 2 == cost["free_dofs"]
    assert red["nnz_K"] < cost["nnz_K"]


def test_fixed_dof_measurement(wall):
    m = reduction.measure_fixed_dofs(wall, repeats=1)
    assert m["dofs_saved"] == int(wall.fixed.sum())
    assert m["nnz_K_free"] < m["nnz_K_all"]
    assert m["seconds_factor_free"] > 0 and m["seconds_factor_all_penalty"] > 0


def test_reduction_measurement(wall):
    r = reduction.measure_reduction(wall, repeats=1)
    assert r["lambda_relative_difference"] <= 1e-3
    assert r["in_plane"]["free_dofs"] * 2 == r["full"]["free_dofs"]


def test_strength_model_measurement(wall):
    r = reduction.measure_strength_model(wall, springs_per_side=8, repeats=1)
    assert r["springs_per_interface"] == 64
    assert r["seconds_closed_form"] > 0 and r["seconds_spring_model"] > 0
