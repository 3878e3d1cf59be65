"""Assertions on the crack pattern of a collapse increment, shared by test_mechanisms.py and
its unit tests (which feed them wrong fields to show they can fail).

Every check takes the model, the wall block indices and the increment dq (n, 6), measures the
joints with masonry_dem.mechanism and raises AssertionError with the measured numbers.
Lengths are in units of the wall's own block length b and course height a, so one tolerance
serves the Orduna-Lourenco, Restrepo Velez and Chee Liang walls alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from masonry_dem import mechanism as mech
from masonry_dem.model import Model

# bed-joint rows whose most-opened joint reaches this share of the largest bed-joint opening
# make the crack path; below it a row is elastic noise (the dry joints all deform a little)
ROW_THRESHOLD = 0.2


@dataclass(frozen=True)
class Wall:
    """In-plane extent of the wall blocks and their typical sizes."""

    x0: float
    x1: float
    y0: float
    y1: float
    b: float  # block length along e1
    a: float  # course height

    @property
    def length(self) -> float:
        return self.x1 - self.x0

    @property
    def height(self) -> float:
        return self.y1 - self.y0

    @property
    def axis(self) -> float:
        return (self.x0 + self.x1) / 2


def wall_of(model: Model, wall: np.ndarray) -> Wall:
    blocks = model.blocks.subset(np.asarray(wall))
    return Wall(
        float(blocks.lower[:, 0].min()),
        float(blocks.upper[:, 0].max()),
        float(blocks.lower[:, 1].min()),
        float(blocks.upper[:, 1].max()),
        float(np.max(blocks.sizes[:, 0])),
        float(np.median(blocks.sizes[:, 1])),
    )


def bed_crack(model: Model, wall: np.ndarray, dq: np.ndarray, region=None) -> mech.CrackLine:
    """The crack line through the most-opened bed joint of each row of the wall joints (in
    ``region``, an extra (m,) mask, if given). Fails if fewer than 3 rows open."""
    mask = mech.between(model, wall)
    if region is not None:
        mask &= region
    opening = mech.joint_motion(model, dq).opening
    pts, w = mech.row_peaks(model, opening, mask, mech.BED, ROW_THRESHOLD)
    assert len(pts) >= 3, f"only {len(pts)} rows of bed joints open: no crack line"
    return mech.fit_crack(pts, w)


def assert_diagonal_from_free_corner(model: Model, wall: np.ndarray, dq: np.ndarray) -> None:
    """Wall held on its left edge: the bed-joint crack runs from the lower part of the free
    (right) edge up to the supported edge near the top.

    - the line falls towards the free edge at 20-83 degrees below the horizontal (angle
      97-160): a horizontal hinge (0/180) and a vertical crack (90) both fail;
    - its lowest point is in the lower 35 % of the height and in the free half of the length;
    - its highest point is in the upper 20 % and within the third of the length by the support;
    - the rows' peaks lie within 0.75 block length of the line (rms): one straight crack. A
      stepped crack in running bond moves half a block per course and each row's peak is
      the one joint that opens most, so the peaks of one crack scatter by about half a block
      on either side of the fitted line; two cracks or a scattered field give more than a
      block.
    """
    g = wall_of(model, wall)
    line = bed_crack(model, wall, dq)
    lo, hi = line.y_range
    info = f"angle {line.angle:.1f}, y {lo:.3f}-{hi:.3f}, rms {line.rms:.4f}"
    assert 97.0 <= line.angle <= 160.0, f"not a diagonal falling to the free edge: {info}"
    assert lo - g.y0 <= 0.35 * g.height, f"the crack does not reach the lower part: {info}"
    assert hi - g.y0 >= 0.80 * g.height, f"the crack does not reach the top: {info}"
    x_lo, x_hi = line.x_at(lo), line.x_at(hi)
    assert x_lo - g.x0 >= 0.5 * g.length, f"lower end x={x_lo:.3f} not by the free edge"
    assert x_hi - g.x0 <= g.length / 3, f"upper end x={x_hi:.3f} not by the support"
    assert line.rms <= 0.75 * g.b, f"the peaks scatter about the line: {info}"


def assert_free_top_corner_moves_most(model: Model, wall: np.ndarray, dq: np.ndarray) -> None:
    """The block that moves most out of plane is at the free top corner: in the top two courses
    (running bond ends every other course with a half block, whose centre sits further out)
    and within one block length of the free (right) end."""
    g = wall_of(model, wall)
    du = mech.out_of_plane(dq, wall)
    c = model.blocks.centres[np.asarray(wall)]
    k = int(np.argmax(np.abs(du)))
    assert c[k, 1] >= g.y1 - 2 * g.a, f"largest motion at height {c[k, 1]:.3f}, not the top"
    assert c[k, 0] >= g.x1 - g.b, f"largest motion at x={c[k, 0]:.3f}, not the free end"


def assert_still_below_diagonal(model: Model, wall: np.ndarray, dq: np.ndarray, tol=0.2) -> None:
    """The blocks below the crack line on the support's half (x < L/2) barely move:
    |u3| <= ``tol`` of the largest (the part below the diagonal stays on the support)."""
    g = wall_of(model, wall)
    line = bed_crack(model, wall, dq)
    du = mech.out_of_plane(dq, wall)
    c = model.blocks.centres[np.asarray(wall)]
    # below the line: on the side of the lower-left corner
    d = line.direction

    def side(p):
        r = np.asarray(p) - line.centre
        return np.sign(d[0] * r[..., 1] - d[1] * r[..., 0])

    below = (side(c[:, :2]) == side([g.x0, g.y0])) & (c[:, 0] < g.axis)
    assert below.sum() >= 3, "no blocks below the crack near the support"
    worst = float(np.abs(du[below]).max())
    assert worst <= tol, f"a block below the diagonal moves {worst:.2f} of the largest"


def assert_vertical_crack_on_axis(model: Model, wall: np.ndarray, dq: np.ndarray) -> None:
    """Walls held on both edges (or free at the top): in at least 60 % of the rows of head
    joints in the upper half that open (peak >= 20 % of the largest head-joint opening), the
    most-opened head joint lies within one block length of the axis."""
    g = wall_of(model, wall)
    mask = mech.between(model, wall) & (model.interfaces.centre[:, 1] > g.y0 + g.height / 2)
    opening = mech.joint_motion(model, dq).opening
    pts, _ = mech.row_peaks(model, opening, mask, mech.HEAD, ROW_THRESHOLD)
    assert len(pts) >= 3, f"only {len(pts)} rows of head joints open in the upper half"
    on_axis = np.abs(pts[:, 0] - g.axis) <= g.b
    assert on_axis.mean() >= 0.6, (
        f"{on_axis.sum()} of {len(pts)} rows open on the axis; peaks at x={pts[:, 0].round(3)}"
    )


def assert_diagonals_down_to_axis(model: Model, wall: np.ndarray, dq: np.ndarray) -> None:
    """Held on both edges: in each half the bed-joint crack runs from the upper part of the
    held edge down towards the axis: left half falling to the right (angle 97-160), right half
    its mirror (20-83), the two angles mirror images within 5 degrees."""
    g = wall_of(model, wall)
    x = model.interfaces.centre[:, 0]
    left = bed_crack(model, wall, dq, x < g.axis)
    right = bed_crack(model, wall, dq, x > g.axis)
    assert 97.0 <= left.angle <= 160.0, f"left half: angle {left.angle:.1f}"
    assert 20.0 <= right.angle <= 83.0, f"right half: angle {right.angle:.1f}"
    assert abs(left.angle + right.angle - 180.0) <= 5.0, (left.angle, right.angle)


def assert_symmetric(model: Model, wall: np.ndarray, dq: np.ndarray, tol: float = 0.02) -> None:
    """u3 of every block equals that of its mirror block about the axis within ``tol`` of the
    largest (the model and the loads are symmetric; 2 % leaves room for round-off only)."""
    g = wall_of(model, wall)
    du = mech.out_of_plane(dq, wall)
    c = model.blocks.centres[np.asarray(wall)]
    mismatch = mech.mirror_mismatch(c, du, g.axis)
    assert mismatch <= tol, f"mirror mismatch {mismatch:.3f} of the largest motion"


def assert_diagonals_from_corners(model: Model, wall: np.ndarray, dq: np.ndarray) -> None:
    """Supported on four sides: in each quadrant the bed-joint crack is a diagonal (20-70 or
    110-160 degrees, rising towards the centre) that passes within 20 % of the quadrant's
    diagonal from its outer corner and within 10 % of it from the panel centre."""
    g = wall_of(model, wall)
    x, y = model.interfaces.centre[:, 0], model.interfaces.centre[:, 1]
    centre = np.array([g.axis, g.y0 + g.height / 2])
    half_diag = float(np.hypot(g.length / 2, g.height / 2))
    for right in (False, True):
        for top in (False, True):
            region = ((x > centre[0]) == right) & ((y > centre[1]) == top)
            line = bed_crack(model, wall, dq, region)
            corner = (g.x1 if right else g.x0, g.y1 if top else g.y0)
            rising = right == top  # lower-left and upper-right diagonals rise to the right
            lo, hi = (20.0, 70.0) if rising else (110.0, 160.0)
            where = f"quadrant {'right' if right else 'left'}-{'top' if top else 'bottom'}"
            assert lo <= line.angle <= hi, f"{where}: angle {line.angle:.1f}"
            assert line.distance(corner) <= 0.2 * half_diag, f"{where}: misses the corner"
            assert line.distance(centre) <= 0.1 * half_diag, f"{where}: misses the centre"


def assert_peak_near(model, wall, dq, point, dx: float, dy: float) -> None:
    """The block that moves most out of plane lies within dx, dy of ``point`` (x, y)."""
    du = mech.out_of_plane(dq, wall)
    c = model.blocks.centres[np.asarray(wall)]
    k = int(np.argmax(np.abs(du)))
    assert abs(c[k, 0] - point[0]) <= dx and abs(c[k, 1] - point[1]) <= dy, (
        f"largest motion at {c[k, :2].round(3)}, expected near {np.round(point, 3)}"
    )
