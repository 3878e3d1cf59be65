"""Selectors: indices of blocks by column, course, edge or predicate.

Every selector raises ValueError when it matches nothing, so a typo in a case file cannot
silently leave a wall unsupported.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from masonry_dem.geometry.blocks import Blocks

EDGES = ("left", "right", "bottom", "top", "back", "front")
_EDGE_AXIS = {
    "left": (0, -1),
    "right": (0, 1),
    "bottom": (1, -1),
    "top": (1, 1),
    "back": (2, -1),
    "front": (2, 1),
}


def _as_mask(blocks: Blocks, among) -> np.ndarray | None:
    """``among`` as an (n,) boolean mask. Block indices are accepted too: before, an index
    array went through ``mask & among`` as a bitwise AND of bools and ints and silently
    selected the wrong blocks."""
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


def _checked(name: str, mask: np.ndarray, among: np.ndarray | None) -> np.ndarray:
    if among is not None:
        mask = mask & among
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        raise ValueError(f"selector {name} matches no block")
    return idx


def _tol(blocks: Blocks) -> float:
    return 1e-6 * float(np.median(blocks.sizes))


def edge(blocks: Blocks, which: str, among: np.ndarray | None = None) -> np.ndarray:
    """Blocks touching one edge of the assembly's bounding box (``left``, ``right``, ``bottom``,
    ``top``, ``back``, ``front``); ``among`` (boolean mask or block indices) restricts the
    search."""
    if which not in _EDGE_AXIS:
        raise ValueError(f"edge must be one of {EDGES}, got {which!r}")
    axis, side = _EDGE_AXIS[which]
    among = _as_mask(blocks, among)
    pool = np.ones(blocks.count, bool) if among is None else among
    if not np.any(pool):
        # an empty ``among`` made min()/max() fail with numpy's "zero-size array" message;
        # say which selector matched nothing instead
        raise ValueError(f"selector edge={which!r} matches no block: `among` selects none")
    if side < 0:
        limit = blocks.lower[pool, axis].min()
        mask = blocks.lower[:, axis] <= limit + _tol(blocks)
    else:
        limit = blocks.upper[pool, axis].max()
        mask = blocks.upper[:, axis] >= limit - _tol(blocks)
    return _checked(f"edge={which!r}", mask, among)


def column(blocks: Blocks, which: str = "left", among: np.ndarray | None = None) -> np.ndarray:
    """The end column of a wall: ``left`` or ``right`` (whole and half end blocks)."""
    if which not in ("left", "right"):
        raise ValueError(f"column must be 'left' or 'right', got {which!r}")
    return edge(blocks, which, among)


def course_levels(blocks: Blocks, among: np.ndarray | None = None) -> np.ndarray:
    """Sorted distinct centre heights (e2) of the blocks: one per course."""
    among = _as_mask(blocks, among)
    y = blocks.centres[among if among is not None else slice(None), 1]
    y = np.sort(y)
    if y.size == 0:
        return y
    gaps = np.diff(y) > _tol(blocks)
    return y[np.concatenate([[True], gaps])]


def course(blocks: Blocks, k: int, among: np.ndarray | None = None) -> np.ndarray:
    """Blocks of course ``k`` (0 = lowest; negative counts from the top)."""
    among = _as_mask(blocks, among)
    levels = course_levels(blocks, among)
    if not -levels.size <= k < levels.size:
        raise ValueError(f"course {k} does not exist: the assembly has {levels.size} courses")
    mask = np.abs(blocks.centres[:, 1] - levels[k]) <= _tol(blocks)
    return _checked(f"course={k}", mask, among)


def where(
    blocks: Blocks, predicate: Callable[[np.ndarray], np.ndarray], name: str = "predicate"
) -> np.ndarray:
    """Blocks whose centres (n, 3) satisfy ``predicate(centres) -> bool mask``."""
    mask = np.asarray(predicate(blocks.centres), dtype=bool)
    if mask.shape != (blocks.count,):
        raise ValueError(
            f"{name} must return a boolean mask of shape ({blocks.count},), got {mask.shape}"
        )
    return _checked(name, mask, None)
