"""Openings with lintels in the facade of walls that meet (``facade_openings`` with
``lintels=True``; ``[geometry] lintels = true`` in case files): the blocks, the parts, the
dead load they stand under, and bad input named.

A dry wall cannot stand with an opening cut in whole blocks (a block of the course above hangs
on head joints that carry no normal force); with lintels the jambs are straightened and a
lintel laid over each opening, in the facade alone, as :func:`cut_openings` builds them in a
plain wall."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from masonry_dem.cases.casefile import build_blocks, case_from_dict
from masonry_dem.cases.schema import CaseError
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import (
    add_base,
    cut_openings,
    running_bond_wall,
    unsupported_blocks,
)
from masonry_dem.geometry.plans import box_wall, l_wall, t_wall, u_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import pushover

A, B, S, GAMMA = 0.081, 0.21, 0.07, 20e3  # b = 3 s: closers at the corners
KN, KT, MU = 2.4e9, 1.0e9, 0.7
WINDOW = (2 * B, 3 * A, 4 * B, 7 * A)  # two blocks wide, courses 3 to 6 (of 10)
DOOR = (6 * B, 0.0, 7 * B, 6 * A)  # one block wide, courses 0 to 5
# two windows a block apart, their tops on an even course: the course over them has a head
# joint at each jamb, so each lintel would take in the block over the pier between them
OVER_ONE_PIER = ((2 * B, 2 * A, 3 * B, 6 * A), (4 * B, 2 * A, 5 * B, 6 * A))


def _boxes(blocks: Blocks, mask: np.ndarray | None = None) -> set[tuple[float, ...]]:
    """The blocks as a set of rounded (lower, upper) corners: equal sets, equal blocks."""
    m = np.ones(blocks.count, bool) if mask is None else mask
    rows = np.hstack([blocks.lower[m], blocks.upper[m]]).round(9) + 0.0
    return {tuple(r) for r in rows.tolist()}


def _lintel_over(blocks: Blocks, rect) -> int:
    """The one facade block that sits on the opening's top and overlaps its span."""
    x0, _, x1, y1 = rect
    over = (
        (blocks.lower[:, 2] >= -1e-9)  # in the facade
        & np.isclose(blocks.lower[:, 1], y1)
        & (blocks.upper[:, 0] > x0 + 1e-9)
        & (blocks.lower[:, 0] < x1 - 1e-9)
    )
    assert over.sum() == 1, over.sum()
    return int(np.flatnonzero(over)[0])


def test_the_blocks_of_a_u_wall_with_a_window_a_door_and_lintels():
    """U wall, n = 10 blocks along the facade, m = 3 along each return, 10 courses; a window
    and a door (from the base) in the facade.

    * Volume: the plan area of the walls (facade n b s, each return (m b - s) s, the corner
      square counted once) times the height 10 a, less b_k h_k s for each opening: the
      lintels take the place of the blocks over the openings, exactly.
    * No block has nothing under it; each lintel spans its opening and bears on a pier at each
      side, sits on the opening's top, and its top is a bed joint (a whole course higher).
    * The lintels are part of the facade and reach into no corner; the returns and the corners
      are the blocks of the wall without openings; away from the corners the facade is the
      plain running-bond wall with the same openings built by ``cut_openings(lintels=True)``.
    """
    n, m, nc = 10, 3, 10
    whole = u_wall(n, nc, A, B, S, GAMMA, return_blocks=m)
    w = u_wall(n, nc, A, B, S, GAMMA, return_blocks=m, facade_openings=[WINDOW, DOOR], lintels=True)
    length = n * B
    plan = length * S + 2 * (m * B - S) * S
    holes = sum((x1 - x0) * (y1 - y0) * S for x0, y0, x1, y1 in (WINDOW, DOOR))
    assert w.volumes.sum() == pytest.approx(nc * A * plan - holes, rel=1e-12)
    assert unsupported_blocks(w).size == 0

    facade = sel.part(w, "facade")
    for rect in (WINDOW, DOOR):
        k = _lintel_over(w, rect)
        x0, _, x1, y1 = rect
        assert w.lower[k, 0] < x0 - 1e-9 and w.upper[k, 0] > x1 + 1e-9  # two piers
        assert w.upper[k, 1] == pytest.approx(y1 + A, rel=1e-12)
        assert np.isclose(w.upper[k, 1], w.lower[:, 1]).any()  # a bed joint of the wall
        assert k in facade
        assert w.lower[k, 0] >= S - 1e-9 and w.upper[k, 0] <= length - S + 1e-9
    for part in ("return:left", "return:right", "corner:left", "corner:right"):
        assert _boxes(w, np.isin(np.arange(w.count), sel.part(w, part))) == _boxes(
            whole, np.isin(np.arange(whole.count), sel.part(whole, part))
        ), part

    plain = cut_openings(running_bond_wall(n, nc, A, B, S, GAMMA), [WINDOW, DOOR], lintels=True)
    inner = (1.5 * B, length - 1.5 * B)

    def middle(blocks: Blocks) -> np.ndarray:
        return (
            (blocks.lower[:, 2] >= -1e-9)
            & (blocks.lower[:, 0] >= inner[0] - 1e-9)
            & (blocks.upper[:, 0] <= inner[1] + 1e-9)
        )

    assert _boxes(w, middle(w)) == _boxes(plain, middle(plain))


@pytest.mark.parametrize(
    "build",
    [
        lambda **kw: l_wall(8, 6, A, B, S, GAMMA, **kw),
        lambda **kw: l_wall(8, 6, A, B, S, GAMMA, corner="right", **kw),
        lambda **kw: t_wall(8, 6, A, B, S, GAMMA, cross_at=5.5 * B, **kw),
        lambda **kw: box_wall(8, 6, A, B, S, GAMMA, blocks_along_depth=5, **kw),
    ],
    ids=["l-left", "l-right", "t", "box"],
)
def test_every_plan_takes_lintels_between_its_corners(build):
    """The same window (x from 2 b to 4 b, courses 2 to 4) in an L (either corner), a T (its
    cross wall at 5.5 b) and a box: nothing left hanging, the volume less b h s exactly, the
    lintel in the facade, the walls behind the facade the blocks of the wall without it."""
    rect = (2 * B, 2 * A, 4 * B, 5 * A)
    whole = build()
    w = build(facade_openings=[rect], lintels=True)
    assert unsupported_blocks(w).size == 0
    assert w.volumes.sum() == pytest.approx(whole.volumes.sum() - 2 * B * 3 * A * S, rel=1e-12)
    assert _lintel_over(w, rect) in sel.part(w, "facade")
    behind_w, behind_whole = w.lower[:, 2] < -1e-9, whole.lower[:, 2] < -1e-9
    assert _boxes(w, behind_w) == _boxes(whole, behind_whole)


def test_a_lintel_may_end_at_a_free_end_of_the_facade():
    """An opening one block from the free end of an L's facade (x from 4 b to 5 b, its top on
    an even course): the course over it has head joints at both jambs, so its lintel takes in
    the blocks beside them and runs to the end (x from 3 b to 6 b); it bears on both piers."""
    rect = (4 * B, 2 * A, 5 * B, 6 * A)
    w = l_wall(6, 10, A, B, S, GAMMA, facade_openings=[rect], lintels=True)
    k = _lintel_over(w, rect)
    np.testing.assert_allclose([w.lower[k, 0], w.upper[k, 0]], [3 * B, 6 * B], rtol=1e-12)
    assert unsupported_blocks(w).size == 0


def test_two_lintels_over_one_pier_are_refused_in_a_plain_wall_too():
    """They overlapped: two blocks in one place, the volume counted twice."""
    wall = running_bond_wall(8, 10, A, B, S, GAMMA)
    with pytest.raises(ValueError, match=r"openings\[0\] and openings\[1\]: their lintels"):
        cut_openings(wall, list(OVER_ONE_PIER), lintels=True)


@pytest.mark.parametrize("rect", [(0.0, 2 * A, B, 6 * A), (7 * B, 2 * A, 8 * B, 6 * A)])
def test_an_opening_at_an_end_of_a_plain_wall_is_refused_below_its_top(rect):
    """A lintel over an opening at an end of the wall would bear on one pier only: a
    cantilever that dry joints cannot hold. Reaching the top, the opening needs no lintel and
    leaves a shorter stretch of wall: it is cut, its volume b x 8 a x s."""
    wall = running_bond_wall(8, 10, A, B, S, GAMMA)
    with pytest.raises(
        ValueError, match=r"openings\[0\] = .* reaches an end of the wall .* one pier"
    ):
        cut_openings(wall, [rect], lintels=True)
    notch = (rect[0], rect[1], rect[2], 10 * A)
    cut = cut_openings(wall, [notch], lintels=True)
    # the jamb straightened, exactly the notch's volume goes
    removed = wall.volumes.sum() - cut.volumes.sum()
    np.testing.assert_allclose(removed, B * 8 * A * S, rtol=1e-12)
    assert unsupported_blocks(cut).size == 0


def _dead_load(blocks: Blocks):
    with_base, base = add_base(blocks)
    model = Model.build(
        with_base, InterfaceMaterial(kn=KN, kt=KT, friction=MU), [Support([base])], [SelfWeight()]
    )
    return model, with_base, pushover(model)


def _yielded_beds(model, blocks, history) -> set[tuple[float, ...]]:
    """The bed joints that yield, each by the rounded corners of the two blocks it joins."""
    its = model.interfaces
    out = set()
    for k in np.flatnonzero((history.last.state != 0) & (its.axis == 1)):
        pair = sorted(
            tuple((np.hstack([blocks.lower[i], blocks.upper[i]]).round(9) + 0.0).tolist())
            for i in (its.block_i[k], its.block_j[k])
        )
        out.add(tuple(pair[0] + pair[1]))
    return out


@pytest.mark.parametrize("plan", ["l", "u"])
def test_walls_that_meet_with_a_window_and_lintels_stand_under_their_weight(plan):
    """An L and a U wall (6 blocks, 10 courses, returns of 3) with a window and lintels stand
    under the dead load: the dead-load step converges and every block moves by the joints'
    elastic closure (about gamma H^2 / kn, 5e-5 m here, against a limit of s / 2). Without
    the return walls this is the plain wall of the same window, and the window's arching
    is the same: the joints that slide at mu under the dead load (micrometres: the bed joints
    over the lintel's ends and under the sill's corners, which carry the thrust of the
    masonry arching over and under the opening) are exactly the plain wall's, and no bed joint
    of the return walls yields (a dry head joint at zero compression is flagged at its zero
    capacity, as in a wall without openings). Without lintels the same wall has no dead-load equilibrium,
    and the builder names the block that hangs."""
    build = l_wall if plan == "l" else u_wall
    rect = (2 * B, 3 * A, 4 * B, 7 * A)
    w = build(6, 10, A, B, S, GAMMA, return_blocks=3, facade_openings=[rect], lintels=True)
    model, blocks, h = _dead_load(w)
    assert h.status == "completed", h.reason
    assert np.abs(h.last.q[: w.count, :3]).max() < 1e-3 * S
    plain = cut_openings(running_bond_wall(6, 10, A, B, S, GAMMA), [rect], lintels=True)
    p_model, p_blocks, p_h = _dead_load(plain)
    assert p_h.status == "completed", p_h.reason
    yielded = _yielded_beds(model, blocks, h)
    assert yielded == _yielded_beds(p_model, p_blocks, p_h)
    assert all(r[2] >= -1e-9 and r[8] >= -1e-9 for r in yielded)  # in the facade
    its = model.interfaces
    behind = (blocks.lower[its.block_i, 2] < -1e-9) & (blocks.lower[its.block_j, 2] < -1e-9)
    beds = behind & (its.axis == 1)
    assert beds.any() and np.all(h.last.state[beds] == 0)


@pytest.mark.parametrize("plan", ["l", "u"])
def test_without_lintels_the_block_that_hangs_is_named(plan, caplog):
    """The window of the test above cut in whole blocks: in course 7 the facade's block over
    the window's middle (x from 2.5 b to 3.5 b, centre (3 b, 7.5 a, s / 2)) has nothing
    under it; the warning names it, and the wall has no equilibrium under its weight."""
    build = l_wall if plan == "l" else u_wall
    rect = (2 * B, 3 * A, 4 * B, 7 * A)
    with caplog.at_level("WARNING", logger="masonry_dem.geometry.builders"):
        w = build(6, 10, A, B, S, GAMMA, return_blocks=3, facade_openings=[rect])
    assert "facade_openings leave 1 block(s) with nothing under them" in caplog.text
    assert f"[{3 * B:g}, {7.5 * A:g}, {S / 2:g}]" in caplog.text
    assert "lintels = true" in caplog.text
    assert unsupported_blocks(w).size == 1
    _, _, h = _dead_load(w)
    assert h.status == "failed" and "no equilibrium under the dead load" in h.reason


@pytest.mark.parametrize("plan", ["l", "u"])
def test_walls_that_meet_with_a_window_and_lintels_collapse_certified_on_the_tilt_table(plan):
    """The L and U walls of the test above on the tilt table (a weight-proportional load
    along +e3, pulling the facade away from its returns) collapse, with a certificate that
    holds, above the plain wall of the same window: that one overturns about its base at
    s / H = 0.07 / 0.81 (the window's courses are centred at mid-height, so y_G stays H / 2;
    tests/cases/test_new_user_sweep.py), and the returns, whose courses run through the
    corners, hold the facade back (measured: an L at 0.122, a U at 0.250)."""
    build = l_wall if plan == "l" else u_wall
    rect = (2 * B, 3 * A, 4 * B, 7 * A)
    w = build(6, 10, A, B, S, GAMMA, return_blocks=3, facade_openings=[rect], lintels=True)
    blocks, base = add_base(w)
    loads = [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))]
    material = InterfaceMaterial(kn=KN, kt=KT, friction=MU)
    h = pushover(Model.build(blocks, material, [Support([base])], loads))
    assert h.status == "collapse", h.reason
    assert h.certificate is not None and h.certificate.holds
    assert h.collapse_multiplier > (1 + 1e-6) * S / (10 * A)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        # the opening's jamb inside the corner square x in [0, s]
        (
            lambda **kw: u_wall(
                6, 10, A, B, S, GAMMA, facade_openings=[(0.035, 3 * A, 2 * B, 7 * A)], **kw
            ),
            r"facade_openings\[0\] = \[0.035, .*\] crosses the corner at x in \[0, 0.07\]",
        ),
        # course 6 is a facade course through the corner: the lintel would take its corner block
        (
            lambda **kw: u_wall(
                6, 10, A, B, S, GAMMA, facade_openings=[(B, 2 * A, 2 * B, 6 * A)], **kw
            ),
            r"facade_openings\[0\] = .*: its lintel \(x in \[0, 0.63\].*would reach into the "
            r"corner at x in \[0, 0.07\]",
        ),
        (
            lambda **kw: t_wall(
                8, 6, A, B, S, GAMMA, facade_openings=[(3 * B, A, 5 * B, 3 * A)], **kw
            ),
            r"facade_openings\[0\] = .* crosses the corner at x in \[0.805, 0.875\]",
        ),
        # past the facade's end
        (
            lambda **kw: u_wall(
                6, 10, A, B, S, GAMMA, facade_openings=[(5 * B, 3 * A, 7 * B, 7 * A)], **kw
            ),
            r"facade_openings\[0\] = .* reaches outside the facade: .* x in \[0, 1.26\], "
            r"y in \[0, 0.81\] m",
        ),
        (
            lambda **kw: u_wall(
                6, 10, A, B, S, GAMMA, facade_openings=[(2 * B, 3 * A, 3 * B, 11 * A)], **kw
            ),
            r"facade_openings\[0\] = .* reaches outside the facade",
        ),
        # an opening to the free end of an L's facade: no pier on that side
        (
            lambda **kw: l_wall(
                6, 10, A, B, S, GAMMA, facade_openings=[(5 * B, 2 * A, 6 * B, 6 * A)], **kw
            ),
            r"facade_openings\[0\] = .* reaches the facade's end \(x in \[0, 1.26\]\): a "
            r"lintel over it would bear on one pier only",
        ),
        # two lintels over one pier: they would overlap
        (
            lambda **kw: u_wall(
                8, 10, A, B, S, GAMMA, facade_openings=[OVER_ONE_PIER[0], OVER_ONE_PIER[1]], **kw
            ),
            r"facade_openings\[0\] and facade_openings\[1\]: their lintels would share the "
            r"block\(s\) at x in \[0.63, 0.84\], y in \[0.486, 0.567\]",
        ),
        (
            lambda **kw: u_wall(
                6, 10, A, B, S, GAMMA, facade_openings=[(2 * B, 3 * A, B, 7 * A)], **kw
            ),
            r"facade_openings\[0\] must have x_max > x_min",
        ),
    ],
)
def test_bad_openings_with_lintels_are_named(call, message):
    with pytest.raises(ValueError, match=message):
        call(lintels=True)


def test_lintels_must_be_a_boolean():
    with pytest.raises(ValueError, match='lintels must be true or false, got "yes"'):
        u_wall(6, 10, A, B, S, GAMMA, facade_openings=[WINDOW], lintels="yes")  # type: ignore[arg-type]


U_CASE = {
    "name": "u wall with a window",
    "geometry": {
        "builder": "u_wall",
        "blocks_along_length": 6,
        "courses": 10,
        "a": A,
        "b": B,
        "s": S,
        "unit_weight": GAMMA,
        "return_blocks": 3,
        "facade_openings": [list(WINDOW)],
        "lintels": True,
        "base": True,
    },
    "material": {"kn": KN, "kt": KT, "friction": MU},
    "supports": [{"select": "base"}],
    "loads": [{"type": "self_weight"}, {"type": "weight_proportional", "direction": [0, 0, 1]}],
}


def test_a_case_file_builds_the_lintels_of_a_plan():
    blocks, base, wall = build_blocks(copy.deepcopy(U_CASE["geometry"]))
    python = u_wall(6, 10, A, B, S, GAMMA, return_blocks=3, facade_openings=[WINDOW], lintels=True)
    assert base == python.count and np.all(wall[:-1]) and not wall[-1]
    np.testing.assert_array_equal(blocks.centres[:-1], python.centres)
    np.testing.assert_array_equal(blocks.sizes[:-1], python.sizes)
    case = case_from_dict(copy.deepcopy(U_CASE), "u.toml")
    assert case.model.blocks.count == python.count + 1


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {"facade_openings": None},
            r"lintels = true builds lintels over the openings, but none are given "
            r"\(facade_openings for walls that meet\)",
        ),
        (
            {"facade_openings": None, "openings": [list(WINDOW)]},
            r"lintels = true with builder 'u_wall': give the openings as facade_openings",
        ),
        (
            {"facade_openings": [[0.035, 3 * A, 2 * B, 7 * A]]},
            r"facade_openings\[0\] = \[0.035, .*\] crosses the corner",
        ),
    ],
)
def test_a_case_file_names_bad_lintels_of_a_plan(change, message):
    data = copy.deepcopy(U_CASE)
    for key, value in change.items():
        if value is None:
            data["geometry"].pop(key)
        else:
            data["geometry"][key] = value
    with pytest.raises(CaseError, match=message):
        case_from_dict(data, "u.toml")
