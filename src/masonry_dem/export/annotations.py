"""What makes a results picture explain itself without us: an axes triad (e1 along the wall,
e2 up, e3 out of plane), a length scale in metres, the direction of the live load (one arrow,
the resultant of the live forces the results record), marks on the supported blocks (which
translations a support holds), and a title over the legend saying what its colours measure.

Everything is derived from the results being drawn (the blocks' corners, ``restrained`` and
``live_load`` cell data of the blocks VTU) and sized from the wall (its largest dimension and
its median smallest block dimension): no constant belongs to one wall. The caption line (case,
lambda, status, displacement amplification) is written by :mod:`masonry_dem.export.render`.

All marks of one kind are one mesh built with numpy (a cone template replicated), never a
Python loop over blocks.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: colour of the support marks and of the load arrow (RGB 0-255): near black, far from every
#: damage and mechanism colour
MARK_COLOUR = (25, 25, 25)
LOAD_COLOUR = (0, 110, 130)
#: viewport of the axes triad (x0, y0, x1, y1), normalised, in the column right of the wall
TRIAD_VIEWPORT = (0.82, 0.56, 0.99, 0.84)
#: support mark (cone) height as a fraction of the median smallest block dimension
MARK_SIZE = 0.45
#: load arrow length and the gap between it and the wall's top, fractions of the wall size
ARROW_LENGTH = 0.2
ARROW_GAP = 0.06
#: the length scale is the roundest length (1, 2 or 5 x 10^k m) at most this share of the
#: wall's largest dimension (in a side view it may overhang the thickness: it stays readable)
SCALE_BAR_SHARE = 0.25
#: the longest row of marks under a fully held block
MAX_MARKS_PER_BLOCK = 15

_AXIS_NAMES = ("e1", "e2", "e3")


def nice_length(limit: float) -> float:
    """The largest 1, 2 or 5 x 10^k not above ``limit`` (> 0)."""
    if not (limit > 0 and math.isfinite(limit)):
        raise ValueError(f"a length scale needs a positive length, got {limit!r}")
    k = math.floor(math.log10(limit))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0**k <= limit * (1 + 1e-12):
            return m * 10.0**k
    return 10.0 ** (k - 1) * 5.0  # pragma: no cover - 1 x 10^k always fits


def length_text(length: float) -> str:
    """``0.2 m``, ``50 mm``, ``2 m``: a length in the unit that keeps it a plain number."""
    if length < 0.1:
        return f"{length * 1e3:g} mm"
    return f"{length:g} m"


def direction_text(direction: np.ndarray) -> str:
    """``+e3`` for a direction along an axis, else its components ``(0.71, 0, -0.71)``."""
    d = np.asarray(direction, dtype=float)
    k = int(np.argmax(np.abs(d)))
    if abs(d[k]) > 0.999:
        return ("+" if d[k] > 0 else "-") + _AXIS_NAMES[k]
    return "(" + ", ".join(f"{v:.2g}" if abs(v) > 1e-3 else "0" for v in d) + ")"


def live_load_resultant(
    centres: np.ndarray, live_load: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray] | None:
    """Direction (unit) and point of application (force-weighted centre) of the resultant
    of the live forces (nb, 3) at block centres (nb, 3); None when there is no live force."""
    if live_load is None or not live_load.size:
        return None
    total = live_load.sum(axis=0)
    norm = float(np.linalg.norm(total))
    weight = np.linalg.norm(live_load, axis=1)
    if norm <= 1e-12 * max(float(weight.sum()), 1e-300):
        return None
    point = (weight[:, None] * centres).sum(axis=0) / weight.sum()
    return total / norm, point


def _cone_template(pv: Any) -> tuple[np.ndarray, np.ndarray]:
    """Points (p, 3) and triangles (t, 3) of a unit cone pointing along +e1, tip at 0."""
    cone = pv.Cone(
        center=(-0.5, 0.0, 0.0), direction=(1.0, 0.0, 0.0), height=1.0, radius=0.4, resolution=10
    ).triangulate()
    return np.asarray(cone.points, dtype=float), np.asarray(cone.regular_faces)


# rotations taking e1 to e1, e2, e3 (cyclic permutations), applied as points @ R.T
_TO_AXIS = np.array(
    [np.eye(3), [[0, 0, 1], [1, 0, 0], [0, 1, 0]], [[0, 1, 0], [0, 0, 1], [1, 0, 0]]],
    dtype=float,
)


def support_marks(
    lower: np.ndarray, upper: np.ndarray, restrained: np.ndarray, size: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tips (k, 3), axes (k,) and blocks (k,) of the support marks: cones pointing along
    +e_axis with their tip on the block.

    A block held in every DOF (a foundation) gets a row of upward cones under its bottom
    face along its longer horizontal side (the hatching of a fixed support); a block held in
    some translations gets one cone per held translation u_k, pointing along +e_k onto the
    centre of its face of least e_k (a roller against that face). Held rotations alone get no
    mark. ``lower``/``upper``: (nb, 3) block boxes; ``restrained``: (nb, 6) bool."""
    held = np.asarray(restrained, dtype=bool)
    full = np.asarray(held.all(axis=1), dtype=bool)
    centre = 0.5 * (lower + upper)
    # fixed blocks: a row along the longer of e1 and e3
    fb = np.flatnonzero(full)
    ext = upper[fb] - lower[fb]
    along = np.where(ext[:, 0] >= ext[:, 2], 0, 2)
    length = ext[np.arange(fb.size), along]
    count = np.clip(np.round(length / (2.5 * size)).astype(int), 1, MAX_MARKS_PER_BLOCK)
    owner = np.repeat(np.arange(fb.size), count)
    rank = np.arange(owner.size) - np.repeat(np.cumsum(count) - count, count)
    tips_f = centre[fb][owner].copy()
    tips_f[:, 1] = lower[fb][owner, 1]
    ax = along[owner]
    tips_f[np.arange(owner.size), ax] = (
        lower[fb][owner, ax] + (rank + 0.5) / count[owner] * length[owner]
    )
    # partly held blocks: one cone per held translation
    pb, pk = np.nonzero(held[:, :3] & ~full[:, None])
    tips_p = centre[pb].copy()
    tips_p[np.arange(pb.size), pk] = lower[pb, pk]
    tips = np.concatenate([tips_f, tips_p])
    axes = np.concatenate([np.ones(owner.size, dtype=int), pk])
    blocks = np.concatenate([fb[owner], pb])
    return tips, axes, blocks


def cone_mesh_points(
    template: np.ndarray, tips: np.ndarray, axes: np.ndarray, size: float
) -> np.ndarray:
    """Points (k * p, 3) of cones of height ``size`` with tips ``tips`` along +e_axes."""
    shaped = np.einsum("pj,kij->kpi", size * template, _TO_AXIS[axes])
    return (tips[:, None, :] + shaped).reshape(-1, 3)


class Annotations:
    """The explanatory overlay of one scene: triad, length scale, load arrow, support marks
    and the legend's title, built from the first step drawn; :meth:`update` moves the marks
    with their blocks, :meth:`points` gives what the camera must keep in frame."""

    def __init__(
        self,
        pv: Any,
        plotter: Any,
        data: Any,
        view: dict[str, Any],
        block_size: float,
        legend_title: str,
        legend_box: tuple[float, float, float, float],
    ) -> None:
        self.pv, self.plotter = pv, plotter
        pts = data.block_points
        lower, upper = pts.min(axis=1), pts.max(axis=1)
        lo, hi = lower.min(axis=0), upper.max(axis=0)
        size = float(np.max(hi - lo)) or 1.0
        self._points: list[np.ndarray] = []
        w, h = plotter.window_size
        self._font = max(8, int(round(20 * min(w / 1200, h / 900))))
        self._triad()
        self._legend_title(legend_title, legend_box)
        self.marks = None
        if data.restrained is not None:
            self._support_marks(lower, upper, data.restrained, MARK_SIZE * block_size)
        mark_drop = MARK_SIZE * block_size if self.marks is not None else 0.0
        self._scale_bar(lo, hi, size, view, mark_drop)
        resultant = live_load_resultant(0.5 * (lower + upper), data.live_load)
        if resultant is not None:
            self._load_arrow(lo, hi, size, *resultant)

    # ------------------------------------------------------------------ pieces
    def _triad(self) -> None:
        self.plotter.add_axes(
            interactive=False,
            xlabel="e1",
            ylabel="e2",
            zlabel="e3",
            color="black",
            line_width=2,
            viewport=TRIAD_VIEWPORT,
        )

    def _legend_title(self, text: str, box: tuple[float, float, float, float]) -> None:
        w, h = self.plotter.window_size
        actor = self.pv.Text(text)
        prop = actor.GetTextProperty()
        prop.SetFontSize(max(7, int(round(0.8 * self._font))))
        prop.SetColor(0.0, 0.0, 0.0)
        prop.SetVerticalJustificationToBottom()
        actor.SetDisplayPosition(int(box[0] * w), int((box[1] + box[3]) * h) + 2)
        self.plotter.add_actor(actor, reset_camera=False, name="legend title", pickable=False)

    def _label(self, point: np.ndarray, text: str, colour: tuple[int, int, int]) -> None:
        self.plotter.add_point_labels(
            np.asarray([point], dtype=float),
            [text],
            font_size=self._font,
            text_color=[c / 255 for c in colour],
            shape=None,
            show_points=False,
            always_visible=True,
            bold=False,
            reset_camera=False,
        )

    def _support_marks(
        self, lower: np.ndarray, upper: np.ndarray, restrained: np.ndarray, size: float
    ) -> None:
        tips, axes, blocks = support_marks(lower, upper, restrained, size)
        if not tips.size:
            return
        template, tri = _cone_template(self.pv)
        self._mark_base = cone_mesh_points(template, tips, axes, size)
        self._mark_block = np.repeat(blocks, template.shape[0])
        faces = (template.shape[0] * np.arange(tips.shape[0])[:, None, None] + tri[None]).reshape(
            -1, 3
        )
        self.marks = self.pv.PolyData.from_regular_faces(self._mark_base.copy(), faces)
        self.plotter.add_mesh(
            self.marks, color=[c / 255 for c in MARK_COLOUR], lighting=False, reset_camera=False
        )
        self._points.append(self._mark_base)

    def _scale_bar(
        self, lo: np.ndarray, hi: np.ndarray, size: float, view: dict[str, Any], drop: float
    ) -> None:
        """A bar of a round length along the horizontal axis (e1 or e3) most across the
        screen, under the wall (below the support marks), on the camera's side."""
        direction = np.asarray(view["direction"], dtype=float)
        direction /= np.linalg.norm(direction)
        right = np.cross(np.asarray(view["up"], dtype=float), direction)
        axis = 0 if abs(right[0]) >= abs(right[2]) else 2
        length = nice_length(SCALE_BAR_SHARE * size)
        start = np.array(
            [
                lo[0] if axis == 0 else (hi[0] if direction[0] >= 0 else lo[0]),
                lo[1] - drop - 0.05 * size,
                lo[2] if axis == 2 else (hi[2] if direction[2] >= 0 else lo[2]),
            ]
        )
        end = start.copy()
        end[axis] += length
        tick = np.array([0.0, 0.025 * size, 0.0])
        points = np.array([start, end, start - tick, start + tick, end - tick, end + tick])
        lines = np.array([2, 0, 1, 2, 2, 3, 2, 4, 5])
        bar = self.pv.PolyData(points, lines=lines)
        self.plotter.add_mesh(
            bar, color=[c / 255 for c in MARK_COLOUR], line_width=3, reset_camera=False
        )
        label = 0.5 * (start + end) - 4.0 * tick
        self._label(label, length_text(length), MARK_COLOUR)
        self._points.append(np.vstack([points, label - 2 * tick]))

    def _load_arrow(
        self, lo: np.ndarray, hi: np.ndarray, size: float, direction: np.ndarray, point: np.ndarray
    ) -> None:
        """One arrow along the live load's resultant, above the wall's top (where no view
        hides it) at the resultant's position along the wall, labelled with its direction."""
        length = ARROW_LENGTH * size
        centre = np.array(
            [
                point[0],
                hi[1] + ARROW_GAP * size + 0.5 * length * abs(direction[1]),
                point[2],
            ]
        )
        start = centre - 0.5 * length * direction
        arrow = self.pv.Arrow(
            start=start,
            direction=direction,
            scale=length,
            tip_length=0.3,
            tip_radius=0.09,
            shaft_radius=0.03,
        )
        self.plotter.add_mesh(
            arrow, color=[c / 255 for c in LOAD_COLOUR], lighting=False, reset_camera=False
        )
        label_at = centre + np.array([0.0, 0.5 * length * (1 - abs(direction[1])) + 0.04 * size, 0])
        self._label(label_at, f"live load x lambda, {direction_text(direction)}", LOAD_COLOUR)
        self._points.append(np.vstack([start, start + length * direction, label_at]))

    # ------------------------------------------------------------------ per frame
    def update(self, block_centre_disp: np.ndarray, scale: float) -> None:
        """Move each support mark with its block's mean displacement x ``scale``."""
        if self.marks is not None:
            self.marks.points = self._mark_base + scale * block_centre_disp[self._mark_block]

    def points(self) -> np.ndarray:
        """(k, 3) world points the camera keeps in frame besides the wall."""
        return np.vstack(self._points) if self._points else np.zeros((0, 3))
