"""The compatibility matrix H of Eqs. (A1)-(A3): interface relative displacements from block DOFs.

For an interface with centre c between blocks i and j (centres y_i, y_j), the relative
displacement of j with respect to i at c is d = u_j + w_j x (c - y_j) - u_i - w_i x (c - y_i)
and the relative rotation delta = w_j - w_i. With c halfway between the centres this is exactly
Eq. (A1) (arms -dy/2 and dy/2); taking the arms to the true interface centre keeps it exact for
any centre offset (a base slab, blocks of unequal sizes). Rows are in each interface's local
order [d1, d2, dn, delta1, delta2, delta3].
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.interfaces import Interfaces

# structural non-zeros of the skew matrix [r]x: (row, col, component of r, sign)
_SKEW = np.array(
    [(0, 1, 2, -1), (0, 2, 1, 1), (1, 0, 2, 1), (1, 2, 0, -1), (2, 0, 1, -1), (2, 1, 0, 1)]
)


def compatibility_matrix(blocks: Blocks, interfaces: Interfaces) -> sparse.csr_matrix:
    """H, shape (6m, 6n), built in one sparse call. d_local = H q."""
    m, n = interfaces.count, blocks.count
    i, j = interfaces.block_i, interfaces.block_j
    r_i = interfaces.centre - blocks.centres[i]
    r_j = interfaces.centre - blocks.centres[j]
    # local row of each global component a: y1 = e[(n+1)%3] -> 0, y2 -> 1, normal -> 2
    pos = (np.arange(3)[None, :] - interfaces.axis[:, None] - 1) % 3  # (m, 3)
    base_row = 6 * np.arange(m)[:, None]

    rows, cols, vals = [], [], []
    # translations: +u_j - u_i on rows pos[a]; rotations: +w_j - w_i on rows 3 + pos[a]
    for offset in (0, 3):
        for blk, sign in ((j, 1.0), (i, -1.0)):
            rows.append(base_row + offset + pos)
            cols.append(6 * blk[:, None] + offset + np.arange(3)[None, :])
            vals.append(np.full((m, 3), sign))
    # rotation terms in translations: -[r_j]x w_j + [r_i]x w_i
    a, b, comp, sgn = _SKEW.T
    for blk, arm, sign in ((j, r_j, -1.0), (i, r_i, 1.0)):
        rows.append(base_row + pos[:, a])
        cols.append(6 * blk[:, None] + 3 + b[None, :])
        vals.append(sign * sgn[None, :] * arm[:, comp])
    rows_a = np.concatenate([r.ravel() for r in rows])
    cols_a = np.concatenate([c.ravel() for c in cols])
    vals_a = np.concatenate([v.ravel() for v in vals])
    H = sparse.csr_matrix((vals_a, (rows_a, cols_a)), shape=(6 * m, 6 * n))
    H.eliminate_zeros()
    return H
