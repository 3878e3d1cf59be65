"""Builders of block assemblies: running-bond walls, stack-bond columns, single blocks, openings,
supports (rigid base, return walls), and user lists of boxes.

A block measures ``block_height`` x ``block_length`` x ``thickness`` (the paper's a x b x s,
along e2, e1, e3). Every builder also takes the paper's letters as keywords (``a=``, ``b=``,
``s=``), as case files and older scripts write them; giving both names of one size is an error.

A builder is a frozen dataclass of its parameters, called for the blocks, made a function by
:func:`~masonry_dem._parameters.function_of`: the parameters builders share (the counts, the
unit and its letters) are declared once, in the classes they inherit (``_Along``,
``_Courses``, ``_Unit``).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import KW_ONLY, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem._docstrings import fill
from masonry_dem._parameters import function_of
from masonry_dem._validation import as_finite_array, plain, positive_scalar
from masonry_dem.geometry.blocks import DOCS as BLOCKS_DOCS
from masonry_dem.geometry.blocks import Blocks

log = logging.getLogger(__name__)


#: the most blocks along one direction of a builder: 10^4 already make 10^8 blocks
MOST_BLOCKS_ALONG = 10_000


def _count(name: str, value: object) -> int:
    """A count of blocks along one direction, checked before anything is allocated."""
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not math.isfinite(value)
        or int(value) != value
        or not 1 <= int(value) <= MOST_BLOCKS_ALONG
    ):
        raise ValueError(
            f"{name} must be a whole number from 1 to {MOST_BLOCKS_ALONG} (10^4 blocks along "
            f"one direction already make 10^8 blocks), got {plain(value)}"
        )
    return int(value)


def _one_of(name: str, value: float | None, letter: str, by_letter: float | None) -> float:
    """A size given by its name or by the paper's letter (not both), validated under the name
    the caller used."""
    if value is not None and by_letter is not None:
        raise ValueError(f"give {name} or {letter} (the paper's letter for it), not both")
    if value is None and by_letter is None:
        raise ValueError(f"{name} is required (the paper's {letter})")
    return positive_scalar(name, value) if value is not None else positive_scalar(letter, by_letter)


def block_size(
    block_height: float | None,
    block_length: float | None,
    thickness: float | None,
    a: float | None = None,
    b: float | None = None,
    s: float | None = None,
) -> tuple[float, float, float]:
    """(a, b, s): the block's height, length and thickness [m], each given by its name or by
    the paper's letter."""
    return (
        _one_of("block_height", block_height, "a", a),
        _one_of("block_length", block_length, "b", b),
        _one_of("thickness", thickness, "s", s),
    )


def _weight(unit_weight: float | None) -> float:
    if unit_weight is None:
        raise ValueError("unit_weight is required (weight per unit volume, N/m^3; 0: weightless)")
    return positive_scalar("unit_weight", unit_weight, strict=False)


#: the parameters the builders (and the plans) share, filled into their docstrings
#: (:func:`masonry_dem._docstrings.fill`)
DOCS: dict[str, str] = {
    "courses": """
        courses : int
            Number of courses, 1 to 10^4.
    """,
    "unit": """
        block_height, block_length, thickness : float
            The block's a, b and s [m] (along e2, e1, e3), each > 0; required, by name or by
            letter.
        unit_weight : float
            Weight per unit volume [N/m^3], >= 0 (0: weightless); required.
    """,
    "letters": """
        a, b, s : float, optional, keyword-only
            The paper's letters for ``block_height``, ``block_length`` and ``thickness`` (as
            case files and older scripts write them); giving both names of one size is an
            error.
    """,
}


@dataclass(frozen=True)
class _Along:
    blocks_along_length: int


@dataclass(frozen=True)
class _Courses:
    courses: int


@dataclass(frozen=True)
class _Unit:
    """The masonry unit: a block of ``block_height`` x ``block_length`` x ``thickness`` [m]
    (the paper's a x b x s, along e2, e1, e3; the letters are keywords too) that weighs
    ``unit_weight`` per unit volume [N/m^3]."""

    block_height: float | None = None
    block_length: float | None = None
    thickness: float | None = None
    unit_weight: float | None = None
    _: KW_ONLY
    a: float | None = None
    b: float | None = None
    s: float | None = None

    def size(self) -> tuple[float, float, float]:
        """(a, b, s), validated: each given by its name or by its letter."""
        return block_size(
            self.block_height, self.block_length, self.thickness, self.a, self.b, self.s
        )

    def weight(self) -> float:
        return _weight(self.unit_weight)


@fill(DOCS)
@dataclass(frozen=True)
class _RunningBondWall(_Unit, _Courses, _Along):
    """A single-leaf running-bond wall with straight ends.

    Course k (from the bottom) holds ``blocks_along_length`` whole blocks when k is even and,
    when k is odd, a half block at each end with ``blocks_along_length - 1`` whole blocks between
    (``start_with_half`` swaps the two). Block pitch is (b + joint) along e1 and (a + joint)
    along e2: the mortar joint thickness ``joint`` is included in the blocks, so the wall
    measures n(b+e) x courses(a+e) x s. The wall's lower-left-back corner sits at ``origin``.
    Block sizes a, b, s: ``block_height``, ``block_length``, ``thickness``.

    Parameters
    ----------
    blocks_along_length : int
        n, whole blocks in an even course, 1 to 10^4.
    %(courses)s
    %(unit)s
    joint : float, default 0.0
        e, the mortar joint thickness [m], >= 0, included in the blocks.
    origin : sequence of 3 floats, default (0, 0, 0)
        The wall's lower-left-back corner [m].
    start_with_half : bool, default False
        Start the bottom course with half blocks (swaps even and odd courses).
    %(letters)s

    Returns
    -------
    Blocks
        The wall's blocks, course by course from the bottom.

    Raises
    ------
    ValueError
        If a size is missing, given twice (by name and by letter) or not positive, or
        ``unit_weight`` is missing or negative, a count is not a whole number from 1 to
        10^4, or ``joint`` is negative.

    Examples
    --------
    >>> import masonry_dem as md
    >>> wall = md.running_bond_wall(4, 3, 0.1, 0.2, 0.1, 18e3)
    >>> wall.count  # 4 + 5 + 4 blocks
    13
    >>> wall.upper.max(axis=0).tolist()
    [0.8, 0.30000000000000004, 0.1]
    >>> md.running_bond_wall(4, 3, a=0.1, b=0.2, s=0.1, unit_weight=18e3).count
    13
    """

    joint: float = 0.0
    origin: Sequence[float] = (0.0, 0.0, 0.0)
    start_with_half: bool = False

    def __call__(self) -> Blocks:
        n = _count("blocks_along_length", self.blocks_along_length)
        nc = _count("courses", self.courses)
        a, b, s = self.size()
        e = positive_scalar("joint", self.joint, strict=False)
        gamma = self.weight()
        px, py = b + e, a + e
        half_course = (np.arange(nc) % 2 == 1) ^ bool(self.start_with_half)
        # Each course is cut at integer or half-integer pitches; describe blocks by their cut
        # points.
        per_course = np.where(half_course, n + 1, n)
        course = np.repeat(np.arange(nc), per_course)
        pos = np.arange(course.size) - np.repeat(np.cumsum(per_course) - per_course, per_course)
        shifted = half_course[course]
        left = np.where(shifted, np.maximum(pos - 0.5, 0.0), pos)
        right = np.where(shifted, np.minimum(pos + 0.5, n), pos + 1.0)
        x0, y0, z0 = as_finite_array("origin", self.origin, (3,))
        lower = np.stack([x0 + left * px, y0 + course * py, np.full(course.size, z0)], axis=1)
        upper = np.stack(
            [x0 + right * px, y0 + (course + 1) * py, np.full(course.size, z0 + s)], axis=1
        )
        return Blocks.from_boxes(lower, upper, gamma)


@dataclass(frozen=True)
class _Extent:
    length: float
    height: float


@fill(DOCS)
@dataclass(frozen=True)
class _RunningBondWallOfSize(_Unit, _Extent):
    """A running-bond wall of the given overall size (``length`` x ``height`` [m]).

    The wall has the nearest whole numbers of blocks of ``block_length`` (b) and courses of
    ``block_height`` (a), with the pitch stretched (by less than half a block) so the wall is
    exactly that size; ``thickness`` (s).

    Parameters
    ----------
    length, height : float
        The wall's overall length (along e1) and height (along e2) [m], each > 0.
    %(unit)s
    joint : float, default 0.0
        The mortar joint thickness [m], >= 0, included in the blocks.
    %(letters)s

    Returns
    -------
    Blocks
        The wall's blocks (as :func:`running_bond_wall` builds them, lower-left-back corner at
        the origin).

    Raises
    ------
    ValueError
        If a size is missing, given twice (by name and by letter) or not positive, or
        ``unit_weight`` is missing or negative, or ``length``, ``height`` or ``joint`` is out
        of range.

    Examples
    --------
    >>> import masonry_dem as md
    >>> wall = md.running_bond_wall_of_size(1.0, 0.5, 0.1, 0.25, 0.12, 18e3)
    >>> wall.count  # 4 blocks along, 5 courses
    22
    >>> wall.upper.max(axis=0).tolist()
    [1.0, 0.5, 0.12]
    """

    joint: float = 0.0

    def __call__(self) -> Blocks:
        length = positive_scalar("length", self.length)
        height = positive_scalar("height", self.height)
        a, b, s = self.size()
        e = positive_scalar("joint", self.joint, strict=False)
        n = max(1, round(length / (b + e)))
        nc = max(1, round(height / (a + e)))
        pitch_x, pitch_y = length / n, height / nc
        return running_bond_wall(n, nc, pitch_y, pitch_x, s, self.unit_weight, joint=0.0)


@fill(DOCS)
@dataclass(frozen=True)
class _StackBondColumn(_Unit, _Courses):
    """Blocks stacked one on another, the column's base on y = 0.

    A column of ``courses`` blocks of ``block_height`` (a) x ``block_length`` (b) x
    ``thickness`` (s).

    Parameters
    ----------
    courses : int
        Number of blocks, 1 to 10^4.
    %(unit)s
    %(letters)s

    Returns
    -------
    Blocks
        The blocks from the bottom up.

    Raises
    ------
    ValueError
        If a size is missing, given twice (by name and by letter) or not positive, or
        ``unit_weight`` is missing or negative, or ``courses`` is not a whole number from 1 to 10^4.

    Examples
    --------
    >>> import masonry_dem as md
    >>> column = md.stack_bond_column(5, 0.1, 0.2, 0.1, 18e3)
    >>> column.count, column.upper.max(axis=0).tolist()
    (5, [0.2, 0.5, 0.1])
    """

    def __call__(self) -> Blocks:
        nc = _count("courses", self.courses)
        a, b, s = self.size()
        k = np.arange(nc)
        centres = np.stack([np.full(nc, b / 2), (k + 0.5) * a, np.full(nc, s / 2)], axis=1)
        return Blocks(centres, np.tile([b, a, s], (nc, 1)), np.full(nc, self.weight()))


@fill(DOCS)
@dataclass(frozen=True)
class _SingleBlock(_Unit):
    """One block, its base on y = 0.

    The block measures ``block_height`` (a) x ``block_length`` (b) x ``thickness`` (s).

    Parameters
    ----------
    %(unit)s
    %(letters)s

    Returns
    -------
    Blocks
        The one block, its lower-left-back corner at the origin.

    Raises
    ------
    ValueError
        If a size is missing, given twice (by name and by letter) or not positive, or
        ``unit_weight`` is missing or negative.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.single_block(0.1, 0.2, 0.1, 18e3).centres.tolist()
    [[0.1, 0.05, 0.05]]
    """

    def __call__(self) -> Blocks:
        return stack_bond_column(1, *self.size(), self.unit_weight)


running_bond_wall = function_of(_RunningBondWall)
running_bond_wall_of_size = function_of(_RunningBondWallOfSize)
stack_bond_column = function_of(_StackBondColumn)
single_block = function_of(_SingleBlock)


@fill(BLOCKS_DOCS)
def boxes(lower: ArrayLike, upper: ArrayLike, unit_weight: ArrayLike) -> Blocks:
    """Any user list of boxes given by their lower and upper corners.

    %(boxes)s

    Raises
    ------
    ValueError
        If a box has no positive size along an axis, or an array has the wrong shape.

    Examples
    --------
    >>> import masonry_dem as md
    >>> two = md.boxes([[0, 0, 0], [0, 0.1, 0]], [[0.2, 0.1, 0.1], [0.2, 0.2, 0.1]], 18e3)
    >>> two.count
    2
    """
    return Blocks.from_boxes(lower, upper, unit_weight)


def cut_openings(
    blocks: Blocks,
    openings: Sequence[Sequence[float]],
    among: NDArray[np.bool_] | None = None,
    field: str = "openings",
    lintels: bool = False,
) -> Blocks:
    """Remove every block whose centre lies inside one of the rectangular openings.

    Openings are cut in whole blocks: choose their edges on block boundaries for clean jambs.
    Dry joints cannot span an opening: a block of the course above it with nothing under it
    hangs on the friction of head joints that carry no normal force, and the wall has no
    equilibrium under its own weight. ``lintels=True`` builds the openings as the paper's
    specimens were built: straight jambs (the blocks that straddle a jamb are cut at it,
    :func:`split_at_jambs`) and a lintel over each opening whose top is a bed joint below the
    top of the wall (:func:`add_lintels`). Without lintels, blocks left with nothing under
    them are named in a warning.

    Parameters
    ----------
    blocks : Blocks
        The wall.
    openings : sequence of (x_min, y_min, x_max, y_max)
        Rectangles in the wall plane (e1, e2) [m], max above min.
    among : numpy.ndarray of bool, shape (n,), optional
        A mask of the blocks an opening may remove (None: every block), e.g. the facade of
        walls that meet.
    field : str, default "openings"
        Names the argument in errors.
    lintels : bool, default False
        Straight jambs and a lintel over each opening (plain walls only).

    Returns
    -------
    Blocks
        The wall without the blocks inside the openings (and with the lintels).

    Raises
    ------
    ValueError
        If an opening is not four finite numbers with the max above the min, removes no
        block, or the openings remove every block; with ``lintels``: if ``among`` is given, an
        opening reaches an end of the wall below its top, two lintels would share a block, or
        an opening's top is not on a bed joint.

    Examples
    --------
    >>> import masonry_dem as md
    >>> wall = md.running_bond_wall(6, 6, 0.1, 0.2, 0.1, 18e3)
    >>> window = md.cut_openings(wall, [(0.4, 0.2, 0.8, 0.4)], lintels=True)
    >>> wall.count, window.count
    (39, 33)
    """
    rects = [checked_opening(field, k, rect) for k, rect in enumerate(openings)]
    if lintels:
        if among is not None:
            raise ValueError(f"{field}: lintels are built for the openings of a plain wall only")
        course = float(np.median(blocks.sizes[:, 1]))
        return openings_with_lintels(blocks, rects, course, field=field)
    cut = _remove_inside(blocks, rects, among, field)
    hanging = unsupported_blocks(cut)
    if hanging.size:
        log.warning(
            "%s leave %d block(s) with nothing under them (first: centre %s): dry joints "
            "(tensile strength 0) cannot carry them and the wall has no equilibrium under "
            "its own weight; build lintels over the openings (lintels = true)",
            field,
            hanging.size,
            plain(cut.centres[hanging[0]].round(6).tolist()),
        )
    return cut


def openings_with_lintels(
    blocks: Blocks, rects: Sequence[Sequence[float]], course: float, field: str = "openings"
) -> Blocks:
    """The openings (x_min, y_min, x_max, y_max) built as the paper's specimens were: jambs
    straightened (:func:`split_at_jambs`), the blocks inside removed, and a lintel over each
    opening (:func:`add_lintels`; ``course``: the course height [m]). An opening that reaches
    an end of the wall below its top is refused, named: the lintel over it would bear on one
    pier only, a cantilever that dry joints cannot hold."""
    checked = [checked_opening(field, k, rect) for k, rect in enumerate(rects)]
    tol = 1e-6 * course
    (x_lo, _, _), (x_hi, y_top, _) = blocks.lower.min(axis=0), blocks.upper.max(axis=0)
    for k, (x0, _, x1, y1) in enumerate(checked):
        if (x0 <= x_lo + tol or x1 >= x_hi - tol) and y1 < y_top - tol:
            raise ValueError(
                f"{field}[{k}] = {plain([round(v, 9) for v in checked[k]])} reaches an end of "
                f"the wall (x in [{x_lo:.9g}, {x_hi:.9g}]) below its top: a lintel over it "
                "would bear on one pier only"
            )
    cut = _remove_inside(split_at_jambs(blocks, checked), checked, None, field)
    return add_lintels(cut, checked, course, field=field)


def _remove_inside(
    blocks: Blocks,
    rects: Sequence[tuple[float, float, float, float]],
    among: NDArray[np.bool_] | None,
    field: str,
) -> Blocks:
    c = blocks.centres
    eligible = np.ones(blocks.count, dtype=bool) if among is None else among
    keep = np.ones(blocks.count, dtype=bool)
    for k, (x0, y0, x1, y1) in enumerate(rects):
        inside = eligible & (c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0) & (c[:, 1] < y1)
        if not inside.any():
            raise ValueError(f"{field}[{k}] = {plain(list(rects[k]))} removes no block")
        keep &= ~inside
    if not keep.any():
        raise ValueError(f"{field} = {plain([list(r) for r in rects])} remove every block")
    return blocks.subset(np.flatnonzero(keep))


def checked_opening(field: str, k: int, rect: Sequence[float]) -> tuple[float, float, float, float]:
    """Opening ``k`` of ``field`` as (x_min, y_min, x_max, y_max), four finite numbers with
    the max above the min (else a ValueError naming ``field[k]``)."""
    x0, y0, x1, y1 = (float(v) for v in as_finite_array(f"{field}[{k}]", rect, (4,)))
    if x1 <= x0 or y1 <= y0:
        raise ValueError(
            f"{field}[{k}] must have x_max > x_min and y_max > y_min, got {plain(rect)}"
        )
    return x0, y0, x1, y1


def unsupported_blocks(blocks: Blocks) -> NDArray[np.intp]:
    """Blocks above the lowest level with no block under them (no bed joint below): under
    their own weight they hang on the friction of their head joints alone."""
    from masonry_dem.geometry.interfaces import detect_interfaces

    its = detect_interfaces(blocks)
    bed = its.axis == 1
    i, j = its.block_i[bed], its.block_j[bed]
    upper = np.where(blocks.centres[i, 1] > blocks.centres[j, 1], i, j)
    held = np.zeros(blocks.count, dtype=bool)
    held[upper] = True
    bottom = blocks.lower[:, 1].min()
    held |= blocks.lower[:, 1] <= bottom + 1e-6 * float(np.median(blocks.sizes))
    return np.flatnonzero(~held)


def split_at_jambs(blocks: Blocks, rects: Sequence[Sequence[float]]) -> Blocks:
    """Cut the blocks that straddle a jamb of an opening at the jamb, so the openings have
    straight jambs of half blocks (as built) instead of blocks balanced on a corner."""
    lo, hi = blocks.lower.copy(), blocks.upper.copy()
    gamma = blocks.unit_weight.copy()
    for x0, y0, x1, y1 in rects:
        yc = (lo[:, 1] + hi[:, 1]) / 2
        rows = (yc > y0) & (yc < y1)
        for x in (x0, x1):
            cut = rows & (lo[:, 0] < x - 1e-9) & (hi[:, 0] > x + 1e-9)
            left_hi, right_lo = hi[cut].copy(), lo[cut].copy()
            left_hi[:, 0] = x
            right_lo[:, 0] = x
            lo = np.vstack([lo[~cut], lo[cut], right_lo])
            hi = np.vstack([hi[~cut], left_hi, hi[cut]])
            gamma = np.concatenate([gamma[~cut], gamma[cut], gamma[cut]])
            rows = np.concatenate([rows[~cut], rows[cut], rows[cut]])
    return Blocks.from_boxes(lo, hi, gamma)


def add_lintels(
    blocks: Blocks, rects: Sequence[Sequence[float]], course: float, field: str = "openings"
) -> Blocks:
    """A lintel over each opening: the blocks of the course above it that overlap the opening
    become one block (dry joints cannot span an opening). Where head joints of that course
    fall on the jambs, the blocks beside them are taken in too, so that a lintel always bears
    on both piers (one exactly as wide as the opening fell in). ``course``: the course height
    [m]; an opening that reaches the top of the wall needs no lintel."""
    keep = np.ones(blocks.count, dtype=bool)
    taken = np.full(blocks.count, -1)  # the opening whose lintel took each block
    lintels = []
    top = blocks.upper[:, 1].max()
    for k, (x0, _, x1, y1) in enumerate(rects):
        over = (
            (np.abs(blocks.lower[:, 1] - y1) < 1e-6 * course)
            & (blocks.upper[:, 0] > x0 - 1e-9)
            & (blocks.lower[:, 0] < x1 + 1e-9)
        )
        shared = over & (taken >= 0)
        if shared.any():  # two lintels in one place: overlapping blocks
            j = int(taken[shared][0])
            x_lo, x_hi = blocks.lower[shared, 0].min(), blocks.upper[shared, 0].max()
            raise ValueError(
                f"{field}[{j}] and {field}[{k}]: their lintels would share the block(s) at "
                f"x in [{x_lo:.9g}, {x_hi:.9g}], y in [{y1:.9g}, {y1 + course:.9g}] over the "
                "pier between them; move the openings apart or give one opening over both"
            )
        taken[over] = k
        if not over.any():
            if y1 >= top - 1e-6 * course:
                continue  # the opening reaches the top: nothing above it to carry
            beds = np.unique(blocks.lower[:, 1])
            near = np.sort(beds[np.argsort(np.abs(beds - y1))[:2]])
            raise ValueError(
                f"{field}[{k}]: a lintel sits on a bed joint, but y_max = {plain(y1)} is none "
                f"(the nearest are y = {' and '.join(plain(round(float(y), 9)) for y in near)})"
            )
        lo = np.array([blocks.lower[over, 0].min(), y1, blocks.lower[over, 2].min()])
        hi = np.array([blocks.upper[over, 0].max(), y1 + course, blocks.upper[over, 2].max()])
        lintels.append(Blocks.from_boxes(lo[None], hi[None], blocks.unit_weight[over][0]))
        keep &= ~over
    return Blocks.concatenate(blocks.subset(np.flatnonzero(keep)), *lintels)


def add_base(
    blocks: Blocks, depth: float | None = None, overhang: float = 0.0
) -> tuple[Blocks, int]:
    """Append a rigid base slab under the assembly; returns the blocks and the base index.

    The base spans the footprint of the assembly (plus ``overhang`` on every side in the plane)
    and its top face touches the lowest blocks, so real interfaces join it to the wall.

    Parameters
    ----------
    blocks : Blocks
        The assembly.
    depth : float, optional
        The slab's depth [m], > 0 (None: the median block height).
    overhang : float, default 0.0
        How far the slab reaches past the footprint on every side in the plane [m], >= 0.

    Returns
    -------
    blocks : Blocks
        The assembly with the base appended last (weightless).
    base : int
        The base's index (the number of blocks given).

    Raises
    ------
    ValueError
        If ``depth`` is not positive or ``overhang`` is negative (or not finite).

    Examples
    --------
    >>> import masonry_dem as md
    >>> wall = md.running_bond_wall(6, 6, 0.1, 0.2, 0.1, 18e3)
    >>> blocks, base = md.add_base(wall)
    >>> base, blocks.sizes[base].tolist()
    (39, [1.2000000000000002, 0.1, 0.1])
    """
    # checked by name: a NaN overhang would surface as a non-finite corner, a negative one
    # would shrink the base silently
    overhang = positive_scalar("overhang", overhang, strict=False)
    return _add_slab(blocks, depth, below=True, overhang=overhang, unit_weight=0.0)


def add_top_beam(
    blocks: Blocks, depth: float | None = None, unit_weight: float = 0.0
) -> tuple[Blocks, int]:
    """Append a rigid loading beam on top of the assembly; returns the blocks and its index.

    The beam spans the footprint of the assembly and its bottom face touches the highest
    blocks, so real interfaces join it to the wall: the top beam of a shear-wall test, to
    load (a dead :class:`~masonry_dem.PointLoad` or :class:`~masonry_dem.Pressure` on it),
    hold (``Support([beam], ["u2", "w3"])`` in a :class:`~masonry_dem.Stage`) and push by
    displacement (:class:`~masonry_dem.DisplacementControl` of its ``u1``).

    Parameters
    ----------
    blocks : Blocks
        The assembly.
    depth : float, optional
        The beam's depth [m], > 0 (None: the median block height).
    unit_weight : float, default 0.0
        The beam's weight per unit volume [N/m^3], >= 0 (0: weightless).

    Returns
    -------
    blocks : Blocks
        The assembly with the beam appended last.
    beam : int
        The beam's index (the number of blocks given).

    Raises
    ------
    ValueError
        If ``depth`` is not positive or ``unit_weight`` is negative (or not finite).

    Examples
    --------
    >>> import masonry_dem as md
    >>> wall = md.running_bond_wall(6, 6, 0.1, 0.2, 0.1, 18e3)
    >>> blocks, beam = md.add_top_beam(wall, depth=0.2)
    >>> beam, blocks.sizes[beam].round(6).tolist(), round(float(blocks.lower[beam, 1]), 6)
    (39, [1.2, 0.2, 0.1], 0.6)
    """
    unit_weight = positive_scalar("unit_weight", unit_weight, strict=False)
    return _add_slab(blocks, depth, below=False, overhang=0.0, unit_weight=unit_weight)


def _add_slab(
    blocks: Blocks, depth: float | None, below: bool, overhang: float, unit_weight: float
) -> tuple[Blocks, int]:
    """One block over the footprint of ``blocks`` (plus ``overhang`` in the plane), ``depth``
    deep (None: the median block height) under their lowest face or over their highest,
    appended last; the blocks and its index."""
    lo, hi = blocks.lower.min(axis=0), blocks.upper.max(axis=0)
    depth = (
        float(np.median(blocks.sizes[:, 1])) if depth is None else positive_scalar("depth", depth)
    )
    y0, y1 = (lo[1] - depth, lo[1]) if below else (hi[1], hi[1] + depth)
    slab_lo = np.array([lo[0] - overhang, y0, lo[2] - overhang])
    slab_hi = np.array([hi[0] + overhang, y1, hi[2] + overhang])
    slab = Blocks.from_boxes(slab_lo[None], slab_hi[None], unit_weight)
    return Blocks.concatenate(blocks, slab), blocks.count
