"""Blocks and builders: shapes, straight running-bond ends, pitch with joints, openings, base,
and bad input rejected with a message naming the field."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

import masonry_dem as md
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import (
    add_base,
    boxes,
    cut_openings,
    running_bond_wall,
    running_bond_wall_of_size,
    single_block,
    stack_bond_column,
)

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0


def test_running_bond_wall_counts_and_straight_ends():
    n, nc = 5, 4
    w = running_bond_wall(n, nc, A, B, S, GAMMA)
    # even courses: n whole blocks; odd courses: 2 half blocks + (n - 1) whole
    assert w.count == 2 * n + 2 * (n + 1)
    np.testing.assert_allclose(w.lower.min(axis=0), [0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(w.upper.max(axis=0), [n * B, nc * A, S], rtol=1e-12)
    # every course starts at x = 0 and ends at x = n b (straight ends)
    for y in (np.arange(nc) + 0.5) * A:
        row = np.isclose(w.centres[:, 1], y)
        assert np.isclose(w.lower[row, 0].min(), 0.0)
        assert np.isclose(w.upper[row, 0].max(), n * B)
        # the course is filled with no gap: total length is n b
        assert np.isclose(w.sizes[row, 0].sum(), n * B)
    widths = np.unique(np.round(w.sizes[:, 0], 12))
    np.testing.assert_allclose(widths, [B / 2, B])
    # the blocks fill the wall volume exactly
    assert np.isclose(w.volumes.sum(), n * B * nc * A * S)
    np.testing.assert_allclose(w.weights, w.volumes * GAMMA)


def test_running_bond_start_with_half_swaps_courses():
    w = running_bond_wall(3, 2, A, B, S, GAMMA, start_with_half=True)
    bottom = np.isclose(w.centres[:, 1], A / 2)
    assert bottom.sum() == 4  # half, whole, whole, half
    np.testing.assert_allclose(np.sort(w.sizes[bottom, 0]), [B / 2, B / 2, B, B])


def test_running_bond_joint_is_included_in_the_pitch():
    e = 0.01
    w = running_bond_wall(4, 3, A, B, S, GAMMA, joint=e, origin=(1.0, 2.0, 3.0))
    np.testing.assert_allclose(w.lower.min(axis=0), [1.0, 2.0, 3.0])
    np.testing.assert_allclose(w.upper.max(axis=0), [1 + 4 * (B + e), 2 + 3 * (A + e), 3 + S])
    assert np.allclose(w.sizes[:, 1], A + e)


def test_running_bond_wall_of_size_is_exact():
    w = running_bond_wall_of_size(1.13, 0.77, A, B, S, GAMMA)
    np.testing.assert_allclose(w.upper.max(axis=0) - w.lower.min(axis=0), [1.13, 0.77, S])


def test_stack_column_single_block_and_boxes():
    c = stack_bond_column(3, A, B, S, GAMMA)
    np.testing.assert_allclose(c.centres[:, 1], [A / 2, 1.5 * A, 2.5 * A])
    assert np.allclose(c.sizes, [B, A, S])
    one = single_block(A, B, S, GAMMA)
    assert one.count == 1 and np.isclose(one.lower[0, 1], 0.0)
    bx = boxes([[0, 0, 0], [1, 0, 0]], [[1, 2, 3], [2, 1, 1]], 10.0)
    np.testing.assert_allclose(bx.sizes, [[1, 2, 3], [1, 1, 1]])
    np.testing.assert_allclose(bx.centres, [[0.5, 1, 1.5], [1.5, 0.5, 0.5]])


def test_blocks_are_frozen_and_permutable():
    w = running_bond_wall(3, 2, A, B, S, GAMMA)
    with pytest.raises(ValueError):
        w.centres[0, 0] = 1.0  # read-only arrays
    order = np.arange(w.count)[::-1]
    p = w.permuted(order)
    np.testing.assert_array_equal(p.centres, w.centres[order])
    both = Blocks.concatenate(w, p)
    assert both.count == 2 * w.count
    corners = w.corner_points()
    assert corners.shape == (w.count, 8, 3)
    np.testing.assert_allclose(corners.min(axis=1), w.lower)
    np.testing.assert_allclose(corners.max(axis=1), w.upper)


def test_cut_openings_removes_whole_blocks():
    w = running_bond_wall(6, 6, A, B, S, GAMMA)
    rect = (2 * B, 2 * A, 4 * B, 4 * A)
    cut = cut_openings(w, [rect])
    c = cut.centres
    inside = (c[:, 0] > rect[0]) & (c[:, 0] < rect[2]) & (c[:, 1] > rect[1]) & (c[:, 1] < rect[3])
    assert not inside.any()
    assert cut.count < w.count
    with pytest.raises(ValueError, match=r"openings\[0\].*removes no block"):
        cut_openings(w, [(10, 10, 11, 11)])
    with pytest.raises(ValueError, match=r"openings\[1\]"):
        cut_openings(w, [rect, (1, 1, 0, 0)])
    with pytest.raises(ValueError, match=r"openings\[0\].*non-finite"):
        cut_openings(w, [(np.nan, 0, 1, 1)])


def test_add_base_touches_the_wall():
    w = running_bond_wall(4, 3, A, B, S, GAMMA)
    wb, ib = add_base(w, depth=0.2)
    assert ib == w.count and wb.count == w.count + 1
    np.testing.assert_allclose(wb.upper[ib], [4 * B, 0.0, S], atol=1e-15)
    np.testing.assert_allclose(wb.lower[ib], [0.0, -0.2, 0.0], atol=1e-15)
    assert wb.unit_weight[ib] == 0.0
    wide, ib2 = add_base(w, overhang=0.05)
    np.testing.assert_allclose(wide.lower[ib2], [-0.05, -A, -0.05], atol=1e-15)
    np.testing.assert_allclose(wide.upper[ib2], [4 * B + 0.05, 0.0, S + 0.05], atol=1e-15)
    with pytest.raises(ValueError, match=r"^overhang"):
        add_base(w, overhang=np.nan)
    with pytest.raises(ValueError, match=r"^overhang must be non-negative"):
        add_base(w, overhang=-0.01)
    with pytest.raises(ValueError, match=r"^depth must be positive"):
        add_base(w, depth=0.0)


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"a": 0.0}, "a"),
        ({"b": -0.25}, "b"),
        ({"s": 0.0}, "s"),
        ({"a": np.nan}, "a"),
        ({"b": np.inf}, "b"),
        ({"s": np.nan}, "s"),
        ({"unit_weight": np.nan}, "unit_weight"),
        ({"unit_weight": -1.0}, "unit_weight"),
        ({"joint": -0.01}, "joint"),
        ({"joint": np.nan}, "joint"),
        ({"blocks_along_length": 0}, "blocks_along_length"),
        ({"courses": 2.5}, "courses"),
        ({"origin": (0.0, np.nan, 0.0)}, "origin"),
    ],
)
def test_running_bond_wall_rejects_bad_parameters_by_name(kwargs, field):
    args = {
        "blocks_along_length": 3,
        "courses": 2,
        "a": A,
        "b": B,
        "s": S,
        "unit_weight": GAMMA,
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=rf"^{field}\b"):
        running_bond_wall(**args)


def test_blocks_reject_non_positive_sizes_and_nan_by_name():
    with pytest.raises(ValueError, match=r"^sizes must be positive"):
        Blocks(np.zeros((2, 3)), [[1, 1, 1], [1, 0, 1]], 1.0)
    with pytest.raises(ValueError, match=r"^sizes must be positive"):
        Blocks(np.zeros((1, 3)), [[1, -1, 1]], 1.0)
    with pytest.raises(ValueError, match=r"^centres contains a non-finite"):
        Blocks([[0, np.nan, 0]], [[1, 1, 1]], 1.0)
    with pytest.raises(ValueError, match=r"^sizes contains a non-finite"):
        Blocks([[0, 0, 0]], [[1, np.nan, 1]], 1.0)
    with pytest.raises(ValueError, match=r"^unit_weight"):
        Blocks([[0, 0, 0]], [[1, 1, 1]], np.nan)
    with pytest.raises(ValueError, match=r"^unit_weight must be a scalar or have shape \(2,\)"):
        Blocks([[0, 0, 0], [2, 0, 0]], [[1, 1, 1]] * 2, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(
        Blocks([[0, 0, 0], [2, 0, 0]], [[1, 1, 1]] * 2, [5.0]).unit_weight, 5.0
    )
    with pytest.raises(ValueError, match=r"^centres must have shape"):
        Blocks([[0, 0]], [[1, 1, 1]], 1.0)
    with pytest.raises(ValueError, match=r"^sizes must have shape"):
        Blocks([[0, 0, 0]], [[1, 1, 1], [1, 1, 1]], 1.0)
    with pytest.raises(ValueError, match="at least one block"):
        Blocks(np.zeros((0, 3)), np.zeros((0, 3)), 1.0)
    with pytest.raises(ValueError, match=r"^upper\[0\] must lie above lower\[0\] along e2"):
        boxes([[0, 0, 0]], [[1, 0, 1]], 1.0)  # flat box: upper == lower along e2
    with pytest.raises(ValueError, match=r"^block_height must be positive"):
        stack_bond_column(2, 0.0, B, S, GAMMA)
    with pytest.raises(ValueError, match=r"^length"):
        running_bond_wall_of_size(np.nan, 1.0, A, B, S, GAMMA)


@pytest.mark.parametrize(
    "build, head",
    [
        (md.running_bond_wall, ["blocks_along_length", "courses"]),
        (md.running_bond_wall_of_size, ["length", "height"]),
        (md.stack_bond_column, ["courses"]),
        (md.single_block, []),
        (md.l_wall, ["blocks_along_length", "courses"]),
        (md.u_wall, ["blocks_along_length", "courses"]),
        (md.t_wall, ["blocks_along_length", "courses"]),
        (md.box_wall, ["blocks_along_length", "courses"]),
    ],
)
def test_every_builder_shows_the_unit_in_its_signature_and_refuses_a_misspelt_keyword(build, head):
    """The unit's parameters are declared once (``builders._Unit``), yet each builder shows
    them in its own signature, after its counts, in the order positional calls rely on, with
    the paper's letters as keywords; a keyword it does not have is a TypeError that names the builder."""
    params = inspect.signature(build).parameters
    unit = ["block_height", "block_length", "thickness", "unit_weight"]
    assert list(params)[: len(head) + 4] == head + unit
    assert all(params[k].kind is inspect.Parameter.KEYWORD_ONLY for k in ("a", "b", "s"))
    assert build.__doc__ and build.__name__ in repr(build)
    with pytest.raises(TypeError, match=rf"^{build.__name__}\(\): .* 'blok_height'"):
        build(*([3] * len(head)), blok_height=0.1)
