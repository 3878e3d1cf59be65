"""The shear-wall validation (issue 41, item 6): the walls of Raijmakers & Vermeltfoort read
from their data file, precompressed then pushed, one row per wall with its curve."""

from __future__ import annotations

import json

import numpy as np
import pytest

from masonry_dem.cases.shear_walls import shear_wall_case, shear_wall_data, wall_names
from masonry_dem.studies.shear_walls import run_shear_wall


def test_the_data_file_names_a_source_for_every_number_it_gives():
    """Each table of numbers says where they come from; a wall without a test peak says it
    has none (the validation names it), and the 16 active courses of 62 mm are the 1000 mm
    (992 mm) between the beams."""
    data = shear_wall_data()
    for table in ("specimen", "joint"):
        assert data[table]["source"]
    for wall in data["wall"]:
        if "peak_test" in wall:
            assert wall["peak_test_source"]
    spec = data["specimen"]
    height = spec["active_courses"] * (spec["brick_height"] + spec["joint"])
    assert height == pytest.approx(1.0, abs=0.01)
    assert wall_names() == ["rv-0.30", "rv-1.21", "rv-2.12"]


def test_a_wall_is_precompressed_by_its_stress_on_the_cross_section_then_pushed():
    """Stage 1 puts sigma x 990 mm x 100 mm on the top beam; stage 2 holds the beam's u2
    and w3 and drives its u1; the joints are the file's (c 0.224 MPa above mu ft)."""
    case = shear_wall_case("rv-0.30")
    load = case.stages[0].loads[0].vector(case.model.blocks)
    assert -load[case.beam, 1] == pytest.approx(0.30e6 * 0.99 * 0.1, rel=1e-12)
    assert case.stages[1].control.block == case.beam and case.stages[1].control.dof == "u1"
    assert case.model.cohesion.max() == pytest.approx(0.224e6, rel=1e-12)
    assert case.reference == 50e3 and case.reference_source == "issue 41"


def test_the_row_of_a_wall_is_its_push_with_its_curve(tmp_path):
    """The row's ours is the largest force of the push and the curve's; the held beam's
    vertical reaction at the peak pushes down (the wall, rocking, lifts against it); the
    curve starts at the end of the precompression, at no horizontal force."""
    row = run_shear_wall("rv-0.30", tmp_path, render=False)
    assert row["status"] == "completed", row["reason"]
    curve = np.loadtxt(row["curve"], delimiter=",", skiprows=1)
    assert curve[:, 1].max() == row["ours"]
    assert curve[0, 1] == pytest.approx(0.0, abs=1e-6)
    assert row["beam_vertical_reaction"] < 0
    assert row["error"] == pytest.approx(row["ours"] / 50e3 - 1.0, rel=1e-12)
    summary = json.loads((tmp_path / "rv-0.30" / "summary.json").read_text())
    assert summary["status"] == "completed"


@pytest.mark.slow
def test_masonry_dem_validate_shear_walls_writes_a_row_curve_and_picture_per_wall(tmp_path, capsys):
    from masonry_dem.cli import main

    main(["validate", "shear-walls", "--json", "--out", str(tmp_path)])
    rows = json.loads(capsys.readouterr().out)
    assert [r["case"] for r in rows] == wall_names()
    for row in rows:
        assert (tmp_path / row["case"] / "curve.csv").is_file()
        if row["status"] == "completed":
            assert (tmp_path / row["case"] / "cracks.png").is_file()
    assert [r["reference"] is None for r in rows] == [False, True, True]
