"""Interfaces cut into pieces (``subdivide_interfaces``).

Proves: the pieces tile their interface (areas, centres, corners); the assembled elastic
stiffness is the same matrix (parallel-axis theorem: the pieces' second moments about the
parent centre sum to the parent's); determinate answers do not move (a block tilts at b/h and
slides at mu); and where the interface law's rocking about the joint centre matters, the
pieces make blocks rock about their edges as rigid blocks do:

* a block jammed between a base and a fixed top plate (no gap) cannot rock: its diagonal is
  longer than the gap, so a rigid block must lift the plate to turn. With one interface per
  joint the law turns it about the joint centres (no lift) at the free-standing b/h; cut into
  pieces it carries three times that (and any load, in the rigid limit);
* the in-plane peer wall (issue 18): cut into pieces it collapses as the rigid wedge of its
  right end tipping about its toe (11/19 = 0.5789, closed form), inside LMGC90's bracket
  [0.575, 0.580] g and below the associative rigid-block bound (an LP solved here), where one
  interface per joint gives 0.546 with its blocks turning about the joint centres
  (``docs/peer_wall.md``).
"""

from __future__ import annotations

import numpy as np
import pytest

import masonry_dem as md
from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.geometry.interfaces import detect_interfaces, subdivide_interfaces
from masonry_dem.solvers.limit_analysis import limit_analysis

MATERIAL = md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.6)


def _wall_interfaces():
    wall = md.running_bond_wall(3, 4, a=0.1, b=0.25, s=0.12, unit_weight=18e3)
    blocks, base = md.add_base(wall)
    return blocks, base, detect_interfaces(blocks)


@pytest.mark.parametrize("n1, n2", [(1, 1), (2, 1), (1, 3), (2, 2), (3, 4)])
def test_pieces_tile_their_interface(n1, n2):
    _, _, its = _wall_interfaces()
    cut = subdivide_interfaces(its, n1, n2)
    k = n1 * n2
    assert cut.count == k * its.count
    parent = np.repeat(np.arange(its.count), k)
    np.testing.assert_array_equal(cut.block_i, its.block_i[parent])
    np.testing.assert_array_equal(cut.block_j, its.block_j[parent])
    np.testing.assert_array_equal(cut.axis, its.axis[parent])
    # areas sum to the parent's, centres average to it, every piece inside its parent
    np.testing.assert_allclose(np.bincount(parent, cut.area), its.area, rtol=1e-14)
    mean = np.stack([np.bincount(parent, cut.centre[:, a]) / k for a in range(3)], axis=1)
    np.testing.assert_allclose(mean, its.centre, atol=1e-15)
    lo_p = its.corner_points().min(axis=1)[parent]
    hi_p = its.corner_points().max(axis=1)[parent]
    corners = cut.corner_points()
    assert np.all(corners >= lo_p[:, None, :] - 1e-15)
    assert np.all(corners <= hi_p[:, None, :] + 1e-15)
    # the pieces' corners are a grid: the parent's corners are among them
    for r in range(its.count):
        mine = corners[r * k : (r + 1) * k].reshape(-1, 3)
        for c in its.corner_points()[r]:
            assert np.min(np.abs(mine - c).sum(axis=1)) < 1e-14


def test_elastic_stiffness_is_unchanged():
    """Pieces of a rectangle about its centre: sum A_p = A, sum (I_p + A_p d_p^2) = I and
    J likewise, so K = H^T Kbar H is the same matrix (to round-off)."""
    blocks, base, its = _wall_interfaces()

    def stiffness(interfaces):
        model = md.Model.build(blocks, MATERIAL, [md.Support([base])], interfaces=interfaces)
        return Assembly.of(model).stiffness().toarray()

    k_whole = stiffness(its)
    k_cut = stiffness(subdivide_interfaces(its, 3, 2))
    np.testing.assert_allclose(k_cut, k_whole, rtol=0, atol=1e-9 * np.abs(k_whole).max())


@pytest.mark.parametrize("value", [0, -1, 1.5, True, "2", None])
def test_bad_piece_counts_are_refused_by_name(value):
    _, _, its = _wall_interfaces()
    with pytest.raises(ValueError, match="n1 must be a whole number >= 1"):
        subdivide_interfaces(its, value, 1)
    with pytest.raises(ValueError, match="n2 must be a whole number >= 1"):
        subdivide_interfaces(its, 1, value)


def _single_block(direction, pieces, friction=0.6, top_plate=False):
    """A 0.2 x 0.4 x 0.2 block (b x h x s) on a fixed base; with ``top_plate`` a fixed plate
    touches its top face."""
    lower = [[0, -0.1, 0], [0, 0, 0]] + ([[0, 0.4, 0]] if top_plate else [])
    upper = [[0.2, 0, 0.2], [0.2, 0.4, 0.2]] + ([[0.2, 0.5, 0.2]] if top_plate else [])
    blocks = md.boxes(lower, upper, 20e3)
    its = subdivide_interfaces(detect_interfaces(blocks), *pieces)
    fixed = [0, 2] if top_plate else [0]
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=friction),
        [md.Support(fixed)],
        [md.SelfWeight(), md.WeightProportional(direction=direction, blocks=[1])],
        interfaces=its,
    )


@pytest.mark.parametrize("pieces", [(1, 1), (2, 2), (1, 4)])
def test_determinate_answers_do_not_move(pieces):
    """A free block tilts at b/h = 0.5 in its plane and slides at mu (friction 0.3 < b/h)."""
    tilt = md.pushover(_single_block((1, 0, 0), pieces))
    assert tilt.status == "collapse"
    assert tilt.collapse_multiplier == pytest.approx(0.5, rel=5e-3)
    slide = md.pushover(_single_block((1, 0, 0), pieces, friction=0.3))
    assert slide.status == "collapse"
    assert slide.collapse_multiplier == pytest.approx(0.3, rel=5e-3)


def test_jammed_block_rocks_only_about_the_joint_centres_when_whole():
    """Friction 10 (no sliding below lambda 10). A rigid block jammed between two plates
    cannot turn without lifting the top plate: no collapse up to lambda 1.5 = 3 b/h with the
    joints cut in pieces. One interface per joint turns the block about the joint centres,
    which lifts nothing, at the free-standing b/h = 0.5."""
    whole = md.pushover(_single_block((1, 0, 0), (1, 1), friction=10.0, top_plate=True))
    assert whole.status == "collapse"
    assert whole.collapse_multiplier == pytest.approx(0.5, rel=5e-3)
    cut = md.pushover(
        _single_block((1, 0, 0), (2, 2), friction=10.0, top_plate=True),
        md.StaticSettings(max_load_factor=1.5),
    )
    assert cut.status == "completed"
    assert cut.final_load_factor == pytest.approx(1.5)


# ------------------------------------------------------------------ the peer wall (issue 18)
LMGC90_BRACKET = (0.575, 0.580)  # compas_dem + compas_lmgc90, issue 18


def peer_wall(pieces=(1, 1)) -> md.Model:
    """5 x 6 running bond of 0.4 x 0.2 x 0.2 m blocks, friction 0.6, 2000 kg/m3, rigid
    slab, lateral acceleration in the plane (e1)."""
    wall = md.running_bond_wall(5, 6, a=0.2, b=0.4, s=0.2, unit_weight=2000 * 9.81)
    blocks, base = md.add_base(wall)
    return md.Model.build(
        blocks,
        MATERIAL,
        [md.Support([base])],
        [md.SelfWeight(), md.WeightProportional(direction=(1, 0, 0))],
        interfaces=subdivide_interfaces(detect_interfaces(blocks), *pieces),
    )


def associative_bound(model: md.Model) -> float:
    """The associative rigid-block multiplier (limit analysis: by the lower-bound theorem the
    largest lambda of a statically admissible state, after Radenkovic an upper bound of the
    non-associative one)."""
    result = limit_analysis(model, associative=True)
    assert result.status == "collapse", result.reason
    return result.load_factor


def wedge_overturning() -> float:
    """The rigid stair-stepped wedge of the right end turning about its toe.

    The wedge: the half block of course 1 and the blocks above it along the diagonal, nine
    blocks (x, y; weight in half blocks): (1.9, 0.3; 1), (1.8, 0.5; 2), (1.6, 0.7; 2),
    (1.9, 0.7; 1), (1.4, 0.9; 2), (1.8, 0.9; 2), (1.2, 1.1; 2), (1.6, 1.1; 2), (1.9, 1.1; 1).
    Its centroid is (24.5 / 15, 12.5 / 15); with the crack open along its whole boundary it
    tips about the toe (2.0, 0.2) when lambda = (x0 - xg) / (yg - y0) = (11/30) / (19/30).
    """
    x = np.array([1.9, 1.8, 1.6, 1.9, 1.4, 1.8, 1.2, 1.6, 1.9])
    y = np.array([0.3, 0.5, 0.7, 0.7, 0.9, 0.9, 1.1, 1.1, 1.1])
    w = np.array([1, 2, 2, 1, 2, 2, 2, 2, 1], dtype=float)
    xg, yg = (w @ x) / w.sum(), (w @ y) / w.sum()
    return (2.0 - xg) / (yg - 0.2)


@pytest.mark.parametrize("pieces", [(1, 2), (2, 2), (1, 4)])
def test_peer_wall_in_pieces_tips_the_rigid_wedge(pieces):
    """Cut in pieces, the wall collapses by the rigid wedge tipping about its toe (11/19), inside
    LMGC90's bracket and under the associative bound of the LP (0.584 in the issue)."""
    assert wedge_overturning() == pytest.approx(11 / 19, rel=1e-12)
    bound = associative_bound(peer_wall())
    assert bound == pytest.approx(0.584, abs=5e-4)
    history = md.pushover(peer_wall(pieces))
    assert history.status == "collapse"
    lam = history.collapse_multiplier
    assert lam == pytest.approx(wedge_overturning(), rel=1e-4)
    assert LMGC90_BRACKET[0] <= lam <= LMGC90_BRACKET[1]
    assert lam <= bound
    # the mode: the nine blocks of the wedge turn together (one w3), the rest stay
    dq = history.steps[-1].q - history.steps[-2].q
    moving = np.flatnonzero(np.abs(dq[:, :3]).max(axis=1) > 1e-3 * np.abs(dq[:, :3]).max())
    centres = peer_wall().blocks.centres[moving, :2]
    assert sorted(map(tuple, np.round(centres, 2))) == sorted(
        zip(
            [1.9, 1.8, 1.6, 1.9, 1.4, 1.8, 1.2, 1.6, 1.9],
            [0.3, 0.5, 0.7, 0.7, 0.9, 0.9, 1.1, 1.1, 1.1],
            strict=True,
        )
    )
    np.testing.assert_allclose(dq[moving, 5], dq[moving[0], 5], rtol=1e-3)


def test_peer_wall_whole_joints_rock_about_their_centres():
    """The paper's law, one interface per joint: 6 % below LMGC90 (the modelling difference
    of docs/peer_wall.md); the associative bound does not depend on the pieces."""
    history = md.pushover(peer_wall())
    assert history.status == "collapse"
    assert history.collapse_multiplier < 0.96 * LMGC90_BRACKET[0]
    assert history.collapse_multiplier < 0.95 * wedge_overturning()
    # its mode is no rigid wedge: blocks of it turn the other way (about their joint centres)
    dq = history.steps[-1].q - history.steps[-2].q
    moving = np.abs(dq[:, :3]).max(axis=1) > 1e-3 * np.abs(dq[:, :3]).max()
    w3 = dq[moving, 5]
    assert w3.max() > 0.1 * np.abs(w3).max() and w3.min() < -0.1 * np.abs(w3).max()
    assert associative_bound(peer_wall((2, 2))) == pytest.approx(
        associative_bound(peer_wall()), rel=1e-6
    )
