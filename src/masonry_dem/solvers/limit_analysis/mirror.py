"""A mirror plane of the model, and the velocities that vanish on its symmetric mechanisms.

Why the associative problem may be solved on the symmetric mechanisms only. Let a
reflection R (through a plane normal to a global axis k) map the model onto itself: every
block, interface, support and load onto itself. R maps an admissible mechanism onto an
admissible one doing the same work (it maps each interface's corners onto its corners and
each friction cone onto itself), and the admissible mechanisms form a convex set, so the
mean of a mechanism and its mirror image is admissible with the same multiplier: an optimal
mechanism exists among the symmetric ones, whose velocities have ``u_k = 0`` and the
rotations about the two other axes ``w_j = 0`` (a rotation is a pseudo-vector: R keeps
``w_k`` and flips the others). A wall of one leaf loaded in its own plane is such a model:
its problem is the plane one, 3 velocities a block instead of 6.

The reduction is a guess that the solver certifies: any restricted mechanism is admissible
in the whole problem (an upper bound in any case), and ``normal_ipm`` checks the lower bound
against the equilibrium of every DOF, the dropped ones included (the forces of a symmetric
solution balance there by symmetry, to rounding).

The same argument holds for a reflection that swaps blocks in pairs (``mirror_pairs``): a wall
pushed out of its plane and symmetric about a vertical plane across it (the same bond, the same
supports at both ends) maps onto itself with block b and its image R(b) exchanged. Its
symmetric mechanisms have ``u_R(b) = S u_b`` (S: +1 on the DOFs R keeps, -1 on those it flips)
and, on the blocks the plane cuts through their centre, the antisymmetric DOFs at zero: about
half the velocities.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from masonry_dem.model import Model

from .formulation import Problem

#: relative tolerance of the plane's detection (of the median block size; of the loads)
TOLERANCE = 1e-9


def mirror_dofs(model: Model) -> np.ndarray | None:
    """(6n,) bool: the DOFs that vanish on the mechanisms symmetric about a plane normal to a
    global axis that holds every block centre and every interface centre, with no interface
    normal to that axis and no load on those DOFs; None where the model has no such plane."""
    blocks, its = model.blocks, model.interfaces
    if blocks.count == 0 or its.count == 0:
        return None
    length = float(np.median(blocks.sizes))
    forces = np.abs(np.concatenate([model.dead.reshape(-1), model.live.reshape(-1)]))
    force = float(forces.max(initial=0.0))
    for k in range(3):
        plane = float(blocks.centres[0, k])
        off = max(
            float(np.abs(blocks.centres[:, k] - plane).max()),
            float(np.abs(its.centre[:, k] - plane).max()),
        )
        if off > TOLERANCE * length or np.any(its.axis == k):
            continue
        anti = np.zeros((blocks.count, 6), dtype=bool)
        anti[:, k] = True
        anti[:, 3 + (k + 1) % 3] = True
        anti[:, 3 + (k + 2) % 3] = True
        loaded = max(
            float(np.abs(model.dead[anti]).max(initial=0.0)),
            float(np.abs(model.live[anti]).max(initial=0.0)),
        )
        if loaded > TOLERANCE * force:
            continue
        return anti.reshape(-1)
    return None


def reflection_signs(k: int) -> np.ndarray:
    """(6,): the sign a reflection through a plane normal to axis k gives each DOF: -1 on the
    translation along k and on the rotations about the two other axes (pseudo-vectors)."""
    signs = np.ones(6)
    signs[k] = -1.0
    signs[3 + (k + 1) % 3] = -1.0
    signs[3 + (k + 2) % 3] = -1.0
    return signs


def mirror_pairs(problem: Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(image of every block, the DOFs' signs, image of every interface) of a reflection through a plane normal to a
    global axis (at the middle of the blocks' extent) that maps the model onto itself and
    swaps at least one pair of blocks: every block onto one of the same size, every
    interface onto one of the same rectangle and friction, the held DOFs, the loads and the
    tensile strengths (``problem.rhs``, ``problem.live``) onto their images; None where there
    is no such plane. A plane that holds every block is ``mirror_dofs``'s."""
    from scipy.spatial import cKDTree

    model = problem.model
    blocks, its = model.blocks, model.interfaces
    n = blocks.count
    if n < 2 or its.count == 0:
        return None
    length = float(np.median(blocks.sizes))
    tol = 1e-6 * length
    tree = cKDTree(blocks.centres)
    full = np.zeros(model.n_dofs)
    for k in range(3):
        plane = 0.5 * (float(blocks.lower[:, k].min()) + float(blocks.upper[:, k].max()))
        image = blocks.centres.copy()
        image[:, k] = 2.0 * plane - image[:, k]
        dist, perm = tree.query(image)
        if float(dist.max()) > tol or np.array_equal(perm, np.arange(n)):
            continue
        if not np.array_equal(perm[perm], np.arange(n)):
            continue
        if float(np.abs(blocks.sizes[perm] - blocks.sizes).max()) > tol:
            continue
        if not np.array_equal(model.fixed[perm], model.fixed):
            continue
        signs = reflection_signs(k)
        same = True
        for vector in (problem.rhs, problem.live):
            full[:] = 0.0
            full[problem.free] = vector / problem.row_scale
            v = full.reshape(n, 6)
            scale = max(float(np.abs(v).max(initial=0.0)), 1e-300)
            if float(np.abs(v[perm] - v * signs).max()) > TOLERANCE * 1e3 * scale:
                same = False
                break
        if not same:
            continue
        image_interfaces = _interfaces_map(model, perm, tol)
        if image_interfaces is None:
            continue
        return perm, signs, image_interfaces
    return None


def _interfaces_map(model: Model, perm: np.ndarray, tol: float) -> np.ndarray | None:
    """The image of every interface (the interface between its blocks' images), where each
    is one of the same rectangle, friction and tensile strength; else None."""
    its = model.interfaces
    n = model.blocks.count
    lo = np.minimum(its.block_i, its.block_j).astype(np.int64)
    hi = np.maximum(its.block_i, its.block_j).astype(np.int64)
    keys = lo * n + hi
    order = np.argsort(keys)
    pi, pj = perm[its.block_i], perm[its.block_j]
    image_keys = np.minimum(pi, pj).astype(np.int64) * n + np.maximum(pi, pj)
    at = np.searchsorted(keys[order], image_keys)
    if np.any(at >= keys.size):
        return None
    found = order[at]
    if not np.array_equal(keys[found], image_keys) or np.unique(keys).size != keys.size:
        return None  # two interfaces between the same blocks: not told apart here
    dims = np.stack([its.l1, its.l2], axis=1)
    if float(np.abs(dims[found] - dims).max()) > tol:
        return None
    ft = np.broadcast_to(np.asarray(model.tensile_strength, dtype=float), (its.count,))
    for values in (np.broadcast_to(model.friction, (its.count,)), its.area, ft):
        values = np.asarray(values, dtype=float)
        if not np.allclose(values[found], values, rtol=1e-9, atol=0.0):
            return None
    return found


def symmetric_basis(
    problem: Problem, pairs: tuple[np.ndarray, np.ndarray, np.ndarray]
) -> tuple[sparse.csr_matrix, np.ndarray, np.ndarray]:
    """The symmetric mechanisms of ``mirror_pairs``'s reflection as ``u_free = P v``: P
    (free DOFs x kept velocities), the DOF each kept velocity is (a block of each pair and its
    6 DOFs; of a block the plane maps onto itself, the DOFs the reflection keeps), and the
    column of P of every DOF of the model (-1 for none; a block's image shares its
    columns)."""
    perm, signs = pairs[0], pairs[1]
    model = problem.model
    n = model.blocks.count
    free_mask = np.asarray(problem.free, dtype=bool).reshape(n, 6)
    rep = np.minimum(np.arange(n), perm)
    keep = free_mask.copy()
    keep &= (rep == np.arange(n))[:, None]  # the first block of each pair
    on_plane = perm == np.arange(n)
    keep[on_plane] &= signs[None, :] > 0  # the plane's blocks: the kept DOFs
    kept = np.flatnonzero(keep.reshape(-1))
    column = np.full(6 * n, -1, dtype=np.int64)
    column[kept] = np.arange(kept.size)
    # every DOF: its pair's first block's column, with the sign of the reflection
    dofs = np.arange(6 * n)
    source = 6 * rep[dofs // 6] + dofs % 6
    columns = column[source]
    sign = np.where(rep[dofs // 6] == dofs // 6, 1.0, signs[dofs % 6])
    free = np.flatnonzero(problem.free)
    rows = np.flatnonzero(columns[free] >= 0)
    P = sparse.csr_matrix(
        (sign[free[rows]], (rows, columns[free[rows]])), shape=(free.size, kept.size)
    )
    return P, kept, columns
