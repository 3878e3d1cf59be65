"""Walls that meet: L, T and U plans and a closed four-wall box, in running bond, with the
courses interlocked at every corner (alternate courses run through).

Plan axes: e1 along the facade, e3 across it (the facade's outer face is z = s, the others
stand behind it, towards -e3, so a live load towards +e3 pulls the facade away from them, as
on a tilt table that overturns the facade), e2 up. The facade is the wall of
:func:`~masonry_dem.geometry.builders.running_bond_wall`: ``blocks_along_length`` x b long
outside to outside, x in [0, n b], z in [0, s]. A return wall of ``return_blocks`` = m is m b
long, measured from the facade's outer face (z from s down to s - m b).

Every straight wall is a *run* of blocks along its axis, described by its distance d from the
outer corner where it starts. Course by course a run covers [d0, d1] and is cut at the bond
points d = (j + phase / 2) b: phase 0 puts whole blocks from the corner, phase 1 shifts the
head joints half a block (running bond). At a corner one wall runs through the corner square
(d0 = 0 there) and the other butts against it (d0 = s); the next course swaps them, which is
the interlock. A piece shorter than 0.3 block is not cut: it stays with its neighbour
(a bricklayer lays a closer, not a sliver): pieces are between 0.3 b and 1.3 b long. Bricks
with b = 2 s give whole blocks at a corner; at a T junction of such bricks the quarter-block
pieces beside the cross wall are taken into their neighbours (a threshold of b / 4 would
leave that to round-off).

Which walls run through: L, U and T walls run the facade through their corners in the even
courses (0, 2, ...) and the returns (or the cross wall) in the odd ones, so the U is mirror
symmetric about x = n b / 2. The box runs each wall through the corner where it starts (walking
round the plan anticlockwise seen from above: front, right, back, left) in the even courses
and through the corner where it ends in the odd ones; with as many blocks along the depth as
along the length it is then symmetric under a quarter turn about its vertical axis.

``facade_openings`` are cut out of the facade alone; with ``lintels`` the jambs are
straightened and a lintel laid over each opening, as in a plain wall, in the facade alone: a
lintel stays between the corners (an opening too near one is refused, named). The lintels
are part of the facade.

The parts are found back by :func:`masonry_dem.geometry.selectors.part` (``facade``,
``return:left``, ``return:right``, ``back``, ``cross``, ``corner:left``, ...).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import KW_ONLY, dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from masonry_dem._docstrings import fill, filled
from masonry_dem._parameters import function_of
from masonry_dem._validation import plain, positive_scalar
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import DOCS as BUILDER_DOCS
from masonry_dem.geometry.builders import (
    _Along,
    _count,
    _Courses,
    _Unit,
    _weight,
    checked_opening,
    cut_openings,
    openings_with_lintels,
)

SHORTEST_PIECE = 0.3  # in block lengths: a shorter piece stays with its neighbour

Corner = Literal["left", "right"]
CORNERS: tuple[str, ...] = get_args(Corner)


@dataclass(frozen=True)
class _Run:
    """One straight wall. ``axis`` 0 (along e1) or 2 (along e3); d = 0 at ``origin`` on that
    axis, growing towards ``sense`` x e[axis]; ``band``: the wall's thickness interval on
    the other horizontal axis; ``even``, ``odd``: (d0, d1, phase) of the even and odd courses."""

    axis: int
    origin: float
    sense: int
    band: tuple[float, float]
    even: tuple[float, float, int]
    odd: tuple[float, float, int]


def _pieces(d0: float, d1: float, phase: int, pitch: float) -> NDArray[np.float64]:
    """Cut points of one course of a run, [d0, ..., d1]: the bond points strictly inside,
    at least ``SHORTEST_PIECE`` blocks from either end."""
    shortest = SHORTEST_PIECE * pitch
    j = np.arange(np.floor(d0 / pitch) - 1, np.ceil(d1 / pitch) + 2)
    cuts = (j + 0.5 * phase) * pitch
    cuts = cuts[(cuts >= d0 + shortest) & (cuts <= d1 - shortest)]
    return np.concatenate([[d0], cuts, [d1]])


def _run_boxes(
    run: _Run, courses: int, pitch: float, course_pitch: float
) -> tuple[list[NDArray[np.float64]], list[NDArray[np.float64]]]:
    """Lower and upper corners of every block of a run, all courses (course-major)."""
    k = np.arange(courses)
    lowers: list[NDArray[np.float64]] = []
    uppers: list[NDArray[np.float64]] = []
    for parity, (d0, d1, phase) in enumerate((run.even, run.odd)):
        ks = k[k % 2 == parity]
        if ks.size == 0 or d1 - d0 <= 0:
            continue
        cut = _pieces(d0, d1, phase, pitch)
        a_lo, a_hi = cut[:-1], cut[1:]
        p = a_lo.size
        # positions along the axis, whichever way d runs
        x_lo = run.origin + run.sense * np.where(run.sense > 0, a_lo, a_hi)
        x_hi = run.origin + run.sense * np.where(run.sense > 0, a_hi, a_lo)
        lo = np.zeros((ks.size, p, 3))
        hi = np.zeros((ks.size, p, 3))
        other = 2 - run.axis
        lo[:, :, run.axis], hi[:, :, run.axis] = x_lo, x_hi
        lo[:, :, other], hi[:, :, other] = run.band
        lo[:, :, 1] = (ks * course_pitch)[:, None]
        hi[:, :, 1] = ((ks + 1) * course_pitch)[:, None]
        lowers.append(lo.reshape(-1, 3))
        uppers.append(hi.reshape(-1, 3))
    return lowers, uppers


def _assemble(
    runs: list[_Run], courses: int, pitch: float, course_pitch: float, gamma: float
) -> Blocks:
    lowers: list[NDArray[np.float64]] = []
    uppers: list[NDArray[np.float64]] = []
    for run in runs:
        run_lo, run_hi = _run_boxes(run, courses, pitch, course_pitch)
        lowers += run_lo
        uppers += run_hi
    lo, hi = np.vstack(lowers), np.vstack(uppers)
    order = np.lexsort((lo[:, 2], lo[:, 0], lo[:, 1]))  # course by course, then along e1
    return Blocks.from_boxes(lo[order], hi[order], gamma)


def _common(
    blocks_along_length: int,
    courses: int,
    size: tuple[float, float, float],
    unit_weight: float | None,
    joint: float,
) -> tuple[int, int, float, float, float, float]:
    """Counts, course pitch, block pitch, thickness and unit weight of a plan, validated."""
    n = _count("blocks_along_length", blocks_along_length)
    nc = _count("courses", courses)
    a, b, s = size
    e = positive_scalar("joint", joint, strict=False)
    gamma = _weight(unit_weight)
    pitch = b + e
    if n * pitch <= 2 * s + 2 * SHORTEST_PIECE * pitch:
        # the corners' squares would meet: no facade between them
        raise ValueError(
            f"blocks_along_length = {n} gives a facade {n * pitch:g} m long, too short for "
            f"two corners of thickness s = {s:g} m: it needs more than "
            f"{2 * s + 2 * SHORTEST_PIECE * pitch:g} m"
        )
    return n, nc, a + e, pitch, s, gamma


def _returns(m: int, pitch: float, s: float, band: tuple[float, float]) -> _Run:
    """A return (or cross) wall of m blocks behind the facade: through the corner in the odd
    courses, butting against the facade's back face in the even ones."""
    depth = m * pitch
    if depth <= s + SHORTEST_PIECE * pitch:
        raise ValueError(
            f"return_blocks = {m} gives a return wall {depth:g} m long, no longer than the "
            f"facade is thick (s = {s:g} m): it must reach behind the facade"
        )
    return _Run(2, s, -1, band, (s, depth, 1), (0.0, depth, 0))


def _facade_openings(
    blocks: Blocks,
    openings: Sequence[Sequence[float]] | None,
    s: float,
    lintels: bool = False,
) -> Blocks:
    """Remove the facade blocks (z within [0, s]) whose centre lies inside an opening
    (x_min, y_min, x_max, y_max); the walls behind the facade are left whole. With
    ``lintels``, the openings are built as in a plain wall (straight jambs, a lintel over
    each: :func:`~masonry_dem.geometry.builders.openings_with_lintels`) in the facade alone
    (:func:`_facade_with_lintels`)."""
    if openings is None or len(openings) == 0:
        return blocks
    facade = blocks.lower[:, 2] >= -1e-9 * s
    if lintels:
        return _facade_with_lintels(blocks, openings, facade)
    return cut_openings(blocks, openings, among=facade, field="facade_openings")


def _facade_with_lintels(
    blocks: Blocks, openings: Sequence[Sequence[float]], facade: NDArray[np.bool_]
) -> Blocks:
    """The facade's openings with straight jambs and a lintel over each, built in the facade
    alone; the walls behind it are left whole.

    A lintel bears on a pier of the facade at each side of its opening. Where another wall
    meets the facade (a corner square, the junction of a T's cross wall: the plan extent of
    the blocks of that wall that reach the facade) the courses interlock, and a lintel cut
    there would take in blocks of the other wall's bond, so an opening that crosses such a
    junction or reaches an end of the facade, or whose lintel would reach into a junction, is
    refused, named. The blocks come back sorted course by course, then along e1, as the
    plans assemble them."""
    field = "facade_openings"
    rects = [checked_opening(field, k, rect) for k, rect in enumerate(openings)]
    named = [f"{field}[{k}] = {plain([round(v, 9) for v in rect])}" for k, rect in enumerate(rects)]
    front = blocks.subset(np.flatnonzero(facade))
    behind = blocks.subset(np.flatnonzero(~facade))
    course = float(np.median(front.sizes[:, 1]))
    tol = 1e-6 * course
    (x_lo, y_lo, _), (x_hi, y_hi, _) = front.lower.min(axis=0), front.upper.max(axis=0)
    meets = behind.upper[:, 2] >= -tol  # blocks of other walls that reach the facade
    junctions = np.unique(np.stack([behind.lower[meets, 0], behind.upper[meets, 0]], 1), axis=0)

    def junction_across(x0: float, x1: float) -> str | None:
        across = (junctions[:, 1] > x0 + tol) & (junctions[:, 0] < x1 - tol)
        if not across.any():
            return None
        j0, j1 = junctions[np.argmax(across)]
        return f"x in [{j0:.9g}, {j1:.9g}]"

    for k, (x0, y0, x1, y1) in enumerate(rects):
        if x0 < x_lo - tol or x1 > x_hi + tol or y0 < y_lo - tol or y1 > y_hi + tol:
            raise ValueError(
                f"{named[k]} reaches outside the facade: openings with lintels lie within "
                f"x in [{x_lo:.9g}, {x_hi:.9g}], y in [{y_lo:.9g}, {y_hi:.9g}] m"
            )
        if x0 <= x_lo + tol or x1 >= x_hi - tol:
            raise ValueError(
                f"{named[k]} reaches the facade's end (x in [{x_lo:.9g}, {x_hi:.9g}]): a "
                "lintel over it would bear on one pier only"
            )
        where = junction_across(x0, x1)
        if where is not None:
            raise ValueError(
                f"{named[k]} crosses the corner at {where}, where "
                "another wall meets the facade: openings with lintels lie between the corners"
            )
    cut = openings_with_lintels(front, rects, course, field=field)
    for k, (x0, _, x1, y1) in enumerate(rects):
        over = (
            (np.abs(cut.lower[:, 1] - y1) < tol)
            & (cut.upper[:, 0] > x0 + tol)
            & (cut.lower[:, 0] < x1 - tol)
        )
        if not over.any():
            continue  # the opening reaches the top of the wall: no lintel
        lx0, lx1 = float(cut.lower[over, 0].min()), float(cut.upper[over, 0].max())
        span = f"x in [{lx0:.9g}, {lx1:.9g}]"
        where = junction_across(lx0, lx1)
        if where is not None:
            raise ValueError(
                f"{named[k]}: its lintel ({span}, the blocks of the "
                f"course over it) would reach into the corner at {where}; move the opening "
                "further from the corner"
            )
    both = Blocks.concatenate(cut, behind)
    lo = both.lower
    return both.subset(np.lexsort((lo[:, 2], lo[:, 0], lo[:, 1])))


#: the parameters and the Returns the plans share, filled into their docstrings
#: (:func:`masonry_dem._docstrings.fill`)
DOCS: dict[str, str] = {
    "facade": """
        blocks_along_length : int
            n, the facade's length in blocks (n b outside to outside), 1 to 10^4; long enough
            for its corners.
        %(courses)s
        %(unit)s
    """,
    "return_blocks": """
        return_blocks : int, default 4
            m, the return wall's length in blocks (m b from the facade's outer face), 1 to
            10^4, longer than the facade is thick.
    """,
    "plan_keywords": """
        %(letters)s
        joint : float, default 0.0, keyword-only
            The mortar joint thickness [m], >= 0, included in the blocks.
        facade_openings : sequence of (x_min, y_min, x_max, y_max), optional, keyword-only
            Rectangles cut out of the facade alone [m].
        lintels : bool, default False, keyword-only
            Straight jambs and a lintel over each facade opening (a dry wall cannot stand
            without), within the facade, between the corners.
    """,
    "plan_returns": """
        Returns
        -------
        Blocks
            The walls' blocks, course by course from the bottom; the parts are found back by
            :func:`masonry_dem.geometry.selectors.part`.

        Raises
        ------
        ValueError
            If a count, a size or ``unit_weight`` is out of range, the facade is too short
            for its corners or a return wall does not reach behind the facade, or an opening
            is refused (it removes no block, or with ``lintels`` it reaches outside the
            facade, its end or a corner).
    """,
}
DOCS = {key: filled(text, BUILDER_DOCS) or "" for key, text in DOCS.items()}


@dataclass(frozen=True)
class _Plan(_Unit, _Courses, _Along):
    """The parameters every plan shares (the facade's, the unit's, ``joint`` and the
    ``facade_openings`` and their ``lintels``); a plan gives its runs of blocks."""

    _: KW_ONLY
    joint: float = 0.0
    facade_openings: Sequence[Sequence[float]] | None = None
    lintels: bool = False

    def __call__(self) -> Blocks:
        if not isinstance(self.lintels, (bool, np.bool_)):
            raise ValueError(f"lintels must be true or false, got {plain(self.lintels)}")
        size = self.size()
        n, nc, cp, p, s, gamma = _common(
            self.blocks_along_length, self.courses, size, self.unit_weight, self.joint
        )
        blocks = _assemble(self.runs(n * p, p, s), nc, p, cp, gamma)
        placed = self.arranged(blocks, n * p, gamma)
        return _facade_openings(placed, self.facade_openings, s, self.lintels)

    def runs(self, length: float, pitch: float, s: float) -> list[_Run]:
        """The runs of the plan, its facade ``length`` long (outside to outside)."""
        raise NotImplementedError

    def arranged(self, blocks: Blocks, length: float, gamma: float) -> Blocks:
        """The blocks of the runs as the plan places them (as assembled by default)."""
        return blocks


@fill(DOCS)
@dataclass(frozen=True)
class _LWall(_Plan):
    """A facade with one return wall at one corner, interlocked there.

    The return wall stands at ``corner`` (``left``: x = 0, or ``right``); the other end of
    the facade is straight, as in a running-bond wall.
    ``facade_openings``: (x_min, y_min, x_max, y_max) rectangles cut out of the facade;
    ``lintels``: straight jambs and a lintel over each (a dry wall cannot stand without).

    Parameters
    ----------
    %(facade)s
    %(return_blocks)s
    corner : {"left", "right"}, default "left"
        Where the return wall stands: x = 0 (``left``) or x = n b (``right``).
    %(plan_keywords)s

    %(plan_returns)s
        Or if ``corner`` is not one of the two.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.l_wall(6, 4, 0.1, 0.2, 0.1, 18e3).count
    40
    >>> md.l_wall(6, 4, 0.1, 0.2, 0.1, 18e3, corner="right",
    ...           facade_openings=[(0.4, 0.1, 0.8, 0.3)], lintels=True).count
    35
    """

    return_blocks: int = 4
    corner: Corner = "left"

    def runs(self, length: float, pitch: float, s: float) -> list[_Run]:
        m = _count("return_blocks", self.return_blocks)
        if self.corner not in CORNERS:
            raise ValueError(f"corner must be one of {CORNERS}, got {self.corner!r}")
        facade = _Run(0, 0.0, 1, (0.0, s), (0.0, length, 0), (s, length, 1))
        return [facade, _returns(m, pitch, s, (0.0, s))]

    def arranged(self, blocks: Blocks, length: float, gamma: float) -> Blocks:
        if self.corner == "left":
            return blocks
        # the mirror image about the facade's middle
        lo, hi = blocks.lower.copy(), blocks.upper.copy()
        lo[:, 0], hi[:, 0] = length - blocks.upper[:, 0], length - blocks.lower[:, 0]
        order = np.lexsort((lo[:, 2], lo[:, 0], lo[:, 1]))
        return Blocks.from_boxes(lo[order], hi[order], gamma)


@fill(DOCS)
@dataclass(frozen=True)
class _UWall(_Plan):
    """A facade between two return walls, interlocked at both corners.

    The return walls are ``return_blocks`` blocks long; the plan is mirror symmetric about
    x = n b / 2.

    Parameters
    ----------
    %(facade)s
    %(return_blocks)s
    %(plan_keywords)s

    %(plan_returns)s

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.u_wall(6, 4, 0.1, 0.2, 0.1, 18e3).count
    54
    """

    return_blocks: int = 4

    def runs(self, length: float, pitch: float, s: float) -> list[_Run]:
        m = _count("return_blocks", self.return_blocks)
        facade = _Run(0, 0.0, 1, (0.0, s), (0.0, length, 0), (s, length - s, 1))
        left = _returns(m, pitch, s, (0.0, s))
        right = _returns(m, pitch, s, (length - s, length))
        return [facade, left, right]


@fill(DOCS)
@dataclass(frozen=True)
class _TWall(_Plan):
    """A facade with a cross wall behind it.

    The cross wall, ``return_blocks`` blocks long, is centred at x = ``cross_at`` (default:
    the facade's middle); it runs through the facade in the odd courses (its end block shows
    in the outer face) and butts against the facade's back in the even ones. Both ends of
    the facade are straight.

    Parameters
    ----------
    %(facade)s
    %(return_blocks)s
    cross_at : float, optional
        x of the cross wall's centre line [m] (None: the facade's middle); the cross wall
        must stay 0.3 block from the facade's ends.
    %(plan_keywords)s

    %(plan_returns)s
        Or if ``cross_at`` puts the cross wall within 0.3 block of the facade's ends.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.t_wall(6, 4, 0.1, 0.2, 0.1, 18e3).count
    40
    """

    return_blocks: int = 4
    cross_at: float | None = None

    def runs(self, length: float, pitch: float, s: float) -> list[_Run]:
        m = _count("return_blocks", self.return_blocks)
        xc = length / 2 if self.cross_at is None else positive_scalar("cross_at", self.cross_at)
        x0, x1 = xc - s / 2, xc + s / 2
        shortest = SHORTEST_PIECE * pitch
        if x0 < shortest or x1 > length - shortest:
            raise ValueError(
                f"cross_at = {xc:g} puts the cross wall within 0.3 block of the facade's "
                f"ends; allowed range [{s / 2 + shortest:g}, {length - s / 2 - shortest:g}] m"
            )
        facade = _Run(0, 0.0, 1, (0.0, s), (0.0, length, 0), (0.0, x0, 1))
        facade_right = _Run(0, 0.0, 1, (0.0, s), (0.0, 0.0, 0), (x1, length, 1))
        return [facade, facade_right, _returns(m, pitch, s, (x0, x1))]


@fill(DOCS)
@dataclass(frozen=True)
class _BoxWall(_Plan):
    """A closed box of four walls.

    The box measures n b by m b outside (``blocks_along_depth`` = m, default
    n), the front wall (the facade) at z in [0, s], the back wall at z in [s - m b, 2 s - m b].
    Each wall runs through the corner where it starts (anticlockwise from above) in the even
    courses and through the one where it ends in the odd courses: a square box (m = n) is
    the same seen from each side.

    Parameters
    ----------
    %(facade)s
    blocks_along_depth : int, optional
        m, the box's depth in blocks (None: n, a square box); it must leave a side wall
        between the corners.
    %(plan_keywords)s

    %(plan_returns)s
        Or if ``blocks_along_depth`` leaves no side wall between the corners.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.box_wall(6, 4, 0.1, 0.2, 0.1, 18e3).count
    96
    """

    blocks_along_depth: int | None = None

    def runs(self, length: float, pitch: float, s: float) -> list[_Run]:
        lx, lz = length, length  # square unless a depth is given
        if self.blocks_along_depth is not None:
            m = _count("blocks_along_depth", self.blocks_along_depth)
            lz = m * pitch
            if lz <= 2 * s + 2 * SHORTEST_PIECE * pitch:
                raise ValueError(
                    f"blocks_along_depth = {m} leaves no side wall between the corners"
                )
        back = s - lz  # z of the back wall's outer face

        def run(
            axis: int, origin: float, sense: int, band: tuple[float, float], side: float
        ) -> _Run:
            return _Run(axis, origin, sense, band, (0.0, side - s, 0), (s, side, 1))

        return [
            run(0, 0.0, 1, (0.0, s), lx),  # front, from the front-left corner
            run(2, s, -1, (lx - s, lx), lz),  # right, from the front-right corner
            run(0, lx, -1, (back, back + s), lx),  # back, from the back-right corner
            run(2, back, 1, (0.0, s), lz),  # left, from the back-left corner
        ]


l_wall = function_of(_LWall)
u_wall = function_of(_UWall)
t_wall = function_of(_TWall)
box_wall = function_of(_BoxWall)


__all__ = ["box_wall", "l_wall", "t_wall", "u_wall"]
