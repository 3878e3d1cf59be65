"""Axis-aligned box blocks stored as arrays, one row per block.

Global axes: e1 along the wall, e2 vertical (up), e3 out of plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from masonry_dem._arrays import FloatArray, Rows
from masonry_dem._docstrings import fill
from masonry_dem._validation import as_finite_array, require_positive

#: the text :meth:`Blocks.from_boxes` and :func:`~masonry_dem.geometry.builders.boxes` share
#: (:func:`masonry_dem._docstrings.fill`)
DOCS: dict[str, str] = {
    "boxes": """
        Parameters
        ----------
        lower, upper : array_like, shape (n, 3)
            Lower and upper corners [m]; ``upper`` above ``lower`` along every axis.
        unit_weight : float or array_like, shape (n,)
            Weight per unit volume [N/m^3], >= 0.

        Returns
        -------
        Blocks
            The boxes, in the order given.
    """,
}


@fill(DOCS)
@dataclass(frozen=True)
class Blocks(Rows):
    """Rigid box blocks, one row per block.

    ``count``, ``len`` and ``subset`` come from :class:`~masonry_dem._arrays.Rows`. The arrays
    are checked and frozen (read-only) at construction.

    Parameters
    ----------
    centres : array_like, shape (n, 3)
        Block centres [m], n >= 1.
    sizes : array_like, shape (n, 3)
        Edge lengths along e1, e2, e3 [m], each > 0.
    unit_weight : float or array_like, shape (n,)
        Weight per unit volume [N/m^3], >= 0 (0: weightless).

    Raises
    ------
    ValueError
        If there is no block, an array has the wrong shape or a non-finite entry, a size is
        not positive or a unit weight is negative.

    Examples
    --------
    >>> import masonry_dem as md
    >>> blocks = md.Blocks([[0.1, 0.05, 0.05]], [[0.2, 0.1, 0.1]], 18e3)
    >>> blocks.count, round(float(blocks.weights[0]), 6)
    (1, 36.0)
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
        """Blocks from their lower and upper corners.

        %(boxes)s

        Raises
        ------
        ValueError
            If a box has no positive size along an axis (named by the corners given), or as
            :class:`Blocks` raises.
        """
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
        """(n, 3) lower corners [m]."""
        return self.centres - self.sizes / 2

    @property
    def upper(self) -> FloatArray:
        """(n, 3) upper corners [m]."""
        return self.centres + self.sizes / 2

    @property
    def volumes(self) -> FloatArray:
        """(n,) block volumes [m^3]."""
        return np.asarray(np.prod(self.sizes, axis=1), dtype=np.float64)

    @property
    def weights(self) -> FloatArray:
        """(n,) block weights [N]: volume times unit weight."""
        return self.volumes * self.unit_weight

    def permuted(self, order: ArrayLike) -> Blocks:
        """The same blocks in another order (for numbering-independence checks).

        Parameters
        ----------
        order : array_like of int, shape (n,)
            The old index of each new block.

        Returns
        -------
        Blocks
            Block ``k`` is block ``order[k]`` of these.
        """
        return self.subset(np.asarray(order))

    @staticmethod
    def concatenate(*parts: Blocks) -> Blocks:
        """The blocks of several assemblies, in the order given.

        Parameters
        ----------
        *parts : Blocks
            The assemblies, numbered one after another.

        Returns
        -------
        Blocks
            All their blocks.
        """
        return Blocks(
            np.vstack([p.centres for p in parts]),
            np.vstack([p.sizes for p in parts]),
            np.concatenate([p.unit_weight for p in parts]),
        )

    def corner_points(self) -> FloatArray:
        """The corners of every block, in VTK hexahedron order.

        Returns
        -------
        numpy.ndarray, shape (n, 8, 3)
            Corner coordinates [m].
        """
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
