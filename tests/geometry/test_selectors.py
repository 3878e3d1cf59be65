"""Selectors by column, course, edge and predicate; each raises a ValueError naming itself when
it matches nothing."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.builders import add_base, running_bond_wall

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0
N, NC = 5, 4


@pytest.fixture(scope="module")
def wall():
    return running_bond_wall(N, NC, A, B, S, GAMMA)


def test_left_and_right_columns_hold_whole_and_half_end_blocks(wall):
    left = sel.column(wall, "left")
    right = sel.column(wall, "right")
    assert left.size == NC and right.size == NC
    np.testing.assert_allclose(wall.lower[left, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(wall.upper[right, 0], N * B, rtol=1e-12)
    # odd courses end in half blocks
    np.testing.assert_allclose(np.sort(wall.sizes[left, 0]), [B / 2] * (NC // 2) + [B] * (NC // 2))
    np.testing.assert_array_equal(sel.edge(wall, "left"), left)


def test_courses(wall):
    levels = sel.course_levels(wall)
    np.testing.assert_allclose(levels, (np.arange(NC) + 0.5) * A)
    for k in range(NC):
        idx = sel.course(wall, k)
        assert idx.size == (N if k % 2 == 0 else N + 1)
        np.testing.assert_allclose(wall.centres[idx, 1], (k + 0.5) * A)
    np.testing.assert_array_equal(sel.course(wall, -1), sel.course(wall, NC - 1))
    with pytest.raises(ValueError, match=r"course 4 does not exist: the assembly has 4 courses"):
        sel.course(wall, NC)
    with pytest.raises(ValueError, match="course -5 does not exist"):
        sel.course(wall, -NC - 1)


def test_edges(wall):
    assert sel.edge(wall, "bottom").size == N
    assert sel.edge(wall, "top").size == (N if (NC - 1) % 2 == 0 else N + 1)
    # a single-leaf wall touches the back and the front with every block
    assert sel.edge(wall, "back").size == wall.count
    assert sel.edge(wall, "front").size == wall.count
    with pytest.raises(ValueError, match="edge must be one of"):
        sel.edge(wall, "middle")
    with pytest.raises(ValueError, match="column must be 'left' or 'right'"):
        sel.column(wall, "top")


def test_among_restricts_the_search(wall):
    top_course = np.zeros(wall.count, bool)
    top_course[sel.course(wall, -1)] = True
    left_top = sel.column(wall, "left", among=top_course)
    assert left_top.size == 1 and top_course[left_top[0]]
    # the bottom edge of the top course is the top course itself
    np.testing.assert_array_equal(
        sel.edge(wall, "bottom", among=top_course), np.flatnonzero(top_course)
    )
    with pytest.raises(ValueError, match=r"selector edge='left' matches no block"):
        sel.edge(wall, "left", among=np.zeros(wall.count, bool))


def test_base_is_the_bottom_edge_after_add_base(wall):
    wb, ib = add_base(wall)
    np.testing.assert_array_equal(sel.edge(wb, "bottom"), [ib])


def test_predicate(wall):
    idx = sel.where(wall, lambda c: c[:, 0] < B, name="near_left")
    assert np.all(wall.centres[idx, 0] < B) and idx.size > 0
    with pytest.raises(ValueError, match="selector near_right matches no block"):
        sel.where(wall, lambda c: c[:, 0] > 100.0, name="near_right")
    with pytest.raises(ValueError, match="predicate must return a boolean mask of shape"):
        sel.where(wall, lambda c: c[:3, 0] > 0.0)  # wrong shape: 3 of n


def test_among_accepts_block_indices_like_a_mask(wall):
    top = sel.course(wall, -1)
    mask = np.zeros(wall.count, bool)
    mask[top] = True
    for which in ("left", "right"):
        np.testing.assert_array_equal(
            sel.column(wall, which, among=top), sel.column(wall, which, among=mask)
        )
    np.testing.assert_array_equal(sel.course(wall, 0, among=top), top)
    np.testing.assert_allclose(sel.course_levels(wall, among=top), [(NC - 0.5) * A])
    with pytest.raises(ValueError, match="among must be a boolean mask of shape"):
        sel.edge(wall, "left", among=np.ones(3, bool))
    with pytest.raises(ValueError, match="among: block index out of range"):
        sel.edge(wall, "left", among=[wall.count])
