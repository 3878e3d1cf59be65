"""The shear-wall specimen (``md.shear_wall``): its bond as the Raijmakers & Vermeltfoort walls
were laid, its beams, its openings, its case file, and the closed form of a dry wall whose top
beam slides over the top course."""

from __future__ import annotations

import numpy as np
import pytest

import masonry_dem as md
from helpers.case_files import write_case
from masonry_dem.cases.casefile import load_case

# 210 x 52 x 100 mm bricks with 10 mm joints, 990 mm long, 16 active courses
RV = {"block_height": 0.052, "block_length": 0.21, "thickness": 0.1, "joint": 0.01}


def test_a_990_mm_wall_lays_four_bricks_and_a_half_in_every_course():
    """The pitch is 220 mm: 990 mm is 4.5 bricks, so every course holds four whole bricks and
    a half, the half at the right end of even courses and at the left end of odd ones; the
    courses are 62 mm high and the beams, one course deep, span the wall."""
    blocks = md.shear_wall(0.99, 16, unit_weight=18e3, **RV)
    wall, bottom, top = np.arange(80), 80, 81
    assert blocks.count == 82
    levels = np.round(blocks.lower[wall, 1] / 0.062).astype(int)
    assert np.bincount(levels).tolist() == [5] * 16
    lengths = blocks.sizes[wall, 0].reshape(16, 5)
    assert np.allclose(lengths[0::2], [0.22, 0.22, 0.22, 0.22, 0.11], atol=1e-12)
    assert np.allclose(lengths[1::2], [0.11, 0.22, 0.22, 0.22, 0.22], atol=1e-12)
    assert np.allclose(blocks.lower[bottom], [0.0, -0.062, 0.0], atol=1e-12)
    assert np.allclose(blocks.upper[bottom], [0.99, 0.0, 0.1], atol=1e-12)
    assert np.allclose(blocks.lower[top], [0.0, 0.992, 0.0], atol=1e-12)
    assert np.allclose(blocks.upper[top], [0.99, 1.054, 0.1], atol=1e-12)
    assert blocks.weights[[bottom, top]].tolist() == [0.0, 0.0]  # beams weightless by default
    # the wall weighs its volume: 0.99 x 0.992 x 0.1 m^3 at 18 kN/m^3
    assert blocks.weights[wall].sum() == pytest.approx(18e3 * 0.99 * 0.992 * 0.1, rel=1e-12)


def test_stack_bond_lines_up_the_head_joints_and_start_with_half_swaps_the_courses():
    stack = md.shear_wall(0.99, 4, unit_weight=0.0, bond="stack", **RV)
    lengths = stack.sizes[:-2, 0].reshape(4, 5)
    assert np.allclose(lengths, [0.22, 0.22, 0.22, 0.22, 0.11], atol=1e-12)
    swapped = md.shear_wall(0.99, 2, unit_weight=0.0, start_with_half=True, **RV)
    assert np.allclose(swapped.sizes[:5, 0], [0.11, 0.22, 0.22, 0.22, 0.22], atol=1e-12)


def test_an_opening_is_cut_out_of_the_wall_and_never_out_of_a_beam():
    """A window over the middle of the wall: the beams stay whole, the lintel spans it."""
    solid = md.shear_wall(0.99, 16, unit_weight=18e3, **RV)
    window = md.shear_wall(0.99, 16, unit_weight=18e3, openings=[(0.33, 0.31, 0.66, 0.62)], **RV)
    assert window.count < solid.count
    for which in ("top", "bottom"):
        beam = md.select.edge(window, which)
        assert beam.size == 1 and window.sizes[beam[0], 0] == pytest.approx(0.99, rel=1e-12)
    inside = (
        (window.centres[:, 0] > 0.33)
        & (window.centres[:, 0] < 0.66)
        & (window.centres[:, 1] > 0.31)
        & (window.centres[:, 1] < 0.62)
    )
    assert not inside.any()


@pytest.mark.parametrize(
    "change, message",
    [
        ({"length": 0.2}, "length"),
        ({"courses": 0}, "courses"),
        ({"bond": "flemish"}, "bond"),
        ({"beam_depth": -0.1}, "beam_depth"),
        ({"beam_unit_weight": -1.0}, "beam_unit_weight"),
    ],
)
def test_bad_shear_wall_arguments_are_named(change, message):
    arguments = {"length": 0.99, "courses": 16, "unit_weight": 18e3, **RV, **change}
    with pytest.raises(ValueError, match=message):
        md.shear_wall(**arguments)


def _dry_shear_wall(unit_weight: float, precompression: float) -> md.Model:
    """The wall on its clamped bottom beam, the precompression on the top beam (dead) and a
    horizontal force on it (live); the top beam held against rotation and out of plane."""
    blocks = md.shear_wall(0.99, 16, unit_weight=unit_weight, **RV)
    bottom, top = md.select.edge(blocks, "bottom"), md.select.edge(blocks, "top")
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=82e9, kt=36e9, friction=0.75),
        supports=[md.Support(bottom), md.Support(top, ["u3", "w1", "w2", "w3"])],
        loads=[
            md.SelfWeight(),
            md.PointLoad(top, (0.0, -precompression, 0.0)),
            md.PointLoad(top, (1000.0, 0.0, 0.0), live=True),
        ],
    )


@pytest.mark.parametrize("unit_weight", [0.0, 18e3])
def test_a_dry_wall_gives_way_where_its_top_beam_slides_over_the_top_course(unit_weight):
    """Dry joints (tension 0, mu 0.75) under 0.30 MPa on 990 x 100 mm (29.7 kN) with the top
    beam held against rotation: every bed joint below carries the precompression and the
    weight above it, so the least resistant is the one under the beam, which slides at
    H = mu N = 0.75 x 29.7 kN = 22.275 kN, whatever the wall weighs (1 %)."""
    precompression = 0.30e6 * 0.99 * 0.1
    model = _dry_shear_wall(unit_weight, precompression)
    result = md.analyze(model, "pushover")
    assert result.status == "collapse"
    assert result.load_factor * 1000.0 == pytest.approx(0.75 * precompression, rel=0.01)


def test_a_case_file_builds_the_same_shear_wall(tmp_path):
    """``builder = "shear_wall"`` in a case file, with an opening: the blocks the Python call
    builds; ``base`` selects the bottom beam and ``beam`` the top one, and ``base = true``
    (a second base) is refused, named."""
    geometry = {
        "builder": "shear_wall",
        "length": 0.99,
        "courses": 16,
        "unit_weight": 18e3,
        "openings": [[0.33, 0.31, 0.66, 0.62]],
        "lintels": True,
        **RV,
    }
    case = {
        "name": "shear wall",
        "geometry": geometry,
        "material": {"kn": 82e9, "kt": 36e9, "friction": 0.75},
        "supports": [{"select": "base"}, {"select": "beam", "dofs": ["w3"]}],
        "loads": [
            {"type": "self_weight"},
            {"type": "point", "select": "beam", "force": [1000.0, 0.0, 0.0], "live": True},
        ],
    }
    loaded = load_case(write_case(tmp_path, case))
    expected = md.shear_wall(
        0.99, 16, unit_weight=18e3, openings=[(0.33, 0.31, 0.66, 0.62)], lintels=True, **RV
    )
    assert np.array_equal(loaded.model.blocks.centres, expected.centres)
    assert np.array_equal(loaded.model.blocks.sizes, expected.sizes)
    top = md.select.edge(expected, "top")
    assert np.flatnonzero(loaded.model.live[:, 0]).tolist() == top.tolist()
    assert loaded.model.fixed[md.select.edge(expected, "bottom")].all()
    geometry["base"] = True
    with pytest.raises(
        ValueError, match=r"\[geometry\]: base: builder 'shear_wall' builds its own slabs"
    ):
        load_case(write_case(tmp_path, case))


def test_split_units_halves_each_unit_in_place_and_names_the_pairs():
    """Every whole brick of a two-course wall split: each becomes its left and right halves
    (equal, together the brick: volume and weight kept), in the brick's place, and the pairs
    are the halves; the beams and half bricks stay whole."""
    wall = md.shear_wall(0.99, 2, unit_weight=18e3, **RV)
    whole = np.flatnonzero(np.isclose(wall.sizes[:, 0], 0.22))
    split, pairs = md.split_units(wall, whole)
    assert split.count == wall.count + whole.size and pairs.shape == (whole.size, 2)
    left, right = pairs.T
    assert np.allclose(split.sizes[left, 0], 0.11) and np.allclose(split.sizes[right, 0], 0.11)
    assert np.allclose(split.upper[left, 0], split.lower[right, 0], atol=0)
    assert np.allclose(split.lower[left], wall.lower[whole], atol=0)
    assert np.allclose(split.upper[right], wall.upper[whole], atol=0)
    assert split.weights.sum() == pytest.approx(wall.weights.sum(), rel=1e-12)
    # the order of the rest is kept: the blocks not split, in their order
    rest = np.setdiff1d(np.arange(split.count), pairs.ravel())
    kept = np.setdiff1d(np.arange(wall.count), whole)
    assert np.array_equal(split.centres[rest], wall.centres[kept])


def _pulled_unit(crack: md.InterfaceMaterial | None) -> md.Model:
    """One 220 x 52 x 100 mm unit split in two, its left half held, its right half (hanging
    on the crack alone, weightless) pulled along e1 by lambda x 1 kN."""
    unit = md.Blocks.from_boxes([[0.0, 0.0, 0.0]], [[0.22, 0.052, 0.1]], 0.0)
    blocks, pairs = md.split_units(unit)
    joint = md.InterfaceMaterial(kn=82e9, kt=36e9, friction=0.75, tensile_strength=0.16e6)
    return md.Model.build(
        blocks,
        joint,
        supports=[md.Support([0])],
        loads=[md.PointLoad([1], (1000.0, 0.0, 0.0), live=True)],
        interface_overrides=[] if crack is None else [(pairs, crack)],
    )


@pytest.mark.parametrize("unit_tension", [None, 2.0e6])
def test_a_split_unit_opens_at_the_tensile_strength_of_its_crack(unit_tension):
    """Pulled apart, the halves part when the crack's tensile force ft x a x s is reached:
    the joints' 0.16 MPa without an override, the unit's 2.0 MPa with one (1 %)."""
    crack = (
        None
        if unit_tension is None
        else md.InterfaceMaterial(kn=1e12, kt=1e12, friction=1.0, tensile_strength=unit_tension)
    )
    model = _pulled_unit(crack)
    ft = 0.16e6 if unit_tension is None else unit_tension
    assert model.tensile_strength.tolist() == [ft]
    result = md.analyze(model, "pushover")
    assert result.load_factor * 1000.0 == pytest.approx(ft * 0.052 * 0.1, rel=0.01)


def test_interface_overrides_name_a_pair_that_shares_no_interface():
    wall = md.shear_wall(0.99, 2, unit_weight=18e3, **RV)
    joint = md.InterfaceMaterial(kn=82e9, kt=36e9, friction=0.75)
    bottom = md.select.edge(wall, "bottom")
    with pytest.raises(ValueError, match=r"interface_overrides\[0\]: blocks 0 and 9"):
        md.Model.build(wall, joint, [md.Support(bottom)], interface_overrides=[([[0, 9]], joint)])
    with pytest.raises(ValueError, match="shape"):
        md.Model.build(wall, joint, [md.Support(bottom)], interface_overrides=[([0, 1], joint)])


def test_a_case_file_splits_the_units_of_its_wall_by_unit_cracks(tmp_path):
    """``[unit_cracks]`` splits every unit of the wall (never a beam) at mid-length and gives
    the cracks its material; ``base`` and ``beam`` still select the beams; a law option in
    it is refused, named."""
    case = {
        "name": "cracking units",
        "geometry": {"builder": "shear_wall", "length": 0.99, "courses": 2, "unit_weight": 0.0}
        | RV,
        "material": {"kn": 82e9, "kt": 36e9, "friction": 0.75},
        "unit_cracks": {"kn": 1e12, "kt": 1e12, "friction": 1.0, "tensile_strength": 2.0e6},
        "supports": [{"select": "base"}, {"select": "beam", "dofs": ["w3"]}],
        "loads": [{"type": "point", "select": "beam", "force": [1000.0, 0.0, 0.0], "live": True}],
    }
    model = load_case(write_case(tmp_path, case)).model
    wall = md.shear_wall(0.99, 2, unit_weight=0.0, **RV)
    assert model.blocks.count == wall.count + 10  # 2 courses of 5 units, each split
    assert (model.tensile_strength == 2.0e6).sum() == 10
    beams = np.isclose(model.blocks.sizes[:, 0], 0.99)
    assert beams.sum() == 2 and model.fixed[np.flatnonzero(beams)[0]].all()
    assert np.flatnonzero(model.live[:, 0]).tolist() == [np.flatnonzero(beams)[1]]
    case["unit_cracks"]["tension"] = "plastic"
    with pytest.raises(ValueError, match=r"\[unit_cracks\]\.tension"):
        load_case(write_case(tmp_path, case))
