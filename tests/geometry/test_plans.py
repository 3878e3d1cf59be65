"""Walls that meet (L, T, U plans and a closed box): blocks that fill the plan without overlap,
the running bond in every wall, the courses interlocked at each corner, the parts found back by
the selectors, the case-file forms, and bad input named."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.cases.casefile import case_from_dict
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.builders import running_bond_wall
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.geometry.plans import SHORTEST_PIECE, box_wall, l_wall, t_wall, u_wall

# Restrepo Velez's stones (b = 2.01 s: whole-block corners) and Orduna-Lourenco's (b = 3 s:
# closers at the corners)
SIZES = {"stone": (0.02824, 0.07978, 0.03968), "brick": (0.081, 0.210, 0.070)}
GAMMA = 20e3


def _overlaps(blocks) -> int:
    lo, hi = blocks.lower, blocks.upper
    tol = 1e-9 * float(np.median(blocks.sizes))
    gap = np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None])
    both = (gap > tol).all(axis=-1)
    np.fill_diagonal(both, False)
    return int(both.sum())


def _course(blocks, k, a):
    return np.flatnonzero(np.isclose(blocks.centres[:, 1], (k + 0.5) * a))


def _plan_area(kind, n, m, b, s):
    """The plan area of the walls, from their outer sizes (corner squares counted once)."""
    length, depth = n * b, m * b
    return {
        "l": length * s + (depth - s) * s,
        "u": length * s + 2 * (depth - s) * s,
        "t": length * s + (depth - s) * s,
        "box": 2 * length * s + 2 * (depth - 2 * s) * s,
    }[kind]


BUILD = {
    "l": lambda n, nc, a, b, s, m: l_wall(n, nc, a, b, s, GAMMA, return_blocks=m),
    "u": lambda n, nc, a, b, s, m: u_wall(n, nc, a, b, s, GAMMA, return_blocks=m),
    "t": lambda n, nc, a, b, s, m: t_wall(n, nc, a, b, s, GAMMA, return_blocks=m),
    "box": lambda n, nc, a, b, s, m: box_wall(n, nc, a, b, s, GAMMA, blocks_along_depth=m),
}


@pytest.mark.parametrize("size", sorted(SIZES))
@pytest.mark.parametrize("kind", sorted(BUILD))
@pytest.mark.parametrize(("n", "m"), [(6, 2), (7, 5)])
def test_every_course_fills_the_plan_without_overlap(kind, size, n, m):
    a, b, s = SIZES[size]
    nc = 4
    w = BUILD[kind](n, nc, a, b, s, m)
    assert _overlaps(w) == 0
    for k in range(nc):
        idx = _course(w, k, a)
        area = float(np.sum(w.sizes[idx, 0] * w.sizes[idx, 2]))
        assert area == pytest.approx(_plan_area(kind, n, m, b, s), rel=1e-12)
    # every piece is a closer at least 0.3 block long and at most 1.3 blocks, whole otherwise
    lengths = np.max(w.sizes[:, [0, 2]], axis=1)
    assert lengths.min() >= min(SHORTEST_PIECE * b, s) * (1 - 1e-12)
    assert lengths.max() <= (1 + SHORTEST_PIECE) * b * (1 + 1e-12)
    assert np.isclose(w.sizes[:, 1], a).all()
    # the blocks form one connected assembly through face contacts
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    its = detect_interfaces(w)
    graph = coo_matrix((np.ones(its.count), (its.block_i, its.block_j)), shape=(w.count,) * 2)
    assert connected_components(graph, directed=False)[0] == 1


def _head_joints(w, idx, axis):
    """Positions along ``axis`` of the head joints between the blocks ``idx`` of a course."""
    ends = np.concatenate([w.lower[idx, axis], w.upper[idx, axis]])
    inner = np.unique(np.round(ends, 12))
    return inner[1:-1]


@pytest.mark.parametrize("size", sorted(SIZES))
def test_running_bond_in_the_facade_and_the_return(size):
    """In each wall the head joints of one course lie at least 0.3 block from those of the
    course below (half a block away from the corners)."""
    a, b, s = SIZES[size]
    w = u_wall(8, 6, a, b, s, GAMMA, return_blocks=4)
    facade = np.zeros(w.count, bool)
    facade[sel.part(w, "facade")] = True
    ret = np.zeros(w.count, bool)
    ret[sel.part(w, "return:left")] = True
    for wall, axis in ((facade, 0), (ret, 2)):
        for k in range(5):
            lower = _head_joints(
                w, np.flatnonzero(wall & np.isin(np.arange(w.count), _course(w, k, a))), axis
            )
            upper = _head_joints(
                w, np.flatnonzero(wall & np.isin(np.arange(w.count), _course(w, k + 1, a))), axis
            )
            gaps = np.abs(lower[:, None] - upper[None, :])
            assert gaps.min() >= SHORTEST_PIECE * b * (1 - 1e-9)


@pytest.mark.parametrize("kind", ["l", "u", "box"])
def test_courses_interlock_at_every_corner(kind):
    """At a corner, one course's block that fills the corner square belongs to one wall and
    the next course's to the other: the walls alternate running through."""
    a, b, s = SIZES["stone"]
    nc = 6
    w = BUILD[kind](8, nc, a, b, s, 4)
    corners = {"l": ["corner:left"], "u": ["corner:left", "corner:right"]}.get(
        kind, ["corner:left", "corner:right", "corner:back-left", "corner:back-right"]
    )
    for corner in corners:
        idx = sel.part(w, corner)
        lo = w.lower[idx].min(axis=0)
        hi = w.upper[idx].max(axis=0)
        # the block of each course that covers the centre of the corner square
        side = lo[0] if "left" in corner else hi[0] - s
        front = hi[2] - s if "back" not in corner else lo[2]
        centre = np.array([side + s / 2, front + s / 2])
        runs_along = []
        for k in range(nc):
            ck = idx[np.isclose(w.centres[idx, 1], (k + 0.5) * a)]
            cover = ck[
                (w.lower[ck, 0] < centre[0])
                & (w.upper[ck, 0] > centre[0])
                & (w.lower[ck, 2] < centre[1])
                & (w.upper[ck, 2] > centre[1])
            ]
            assert cover.size == 1
            runs_along.append(int(np.argmax(w.sizes[cover[0], [0, 2]])))
        assert runs_along[0::2] == [runs_along[0]] * (nc // 2)
        assert runs_along[1::2] == [1 - runs_along[0]] * (nc // 2)


def test_l_wall_facade_is_the_flat_wall_where_the_return_runs_behind():
    """In the courses where the facade runs through the corner, the L wall's facade is the
    flat running-bond wall's course; the return is m b long from the facade's outer face."""
    a, b, s = SIZES["stone"]
    n, m = 6, 3
    w = l_wall(n, 4, a, b, s, GAMMA, return_blocks=m)
    flat = running_bond_wall(n, 4, a, b, s, GAMMA)
    facade = sel.part(w, "facade")
    even = facade[np.isclose(w.centres[facade, 1], 0.5 * a)]
    np.testing.assert_allclose(
        np.sort(w.lower[even, 0]), np.sort(flat.lower[_course(flat, 0, a), 0])
    )
    ret = sel.part(w, "return:left")
    assert w.upper[:, 2].max() - w.lower[ret, 2].min() == pytest.approx(m * b)
    right = l_wall(n, 4, a, b, s, GAMMA, return_blocks=m, corner="right")
    np.testing.assert_allclose(
        np.sort(right.centres[:, 0]), np.sort(n * b - w.centres[:, 0]), atol=1e-12
    )
    assert sel.part(right, "return:right").size == ret.size


def test_u_wall_is_mirror_symmetric():
    a, b, s = SIZES["brick"]
    w = u_wall(7, 5, a, b, s, GAMMA, return_blocks=3)
    mirrored = w.centres.copy()
    mirrored[:, 0] = 7 * b - mirrored[:, 0]
    key = lambda c: np.lexsort(np.round(c, 9).T)  # noqa: E731
    np.testing.assert_allclose(w.centres[key(w.centres)], mirrored[key(mirrored)], atol=1e-12)


def test_square_box_is_the_same_after_a_quarter_turn():
    a, b, s = SIZES["brick"]
    n = 5
    w = box_wall(n, 4, a, b, s, GAMMA)
    lo, hi = w.lower.min(axis=0), w.upper.max(axis=0)
    cx, cz = (lo[0] + hi[0]) / 2, (lo[2] + hi[2]) / 2
    # a quarter turn about e2 taking the front (+e3) to the right (+e1): (x, z) -> (z, -x)
    turned = w.centres.copy()
    turned[:, 0] = cx + (w.centres[:, 2] - cz)
    turned[:, 2] = cz - (w.centres[:, 0] - cx)
    key = lambda c: np.lexsort(np.round(c, 9).T)  # noqa: E731
    np.testing.assert_allclose(w.centres[key(w.centres)], turned[key(turned)], atol=1e-12)
    for part in ("facade", "back", "return:left", "return:right"):
        assert sel.part(w, part).size == w.count // 4


def test_parts_of_each_plan():
    a, b, s = SIZES["stone"]
    nc = 4
    counts = {
        "l": {"facade", "return:left", "corner:left"},
        "u": {"facade", "return:left", "return:right", "corner:left", "corner:right"},
        "t": {"facade", "cross", "corner:cross"},
        "box": {
            "facade",
            "back",
            "return:left",
            "return:right",
            "corner:left",
            "corner:right",
            "corner:back-left",
            "corner:back-right",
        },
    }
    for kind, present in counts.items():
        w = BUILD[kind](6, nc, a, b, s, 4)
        walls = [p for p in sel.WALL_PARTS if p in present]
        found = np.concatenate([sel.part(w, p) for p in walls])
        assert np.sort(found).tolist() == list(range(w.count))  # the walls partition the blocks
        for p in sel.PARTS:
            if p in present:
                idx = sel.part(w, p)
                if p.startswith("corner"):
                    assert idx.size == nc + nc // 2 * (kind == "t")  # a T's joint shows two
            else:
                with pytest.raises(ValueError, match=f"part='{p}' matches no block"):
                    sel.part(w, p)
    with pytest.raises(ValueError, match="part must be one of"):
        sel.part(w, "return:middle")


def test_facade_openings_cut_the_facade_only():
    a, b, s = SIZES["brick"]
    rect = (2 * b, 1 * a, 4 * b, 3 * a)
    whole = box_wall(6, 5, a, b, s, GAMMA)
    cut = box_wall(6, 5, a, b, s, GAMMA, facade_openings=[rect])
    gone = whole.count - cut.count
    assert gone > 0
    assert sel.part(cut, "back").size == sel.part(whole, "back").size
    assert sel.part(whole, "facade").size - sel.part(cut, "facade").size == gone
    with pytest.raises(ValueError, match=r"facade_openings\[0\] = .* removes no block"):
        u_wall(6, 5, a, b, s, GAMMA, facade_openings=[(0.0, 10.0, 0.1, 11.0)])


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: u_wall(0, 3, 0.1, 0.2, 0.1, GAMMA),
            "blocks_along_length must be a whole number from 1",
        ),
        (lambda: u_wall(1, 3, 0.1, 0.2, 0.1, GAMMA), "too short for two corners"),
        (lambda: l_wall(4, 3, 0.1, 0.2, 0.1, GAMMA, return_blocks=0), "return_blocks must be"),
        (lambda: l_wall(4, 3, 0.1, 0.2, 0.2, GAMMA, return_blocks=1), "must reach behind"),
        (lambda: l_wall(4, 3, 0.1, 0.2, 0.1, GAMMA, corner="middle"), "corner must be one of"),
        (lambda: t_wall(4, 3, 0.1, 0.2, 0.1, GAMMA, cross_at=0.05), "cross_at = 0.05 puts"),
        (lambda: box_wall(4, 3, 0.1, 0.2, -0.1, GAMMA), "s must be positive"),
        (lambda: box_wall(4, 3, 0.1, 0.2, 0.1, GAMMA, blocks_along_depth=1), "no side wall"),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_case_file_forms_and_part_selectors():
    data = {
        "geometry": {
            "builder": "u_wall",
            "blocks_along_length": 6,
            "courses": 5,
            "a": 0.081,
            "b": 0.21,
            "s": 0.07,
            "unit_weight": 20e3,
            "return_blocks": 3,
            "base": True,
        },
        "material": {"kn": 1e9, "kt": 0.4e9, "friction": 0.7},
        "supports": [{"select": "base"}],
        "loads": [
            {"type": "self_weight"},
            {"type": "weight_proportional", "direction": [0, 0, 1], "select": "facade"},
        ],
    }
    case = case_from_dict(data)
    blocks = case.model.blocks
    wall = u_wall(6, 5, 0.081, 0.21, 0.07, 20e3, return_blocks=3)
    assert blocks.count == wall.count + 1
    facade = sel.part(wall, "facade")
    loaded = np.flatnonzero(case.model.live[:, 2])
    np.testing.assert_array_equal(loaded, facade)
    for builder in ("l_wall", "t_wall", "box_wall"):
        geometry = dict(data["geometry"], builder=builder)
        if builder == "box_wall":
            geometry.pop("return_blocks")
        case_from_dict(dict(data, geometry=geometry))
    bad = dict(data, supports=[{"select": "base"}, {"select": "corner:back-left"}])
    with pytest.raises(ValueError, match="no two walls meet there"):
        case_from_dict(bad)
