"""Contact detection between axis-aligned box faces.

Proves: every face-to-face contact of positive area is found (normal to e1, e2 or e3, with
partial overlaps of any size, the half overlaps of running bond included), with the right
normal axis, orientation (block i on the lower side), centre on the contact plane, and sides
l1, l2 along the local axes y1 = e[(n+1)%3], y2 = e[(n+2)%3]; edge and corner touches and gaps
give no interface; overlapping blocks are refused; the result does not depend on the block
numbering.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import add_base, boxes, running_bond_wall
from masonry_dem.geometry.interfaces import candidate_pairs, detect_interfaces

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0


def _pair_box(axis: int, size_a, size_b, shift_t):
    """Box a at the origin; box b on its +e[axis] face, shifted by shift_t (3,) tangentially."""
    size_a, size_b, shift = (np.asarray(v, float) for v in (size_a, size_b, shift_t))
    lo_a = np.zeros(3)
    lo_b = shift.copy()
    lo_b[axis] = size_a[axis]
    return boxes([lo_a, lo_b], [lo_a + size_a, lo_b + size_b], 1.0)


sizes = st.tuples(*(st.floats(0.05, 2.0) for _ in range(3)))


@settings(max_examples=150, deadline=None, derandomize=True)
@given(
    axis=st.integers(0, 2),
    size_a=sizes,
    size_b=sizes,
    frac=st.tuples(st.floats(-0.95, 0.95), st.floats(-0.95, 0.95)),
    swap=st.booleans(),
)
def test_arbitrary_partial_overlap_is_one_exact_interface(axis, size_a, size_b, frac, swap):
    size_a, size_b = np.array(size_a), np.array(size_b)
    t1, t2 = (axis + 1) % 3, (axis + 2) % 3
    shift = np.zeros(3)
    # shift b tangentially so the overlap along each tangent is a positive fraction of the
    # smaller side: from b sticking out below a to b sticking out above a
    for t, f in zip((t1, t2), frac, strict=True):
        lo_min, lo_max = -size_b[t], size_a[t]  # open range of overlapping positions
        shift[t] = lo_min + (lo_max - lo_min) * (f + 1) / 2
    blocks = _pair_box(axis, size_a, size_b, shift)
    if swap:
        blocks = blocks.permuted([1, 0])
    lower_idx, upper_idx = (1, 0) if swap else (0, 1)
    its = detect_interfaces(blocks)
    assert its.count == 1
    assert its.axis[0] == axis
    assert (its.block_i[0], its.block_j[0]) == (lower_idx, upper_idx)
    lo = np.maximum(blocks.lower[0], blocks.lower[1])
    hi = np.minimum(blocks.upper[0], blocks.upper[1])
    np.testing.assert_allclose(its.l1[0], hi[t1] - lo[t1], rtol=1e-12)
    np.testing.assert_allclose(its.l2[0], hi[t2] - lo[t2], rtol=1e-12)
    centre = (lo + hi) / 2
    centre[axis] = size_a[axis]  # the contact plane
    np.testing.assert_allclose(its.centre[0], centre, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(its.area[0], (hi[t1] - lo[t1]) * (hi[t2] - lo[t2]), rtol=1e-12)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_contact_normal_to_each_axis_local_axes(axis):
    size = np.array([0.3, 0.2, 0.1])
    blocks = _pair_box(axis, size, size, np.zeros(3))
    its = detect_interfaces(blocks)
    assert its.count == 1 and its.axis[0] == axis
    t1, t2 = (axis + 1) % 3, (axis + 2) % 3
    assert its.l1[0] == pytest.approx(size[t1], rel=1e-12)
    assert its.l2[0] == pytest.approx(size[t2], rel=1e-12)
    np.testing.assert_array_equal(its.local_axes[0], [t1, t2, axis])
    # corner points lie in the contact plane and span l1 x l2
    pts = its.corner_points()[0]
    assert np.allclose(pts[:, axis], size[axis])
    np.testing.assert_allclose(
        pts.max(axis=0) - pts.min(axis=0), np.where(np.arange(3) == axis, 0.0, size), atol=1e-15
    )


@pytest.mark.parametrize(
    "offset",
    [
        (1.0, 1.0, 0.0),  # edge along e3
        (1.0, 0.0, 1.0),  # edge along e2
        (0.0, 1.0, 1.0),  # edge along e1
        (1.0, 1.0, 1.0),  # corner
        (1.0, -1.0, 1.0),  # corner
        (1.0 + 1e-3, 0.0, 0.0),  # face-to-face with a gap
        (1.0, 1.0 + 1e-3, 0.0),  # beyond the edge
    ],
)
def test_edge_corner_touches_and_gaps_are_ignored(offset):
    lo = np.array([[0.0, 0.0, 0.0], offset])
    blocks = boxes(lo, lo + 1.0, 1.0)
    assert detect_interfaces(blocks).count == 0


def test_gap_within_tolerance_is_a_contact():
    lo = np.array([[0.0, 0.0, 0.0], [1.0 + 1e-9, 0.2, 0.0]])
    its = detect_interfaces(boxes(lo, lo + 1.0, 1.0))
    assert its.count == 1 and its.axis[0] == 0
    assert its.l1[0] == pytest.approx(0.8)


def test_overlapping_blocks_are_refused():
    lo = np.array([[0.0, 0.0, 0.0], [0.5, 0.2, 0.1]])
    with pytest.raises(ValueError, match=r"blocks overlap: block 0 .* block 1"):
        detect_interfaces(boxes(lo, lo + 1.0, 1.0))
    # a block inside another
    with pytest.raises(ValueError, match="blocks overlap"):
        detect_interfaces(boxes([[0, 0, 0], [0.4, 0.4, 0.4]], [[1, 1, 1], [0.6, 0.6, 0.6]], 1.0))


def _count_running_bond(n, nc):
    full = (nc + 1) // 2  # courses of whole blocks (even index)
    half = nc // 2
    vertical = full * (n - 1) + half * n
    horizontal = (nc - 1) * 2 * n
    return vertical, horizontal


@pytest.mark.parametrize(("n", "nc"), [(1, 1), (1, 3), (2, 2), (5, 4), (7, 9)])
def test_running_bond_half_overlaps(n, nc):
    w = running_bond_wall(n, nc, A, B, S, GAMMA)
    its = detect_interfaces(w)
    nv, nh = _count_running_bond(n, nc)
    assert np.sum(its.axis == 0) == nv
    assert np.sum(its.axis == 1) == nh
    assert np.sum(its.axis == 2) == 0
    h = its.axis == 1
    # every bed joint is a half overlap: l1 = s (along e3), l2 = b/2 (along e1)
    np.testing.assert_allclose(its.l1[h], S, rtol=1e-12)
    np.testing.assert_allclose(its.l2[h], B / 2, rtol=1e-12)
    v = its.axis == 0
    np.testing.assert_allclose(its.l1[v], A, rtol=1e-12)
    np.testing.assert_allclose(its.l2[v], S, rtol=1e-12)
    # orientation: j is above (bed joints) or to the right (head joints) of i
    ci, cj = w.centres[its.block_i], w.centres[its.block_j]
    rows = np.arange(its.count)
    assert np.all(cj[rows, its.axis] > ci[rows, its.axis])
    # bed joints between whole blocks sit halfway between the block centres (offsets
    # dy = (+-b/2, a)); under an end half block the centre is that of the half overlap
    whole = np.isclose(w.sizes[its.block_i, 0], B) & np.isclose(w.sizes[its.block_j, 0], B)
    hw = h & whole
    np.testing.assert_allclose(its.centre[hw], (ci[hw] + cj[hw]) / 2, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.abs(cj[hw, 0] - ci[hw, 0]), B / 2, rtol=1e-12)
    lo = np.maximum(w.lower[its.block_i], w.lower[its.block_j])
    hi = np.minimum(w.upper[its.block_i], w.upper[its.block_j])
    np.testing.assert_allclose(its.centre[h, 0], (lo[h, 0] + hi[h, 0]) / 2, rtol=1e-12)


def test_base_and_two_leaves_give_contacts_normal_to_e3():
    n, nc = 4, 3
    front = running_bond_wall(n, nc, A, B, S, GAMMA)
    back = running_bond_wall(n, nc, A, B, S, GAMMA, origin=(0.0, 0.0, S))
    both = Blocks.concatenate(front, back)
    wb, ib = add_base(both)
    its = detect_interfaces(wb)
    z = its.axis == 2
    # each block touches its twin over its whole face; diagonal twins share only edges
    assert z.sum() == front.count
    np.testing.assert_array_equal(its.block_j[z] - its.block_i[z], front.count)
    np.testing.assert_allclose(its.area[z], front.sizes[:, 0] * front.sizes[:, 1], rtol=1e-12)
    base = (its.block_i == ib) | (its.block_j == ib)
    assert base.sum() == 2 * n  # n whole blocks of each leaf's bottom course
    assert np.all(its.block_i[base] == ib)  # the base is below
    nv, nh = _count_running_bond(n, nc)
    assert its.count == 2 * (nv + nh) + front.count + 2 * n


def test_detection_is_independent_of_block_numbering():
    w, _ = add_base(running_bond_wall(6, 5, A, B, S, GAMMA))
    its = detect_interfaces(w)
    rng = np.random.default_rng(7)
    order = rng.permutation(w.count)
    its_p = detect_interfaces(w.permuted(order))

    def as_set(x, ids):
        return {
            (int(ids[i]), int(ids[j]), int(ax), round(l1, 12), round(l2, 12), *np.round(c, 12))
            for i, j, ax, l1, l2, c in zip(
                x.block_i, x.block_j, x.axis, x.l1, x.l2, x.centre, strict=True
            )
        }

    assert as_set(its, np.arange(w.count)) == as_set(its_p, order)
    # output sorted by (i, j)
    key = its.block_i * w.count + its.block_j
    assert np.all(np.diff(key) > 0)


def test_candidate_pairs_cover_all_touching_pairs_of_a_random_packing():
    # a dense random grid of unequal boxes on a lattice: brute force the touching pairs
    rng = np.random.default_rng(3)
    cuts = [np.concatenate([[0.0], np.cumsum(rng.uniform(0.05, 0.4, k))]) for k in (7, 5, 3)]
    g = np.stack(np.meshgrid(*[np.arange(len(c) - 1) for c in cuts], indexing="ij"), -1)
    g = g.reshape(-1, 3)
    lower = np.stack([cuts[d][g[:, d]] for d in range(3)], axis=1)
    upper = np.stack([cuts[d][g[:, d] + 1] for d in range(3)], axis=1)
    pairs = {tuple(p) for p in candidate_pairs(lower, upper, 1e-9)}
    its = detect_interfaces(boxes(lower, upper, 1.0))
    # face neighbours of a lattice: differ by one in exactly one index
    diff = np.abs(g[:, None, :] - g[None, :, :]).sum(-1)
    expected = {(a, b) for a, b in zip(*np.nonzero(np.triu(diff == 1)), strict=True)}
    found = {(min(i, j), max(i, j)) for i, j in zip(its.block_i, its.block_j, strict=True)}
    assert found == expected
    assert expected <= pairs


def test_no_contacts_gives_empty_interfaces():
    lo = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]])
    its = detect_interfaces(boxes(lo, lo + 1.0, 1.0))
    assert its.count == 0 and its.centre.shape == (0, 3)


def test_corner_points_of_many_interfaces_span_each_contact_rectangle():
    # regression: corner_points() failed to broadcast for more than one interface
    w, _ = add_base(running_bond_wall(4, 3, A, B, S, GAMMA))
    its = detect_interfaces(w)
    assert its.count > 1
    pts = its.corner_points()
    assert pts.shape == (its.count, 4, 3)
    lo = np.maximum(w.lower[its.block_i], w.lower[its.block_j])
    hi = np.minimum(w.upper[its.block_i], w.upper[its.block_j])
    rows = np.arange(its.count)
    lo[rows, its.axis] = hi[rows, its.axis] = its.centre[rows, its.axis]
    np.testing.assert_allclose(pts.min(axis=1), lo, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(pts.max(axis=1), hi, rtol=1e-12, atol=1e-15)
    # counter-clockwise about the normal: (p1 - p0) x (p3 - p0) points along +e[axis]
    normal = np.cross(pts[:, 1] - pts[:, 0], pts[:, 3] - pts[:, 0])
    np.testing.assert_allclose(normal[rows, its.axis], its.area, rtol=1e-12)
