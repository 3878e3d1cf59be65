"""The dead load first: a wall whose blocks hang over an opening (no chain of bearing joints to
a support, dry head joints that do not dilate) gets no multiplier from any limit analysis, and
the blocks are named; with lintels, or with joints whose tension and cohesion carry the
hanging blocks (closed form), the analysis goes on."""

from __future__ import annotations

import json

import numpy as np
import pytest

import masonry_dem as md
from helpers.case_files import write_case
from helpers.walls import on_base
from masonry_dem.cli import main
from masonry_dem.geometry import builders
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.limit_analysis.dead_load import check_dead_load

pytestmark = pytest.mark.filterwarnings("ignore:openings leave")

#: the issue's wall: 10 x 15 blocks of 0.2 x 0.1 x 0.1 m, a 0.6 x 0.6 m window at (0.7, 0.45)
WINDOW = (0.7, 0.45, 1.3, 1.05)
#: the same window on bed joints, as lintels need
WINDOW_ON_BEDS = (0.7, 0.4, 1.3, 1.0)


def wall(window, lintels: bool) -> md.Blocks:
    blocks = md.running_bond_wall(10, 15, 0.1, 0.2, 0.1, 20e3)
    return md.cut_openings(blocks, [window], lintels=lintels)


def hanging_by_hand(blocks: md.Blocks) -> set[int]:
    """The window's top is y = 1.05 inside course 10 (y 1.0-1.1): its blocks at x 0.8-1.0
    and 1.0-1.2 have nothing under them (course 9 is cut away from x 0.7 to 1.3), and the
    block of course 11 at x 0.9-1.1 bears on those two alone."""
    c = blocks.centres
    at = [(0.9, 1.05), (1.1, 1.05), (1.0, 1.15)]
    return {int(np.flatnonzero(np.hypot(c[:, 0] - x, c[:, 1] - y) < 1e-9)[0]) for x, y in at}


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"backend": "clarabel"},
        {"associative": False},
    ],
    ids=["associative HiGHS", "associative Clarabel", "non-associative"],
)
def test_blocks_hanging_over_a_window_are_refused_by_every_analysis(options):
    """The associative analysis gave 0.0667 here (the dilatancy of the head joints holds the
    blocks), and so did the non-associative iteration; the pushover finds no equilibrium
    under the dead load. Now: failed, no lambda, the three hanging blocks named."""
    blocks = wall(WINDOW, lintels=False)
    model = on_base(blocks)
    out = md.limit_analysis(model, **options)
    expected = hanging_by_hand(blocks)
    assert out.status == "failed" and np.isnan(out.load_factor)
    assert set(out.hanging_blocks) == expected
    assert out.reason.startswith("no equilibrium under the dead load: 3 blocks hang")
    for b in expected:
        assert f"block {b} at" in out.reason
    assert out.summary()["lambda"] is None
    assert sorted(out.summary()["hanging_blocks"]) == sorted(expected)


def test_the_same_window_under_a_lintel_keeps_its_multiplier():
    """With lintels every block bears on a chain down to the base: nothing hangs, and the
    multiplier is the associative one (the lintel wall's 0.066066, its mechanism admissible)."""
    model = on_base(wall(WINDOW_ON_BEDS, lintels=True))
    assert check_dead_load(model).stands
    out = md.limit_analysis(model)
    assert out.status == "collapse", out.reason
    assert out.load_factor == pytest.approx(0.066066, rel=1e-4)
    assert out.hanging_blocks == ()
    # without its lintel the same window leaves blocks hanging
    assert not check_dead_load(on_base(wall(WINDOW_ON_BEDS, lintels=False))).stands


def cohesive(blocks: md.Blocks, ft: float) -> Model:
    blocks, base = builders.add_base(blocks)
    return Model.build(
        blocks,
        InterfaceMaterial(1e9, 4e8, 0.7, tensile_strength=ft),
        [Support(np.array([base]))],
        [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )


def test_tension_and_cohesion_that_carry_the_hanging_blocks_let_them_stand():
    """Closed form. The three blocks (3 x 40 N) fall straight down past four head joints of
    0.1 x 0.1 m, which slide (cohesion mu ft A each, mu 0.7), and four bed joints of
    0.1 x 0.1 m where blocks above bear on them, which open (ft A each): they resist
    (4 x 0.7 x 0.01 + 4 x 0.01) ft = 0.068 ft, so they stand for ft > 120 / 0.068 Pa."""
    blocks = wall(WINDOW, lintels=False)
    ft = 120.0 / 0.068
    weak = check_dead_load(cohesive(blocks, 0.999 * ft))
    assert set(weak.hanging) == hanging_by_hand(blocks)
    assert weak.weight == pytest.approx((120.0,), rel=1e-9)
    assert weak.resistance == pytest.approx((0.999 * 120.0,), rel=1e-9)
    assert check_dead_load(cohesive(blocks, 1.001 * ft)).stands


def test_what_bears_on_a_held_block_stands_and_what_hangs_under_one_falls():
    """A column of three blocks with no base: held by its lowest block, the two above it
    bear on it; held by its top block alone (dry joints, no tension), the two under it
    hang."""
    blocks = builders.stack_bond_column(3, 0.1, 0.2, 0.1, 20e3)
    loads = [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))]
    material = InterfaceMaterial(1e9, 4e8, 0.7)
    assert check_dead_load(Model.build(blocks, material, [Support([0])], loads)).stands
    check = check_dead_load(Model.build(blocks, material, [Support([2])], loads))
    assert check.hanging.tolist() == [0, 1]
    assert check.weight == pytest.approx((80.0,), rel=1e-9) and check.resistance == (0.0,)
    np.testing.assert_allclose(check.direction, [0.0, -1.0, 0.0])


def test_the_limit_command_refuses_a_wall_that_cannot_stand(tmp_path, capsys):
    """``masonry-dem limit`` on the issue's wall: exit 1, status failed, no lambda, the
    hanging blocks in summary.json and in the reason it prints; no mechanism written."""
    case = write_case(
        tmp_path,
        {
            "name": "window",
            "geometry": {
                "builder": "running_bond_wall",
                "blocks_along_length": 10,
                "courses": 15,
                "block_height": 0.1,
                "block_length": 0.2,
                "thickness": 0.1,
                "unit_weight": 20e3,
                "base": True,
                "openings": [list(WINDOW)],
                "lintels": False,
            },
            "material": {"kn": 1e9, "kt": 4e8, "friction": 0.7},
            "supports": [{"select": "base"}],
            "loads": [
                {"type": "self_weight"},
                {"type": "weight_proportional", "direction": [0, 0, 1]},
            ],
        },
    )
    out = tmp_path / "la"
    assert main(["limit", str(case), "--out", str(out), "--no-render"]) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["lambda"] is None
    assert summary["bound"] == "none"
    assert len(summary["limit_analysis"]["hanging_blocks"]) == 3
    assert "no equilibrium under the dead load: 3 blocks hang" in summary["reason"]
    assert "3 blocks hang" in capsys.readouterr().out
    assert not (out / "mechanism_blocks.vtu").exists()


def test_each_group_of_hanging_blocks_is_weighed_on_its_own():
    """Two such windows 2 m apart in a 20-block wall: two groups of three blocks, 120 N
    each, none of them resisted (dry joints)."""
    blocks = md.running_bond_wall(20, 15, 0.1, 0.2, 0.1, 20e3)
    second = (WINDOW[0] + 2.0, WINDOW[1], WINDOW[2] + 2.0, WINDOW[3])
    blocks = md.cut_openings(blocks, [WINDOW, second], lintels=False)
    check = check_dead_load(on_base(blocks))
    assert len(check.groups) == 2 and [g.size for g in check.groups] == [3, 3]
    assert check.weight == pytest.approx((120.0, 120.0), rel=1e-9)
    assert check.resistance == (0.0, 0.0)
    x = sorted(float(blocks.centres[g, 0].mean()) for g in check.groups)
    assert x == pytest.approx([1.0, 3.0], abs=1e-9)  # blocks at x 0.9, 1.1, 1.0 (+ 2 m)
    assert np.array_equal(check.hanging, np.sort(np.concatenate(check.groups)))
