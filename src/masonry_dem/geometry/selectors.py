"""Selectors: indices of blocks by column, course, edge or predicate.

Every selector raises ValueError when it matches nothing, so a typo in a case file cannot
silently leave a wall unsupported.

Examples
--------
>>> import masonry_dem as md
>>> wall = md.running_bond_wall(4, 3, 0.1, 0.2, 0.1, 18e3)
>>> md.select.edge(wall, "bottom").tolist()
[0, 1, 2, 3]
>>> md.select.course(wall, -1).tolist()
[9, 10, 11, 12]
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem._docstrings import fill
from masonry_dem.geometry.blocks import Blocks

Edge = Literal["left", "right", "bottom", "top", "back", "front"]
EDGES: tuple[str, ...] = get_args(Edge)
_EDGE_AXIS = {
    "left": (0, -1),
    "right": (0, 1),
    "bottom": (1, -1),
    "top": (1, 1),
    "back": (2, -1),
    "front": (2, 1),
}


def _as_mask(blocks: Blocks, among: ArrayLike | None) -> NDArray[np.bool_] | None:
    """``among`` as an (n,) boolean mask, from a mask or from block indices (which must
    become a mask: ``mask & indices`` would be a bitwise AND of bools and ints)."""
    if among is None:
        return None
    arr = np.asarray(among)
    if arr.dtype == bool:
        if arr.shape != (blocks.count,):
            raise ValueError(
                f"among must be a boolean mask of shape ({blocks.count},), got {arr.shape}"
            )
        return arr
    idx = np.atleast_1d(arr).astype(np.int64)
    if idx.size and (idx.min() < -blocks.count or idx.max() >= blocks.count):
        raise ValueError(f"among: block index out of range 0..{blocks.count - 1}")
    mask = np.zeros(blocks.count, dtype=bool)
    mask[idx] = True
    return mask


def _checked(
    name: str, mask: NDArray[np.bool_], among: NDArray[np.bool_] | None
) -> NDArray[np.intp]:
    if among is not None:
        mask = mask & among
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        raise ValueError(f"selector {name} matches no block")
    return idx


def _tol(blocks: Blocks) -> float:
    return 1e-6 * float(np.median(blocks.sizes))


#: the text the selectors' docstrings share (:func:`masonry_dem._docstrings.fill`)
DOCS: dict[str, str] = {
    "assembly": """
        Parameters
        ----------
        blocks : Blocks
            The assembly.
    """,
    "among": """
        among : array_like of bool or int, optional
            A boolean mask (n,) or block indices that restricts the search (None: every
            block).
    """,
    "indices": """
        Returns
        -------
        numpy.ndarray of int
            The indices of the blocks, ascending.
    """,
    "wall": """
        >>> import masonry_dem as md
        >>> wall = md.running_bond_wall(4, 3, 0.1, 0.2, 0.1, 18e3)
    """,
}


@fill(DOCS)
def edge(blocks: Blocks, which: Edge, among: ArrayLike | None = None) -> NDArray[np.intp]:
    """Blocks touching one edge of the assembly's bounding box.

    %(assembly)s
    which : {"left", "right", "bottom", "top", "back", "front"}
        The edge (smallest or largest e1, e2, e3 of the blocks searched).
    %(among)s

    %(indices)s

    Raises
    ------
    ValueError
        If ``which`` is not an edge, ``among`` is out of range or selects no block, or the
        selector matches no block.

    Examples
    --------
    %(wall)s
    >>> md.select.edge(wall, "bottom").tolist()
    [0, 1, 2, 3]
    """
    if which not in _EDGE_AXIS:
        raise ValueError(f"edge must be one of {EDGES}, got {which!r}")
    axis, side = _EDGE_AXIS[which]
    mask_among = _as_mask(blocks, among)
    pool = np.ones(blocks.count, bool) if mask_among is None else mask_among
    if not np.any(pool):
        # an empty pool has no min()/max(): name the selector that matched nothing
        raise ValueError(f"selector edge={which!r} matches no block: `among` selects none")
    if side < 0:
        limit = blocks.lower[pool, axis].min()
        mask = blocks.lower[:, axis] <= limit + _tol(blocks)
    else:
        limit = blocks.upper[pool, axis].max()
        mask = blocks.upper[:, axis] >= limit - _tol(blocks)
    return _checked(f"edge={which!r}", mask, mask_among)


@fill(DOCS)
def column(
    blocks: Blocks, which: Literal["left", "right"] = "left", among: ArrayLike | None = None
) -> NDArray[np.intp]:
    """The end column of a wall: ``left`` or ``right`` (whole and half end blocks).

    Parameters
    ----------
    blocks : Blocks
        The wall.
    which : {"left", "right"}, default "left"
        The end.
    %(among)s

    %(indices)s

    Raises
    ------
    ValueError
        If ``which`` is neither end, or as :func:`edge` raises.

    Examples
    --------
    %(wall)s
    >>> md.select.column(wall, "left").tolist()
    [0, 4, 9]
    """
    if which not in ("left", "right"):
        raise ValueError(f"column must be 'left' or 'right', got {which!r}")
    return edge(blocks, which, among)


@fill(DOCS)
def course_levels(blocks: Blocks, among: ArrayLike | None = None) -> NDArray[np.float64]:
    """The sorted distinct centre heights (e2) of the blocks: one per course.

    %(assembly)s
    %(among)s

    Returns
    -------
    numpy.ndarray, shape (courses,)
        Heights [m], ascending (empty if ``among`` selects no block).

    Raises
    ------
    ValueError
        If ``among`` is a mask of the wrong shape or an index is out of range.

    Examples
    --------
    %(wall)s
    >>> md.select.course_levels(wall).round(6).tolist()
    [0.05, 0.15, 0.25]
    """
    mask = _as_mask(blocks, among)
    y = blocks.centres[mask if mask is not None else slice(None), 1]
    y = np.sort(y)
    if y.size == 0:
        return y
    gaps = np.diff(y) > _tol(blocks)
    return np.asarray(y[np.concatenate([[True], gaps])], dtype=np.float64)


@fill(DOCS)
def course(blocks: Blocks, k: int, among: ArrayLike | None = None) -> NDArray[np.intp]:
    """Blocks of course ``k`` (0 = lowest; negative counts from the top).

    %(assembly)s
    k : int
        The course.
    %(among)s

    %(indices)s

    Raises
    ------
    ValueError
        If course ``k`` does not exist, or ``among`` is out of range.

    Examples
    --------
    %(wall)s
    >>> md.select.course(wall, -1).tolist()
    [9, 10, 11, 12]
    """
    mask_among = _as_mask(blocks, among)
    levels = course_levels(blocks, mask_among)
    if not -levels.size <= k < levels.size:
        raise ValueError(f"course {k} does not exist: the assembly has {levels.size} courses")
    mask = np.abs(blocks.centres[:, 1] - levels[k]) <= _tol(blocks)
    return _checked(f"course={k}", mask, mask_among)


@fill(DOCS)
def where(
    blocks: Blocks, predicate: Callable[[NDArray[np.float64]], ArrayLike], name: str = "predicate"
) -> NDArray[np.intp]:
    """Blocks whose centres (n, 3) satisfy ``predicate(centres) -> bool mask``.

    %(assembly)s
    predicate : callable
        Takes the (n, 3) centres [m], returns an (n,) boolean mask.
    name : str, default "predicate"
        Names the selector in errors.

    %(indices)s

    Raises
    ------
    ValueError
        If the mask has the wrong shape, or selects no block.

    Examples
    --------
    %(wall)s
    >>> md.select.where(wall, lambda c: c[:, 0] < 0.2).tolist()
    [0, 4, 9]
    """
    mask = np.asarray(predicate(blocks.centres), dtype=bool)
    if mask.shape != (blocks.count,):
        raise ValueError(
            f"{name} must return a boolean mask of shape ({blocks.count},), got {mask.shape}"
        )
    return _checked(name, mask, None)


# --------------------------------------------------------------------------- walls that meet
WALL_PARTS = ("facade", "back", "return:left", "return:right", "cross")
CORNER_PARTS = (
    "corner:left",
    "corner:right",
    "corner:back-left",
    "corner:back-right",
    "corner:cross",
)
PARTS = WALL_PARTS + CORNER_PARTS


def _plan(
    blocks: Blocks, pool: NDArray[np.bool_]
) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Plan bands of an assembly of walls that meet (see :mod:`masonry_dem.geometry.plans`):
    the wall thickness t (the median of each block's smaller plan size) and the outer plan
    extent of ``pool``."""
    plan = blocks.sizes[pool][:, [0, 2]]
    t = float(np.median(plan.min(axis=1)))
    lo = blocks.lower[pool].min(axis=0)
    hi = blocks.upper[pool].max(axis=0)
    return t, lo, hi


def _within(blocks: Blocks, axis: int, lo: float, hi: float, tol: float) -> NDArray[np.bool_]:
    return (blocks.lower[:, axis] >= lo - tol) & (blocks.upper[:, axis] <= hi + tol)


def _wall_labels(
    blocks: Blocks, pool: NDArray[np.bool_]
) -> tuple[NDArray[np.int_], float, NDArray[np.float64]]:
    """Label every block of ``pool`` with its wall (index into WALL_PARTS, -1 outside pool).

    A block belongs to the facade if its plan lies in the front band (z within t of the
    largest z); else to a return wall if it lies in the left or right band and a wall runs
    along that band (some block in it is longer along e3 than t); else to the back wall (the
    back band, with a block in it longer along e1 than t); else to the cross wall. A block
    that fills a corner square exactly lies in two bands and goes to the first of them."""
    t, lo, hi = _plan(blocks, pool)
    tol = 1e-6 * t
    front = _within(blocks, 2, hi[2] - t, hi[2], tol)
    left = _within(blocks, 0, lo[0], lo[0] + t, tol)
    right = _within(blocks, 0, hi[0] - t, hi[0], tol)
    back = _within(blocks, 2, lo[2], lo[2] + t, tol)
    along_z = blocks.sizes[:, 2] > t + tol
    along_x = blocks.sizes[:, 0] > t + tol
    label = np.full(blocks.count, 4)
    label[back & np.any(back & along_x & pool)] = 1
    label[right & np.any(right & along_z & pool)] = 3
    label[left & np.any(left & along_z & pool)] = 2
    label[front] = 0
    label[~pool] = -1
    return label, t, np.stack([lo, hi])


@fill(DOCS)
def part(blocks: Blocks, name: str, among: ArrayLike | None = None) -> NDArray[np.intp]:
    """Blocks of one part of walls that meet, found from the plan alone.

    The walls that meet are the L, T, U plans and boxes of :mod:`masonry_dem.geometry.plans`.

    Walls: ``facade`` (the front wall, largest e3), ``back`` (the back wall of a box),
    ``return:left``, ``return:right`` (the walls along e3 at the smallest and largest e1; the
    side walls of a box), ``cross`` (the cross wall of a T). Corners: ``corner:left``,
    ``corner:right`` (front corners), ``corner:back-left``, ``corner:back-right``, and
    ``corner:cross`` (the junction of a T): the blocks of either wall that overlap the corner
    square, course by course the one that runs through and the one that butts against it.
    ``among`` restricts the search (e.g. the wall without its base slab).

    Parameters
    ----------
    blocks : Blocks
        The walls.
    name : str
        The part: one of the walls or corners above.
    %(among)s

    %(indices)s

    Raises
    ------
    ValueError
        If ``name`` is not a part, ``among`` selects no block, or the part matches no block
        (``corner:cross`` without a cross wall; a corner where no two walls meet).

    Examples
    --------
    >>> import masonry_dem as md
    >>> walls = md.l_wall(6, 4, 0.1, 0.2, 0.1, 18e3)
    >>> corner = md.select.part(walls, "corner:left")
    >>> corner.tolist()
    [4, 13, 24, 33]
    """
    if name not in PARTS:
        raise ValueError(f"part must be one of {PARTS}, got {name!r}")
    mask = _as_mask(blocks, among)
    pool = np.ones(blocks.count, bool) if mask is None else mask
    if not np.any(pool):
        raise ValueError(f"selector part={name!r} matches no block: `among` selects none")
    label, t, (lo, hi) = _wall_labels(blocks, pool)
    if name in WALL_PARTS:
        return _checked(f"part={name!r}", label == WALL_PARTS.index(name), mask)
    tol = 1e-6 * t
    if name == "corner:cross":
        cross = label == WALL_PARTS.index("cross")
        if not cross.any():
            raise ValueError("selector part='corner:cross' matches no block: no cross wall")
        x0, x1 = blocks.lower[cross, 0].min(), blocks.upper[cross, 0].max()
        z0, z1 = hi[2] - t, hi[2]
    else:
        side = name.rpartition("-")[2].removeprefix("corner:")
        x0, x1 = (lo[0], lo[0] + t) if side == "left" else (hi[0] - t, hi[0])
        z0, z1 = (lo[2], lo[2] + t) if "back" in name else (hi[2] - t, hi[2])
    overlaps = (
        (blocks.upper[:, 0] > x0 + tol)
        & (blocks.lower[:, 0] < x1 - tol)
        & (blocks.upper[:, 2] > z0 + tol)
        & (blocks.lower[:, 2] < z1 - tol)
    )
    walls = np.unique(label[overlaps & pool])
    if walls.size < 2:
        # a free end of a wall, or the outer corner of a flat wall: no two walls meet there
        raise ValueError(f"selector part={name!r} matches no block: no two walls meet there")
    return _checked(f"part={name!r}", overlaps & pool, mask)
