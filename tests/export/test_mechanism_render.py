"""The collapse mechanism written with a run and its picture.

Proves: a run that ends in collapse writes ``mechanism_blocks.vtu`` and
``mechanism_interfaces.vtu``; for a free-standing running-bond wall tilting over its base
(a rigid rotation about the base, lambda = s/H), the joint motion of the mode is the largest
at the base joints and below 5 % of it at every joint inside the wall; the front-view picture
shows the crack colour only along the base and no crack colour above it; a folder without a
mechanism gets a clear error naming the missing file.
"""

from __future__ import annotations

import imageio.v3 as iio
import meshio
import numpy as np
import pytest

from masonry_dem.export import render
from masonry_dem.export.vtu import MECHANISM_FILES
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import pushover

A, S, COURSES = 0.081, 0.07, 6


@pytest.fixture(scope="module")
def tilted(tmp_path_factory):
    blocks, base = add_base(running_bond_wall(3, COURSES, A, 0.21, S, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7),
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )
    folder = tmp_path_factory.mktemp("mech") / "wall"
    hist = pushover(model, out=folder)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(S / (COURSES * A), rel=0.005)
    return model, base, folder


def test_collapse_writes_the_mode_with_the_base_joints_moving(tilted):
    model, base, folder = tilted
    for name in MECHANISM_FILES:
        assert (folder / name).is_file()
    mesh = meshio.read(folder / MECHANISM_FILES[1])
    motion = mesh.cell_data["joint_motion"][0]
    its = model.interfaces
    at_base = (its.block_i == base) | (its.block_j == base)
    assert motion.max() == pytest.approx(1.0)
    assert motion[at_base].max() == pytest.approx(1.0)
    assert np.all(motion[~at_base] < 0.05)  # the wall above turns as one body
    assert "joint_motion_last_increment" in mesh.cell_data
    blocks = meshio.read(folder / MECHANISM_FILES[0])
    disp = blocks.point_data["displacement"]
    assert np.abs(disp).max() > 0


def test_mechanism_picture_shows_the_crack_at_the_base_only(tilted, tmp_path):
    _, _, folder = tilted
    png = render.render_mechanism(folder, view="front", out=tmp_path / "m.png", scale=0.0)
    img = iio.imread(png)[..., :3].astype(int)
    crack = np.all(np.abs(img - np.array(render.MECHANISM_COLOURS[-1])) <= 12, axis=2)
    crack[:, int(0.78 * img.shape[1]) :] = False  # the legend
    rows = np.flatnonzero(crack.any(axis=1))
    assert rows.size > 0
    # every crack pixel within one course of the lowest one (image rows grow downwards)
    wall_rows = np.flatnonzero(
        np.all(np.abs(img - np.array(render.BLOCK_COLOUR)) <= 12, axis=2).any(axis=1)
    )
    course_px = (wall_rows.max() - wall_rows.min()) / COURSES
    assert rows.max() - rows.min() <= course_px


def test_missing_mechanism_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="mechanism_blocks.vtu"):
        render.render_mechanism(tmp_path)


def test_side_by_side_gallery_of_mechanisms(tilted, tmp_path):
    _, _, folder = tilted
    out = render.render_side_by_side(
        [folder, folder],
        tmp_path / "g.png",
        view=["front", "side"],
        window_size=(200, 150),
        mechanism=True,
    )
    img = iio.imread(out)[..., :3].astype(int)
    assert img.shape[:2] == (150, 400)
    crack = np.all(np.abs(img - np.array(render.MECHANISM_COLOURS[-1])) <= 12, axis=2)
    assert crack[:, :200].any() and crack[:, 200:].any()  # the base crack in both panels
