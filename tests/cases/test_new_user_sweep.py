"""What a new user tried (docs/new_user_sweep.md): closed forms through case files on the
builders nobody tuned for, and inputs whose errors named no field or the wrong table.

Each error case ends the command line with exit code 2 and one line naming the file, the
table path and the value (never a traceback), and raises a ValueError (CaseError) from Python.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from helpers.case_files import write_case
from masonry_dem.cases.casefile import build_blocks, case_from_dict
from masonry_dem.cases.schema import CaseError
from masonry_dem.cli import main
from masonry_dem.export.analyses import pushover
from masonry_dem.export.writer import warn_large_closure
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import add_base, single_block, stack_bond_column
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.run_case import run_case
from masonry_dem.solvers.incremental import StaticSettings

A, B, S = 0.2, 0.21, 0.07  # s / a = 0.35, below mu = 0.7: the blocks tilt before they slide
S_WALL = 0.07  # the thickness of WALL

WALL = {
    "name": "wall",
    "geometry": {
        "builder": "running_bond_wall",
        "blocks_along_length": 2,
        "courses": 3,
        "block_height": 0.081,
        "block_length": 0.21,
        "thickness": 0.07,
        "unit_weight": 20e3,
        "base": True,
    },
    "material": {"kn": 1e9, "kt": 0.4e9, "friction": 0.7},
    "supports": [{"select": "base"}],
    "loads": [{"type": "self_weight"}, {"type": "weight_proportional", "direction": [0, 0, 1]}],
}


def _one_line_error(tmp_path, capsys, data: dict) -> str:
    case = write_case(tmp_path, data)
    code = main(["run", str(case), "--out", str(tmp_path / "out"), "--no-render", "--quiet"])
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert code == 2, err
    assert len(err) == 1, err
    assert str(case) in err[0], err[0]
    return err[0]


@pytest.mark.parametrize("key", ["courses", "blocks_along_length"])
def test_a_negative_count_is_named_by_the_schema_not_by_the_memory_estimate(key, tmp_path, capsys):
    """The memory estimate counted the blocks of ``courses = -1`` before the schema saw it and
    failed with "blocks must be >= 0, got -2", naming neither the file nor the key."""
    data = copy.deepcopy(WALL)
    data["geometry"][key] = -1
    line = _one_line_error(tmp_path, capsys, data)
    assert f"[geometry].{key} = -1" in line
    assert "from 1 to 10000" in line


def test_a_limit_option_without_the_limit_method_names_the_file_and_the_key(tmp_path, capsys):
    data = copy.deepcopy(WALL)
    data["analysis"] = {"grid": 8}
    line = _one_line_error(tmp_path, capsys, data)
    assert "[analysis].grid = 8" in line
    assert 'method = "limit"' in line


def test_overlapping_blocks_are_a_fault_of_the_geometry(tmp_path, capsys):
    """Two boxes sharing a volume were reported under ``[supports]``."""
    data = copy.deepcopy(WALL)
    data["geometry"] = {
        "builder": "boxes",
        "lower": [[0, 0, 0], [0.1, 0, 0]],
        "upper": [[0.2, 0.1, 0.1], [0.3, 0.1, 0.1]],
        "unit_weight": 20e3,
        "base": True,
    }
    line = _one_line_error(tmp_path, capsys, data)
    assert ": [geometry]: blocks overlap: block 0" in line
    with pytest.raises(CaseError, match=r"\[geometry\]: blocks overlap"):
        case_from_dict(data, "boxes.toml")


def test_a_box_with_its_corners_swapped_names_the_corners():
    """``upper`` below ``lower`` was named as "sizes must be positive", a name the user
    never wrote."""
    with pytest.raises(ValueError, match=r"upper\[1\] must lie above lower\[1\] along e1"):
        Blocks.from_boxes([[0, 0, 0], [0, 0.1, 0]], [[0.2, 0.1, 0.1], [-0.2, 0.2, 0.1]], 20e3)
    with pytest.raises(ValueError, match=r"along e2"):
        Blocks.from_boxes([[0, 0, 0]], [[0.2, 0.0, 0.1]], 20e3)


@pytest.mark.parametrize(
    ("builder", "extra"),
    [
        ("l_wall", {"return_blocks": 2}),
        ("u_wall", {"return_blocks": 2}),
        ("t_wall", {"return_blocks": 2}),
        ("box_wall", {}),
    ],
)
@pytest.mark.parametrize("direction", [[0, 0, 1], [1, 0, 0]])
def test_one_course_of_any_plan_tilts_at_s_over_a(builder, extra, direction, tmp_path):
    """One course on a base, dry joints: no joint above the base carries a normal force, so
    friction ties no block to its neighbours and each block overturns alone about its base
    edge at lambda = (half its width along the load) / (half its height). The narrowest
    width along e3 is the facade's thickness s and along e1 a return wall's (or the cross
    wall's, or a box side's) thickness s: lambda = s / a = 0.35 both ways, below mu = 0.7.
    Run as ``masonry-dem run`` runs a case file, with the certificate and its bound."""
    data = copy.deepcopy(WALL)
    data["geometry"] = {
        "builder": builder,
        "blocks_along_length": 4,
        "courses": 1,
        "block_height": A,
        "block_length": B,
        "thickness": S,
        "unit_weight": 20e3,
        "base": True,
        **extra,
    }
    data["loads"][1]["direction"] = direction
    summary = run_case(case_from_dict(data, f"{builder}.toml"), tmp_path / "out", render=False)
    assert summary["status"] == "collapse", summary["reason"]
    assert summary["lambda"] == pytest.approx(S / A, rel=1e-6)
    assert summary["certificate"]["holds"]
    # the associative bound is above the DEM's multiplier, never below it
    assert summary["limit_analysis_bound"] >= S / A * (1 - 1e-6)


def test_numbers_written_as_text_are_refused_by_name_in_python():
    """``InterfaceMaterial(kn="1e9")`` was accepted (numpy reads the text as a number) and kept
    the text, which failed in the first analysis with numpy's "ufunc 'isnan' not supported"."""
    with pytest.raises(ValueError, match=r'^kn must be a number, got the text "1e9"'):
        InterfaceMaterial(kn="1e9", kt=1e9, friction=0.7)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^block_height must be a number, got the text"):
        single_block("0.4", 0.2, 0.1, 20e3)  # type: ignore[arg-type]


def test_a_negative_contact_tolerance_is_named():
    """It failed inside numpy: "repeats may not contain negative values"."""
    with pytest.raises(ValueError, match=r"^tol must be non-negative, got -1"):
        detect_interfaces(single_block(0.4, 0.2, 0.1, 20e3), tol=-1.0)


def _window_wall(lintels: bool | None, top: float = 0.567) -> dict:
    """A 6 x 10 dry wall with a window two blocks wide over courses 3 to 6."""
    data = copy.deepcopy(WALL)
    data["geometry"].update(blocks_along_length=6, courses=10, openings=[[0.42, 0.243, 0.84, top]])
    if lintels is not None:
        data["geometry"]["lintels"] = lintels
    return data


def test_a_window_without_lintels_names_the_block_that_hangs(caplog):
    """Course 7 over the window has a block (x 0.525 to 0.735) with nothing under it: on dry
    joints it hangs on head joints that carry no normal force, and the pushover fails under
    the dead load (``no equilibrium under the dead load``); the builder now says why."""
    with caplog.at_level("WARNING", logger="masonry_dem.geometry.builders"):
        build_blocks(_window_wall(None)["geometry"])
    assert "openings leave 1 block(s) with nothing under them" in caplog.text
    assert "[0.63, 0.6075, 0.035]" in caplog.text
    assert "lintels = true" in caplog.text


def test_a_window_with_lintels_tilts_at_the_closed_form(tmp_path, caplog):
    """With ``lintels = true`` (straight jambs, a lintel over the window: how the paper's
    specimens S23 and S34 are built) the free-standing wall stands and overturns out of
    plane about a bed joint. For a rigid rotation of everything above the bed joint at
    height z about its front edge, virtual work gives lambda(z) = (s / 2) / (y_G(z) - z),
    y_G(z) the centroid height of the blocks above it; the wall's multiplier is the least
    over its bed joints. Here the least is at the base and equals s / H = 0.07 / 0.81, as
    without the window: the window's courses 3 to 6 are centred at mid-height, so taking
    them out leaves y_G at H / 2."""
    data = _window_wall(True)
    with caplog.at_level("WARNING", logger="masonry_dem.geometry.builders"):
        blocks, _, wall = build_blocks(data["geometry"])
    assert "nothing under them" not in caplog.text
    volume, yc = blocks.volumes[wall], blocks.centres[wall, 1]
    beds = np.unique(blocks.lower[wall, 1])
    closed = min(
        S_WALL / 2 / (np.sum(volume[yc > z] * yc[yc > z]) / np.sum(volume[yc > z]) - z)
        for z in beds
    )
    assert closed == pytest.approx(S_WALL / 0.81, rel=1e-12)
    summary = run_case(case_from_dict(data, "window.toml"), tmp_path / "out", render=False)
    assert summary["status"] == "collapse", summary["reason"]
    assert summary["lambda"] == pytest.approx(closed, rel=1e-6)
    assert summary["certificate"]["holds"]


def test_lintels_need_openings_whose_top_is_a_bed_joint(tmp_path, capsys):
    line = _one_line_error(tmp_path, capsys, _window_wall(True, top=0.6))
    assert "[geometry]: openings[0]: a lintel sits on a bed joint, but y_max = 0.6" in line
    assert "the nearest are y = 0.567 and 0.648" in line
    data = copy.deepcopy(WALL)
    data["geometry"]["lintels"] = True
    with pytest.raises(CaseError, match=r"lintels = true builds lintels over the openings"):
        case_from_dict(data, "wall.toml")


@pytest.mark.parametrize(("kn", "warned"), [(2e6, True), (1e9, False)])
def test_a_wall_too_tall_for_its_kn_is_named_at_the_dead_load(kn, warned, tmp_path, caplog):
    """A 10 m column of 40 blocks 0.25 high on a base: under its own weight the base joint
    carries the whole column, a mean closure of gamma H / kn = 20e3 x 10 / kn, 0.1 m or 40 %
    of the 0.25 m blocks at kn = 2e6 (the run then ends ``failed`` 0.5 % short of t/H with a
    reason about the tangent; at kn = 1e7 and above it collapses at t/H = 0.03). The writer
    now says so at the first step; at kn = 1e9 (a share of 8e-4) it says nothing."""
    column = stack_bond_column(40, 0.25, 0.5, 0.3, 20e3)
    blocks, base = add_base(column)
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=kn, kt=0.4 * kn, friction=0.7),
        [Support([base])],
        [SelfWeight(), WeightProportional((0, 0, 1))],
    )
    with caplog.at_level("WARNING", logger="masonry_dem.export.writer"):
        pushover(model, StaticSettings(max_steps=3), out=tmp_path / "out")
    assert ("outside small displacements" in caplog.text) is warned
    first = pushover(model, StaticSettings(max_steps=1)).steps[0]
    assert warn_large_closure(model, first) == pytest.approx(20e3 * 10 / kn / 0.25, rel=1e-6)


def _live(load: dict) -> dict:
    data = copy.deepcopy(WALL)
    data["loads"][1] = load
    return data


@pytest.mark.parametrize(
    ("data", "said"),
    [
        (_live({"type": "pressure", "value": 0.0}), "is zero on every block"),
        (
            _live({"type": "point", "select": "course:-1", "force": [0, 0, 0], "live": True}),
            "is zero",
        ),
        (_live({"type": "pressure", "value": 100.0, "select": "base"}), "only on held DOFs"),
        ({**WALL, "geometry": {**WALL["geometry"], "unit_weight": 0.0}}, "is zero"),
        ({**WALL, "supports": [{"select": "base"}, {"select": "all"}]}, "only on held DOFs"),
    ],
    ids=["pressure 0", "force 0", "pressure on the base", "weightless", "every block held"],
)
def test_a_live_load_that_pushes_nothing_is_named(data, said, caplog):
    """Each ran to ``completed`` at lambda = 0 ("no live load: the dead-load state is the
    answer"), exit code 0, without a word about the load the user did give."""
    with caplog.at_level("WARNING", logger="masonry_dem.model"):
        case_from_dict(copy.deepcopy(data), "idle.toml")
    assert "loads[1]" in caplog.text and said in caplog.text
    assert "nothing pushes the wall" in caplog.text


def test_a_live_load_that_pushes_is_not_named(caplog):
    with caplog.at_level("WARNING", logger="masonry_dem.model"):
        case_from_dict(copy.deepcopy(WALL), "wall.toml")
    assert "nothing pushes" not in caplog.text
