"""The validation cases of Tables 1-3: built from the published data, not retyped.

Proves: the package's copy of the reference TOML equals the shared one; every case of the
three tables builds, with the paper's block counts, supports and load units; the first case
of Table 1 runs to a collapse with a refined bracket (the value it reaches is recorded, not
tuned: docs/validation.md explains why it is above the paper's FEM reference).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from helpers.paper_runs import run_case
from masonry_dem.cases.paper import Assumptions, build_case, case_names, reference_data
from masonry_dem.mechanism import last_increment, out_of_plane

SHARED = Path(__file__).resolve().parents[3] / "shared" / "reference" / "baraldi_cecchi_2016.toml"


def test_package_copy_equals_the_shared_reference():
    if not SHARED.is_file():
        pytest.skip("no ../shared/reference beside the repository")
    copy = resources.files("masonry_dem.cases").joinpath("data", "baraldi_cecchi_2016.toml")
    assert copy.read_text() == SHARED.read_text()


def test_every_case_of_the_three_tables_is_there():
    data = reference_data()
    expected = (
        [c["name"] for c in data["orduna_lourenco"]["case"]]
        + [c["name"] for c in data["restrepo_velez"]["specimen"]]
        + [c["name"] for c in data["chee_liang"]["wall"]]
    )
    assert case_names() == expected
    assert len(case_names("1")) == 2 and len(case_names("2")) == 10 and len(case_names("3")) == 6


@pytest.mark.parametrize("name", case_names())
def test_case_builds_from_the_published_data(name):
    case = build_case(name)
    model = case.model
    assert model.blocks.count > 10
    assert np.any(model.live) and np.any(model.dead)
    if case.table == "3":
        assert case.unit == "Pa"
        tests = reference_data()["chee_liang"]["wall"][case_names("3").index(name)]
        assert case.reference == pytest.approx(np.mean(tests["pressure_tests"]))
    else:
        assert case.unit == "lambda"


def test_restrepo_velez_walls_have_21_courses_of_n_blocks():
    for spec in reference_data()["restrepo_velez"]["specimen"][:7]:
        case = build_case(spec["name"])
        wall = case.model.blocks.subset(case.wall)
        length = wall.upper[:, 0].max() - wall.lower[:, 0].min()
        height = wall.upper[:, 1].max() - wall.lower[:, 1].min()
        data = reference_data()["restrepo_velez"]
        assert length == pytest.approx(spec["blocks_along_length"] * data["block_width_b"])
        assert height == pytest.approx(21 * data["block_height_a"])


def test_assumptions_are_overridable_in_one_place():
    base = build_case("2-3")
    heavier = build_case("2-3", brick_unit_weight=20e3)
    assert heavier.model.dead.sum() == pytest.approx(base.model.dead.sum() * 20 / 18)
    assert Assumptions().dry_kn == reference_data()["interface_spring_model"]["kn"]


_run = run_case


def _mechanism(name: str):
    """The collapse mechanism as the out-of-plane displacement increment of the last step
    (normalised to 1): which blocks move, not the state flags (a dry head joint is flagged
    at zero compression before anything happens). The joint-by-joint checks of the same
    runs are in test_mechanisms.py."""
    case, h = _run(name)
    assert h.status == "collapse", h.reason
    du = out_of_plane(last_increment(h), case.wall)
    centres = case.model.blocks.centres[case.wall]
    courses = np.unique(np.round(centres[:, 1], 6))
    return du, centres, courses


def test_orduna_lourenco_panel_collapses_with_a_refined_bracket():
    case, h = _run("OL1")
    assert h.status == "collapse", h.reason
    lo, hi = h.collapse_bracket
    assert hi - lo <= 0.005 * lo * 1.0001
    # measured 0.2824: the peak of this model's pushover curve (dynamic relaxation finds
    # 0.2817-0.2826), which work control reaches since it takes pseudo-transient steps where
    # Newton stops at folds of the path (0.2527 before). Not the paper's value: its DEM gives
    # 0.175, FEM 0.210, limit analysis 0.127
    assert 0.275 < lo < 0.29


def test_wall_held_on_one_edge_fails_along_a_diagonal():
    """OL1 (held on its left edge): the moving part grows away from the support in every
    course and reaches lower at the free edge than inside, so it is bounded by a diagonal
    rising from the free edge towards the supported top corner."""
    du, c, courses = _mechanism("OL1")
    assert du.max() == pytest.approx(1.0)
    x0 = c[:, 0].min()
    lowest = {}
    for y in courses:
        row = np.flatnonzero(np.isclose(c[:, 1], y))
        row = row[np.argsort(c[row, 0])]
        assert np.all(np.diff(du[row]) >= -1e-3)  # grows away from the support
        assert abs(du[row[0]]) < 1e-3  # the held column does not move out of plane
        for i in row[du[row] >= 0.25]:
            key = round(float(c[i, 0] - x0), 3)
            lowest[key] = min(lowest.get(key, np.inf), c[i, 1])
    xs = sorted(lowest)
    heights = [lowest[x] for x in xs]
    # the boundary of the moving region goes down from the support towards the free edge
    assert heights[-1] < heights[0]
    top = courses[-1]
    free_edge = np.flatnonzero(np.isclose(c[:, 1], top))
    assert np.argmax(du) in free_edge  # the free top corner moves most


def test_wall_held_on_both_edges_opens_on_the_axis():
    """OL2 (held on both edges): the mechanism is symmetric, largest on the axis at the top:
    a vertical crack on the axis with the two halves turning about diagonals."""
    du, c, courses = _mechanism("OL2")
    axis = (c[:, 0].min() + c[:, 0].max()) / 2
    width = np.median(np.diff(np.unique(np.round(c[:, 0], 6))))
    top = np.flatnonzero(np.isclose(c[:, 1], courses[-1]))
    assert np.argmax(du) in top and abs(c[np.argmax(du), 0] - axis) <= 2 * width
    for y in courses:
        row = np.flatnonzero(np.isclose(c[:, 1], y))
        if du[row].max() < 0.05:
            continue
        peak = row[np.argmax(du[row])]
        assert abs(c[peak, 0] - axis) <= 2 * width  # largest on the axis in every course
        mirror = [row[np.argmin(np.abs(c[row, 0] - (2 * axis - c[i, 0])))] for i in row]
        assert np.allclose(du[row], du[mirror], atol=0.05)  # symmetric
    # the top of the axis moves more than mid-height: the halves rotate about diagonals
    mid = courses[len(courses) // 2]
    assert du[np.isclose(c[:, 1], mid)].max() < 0.5


def test_simple_support_strips_hold_the_edges_at_the_face():
    """Table 3 supports: fixed strips behind the leeward face along the supported edges (and
    a slab under the wall), joined by dry contacts; bad values are named."""
    case = build_case("4-5")  # top edge free: strips on bottom, left, right
    model = case.model
    n_wall = case.wall.size
    supports = np.arange(n_wall, model.blocks.count)
    assert supports.size == 4
    assert model.fixed[supports].all() and not model.fixed[case.wall].any()
    its = model.interfaces
    touch = np.isin(its.block_i, supports) | np.isin(its.block_j, supports)
    assert touch.sum() > 0
    assert np.all(model.tensile_strength[touch] == 0.0)  # dry contacts: no tension
    assert np.all(model.tensile_strength[~touch] > 0.0)  # mortar joints
    # each strip lies behind the leeward face (z beyond the wall), the slab under it
    wall_hi = model.blocks.upper[case.wall].max(axis=0)
    wall_lo = model.blocks.lower[case.wall].min(axis=0)
    behind = model.blocks.lower[supports, 2] >= wall_hi[2] - 1e-12
    under = model.blocks.upper[supports, 1] <= wall_lo[1] + 1e-12
    assert behind.sum() == 3 and under.sum() == 1
    with pytest.raises(ValueError, match="simple_support"):
        build_case("4-5", simple_support="pinned")
    with pytest.raises(ValueError, match="support_strip_width"):
        build_case("4-5", support_strip_width=-1.0)


@pytest.mark.parametrize(
    "changes",
    [{}, {"opening_height": 8}, {"sill_courses": 5}, {"opening_width": 2}, {"opening_width": 4}],
)
@pytest.mark.parametrize("name", ["S23", "S34"])
def test_every_lintel_bears_on_both_piers(name, changes):
    """The lintel over an opening reaches past both jambs, whatever the running bond does at
    them (with head joints on the jambs, a lintel as wide as the opening had no bearing and
    fell in under the dead load)."""
    case = build_case(name, **changes)
    blocks = case.model.blocks
    for x0, _, x1, y1 in case.extra["openings"]:
        lintel = np.flatnonzero(
            np.isclose(blocks.lower[:, 1], y1)
            & (blocks.upper[:, 0] > x0)
            & (blocks.lower[:, 0] < x1)
        )
        assert lintel.size == 1, lintel  # one block spans the opening
        (i,) = lintel
        assert blocks.lower[i, 0] < x0 - 1e-9 and blocks.upper[i, 0] > x1 + 1e-9


@pytest.mark.slow
def test_a_stuck_path_is_checked_before_it_is_called_a_collapse():
    """S34 with 10-course windows: Newton stops at lambda 0.040, below the overturning of
    the whole wall as one free-standing block (s/H = 0.067), which its return walls can only
    raise. The instability rule's damped motion from that state finds rest a little higher,
    and the path goes on to a collapse well above the overturning."""
    from masonry_dem.solvers.incremental import pushover

    case = build_case("S34", opening_height=10)
    data = reference_data()["restrepo_velez"]
    overturning = data["block_thickness_s"] / (data["courses"] * data["block_height_a"])
    checked = pushover(case.model, case.settings)
    assert checked.status == "collapse", checked.reason
    assert checked.collapse_multiplier > 1.5 * overturning
