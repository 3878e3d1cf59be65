"""The compatibility matrix H of Eqs. (A1)-(A3).

Proves: (1) the six rigid-body motions (three translations, three rotations about an arbitrary
point) of a whole running-bond wall with half blocks and a base give zero relative
displacement and zero interface forces, to round-off; (2) on the running-bond offsets
dy = (+-b/2, a) and (b, 0) the 6 x 12 interface block of H is exactly the paper's
H = [[-I, -D_i, I, D_j], [0, -I, 0, I]] of Eqs. (A2)-(A3), once our local rows
[y1, y2, n] are put back in global order; (3) for any interface centre (half blocks, a base
slab) H q is the relative motion of the two blocks' material points at the interface centre.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from masonry_dem.assembly.compatibility import compatibility_matrix
from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.geometry.builders import add_base, boxes, running_bond_wall
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.model import InterfaceMaterial, Model, Support

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0
MAT = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)
POINT = np.array([0.37, -1.3, 0.81])  # an arbitrary centre of rotation


def rigid_motion(centres: np.ndarray, u0, w, point=POINT) -> np.ndarray:
    """(n, 6) block DOFs of the rigid motion u(y) = u0 + w x (y - point), rotation w."""
    u0, w = np.asarray(u0, float), np.asarray(w, float)
    q = np.empty((centres.shape[0], 6))
    q[:, :3] = u0 + np.cross(w, centres - point)
    q[:, 3:] = w
    return q


def _wall_with_base(n=6, nc=5):
    w, ib = add_base(running_bond_wall(n, nc, A, B, S, GAMMA))
    return w, ib


MODES = {
    "u1": ([1e-3, 0, 0], [0, 0, 0]),
    "u2": ([0, 1e-3, 0], [0, 0, 0]),
    "u3": ([0, 0, 1e-3], [0, 0, 0]),
    "w1": ([0, 0, 0], [1e-3, 0, 0]),
    "w2": ([0, 0, 0], [0, 1e-3, 0]),
    "w3": ([0, 0, 0], [0, 0, 1e-3]),
    "all": ([2e-3, -1e-3, 3e-3], [-1e-3, 2e-3, 0.5e-3]),
}


@pytest.mark.parametrize("mode", list(MODES))
def test_rigid_body_motions_give_zero_relative_displacement_and_forces(mode):
    blocks, ib = _wall_with_base()
    assert np.any(np.isclose(blocks.sizes[:, 0], B / 2))  # half blocks are present
    # no support: the model would be a mechanism, so assemble H and Kbar on the interfaces
    its = detect_interfaces(blocks)
    H = compatibility_matrix(blocks, its)
    q = rigid_motion(blocks.centres, *MODES[mode])
    scale = np.abs(q).max()
    d = (H @ q.ravel()).reshape(-1, 6)
    assert np.abs(d).max() <= 1e-13 * scale
    # the interface forces of the supported model vanish too, as does K q on all DOFs
    model = Model.build(blocks, MAT, [Support([ib])])
    asm = Assembly.of(model)
    actions = asm.kbar * asm.relative_displacements(q.ravel())
    force_scale = asm.kbar.max() * scale
    assert np.abs(actions).max() <= 1e-13 * force_scale
    K_all = (asm.H.T @ asm.H.multiply(asm.kbar.reshape(-1, 1))).tocsr()
    assert np.abs(K_all @ q.ravel()).max() <= 1e-12 * force_scale


def test_rigid_body_modes_span_the_null_space_of_the_unsupported_stiffness():
    blocks, _ = _wall_with_base(3, 3)
    its = detect_interfaces(blocks)
    H = compatibility_matrix(blocks, its).toarray()
    # exactly six zero singular values: the assembly is connected, only rigid motions are free
    sv = np.linalg.svd(H, compute_uv=False)
    rank = np.sum(sv > 1e-10 * sv.max())
    assert H.shape[1] - rank == 6


@settings(max_examples=30, deadline=None, derandomize=True)
@given(
    n=st.integers(1, 6),
    nc=st.integers(1, 6),
    dims=st.tuples(st.floats(0.02, 1.0), st.floats(0.02, 1.0), st.floats(0.02, 1.0)),
    u0=st.tuples(*(st.floats(-1, 1, allow_subnormal=False) for _ in range(3))),
    w=st.tuples(*(st.floats(-1, 1, allow_subnormal=False) for _ in range(3))),
    point=st.tuples(*(st.floats(-10, 10, allow_subnormal=False) for _ in range(3))),
)
def test_rigid_body_motions_any_running_bond_wall(n, nc, dims, u0, w, point):
    a, b, s = dims
    blocks, _ = add_base(running_bond_wall(n, nc, a, b, s, GAMMA))
    its = detect_interfaces(blocks)
    H = compatibility_matrix(blocks, its)
    q = rigid_motion(blocks.centres, u0, w, np.asarray(point))
    # round-off of w x r scales with |w| times the arms, even when u0 cancels most of q
    scale = max(np.abs(q).max(), np.abs(w).max() * 10.0, 1e-12)
    assert np.abs(H @ q.ravel()).max() <= 1e-12 * scale


# ------------------------------------------------------------------ Eqs. (A1)-(A3)
def paper_H(dy1: float, dy2: float) -> np.ndarray:
    """The paper's 6 x 12 H of Eqs. (A2)-(A3), global row order (d1 d2 d3 delta1 delta2
    delta3), columns (q_i, q_j)."""
    Di = 0.5 * np.array([[0, 0, -dy2], [0, 0, dy1], [dy2, -dy1, 0]])
    Dj = 0.5 * np.array([[0, 0, dy2], [0, 0, -dy1], [-dy2, dy1, 0]])
    eye, zero = np.eye(3), np.zeros((3, 3))
    return np.block([[-eye, -Di, eye, Dj], [zero, -eye, zero, eye]])


def paper_A1(q_i: np.ndarray, q_j: np.ndarray, dy1: float, dy2: float) -> np.ndarray:
    """Eq. (A1) term by term (with the slip of its last line corrected: delta3 = w3j - w3i)."""
    u1i, u2i, u3i, w1i, w2i, w3i = q_i
    u1j, u2j, u3j, w1j, w2j, w3j = q_j
    return np.array(
        [
            u1j - u1i + dy2 * (w3j + w3i) / 2,
            u2j - u2i - dy1 * (w3j + w3i) / 2,
            u3j - u3i + dy1 * (w2j + w2i) / 2 - dy2 * (w1j + w1i) / 2,
            w1j - w1i,
            w2j - w2i,
            w3j - w3i,
        ]
    )


def _global_rows(axis: int) -> np.ndarray:
    """Rows of our local H (order [y1, y2, n]) holding the global components 1, 2, 3."""
    pos = (np.arange(3) - axis - 1) % 3
    return np.concatenate([pos, 3 + pos])


@pytest.mark.parametrize(
    ("dy", "axis"),
    [((B / 2, A), 1), ((-B / 2, A), 1), ((B, 0.0), 0)],
    ids=["dy=(b/2,a)", "dy=(-b/2,a)", "dy=(b,0)"],
)
def test_H_matches_eq_A1_A3_on_running_bond_offsets(dy, axis):
    dy1, dy2 = dy
    centres = np.array([[0.0, 0.0, 0.0], [dy1, dy2, 0.0]])
    blocks = boxes(centres - [B / 2, A / 2, S / 2], centres + [B / 2, A / 2, S / 2], GAMMA)
    its = detect_interfaces(blocks)
    assert its.count == 1 and its.axis[0] == axis
    assert (its.block_i[0], its.block_j[0]) == (0, 1)  # j is above / to the right of i
    H = compatibility_matrix(blocks, its).toarray()
    assert H.shape == (6, 12)
    H_global = H[_global_rows(axis)]
    np.testing.assert_allclose(H_global, paper_H(dy1, dy2), rtol=1e-12, atol=1e-15)
    # and term by term on random block motions
    rng = np.random.default_rng(11)
    for _ in range(5):
        q = rng.normal(size=12)
        np.testing.assert_allclose(
            H_global @ q, paper_A1(q[:6], q[6:], dy1, dy2), rtol=1e-12, atol=1e-15
        )


def test_H_in_a_wall_matches_eq_A1_block_by_block():
    blocks = running_bond_wall(5, 4, A, B, S, GAMMA)
    its = detect_interfaces(blocks)
    H = compatibility_matrix(blocks, its).toarray()
    whole = np.isclose(blocks.sizes[:, 0], B)
    checked = 0
    for k in range(its.count):
        i, j = its.block_i[k], its.block_j[k]
        if not (whole[i] and whole[j]):
            continue  # end half blocks: centre offset is not the interface midpoint
        dy1, dy2, dy3 = blocks.centres[j] - blocks.centres[i]
        assert dy3 == 0.0
        sub = H[6 * k : 6 * k + 6][_global_rows(its.axis[k])]
        expected = paper_H(dy1, dy2)
        np.testing.assert_allclose(sub[:, 6 * i : 6 * i + 6], expected[:, :6], atol=1e-15)
        np.testing.assert_allclose(sub[:, 6 * j : 6 * j + 6], expected[:, 6:], atol=1e-15)
        others = np.delete(sub, np.r_[6 * i : 6 * i + 6, 6 * j : 6 * j + 6], axis=1)
        assert not others.any()
        checked += 1
    assert checked > 10


def test_H_is_the_relative_motion_at_the_interface_centre_for_any_offset():
    # half blocks next to whole blocks and a base slab: centres are not midpoints
    blocks, _ = _wall_with_base(4, 3)
    its = detect_interfaces(blocks)
    H = compatibility_matrix(blocks, its)
    rng = np.random.default_rng(5)
    q = rng.normal(size=(blocks.count, 6))
    d = (H @ q.ravel()).reshape(-1, 6)
    i, j, c = its.block_i, its.block_j, its.centre
    u_at_c_j = q[j, :3] + np.cross(q[j, 3:], c - blocks.centres[j])
    u_at_c_i = q[i, :3] + np.cross(q[i, 3:], c - blocks.centres[i])
    rel = np.concatenate([u_at_c_j - u_at_c_i, q[j, 3:] - q[i, 3:]], axis=1)
    axes = its.local_axes
    rows = np.arange(its.count)[:, None]
    expected = np.concatenate([rel[rows, axes], rel[rows, 3 + axes]], axis=1)
    np.testing.assert_allclose(d, expected, rtol=1e-12, atol=1e-14)


def test_H_has_an_explicit_shape_and_twelve_or_fewer_entries_per_row_pair():
    # the last block touches nothing: H must still have 6 n columns
    lo = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 0.0, 0.0]])
    blocks = boxes(lo, lo + 1.0, 1.0)
    its = detect_interfaces(blocks)
    H = compatibility_matrix(blocks, its)
    assert H.shape == (6 * its.count, 6 * blocks.count) == (6, 18)
    assert H.format == "csr"
    # translations rows: 2 unit entries + 2 x 2 arm entries at most; rotation rows: 2 entries
    nnz_rows = np.diff(H.indptr)
    assert nnz_rows[:3].max() <= 6 and np.all(nnz_rows[3:] == 2)
