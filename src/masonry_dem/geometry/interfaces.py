"""Contact detection between axis-aligned box faces, and the interface geometry.

Every interface joins block ``i`` (lower coordinate along the normal) to block ``j``. Its local
axes are y1 = e[(n+1)%3], y2 = e[(n+2)%3], y3 = e[n] (right-handed), with sides l1 along y1
and l2 along y2. Local action order everywhere: [f1, f2, fn, m1, m2, m3].
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from masonry_dem._arrays import FloatArray, IndexArray, Rows
from masonry_dem._validation import frozen, positive_scalar
from masonry_dem.geometry.blocks import Blocks


@dataclass(frozen=True)
class Interfaces(Rows):
    """Interfaces as arrays, one row per interface (``count``, ``len`` and ``subset`` of
    :class:`~masonry_dem._arrays.Rows`).

    block_i, block_j: (m,) block indices; axis: (m,) global normal axis 0/1/2;
    centre: (m, 3); l1, l2: (m,) sides along the local axes y1, y2.
    """

    block_i: IndexArray
    block_j: IndexArray
    axis: IndexArray
    centre: FloatArray
    l1: FloatArray
    l2: FloatArray

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, frozen(getattr(self, f.name)))

    @property
    def area(self) -> FloatArray:
        return self.l1 * self.l2

    @property
    def inertia1(self) -> FloatArray:
        """Second moment about y1 (bending m1; stresses vary along y2)."""
        return self.l1 * self.l2**3 / 12.0

    @property
    def inertia2(self) -> FloatArray:
        """Second moment about y2 (bending m2; stresses vary along y1)."""
        return self.l2 * self.l1**3 / 12.0

    @property
    def polar(self) -> FloatArray:
        return self.inertia1 + self.inertia2

    @property
    def local_axes(self) -> IndexArray:
        """(m, 3) global axis index of y1, y2, y3."""
        n = self.axis
        return np.stack([(n + 1) % 3, (n + 2) % 3, n], axis=1)

    def corner_points(self) -> FloatArray:
        """(m, 4, 3) corners of each interface rectangle, counter-clockwise about y3."""
        axes = self.local_axes
        rows = np.arange(self.count)
        signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
        pts = np.repeat(self.centre[:, None, :], 4, axis=1)
        # all three axes indexed by arrays, (m, 1) x (1, 4) x (m, 1) -> (m, 4): a slice
        # between advanced indices would move the indexed shape to the front
        corner = np.arange(4)[None, :]
        pts[rows[:, None], corner, axes[:, 0:1]] += 0.5 * signs[None, :, 0] * self.l1[:, None]
        pts[rows[:, None], corner, axes[:, 1:2]] += 0.5 * signs[None, :, 1] * self.l2[:, None]
        return pts


def subdivide_interfaces(interfaces: Interfaces, n1: int, n2: int) -> Interfaces:
    """Cut every interface into an ``n1`` x ``n2`` grid of equal rectangles.

    n1 pieces along y1, n2 along y2, each an interface of its own between the same two
    blocks.

    Why: the interface law rocks a joint about its centre (the bending moment is clipped at
    fixed normal force, the normal stiffness kept), so a rocking joint does not lift the block
    it carries. A rigid block on a dry joint rocks about the compressed edge and lifts. Cut
    into pieces, a joint opens piece by piece: the detached pieces carry nothing and the
    joint turns about its last compressed piece, within 1 / (2 n) of the side from the edge.
    The elastic stiffness is the same matrix (the pieces' areas and second moments about the
    joint centre sum to the joint's), and so is the strength of the joint in shear and
    bending (``mu |fn|`` and ``|fn| l / 2``); the torsion capacity grows (the pieces' shear forces
    act as a couple, as the four corner points of a contact-dynamics code do), and with a
    tensile strength each piece cracks on its own. ``docs/peer_wall.md`` measures what it
    changes: the in-plane peer wall goes from 0.546 to 0.579, inside LMGC90's bracket; on the
    out-of-plane and mortar validation walls it moves lambda away from the tests, so it is a
    setting, not the default.

    Pieces of interface r are rows ``r * n1 * n2`` to ``(r + 1) * n1 * n2 - 1`` (so the
    per-interface properties of the result are ``np.repeat(props, n1 * n2)``).

    Parameters
    ----------
    interfaces : Interfaces
        The interfaces to cut (from :func:`detect_interfaces`).
    n1, n2 : int
        Pieces along y1 and along y2, each a whole number >= 1.

    Returns
    -------
    Interfaces
        ``interfaces.count * n1 * n2`` pieces, those of interface r in rows ``r * n1 * n2`` to
        ``(r + 1) * n1 * n2 - 1``.

    Raises
    ------
    ValueError
        If ``n1`` or ``n2`` is not a whole number >= 1.

    Examples
    --------
    >>> import masonry_dem as md
    >>> joints = md.detect_interfaces(md.running_bond_wall(4, 3, 0.1, 0.2, 0.1, 18e3))
    >>> pieces = md.subdivide_interfaces(joints, 2, 1)
    >>> joints.count, pieces.count
    (26, 52)
    """
    counts = []
    for name, value in (("n1", n1), ("n2", n2)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name} must be a whole number >= 1, got {value!r}")
        counts.append(int(value))
    k1, k2 = counts
    k = k1 * k2
    m = interfaces.count
    # offsets of the piece centres in units of the sides, piece p = a * k2 + b
    f1 = np.repeat((np.arange(k1) + 0.5) / k1 - 0.5, k2)  # (k,)
    f2 = np.tile((np.arange(k2) + 0.5) / k2 - 0.5, k1)
    axes = interfaces.local_axes
    rows = np.arange(m)[:, None]
    piece = np.arange(k)[None, :]
    centre = np.repeat(interfaces.centre[:, None, :], k, axis=1)
    centre[rows, piece, axes[:, 0:1]] += f1[None, :] * interfaces.l1[:, None]
    centre[rows, piece, axes[:, 1:2]] += f2[None, :] * interfaces.l2[:, None]
    return Interfaces(
        np.repeat(interfaces.block_i, k),
        np.repeat(interfaces.block_j, k),
        np.repeat(interfaces.axis, k),
        centre.reshape(m * k, 3),
        np.repeat(interfaces.l1 / k1, k),
        np.repeat(interfaces.l2 / k2, k),
    )


def _pairs_sharing_keys(keys: IndexArray, owners: IndexArray) -> IndexArray:
    """All pairs (a, b), a < b, of owners that share a key; (k, 2), unique."""
    order = np.argsort(keys, kind="stable")
    keys, owners = keys[order], owners[order]
    end_of = np.searchsorted(keys, keys, side="right")
    pos = np.arange(keys.size)
    later = end_of - pos - 1  # partners after this entry in the same group
    first = np.repeat(pos, later)
    offset = np.arange(first.size) - np.repeat(np.cumsum(later) - later, later)
    second = first + 1 + offset
    a, b = owners[first], owners[second]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    keep = lo != hi
    lo, hi = lo[keep], hi[keep]
    if lo.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    # deduplicated on one int64 code per pair by sort + mask, the cheapest way numpy offers
    # (docs/history/measurements.md); pairs come out sorted lexicographically by (a, b)
    n = np.int64(hi.max()) + 1
    code = np.sort(lo.astype(np.int64) * n + hi)
    code = code[np.concatenate(([True], code[1:] != code[:-1]))]
    return np.stack([code // n, code % n], axis=1)


def candidate_pairs(lower: FloatArray, upper: FloatArray, pad: float) -> IndexArray:
    """Pairs of boxes whose padded bounding boxes may touch, by uniform grid hashing.

    Near-linear in the number of boxes for walls of similar blocks; a large box (a base slab)
    simply covers more cells.
    """
    n = lower.shape[0]
    extent = upper - lower
    cell = np.maximum(np.median(extent, axis=0), pad * 10)
    origin = lower.min(axis=0) - 2 * pad
    lo_cell = np.floor((lower - pad - origin) / cell).astype(np.int64)
    hi_cell = np.floor((upper + pad - origin) / cell).astype(np.int64)
    span = hi_cell - lo_cell + 1
    ncells = hi_cell.max(axis=0) + 1
    counts = np.prod(span, axis=1)
    owner = np.repeat(np.arange(n), counts)
    local = np.arange(owner.size) - np.repeat(np.cumsum(counts) - counts, counts)
    sp = span[owner]
    c0 = lo_cell[owner, 0] + local % sp[:, 0]
    c1 = lo_cell[owner, 1] + (local // sp[:, 0]) % sp[:, 1]
    c2 = lo_cell[owner, 2] + local // (sp[:, 0] * sp[:, 1])
    key = (c2 * ncells[1] + c1) * ncells[0] + c0
    return _pairs_sharing_keys(key, owner)


def detect_interfaces(blocks: Blocks, tol: float | None = None) -> Interfaces:
    """Find every face-to-face contact of positive area between the blocks.

    Parameters
    ----------
    blocks : Blocks
        The assembly.
    tol : float, optional
        Gap or overlap [m] still taken as contact, >= 0 (None: 10^-6 times the median block
        size).

    Returns
    -------
    Interfaces
        One row per contact, block ``i`` on the lower side along the normal, sorted by
        (i, j).

    Raises
    ------
    ValueError
        If two blocks overlap (share a volume larger than ``tol`` in every axis), or ``tol``
        is negative.

    Examples
    --------
    >>> import masonry_dem as md
    >>> joints = md.detect_interfaces(md.running_bond_wall(4, 3, 0.1, 0.2, 0.1, 18e3))
    >>> joints.count, joints.axis.tolist()[:5]  # axis 1: a bed joint, 0: a head joint
    (26, [0, 1, 1, 0, 1])
    """
    size_scale = float(np.median(blocks.sizes))
    # a negative tolerance failed inside numpy ("repeats may not contain negative values")
    tol = 1e-6 * size_scale if tol is None else positive_scalar("tol", tol, strict=False)
    lower, upper = blocks.lower, blocks.upper
    pairs = candidate_pairs(lower, upper, tol)
    if pairs.size == 0:
        return _empty_interfaces()
    a, b = pairs[:, 0], pairs[:, 1]
    overlap = np.minimum(upper[a], upper[b]) - np.maximum(lower[a], lower[b])  # (k, 3)
    solid = overlap > tol
    n_solid = solid.sum(axis=1)
    if np.any(n_solid == 3):
        k = int(np.argmax(n_solid == 3))
        raise ValueError(
            f"blocks overlap: block {a[k]} (centre {blocks.centres[a[k]].tolist()}) and block "
            f"{b[k]} (centre {blocks.centres[b[k]].tolist()}) share a volume of "
            f"{np.prod(overlap[k]):.3g} m^3"
        )
    touching = (n_solid == 2) & (np.abs(overlap).min(axis=1) <= tol)
    a, b, overlap = a[touching], b[touching], overlap[touching]
    axis = np.argmin(overlap, axis=1)  # the thin direction is the normal
    rows = np.arange(a.size)
    # block i is the one on the lower side along the normal
    swap = blocks.centres[a, axis] > blocks.centres[b, axis]
    i = np.where(swap, b, a)
    j = np.where(swap, a, b)
    lo = np.maximum(lower[i], lower[j])
    hi = np.minimum(upper[i], upper[j])
    centre = (lo + hi) / 2
    centre[rows, axis] = upper[i, axis]  # the contact plane
    t1, t2 = (axis + 1) % 3, (axis + 2) % 3
    l1 = (hi - lo)[rows, t1]
    l2 = (hi - lo)[rows, t2]
    order = np.lexsort((j, i))
    return Interfaces(i[order], j[order], axis[order], centre[order], l1[order], l2[order])


def _empty_interfaces() -> Interfaces:
    z = np.zeros(0)
    zi = np.zeros(0, dtype=np.int64)
    return Interfaces(zi, zi, zi, np.zeros((0, 3)), z, z)
