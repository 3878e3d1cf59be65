"""Where a wall cracks at collapse: the joints that open in the last increment of a run.

The interface states are not a good map of the mechanism of a dry-jointed wall: a head joint
with no compression is "detached" from the first step, long before anything moves. What
shows the mechanism is the last displacement increment dq = q[-1] - q[-2] of a run that
ended in collapse: the blocks that move, and the joints across which they move apart
(opening) or turn (relative rotation). This module measures that increment and locates the
cracks in it:

* :func:`collapse_mode` - the mechanism the live load drives through the damaged stiffness
  of a step (Eqs. 13-14): crisp even when the last step stopped short of a full mechanism;
* :func:`last_increment`, :func:`out_of_plane` - the increment and its normalised u3 field;
* :func:`joint_motion` - opening, sliding and relative rotation of every interface;
* :func:`row_peaks` - in each row of joints, the one that opens most (a crack path);
* :func:`fit_crack` - a straight crack line fitted through such points (total least squares);
* :func:`opening_by_row` - the largest opening of each row of joints (horizontal hinges);
* :func:`mirror_mismatch` - how far a block field is from symmetric about a vertical axis.

Axes: e1 along the wall (x), e2 up (y), e3 out of plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem._docstrings import SHARED, fill
from masonry_dem.assembly.compatibility import compatibility_matrix
from masonry_dem.model import Model
from masonry_dem.results import History, StepResult

HEAD, BED = 0, 1  # normal axis of the head (vertical) and bed (horizontal) joints


def last_increment(history: History) -> NDArray[np.float64]:
    """(n, 6) displacement increment of the last converged step: the collapse mechanism."""
    if len(history.steps) < 2:
        raise ValueError("the mechanism needs two converged steps; the run has fewer")
    return history.steps[-1].q - history.steps[-2].q


@fill(SHARED)
def collapse_mode(model: Model, step: StepResult, floor: float = 1e-9) -> NDArray[np.float64]:
    """The collapse mechanism at a converged step.

    The displacement field that the live load drives through the damaged stiffness of the
    assembly (Eqs. 13-14 of the paper).

    Each interface keeps the stiffness components its state at ``step`` leaves it (zero
    shear and torsion where it slides, zero bending about a rocking axis, nothing where it is
    detached), plus ``floor`` x its elastic stiffness so the matrix stays regular. At
    collapse this matrix is (nearly) singular along the mechanism, so K_d^-1 F_L is
    dominated by the mechanism the load drives: the blocks that turn and the joints across
    which they do. Unlike the last increment of a run, it does not depend on how close to
    the limit the last step came. Scaled so that the largest translation is 1.

    Parameters
    ----------
    model : Model
        The model the step belongs to.
    step : StepResult
        A converged step with its interface flags (as every solver records them).
    floor : float, default 1e-9
        The fraction of each interface's elastic stiffness kept.

    Returns
    -------
    numpy.ndarray, shape (n, 6)
        The mechanism, its largest block translation 1.

    Raises
    ------
    ValueError
        If the step has no interface flags, or the live load drives no motion.

    Examples
    --------
    %(sliding_block)s
    >>> mode = md.collapse_mode(model, md.pushover(model).last)
    >>> mode[0, :3].round(3).tolist()  # the block slides along e1
    [1.0, 0.0, 0.0]
    """
    from scipy.sparse.linalg import spsolve

    from masonry_dem.assembly.stiffness import Assembly
    from masonry_dem.constitutive.states import stiffness_factors_of_flags

    if step.flags is None:
        raise ValueError("the step has no interface flags: there is no collapse mode")
    asm = Assembly.of(model)
    factors = np.maximum(stiffness_factors_of_flags(step.flags), floor)
    K = asm.stiffness(factors).tocsc()
    x = spsolve(K, model.live.reshape(-1)[asm.free_index])
    q: NDArray[np.float64] = np.zeros(model.n_dofs)
    q[asm.free_index] = x
    q = q.reshape(-1, 6)
    scale = float(np.abs(q[:, :3]).max(initial=0.0))
    if not np.isfinite(scale) or scale == 0:
        raise ValueError("the live load drives no motion: there is no collapse mode")
    return q / scale


def out_of_plane(dq: NDArray[np.float64], blocks: ArrayLike | None = None) -> NDArray[np.float64]:
    """u3 of the increment on ``blocks`` (default: all), divided by its largest magnitude."""
    du = dq[:, 2] if blocks is None else dq[np.asarray(blocks), 2]
    peak = float(np.abs(du).max())
    if peak == 0.0:
        raise ValueError("the increment has no out-of-plane motion")
    return du / peak


@dataclass(frozen=True)
class JointMotion:
    """Per interface, in the increment: ``opening`` the largest normal separation over the
    interface rectangle (negative: the joint closes everywhere), ``sliding`` the tangential
    relative translation at its centre, ``rotation`` the norm of the relative rotation."""

    opening: NDArray[np.float64]
    sliding: NDArray[np.float64]
    rotation: NDArray[np.float64]


def joint_motion(model: Model, dq: NDArray[np.float64]) -> JointMotion:
    """Opening, sliding and relative rotation of every interface for the increment ``dq``."""
    itf = model.interfaces
    d = (compatibility_matrix(model.blocks, itf) @ np.asarray(dq).ravel()).reshape(-1, 6)
    # [d1, d2, dn, delta1, delta2, delta3]: delta1 (about y1) tilts the normal gap along y2
    opening = d[:, 2] + np.abs(d[:, 3]) * itf.l2 / 2 + np.abs(d[:, 4]) * itf.l1 / 2
    return JointMotion(
        opening=opening,
        sliding=np.linalg.norm(d[:, :2], axis=1),
        rotation=np.linalg.norm(d[:, 3:], axis=1),
    )


def between(model: Model, blocks: ArrayLike) -> NDArray[np.bool_]:
    """(m,) mask of the interfaces joining two of ``blocks`` (e.g. the wall, not the base)."""
    inside = np.zeros(model.blocks.count, dtype=bool)
    inside[np.asarray(blocks)] = True
    return inside[model.interfaces.block_i] & inside[model.interfaces.block_j]


def _rows(model: Model, mask: NDArray[np.bool_]) -> list[NDArray[np.intp]]:
    idx = np.flatnonzero(mask)
    y = np.round(model.interfaces.centre[idx, 1], 9)
    return [idx[y == h] for h in np.unique(y)]


def row_peaks(
    model: Model,
    value: NDArray[np.float64],
    mask: NDArray[np.bool_],
    axis: int = BED,
    threshold: float = 0.2,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The crack path through one family of joints.

    Among the interfaces in ``mask`` with normal ``axis`` (``BED``: horizontal joints,
    ``HEAD``: vertical ones), take in each row (same height) the one where ``value`` is
    largest, and keep it if that peak is at least ``threshold`` times the largest of all.
    Returns the (k, 2) in-plane points (x, y) of those joints and their values (the weights
    of :func:`fit_crack`). A field with no opening at all gives no points.
    """
    value = np.asarray(value, dtype=float)
    fam = mask & (model.interfaces.axis == axis)
    if not fam.any():
        return np.empty((0, 2)), np.empty(0)
    top = value[fam].max()
    if top <= 0.0:
        return np.empty((0, 2)), np.empty(0)
    pts, w = [], []
    for row in _rows(model, fam):
        k = row[np.argmax(value[row])]
        if value[k] >= threshold * top:
            pts.append(model.interfaces.centre[k, :2])
            w.append(value[k])
    return np.reshape(pts, (-1, 2)), np.asarray(w)


def opening_by_row(
    model: Model, value: NDArray[np.float64], mask: NDArray[np.bool_], axis: int = BED
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Heights of the rows of joints (normal ``axis``) in ``mask`` and the largest ``value``
    in each: a horizontal hinge is the row whose every joint opens, far above the others."""
    rows = _rows(model, mask & (model.interfaces.axis == axis))
    heights = np.array([model.interfaces.centre[r[0], 1] for r in rows])
    return heights, np.array([np.max(value[r]) for r in rows])


@dataclass(frozen=True)
class CrackLine:
    """A straight crack through weighted points: ``centre`` (x, y), unit ``direction``,
    ``angle`` in degrees from the horizontal in [0, 180) (0 horizontal, 90 vertical, below 90
    rising to the right, above 90 falling to the right), ``rms`` distance of the points from
    the line, and the ``y_range`` (lowest, highest) of the points."""

    centre: NDArray[np.float64]
    direction: NDArray[np.float64]
    angle: float
    rms: float
    y_range: tuple[float, float]
    count: int

    def x_at(self, y: float) -> float:
        """x of the line at height y (the line must not be horizontal)."""
        if abs(self.direction[1]) < 1e-12:
            raise ValueError("a horizontal crack line has no single x at a height")
        return float(self.centre[0] + (y - self.centre[1]) * self.direction[0] / self.direction[1])

    def distance(self, point: ArrayLike) -> float:
        """Distance of an in-plane point (x, y) from the line."""
        r = np.asarray(point, dtype=float) - self.centre
        return float(abs(r[0] * self.direction[1] - r[1] * self.direction[0]))


def fit_crack(points: ArrayLike, weights: ArrayLike | None = None) -> CrackLine:
    """Weighted total-least-squares line through in-plane points (vertical lines allowed)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if pts.shape[0] < 2:
        raise ValueError(f"a crack line needs at least 2 points, got {pts.shape[0]}")
    w = np.ones(len(pts)) if weights is None else np.asarray(weights, dtype=float)
    w = w / w.sum()
    centre = w @ pts
    r = pts - centre
    cov = (r * w[:, None]).T @ r
    vals, vecs = np.linalg.eigh(cov)
    direction = vecs[:, 1]
    if direction[1] < 0 or (direction[1] == 0 and direction[0] < 0):
        direction = -direction  # pointing up (or right)
    normal = np.array([-direction[1], direction[0]])
    angle = float(np.degrees(np.arctan2(direction[1], direction[0]))) % 180.0
    rms = float(np.sqrt(np.average((r @ normal) ** 2, weights=w)))
    return CrackLine(
        centre, direction, angle, rms, (float(pts[:, 1].min()), float(pts[:, 1].max())), len(pts)
    )


def mirror_mismatch(
    centres: NDArray[np.float64], field: NDArray[np.float64], axis_x: float
) -> float:
    """Largest |field(block) - field(mirror block)| about the vertical line x = axis_x, the
    mirror block being the one nearest to the reflected centre (inf if none lies within a
    millimetre: the layout itself is not symmetric)."""
    c = np.asarray(centres, dtype=float)[:, :2]
    f = np.asarray(field, dtype=float)
    mirrored = c.copy()
    mirrored[:, 0] = 2.0 * axis_x - c[:, 0]
    d = np.linalg.norm(mirrored[:, None, :] - c[None, :, :], axis=2)
    j = np.argmin(d, axis=1)
    if np.any(d[np.arange(len(c)), j] > 1e-3):
        return float("inf")
    return float(np.max(np.abs(f - f[j])))


__all__ = [
    "BED",
    "HEAD",
    "CrackLine",
    "JointMotion",
    "between",
    "fit_crack",
    "joint_motion",
    "last_increment",
    "mirror_mismatch",
    "opening_by_row",
    "out_of_plane",
    "row_peaks",
]
