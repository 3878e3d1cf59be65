"""Axis-aligned box blocks stored as arrays, one row per block.

Global axes: e1 along the wall, e2 vertical (up), e3 out of plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from masonry_dem._arrays import FloatArray, Rows
from masonry_dem._validation import as_finite_array, require_positive


@dataclass(frozen=True)
class Blocks(Rows):
    """Rigid box blocks (``count``, ``len`` and ``subset`` of :class:`~masonry_dem._arrays.Rows`).

    centres: (n, 3) block centres [m]; sizes: (n, 3) edge lengths along e1, e2, e3 [m];
    unit_weight: (n,) weight per unit volume [N/m^3].
    """

    centres: FloatArray
    sizes: FloatArray
    unit_weight: FloatArray

    def __post_init__(self) -> None:
        centres = as_finite_array("centres", self.centres, (None, 3))
        n = centres.shape[0]
        if n == 0:
            raise ValueError("blocks: an assembly needs at least one block, got 0")
        sizes = as_finite_array("sizes", self.sizes, (n, 3))
        require_positive("sizes", sizes)
        gamma = as_finite_array("unit_weight", self.unit_weight)
        if gamma.ndim > 1 or gamma.size not in (1, n):
            # checked here: np.broadcast_to's own error does not name the field
            raise ValueError(
                f"unit_weight must be a scalar or have shape ({n},), got {gamma.shape}"
            )
        gamma = np.broadcast_to(gamma.reshape(-1) if gamma.ndim else gamma, (n,))
        require_positive("unit_weight", gamma, strict=False)
        object.__setattr__(self, "centres", centres)
        object.__setattr__(self, "sizes", sizes)
        object.__setattr__(self, "unit_weight", gamma.copy())
        for arr in (self.centres, self.sizes, self.unit_weight):
            arr.flags.writeable = False

    @classmethod
    def from_boxes(cls, lower: ArrayLike, upper: ArrayLike, unit_weight: ArrayLike) -> Blocks:
        """Blocks from lower and upper corners, each (n, 3)."""
        lo = as_finite_array("lower", lower, (None, 3))
        hi = as_finite_array("upper", upper, (lo.shape[0], 3))
        flat = hi <= lo
        if flat.any():  # named by the corners given, not by the sizes they make
            k, axis = (int(i) for i in np.argwhere(flat)[0])
            raise ValueError(
                f"upper[{k}] must lie above lower[{k}] along e{axis + 1} (a box of positive "
                f"size): got lower[{k}] = {lo[k].tolist()}, upper[{k}] = {hi[k].tolist()}"
            )
        return cls((lo + hi) / 2, hi - lo, as_finite_array("unit_weight", unit_weight))

    @property
    def lower(self) -> FloatArray:
        return self.centres - self.sizes / 2

    @property
    def upper(self) -> FloatArray:
        return self.centres + self.sizes / 2

    @property
    def volumes(self) -> FloatArray:
        return np.asarray(np.prod(self.sizes, axis=1), dtype=np.float64)

    @property
    def weights(self) -> FloatArray:
        return self.volumes * self.unit_weight

    def permuted(self, order: ArrayLike) -> Blocks:
        """The same blocks in another order (for numbering-independence checks)."""
        return self.subset(np.asarray(order))

    @staticmethod
    def concatenate(*parts: Blocks) -> Blocks:
        return Blocks(
            np.vstack([p.centres for p in parts]),
            np.vstack([p.sizes for p in parts]),
            np.concatenate([p.unit_weight for p in parts]),
        )

    def corner_points(self) -> FloatArray:
        """(n, 8, 3) corners in VTK hexahedron order."""
        signs = np.array(
            [
                [-1, -1, -1],
                [1, -1, -1],
                [1, 1, -1],
                [-1, 1, -1],
                [-1, -1, 1],
                [1, -1, 1],
                [1, 1, 1],
                [-1, 1, 1],
            ],
            dtype=float,
        )
        return self.centres[:, None, :] + 0.5 * signs[None, :, :] * self.sizes[:, None, :]
