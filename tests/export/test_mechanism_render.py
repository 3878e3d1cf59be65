"""The collapse mechanism written with a run and its picture.

Proves: a run that ends in collapse writes ``mechanism_blocks.vtu`` and
``mechanism_interfaces.vtu``; for a free-standing running-bond wall tilting over its base
(a rigid rotation about the base, lambda = s/H), the joint motion of the mode is the largest
at the base joints and below 5 % of it at every joint inside the wall; the front-view picture
shows the crack colour only along the base and no crack colour above it; a folder without a
mechanism gets a clear error naming the missing file; the picture ``run`` writes is taken
in the view in which the mode moves the most (a wall overturning out of its plane from the
side, an in-plane mechanism from the front, walls that meet in the oblique view).
"""

from __future__ import annotations

import imageio.v3 as iio
import meshio
import numpy as np
import pytest

from masonry_dem.export import render
from masonry_dem.export.analyses import pushover
from masonry_dem.export.scene import StepData, motion_in_view, view_of_motion
from masonry_dem.export.vtu import MECHANISM_FILES
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.plans import u_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional

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


def _rigid_mode(blocks, rotation, about):
    """StepData of ``blocks`` moved by a small rigid rotation (vector ``rotation``) about the
    point ``about``: u = theta x (x - about) at every corner."""
    pts = blocks.corner_points()
    disp = np.cross(np.asarray(rotation, dtype=float), pts - np.asarray(about, dtype=float))
    fixed = np.zeros(len(pts), dtype=bool)
    return StepData(pts, disp, fixed, None, None, None, None, None)


def test_the_mechanism_view_shows_the_motion_in_its_image_plane():
    """Out-of-plane overturning (rotation about the base's e1 edge: the motion is along e3,
    the thickness, and e2) is seen from the side, where the front view sees only the small
    vertical part of it; in-plane rocking about the toe (rotation about e3: e1 and e2) from
    the front, where the side view sees only the vertical part; walls that meet (a U plan) in
    the oblique view, whatever they do; a mode that moves nothing in the oblique view."""
    wall = running_bond_wall(3, COURSES, A, 0.21, S, 20e3)
    overturning = _rigid_mode(wall, (-1e-3, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert (
        np.abs(overturning.block_disp[..., 2]).max()
        > 10 * np.abs(overturning.block_disp[..., 0]).max()
    )
    assert motion_in_view(overturning.block_disp, "side") > 5 * motion_in_view(
        overturning.block_disp, "front"
    )
    assert view_of_motion(overturning) == "side"
    length = 3 * 0.21
    rocking = _rigid_mode(wall, (0.0, 0.0, -1e-3), (length, 0.0, 0.0))
    assert view_of_motion(rocking) == "front"
    # the same modes, the support blocks (fixed, not moving) do not count
    blocks, base = add_base(wall)
    held = _rigid_mode(blocks, (-1e-3, 0.0, 0.0), (0.0, 0.0, 0.0))
    held.fixed[base] = True
    held.block_disp[base] = 0.0
    assert view_of_motion(held) == "side"
    returns = u_wall(5, COURSES, A, 0.21, S, 20e3, return_blocks=3)
    assert view_of_motion(_rigid_mode(returns, (-1e-3, 0.0, 0.0), (0.0, 0.0, 0.0))) == "oblique"
    still = _rigid_mode(wall, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert view_of_motion(still) == "oblique"


def test_run_draws_an_out_of_plane_overturning_from_the_side(tilted, tmp_path):
    """The free wall on a tilt table along e3 overturns about its base: its mechanism
    picture, without a view asked, is the side view (``mechanism_side.png``)."""
    _, _, folder = tilted
    assert render.mechanism_view(folder) == "side"
    png = render.render_mechanism(folder, window_size=(300, 225))
    assert png.name == "mechanism_side.png" and png.is_file()


def test_an_in_plane_mechanism_is_drawn_from_the_front(tmp_path):
    """The same wall on a tilt table along e1 (its own plane), held out of plane: it rocks
    or slides in its plane and its mechanism picture is the front view."""
    blocks, base = add_base(running_bond_wall(3, 3, A, 0.21, S, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7),
        supports=[Support([base]), Support(list(range(len(blocks) - 1)), ["u3"])],
        loads=[SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
    )
    folder = tmp_path / "in_plane"
    hist = pushover(model, out=folder)
    assert hist.status == "collapse", hist.reason
    assert render.mechanism_view(folder) == "front"
    png = render.render_mechanism(folder, window_size=(300, 225))
    assert png.name == "mechanism_front.png" and png.is_file()


def test_render_command_picks_the_mechanism_view_unless_one_is_asked(tilted, capsys):
    """``masonry-dem render --mechanism`` without ``--view`` draws the overturning wall's
    mode from the side; with ``--view front`` it draws what was asked."""
    from masonry_dem.cli import main

    _, _, folder = tilted
    assert main(["render", str(folder), "--mechanism", "--size", "300x225"]) == 0
    written = capsys.readouterr().out.split()
    assert str(folder / "mechanism_side.png") in written
    assert not any(name.endswith("mechanism_oblique.png") for name in written)
    assert main(["render", str(folder), "--mechanism", "--view", "front", "--size", "300x225"]) == 0
    assert str(folder / "mechanism_front.png") in capsys.readouterr().out.split()
