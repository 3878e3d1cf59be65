"""What makes a picture explain itself, checked against closed forms: the length scale is the
roundest length under its share of the wall, the load arrow is the resultant of the live
forces, the support marks sit on the held blocks and point the way the support holds them,
and the pushover axis names the displacement the run recorded (the largest translation, or
the block and DOF a displacement control or a monitor drives)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from masonry_dem.export import annotations as an
from masonry_dem.export.plots import LARGEST_TRANSLATION, control_dof, control_label


def test_nice_length_is_the_largest_round_length_below_the_limit():
    for limit, want in (
        (0.27, 0.2),
        (0.5, 0.5),
        (0.499, 0.2),
        (1.0, 1.0),
        (7.3, 5.0),
        (0.011, 0.01),
    ):
        assert an.nice_length(limit) == pytest.approx(want)
    with pytest.raises(ValueError, match="positive length"):
        an.nice_length(0.0)
    assert an.length_text(0.2) == "0.2 m" and an.length_text(0.05) == "50 mm"


def test_direction_text():
    assert an.direction_text(np.array([0.0, 0.0, 1.0])) == "+e3"
    assert an.direction_text(np.array([0.0, -1.0, 0.0])) == "-e2"
    assert an.direction_text(np.array([0.6, 0.0, 0.8])) == "(0.6, 0, 0.8)"


def test_live_load_resultant_is_the_force_weighted_centre():
    """Two blocks pushed along +e3 by 1 N and 3 N: the resultant acts along +e3 at the
    point 3/4 of the way to the second block."""
    centres = np.array([[0.0, 0.0, 0.0], [4.0, 2.0, 0.0]])
    forces = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 3.0]])
    direction, point = an.live_load_resultant(centres, forces)
    np.testing.assert_allclose(direction, [0, 0, 1])
    np.testing.assert_allclose(point, [3.0, 1.5, 0.0])
    assert an.live_load_resultant(centres, np.zeros((2, 3))) is None
    assert an.live_load_resultant(centres, None) is None


def test_support_marks_sit_on_the_held_faces():
    """Block 0 held in every DOF (a 1 m slab): a row of upward cones under its bottom face;
    block 1 held in u1 and u3: one cone onto its face of least e1 and one onto its face of
    least e3; block 2 free (or held in rotations only): none."""
    lower = np.array([[0.0, -0.2, 0.0], [0.0, 0.0, 0.0], [0.3, 0.0, 0.0]])
    upper = np.array([[1.0, 0.0, 0.1], [0.2, 0.1, 0.1], [0.5, 0.1, 0.1]])
    held = np.zeros((3, 6), dtype=bool)
    held[0] = True
    held[1, [0, 2]] = True
    held[2, 3:] = True
    size = 0.04
    tips, axes, blocks = an.support_marks(lower, upper, held, size)
    row = blocks == 0
    n = int(round(1.0 / (2.5 * size)))
    assert row.sum() == n
    assert np.all(axes[row] == 1)  # upward
    np.testing.assert_allclose(tips[row, 1], -0.2)  # on the bottom face
    np.testing.assert_allclose(np.sort(tips[row, 0]), (np.arange(n) + 0.5) / n)
    side = blocks == 1
    assert sorted(axes[side].tolist()) == [0, 2]
    for tip, axis in zip(tips[side], axes[side], strict=True):
        assert tip[axis] == 0.0  # the face of least e_axis
    assert not np.any(blocks == 2)
    # the cones point along +e_axis: every point of a cone lies on the negative side of its tip
    pts = an.cone_mesh_points(np.array([[0.0, 0, 0], [-1.0, 0.4, 0]]), tips, axes, size)
    pts = pts.reshape(len(tips), 2, 3)
    k = np.arange(len(tips))
    np.testing.assert_allclose(pts[k, 0, axes], tips[k, axes])
    np.testing.assert_allclose(pts[k, 1, axes], tips[k, axes] - size)


def test_pushover_names_the_displacement_it_plots(results):
    """The damage-pattern run records the largest translation: the name is a block DOF whose
    value is the recorded one at the last step, or the largest translation."""
    import meshio

    from masonry_dem.export.plots import DOF_NAMES, read_pushover

    which = control_dof(results)
    if isinstance(which, tuple):
        block, dof = which
        last = sorted((results / "steps").glob("blocks_*.vtu"))[-1]
        q = meshio.read(last).cell_data["translation"][0]
        recorded = read_pushover(results)["control_displacement"][-1]
        assert q[block, DOF_NAMES.index(dof)] == pytest.approx(recorded, rel=1e-9)
    else:
        assert which.startswith(LARGEST_TRANSLATION)
    label, factor = control_label(which)
    assert label.endswith("[mm]") and factor == 1e3


def test_pushover_names_the_monitored_block_and_dof(tmp_path):
    """A run with a monitor on a mid-height block (never the largest translation) records
    that DOF: the axis names its block and DOF."""
    from helpers.damage_pattern import build_model
    from masonry_dem.export.analyses import pushover

    model = build_model(3, 3)
    y = model.blocks.centres[:, 1]
    middle = np.abs(y - np.median(y[~model.fixed.all(axis=1)]))
    block = int(np.argmin(np.where(model.fixed.all(axis=1), np.inf, middle)))  # mid-height
    csv_path = tmp_path / "run" / "pushover.csv"
    while_running: list[tuple[str, int]] = []  # (header, rows) as each step is handed over

    def look(step) -> None:
        lines = csv_path.read_text().splitlines()
        while_running.append((lines[0], len(lines) - 1))

    history = pushover(model, out=tmp_path / "run", monitor=(block, "u3"), callback=look)
    assert control_dof(tmp_path / "run") == (block, "u3")
    header = csv_path.read_text().splitlines()[0]
    assert header == f"step,lambda,control_displacement [m] block {block} u3"
    # written row by row, the file names the same DOF as soon as a step has moved it, and
    # its header at the last step is the one the end of the run writes again
    assert [rows for _, rows in while_running] == list(range(1, len(history.steps) + 1))
    assert while_running[-1][0] == header
    assert {h for h, _ in while_running[1:]} == {header}
    shutil.rmtree(tmp_path / "run" / "steps")  # the header alone names it
    assert control_dof(tmp_path / "run") == (block, "u3")
    assert control_label((block, "u3")) == (f"block {block}, u3 [mm]", 1e3)
    assert control_label((block, "w1"))[0] == f"block {block}, w1 [mrad]"


def test_a_pushover_csv_with_a_bare_header_is_still_read(results_copy):
    """Files written before the header named its block, DOF and unit: the columns are read
    by name, and the block motions name the displacement."""
    from masonry_dem.export.results_series import read_pushover, recorded_in_pushover

    path = results_copy / "pushover.csv"
    lines = path.read_text().splitlines()
    path.write_text("\n".join(["step,lambda,control_displacement", *lines[1:]]) + "\n")
    assert recorded_in_pushover(results_copy) is None
    assert read_pushover(results_copy)["lambda"].size == len(lines) - 1
    assert control_dof(results_copy) is not None


def test_a_rotation_is_recorded_in_radians():
    from masonry_dem.export.pushover_file import displacement_column, recorded_of_header

    assert displacement_column((7, "w1")) == "control_displacement [rad] block 7 w1"
    assert recorded_of_header(displacement_column((7, "w1"))) == (7, "w1")
    assert displacement_column(LARGEST_TRANSLATION) == (
        "control_displacement [m] largest block translation"
    )
    assert recorded_of_header(displacement_column(None)) is None
