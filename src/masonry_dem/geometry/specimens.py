"""Test specimens: the in-plane shear wall, a wall built between a bottom and a top beam, and
units split by a potential crack.

In the classic shear test of masonry (Raijmakers & Vermeltfoort, TU Eindhoven, 1992, as
Lourenco used them, 1996) the wall stands on a concrete (or steel) beam clamped to the floor;
a second beam on its top course carries the vertical precompression, is then held at its
height and against rotation and pushed sideways. Both beams are built here as single rigid
blocks, so that a support holds the bottom beam and loads, supports and a displacement drive
act on the top beam as one body.

The wall is a run of ``courses`` courses cut at the bond points: in running bond the head
joints of alternate courses shift by half a block, and a wall whose length is not a whole
number of blocks ends in shorter pieces (the 990 mm wall of 210 mm bricks with 10 mm joints:
four whole bricks and a half in every course, the half at alternate ends), as a bricklayer
lays it; a piece shorter than 0.3 block stays with its neighbour
(:data:`~masonry_dem.geometry.plans.SHORTEST_PIECE`).

Rigid units cannot crack, while the diagonal cracks of shear walls under high precompression
run through the bricks. :func:`split_units` splits units at mid-length into two blocks and
names the pairs, whose interface takes the unit's own strength (``Model.build``'s
``interface_overrides``): the potential crack of Lourenco & Rots (1997), one per unit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem._docstrings import fill
from masonry_dem._parameters import function_of
from masonry_dem._validation import block_indices, check_choice, positive_scalar
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import (
    DOCS,
    _count,
    _Courses,
    _Unit,
    add_base,
    add_top_beam,
    cut_openings,
)
from masonry_dem.geometry.plans import _assemble, _Run

#: the bonds a shear wall is built in (``running``: head joints shift by half a block from
#: course to course; ``stack``: they line up)
Bond = Literal["running", "stack"]
BONDS: tuple[str, ...] = get_args(Bond)


@dataclass(frozen=True)
class _ShearWallLength:
    length: float


@fill(DOCS)
@dataclass(frozen=True)
class _ShearWall(_Unit, _Courses, _ShearWallLength):
    """A wall between a bottom and a top beam, as in-plane shear tests are built.

    The wall is ``length`` long (along e1) and ``courses`` x (a + e) high (along e2), of
    blocks a x b x s with the joint e included in them, cut at the bond points (running
    bond: ends in shorter pieces where ``length`` is not a whole number of blocks). Under it
    a bottom beam, over it a top beam: each one rigid block as long and thick as the wall.
    The blocks come course by course from the bottom, then the bottom beam, then the top
    beam (``md.select.edge(blocks, "bottom")`` and ``"top"`` find the beams).

    Parameters
    ----------
    length : float
        The wall's length [m], > 0, at least one block.
    %(courses)s
    %(unit)s
    joint : float, default 0.0
        e, the mortar joint thickness [m], >= 0, included in the blocks.
    bond : {"running", "stack"}, default "running"
        Running bond (head joints shifted by half a block in alternate courses) or stack
        bond.
    start_with_half : bool, default False
        Running bond: shift the bottom course's head joints (and so every course's).
    beam_depth : float, optional
        Each beam's depth [m], > 0 (None: one course, a + e).
    beam_unit_weight : float, default 0.0
        Weight per unit volume of the beams [N/m^3], >= 0 (0: the top beam's weight is left
        to the precompression a case applies).
    openings : sequence of (x_min, y_min, x_max, y_max), default ()
        Openings in the wall [m] (y from the wall's bottom, the top of the bottom beam), cut
        out of the wall alone as :func:`~masonry_dem.cut_openings` cuts them.
    lintels : bool, default True
        Straight jambs and a lintel over each opening (:func:`~masonry_dem.cut_openings`).
    %(letters)s

    Returns
    -------
    Blocks
        The wall course by course, then the bottom beam, then the top beam.

    Raises
    ------
    ValueError
        If a size, count or weight is out of its range (named), ``length`` is shorter than a
        block, ``bond`` is not one of its values, or an opening is out of the wall.

    Examples
    --------
    The 0.30 MPa wall of Raijmakers & Vermeltfoort: 16 active courses of 210 x 52 mm bricks
    with 10 mm joints, 990 mm long (four bricks and a half in every course).

    >>> import masonry_dem as md
    >>> wall = md.shear_wall(0.99, 16, 0.052, 0.21, 0.1, 18e3, joint=0.01)
    >>> wall.count  # 16 courses of 5 pieces, two beams
    82
    >>> wall.upper.max(axis=0).round(6).tolist()  # the top beam: one course deep
    [0.99, 1.054, 0.1]
    >>> md.select.edge(wall, "top").tolist(), md.select.edge(wall, "bottom").tolist()
    ([81], [80])
    """

    #: the slabs it builds last, in order, by the selector that names each in a case file:
    #: the bottom beam (``select = "base"``), then the top beam (``select = "beam"``)
    SLABS: ClassVar[tuple[str, ...]] = ("base", "beam")

    joint: float = 0.0
    bond: Bond = "running"
    start_with_half: bool = False
    beam_depth: float | None = None
    beam_unit_weight: float = 0.0
    openings: Sequence[Sequence[float]] = ()
    lintels: bool = True

    def __call__(self) -> Blocks:
        length = positive_scalar("length", self.length)
        courses = _count("courses", self.courses)
        a, b, s = self.size()
        gamma = self.weight()
        e = positive_scalar("joint", self.joint, strict=False)
        check_choice("bond", self.bond, BONDS)
        pitch, course_pitch = b + e, a + e
        if length < pitch:
            raise ValueError(
                f"length = {length:g} m is shorter than one block with its joint "
                f"({pitch:g} m): a shear wall needs at least one whole block"
            )
        depth = (
            course_pitch
            if self.beam_depth is None
            else positive_scalar("beam_depth", self.beam_depth)
        )
        beam_gamma = positive_scalar("beam_unit_weight", self.beam_unit_weight, strict=False)
        # the bottom course's phase and the next one's: running bond alternates them
        first = int(bool(self.start_with_half)) if self.bond == "running" else 0
        second = 1 - first if self.bond == "running" else 0
        run = _Run(0, 0.0, 1, (0.0, s), (0.0, length, first), (0.0, length, second))
        wall = _assemble([run], courses, pitch, course_pitch, gamma)
        if len(self.openings):
            wall = cut_openings(wall, self.openings, lintels=bool(self.lintels))
        blocks, _ = add_base(wall, depth)
        blocks, _ = add_top_beam(blocks, depth, beam_gamma)
        return blocks


shear_wall = function_of(_ShearWall)


def split_units(blocks: Blocks, among: ArrayLike | None = None) -> tuple[Blocks, NDArray[np.intp]]:
    """Split units at mid-length (along e1) by a vertical potential crack.

    Each unit becomes two blocks, left then right, in the unit's place; the other blocks keep
    their order. Give the pairs to ``Model.build(interface_overrides=[(pairs, material)])``
    so that the crack has the unit's tensile and shear strength (Lourenco & Rots, 1997).

    Parameters
    ----------
    blocks : Blocks
        The assembly.
    among : array_like of int, optional
        The units to split (None: every block), e.g. the whole bricks of a wall.

    Returns
    -------
    blocks : Blocks
        The assembly with the units split.
    pairs : numpy.ndarray of int, shape (k, 2)
        The (left, right) blocks of each split unit, in the new numbering.

    Raises
    ------
    ValueError
        If ``among`` is empty, not block indices or out of range.

    Examples
    --------
    >>> import numpy as np
    >>> import masonry_dem as md
    >>> wall = md.shear_wall(0.99, 2, 0.052, 0.21, 0.1, 18e3, joint=0.01)
    >>> whole = (wall.sizes[:, 0] > 0.2) & (wall.sizes[:, 0] < 0.3)  # the bricks, not beams
    >>> split, pairs = md.split_units(wall, np.flatnonzero(whole))
    >>> wall.count, split.count, pairs[:2].tolist()
    (12, 20, [[0, 1], [2, 3]])
    """
    n = blocks.count
    idx = np.arange(n) if among is None else block_indices("among", among, n)
    if idx.size == 0:
        raise ValueError("split_units: among selects no block")
    split = np.zeros(n, dtype=bool)
    split[idx] = True
    # every block in its place, the right half of a split unit right after its left half
    first = np.cumsum(1 + split) - (1 + split)
    lower, upper = blocks.lower, blocks.upper
    middle = blocks.centres[split, 0]
    new_lower = np.empty((n + int(split.sum()), 3))
    new_upper = np.empty_like(new_lower)
    gamma = np.empty(new_lower.shape[0])
    new_lower[first], new_upper[first], gamma[first] = lower, upper, blocks.unit_weight
    new_upper[first[split], 0] = middle
    right = first[split] + 1
    new_lower[right], new_upper[right] = lower[split], upper[split]
    new_lower[right, 0] = middle
    gamma[right] = blocks.unit_weight[split]
    pairs = np.stack([first[split], right], axis=1).astype(np.intp)
    return Blocks.from_boxes(new_lower, new_upper, gamma), pairs
