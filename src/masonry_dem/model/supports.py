"""The blocks' DOFs, their names and groups, and the supports that hold them: which DOFs of
which blocks are fixed, from the first load on (or from a later loading stage on).

Block DOFs q = (u1, u2, u3, w1, w2, w3) at the block centre.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike

from masonry_dem._arrays import BoolArray
from masonry_dem._validation import (
    block_indices,
)

#: a block DOF: translations u1-u3 and rotations w1-w3 along / about e1, e2, e3
DofName = Literal["u1", "u2", "u3", "w1", "w2", "w3"]
#: a named group of DOFs (``in_plane``: u1, u2, w3; ``out_of_plane``: u3, w1, w2)
DofGroup = Literal["all", "translations", "rotations", "in_plane", "out_of_plane"]
DOF_NAMES: tuple[str, ...] = get_args(DofName)
#: (block, DOF): the displacement a run puts on its pushover curve
Monitor = tuple[int, DofName]
_DOF_GROUPS: dict[str, tuple[int, ...]] = {
    "all": (0, 1, 2, 3, 4, 5),
    "translations": (0, 1, 2),
    "rotations": (3, 4, 5),
    "in_plane": (0, 1, 5),
    "out_of_plane": (2, 3, 4),
}


def dof_mask(dofs: DofGroup | DofName | Sequence[DofGroup | DofName]) -> BoolArray:
    """Boolean (6,) mask from a group name (``all``, ``translations``, ``rotations``,
    ``in_plane``, ``out_of_plane``) or a list of DOF names (``u1`` ... ``w3``)."""
    mask = np.zeros(6, dtype=bool)
    names = [dofs] if isinstance(dofs, str) else list(dofs)
    for name in names:
        if name in _DOF_GROUPS:
            mask[list(_DOF_GROUPS[name])] = True
        elif name in DOF_NAMES:
            mask[DOF_NAMES.index(name)] = True
        else:
            raise ValueError(
                f"dofs must name a group {sorted(_DOF_GROUPS)} or DOFs {DOF_NAMES}, got {name!r}"
            )
    return mask


@dataclass(frozen=True)
class Support:
    """Fix ``dofs`` of the given blocks (indices) at zero, from the first load on.

    What a held column means (a return wall read as fixed DOFs of the end column):

    * ``u1``, ``u3``: the column cannot move horizontally; it turns and moves vertically with
      the wall (a frictionless guide that only stops it sideways);
    * rotations ``w1``-``w3`` as well: the column cannot turn either (a return wall stiff in
      its own plane and out of it);
    * ``u2`` as well (``all``, ``translations``): the column cannot move vertically at all.
      Under the dead load the rest of the wall settles on its elastic bed joints and the
      column does not, so the wall hangs on the column through the friction of its head
      joints (the column's fixed u2 carries part of the wall's weight) and those joints
      start the live load already sheared. A real return wall settles as much as the
      facade (every point of the plan carries the same height of masonry, so each course of
      an L or U wall sinks by the same amount: ``tests/cases/test_walls_that_meet.py``), so
      this reading stiffens the wall by an artefact of the model.

    ``settles_with_wall``: the column follows the wall's vertical motion: u2 of the held
    blocks stays free whatever ``dofs`` says (the other DOFs stay fixed). Under the dead load
    the column then sinks with its course (no head-joint shear, no weight on the support);
    under the live load it may also rise or sink with the wall, held only by the joints
    around it. Model the return walls as blocks (:mod:`masonry_dem.geometry.plans`) to let
    them resist uplift by their weight and interlock.

    Parameters
    ----------
    blocks : array_like of int or bool
        The held blocks (indices, or a boolean mask), e.g. from :mod:`masonry_dem.select`.
    dofs : str or sequence of str, default "all"
        A group (``all``, ``translations``, ``rotations``, ``in_plane``: u1, u2, w3;
        ``out_of_plane``: u3, w1, w2) or a list of DOF names (``u1`` ... ``w3``) and groups.
    settles_with_wall : bool, default False
        Leave u2 of the held blocks free (the column follows the wall's vertical motion).

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.Support([0, 1], "in_plane").mask(3).astype(int).tolist()
    [[1, 1, 0, 0, 0, 1], [1, 1, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0]]
    """

    blocks: ArrayLike
    dofs: DofGroup | DofName | Sequence[DofGroup | DofName] = "all"
    settles_with_wall: bool = False

    def mask(self, n_blocks: int) -> BoolArray:
        """The DOFs this support fixes.

        Parameters
        ----------
        n_blocks : int
            Blocks in the assembly.

        Returns
        -------
        numpy.ndarray of bool, shape (n_blocks, 6)
            True where a DOF is fixed.

        Raises
        ------
        ValueError
            If the selection is empty or out of range, ``settles_with_wall`` is not true or
            false, or ``dofs`` names no group or DOF.
        """
        idx = block_indices("Support.blocks", self.blocks, n_blocks)
        if idx.size == 0:
            raise ValueError("Support.blocks: the selection is empty")
        if not isinstance(self.settles_with_wall, (bool, np.bool_)):
            raise ValueError(
                f"Support.settles_with_wall must be true or false, got {self.settles_with_wall!r}"
            )
        dofs = dof_mask(self.dofs)
        if self.settles_with_wall:
            # the column follows the wall's vertical settlement: u2 is left free
            dofs[DOF_NAMES.index("u2")] = False
        out = np.zeros((n_blocks, 6), dtype=bool)
        out[np.ix_(idx, np.flatnonzero(dofs))] = True
        return out
