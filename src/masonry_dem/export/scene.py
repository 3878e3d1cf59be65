"""The 3D scene of a results picture (pyvista): one batched mesh of all blocks, one of all
joints, the camera presets and the framing, updated in place from step to step.

The picture (Figures 20-21 of the paper): blocks are drawn slightly shrunk about their centres
and every interface as a thin slab ("joint") filling the gap, coloured by its state with flat,
unlit colours (:data:`STATE_COLOURS`): green elastic, red sliding (shear or torsion), magenta
rocking (flexural), orange sliding and rocking, blue detached. Support blocks are dark grey.
Points move by ``scale`` times their displacement (:func:`auto_scale` unless given). What makes
the picture readable without us (triad, length scale, load arrow, support marks, caption,
legend title) is added by :mod:`masonry_dem.export.annotations`.

This module and the ones it serves are the only ones importing pyvista, lazily (inside the
functions), so ``import masonry_dem`` and the command line stay light. Rendering is always
off-screen: with no ``DISPLAY`` the VTK wheel renders through EGL (or OSMesa).
"""

from __future__ import annotations

import copy
import ctypes.util
import math
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.constitutive.states import STATE_NAMES
from masonry_dem.export.figure_text import fitted_title
from masonry_dem.export.results_series import ResultsSeries

#: RGB colour (0-255) of each interface state, index = :class:`~masonry_dem.constitutive.states.JointState`.
STATE_COLOURS: tuple[tuple[int, int, int], ...] = (
    (0, 170, 0),  # 0 elastic: green
    (220, 0, 0),  # 1 sliding (shear / torsion): red
    (225, 0, 225),  # 2 rocking (flexural): magenta
    (255, 140, 0),  # 3 sliding + rocking: orange
    (0, 70, 255),  # 4 detached: blue
)
#: the mechanism picture colours joints by their relative motion in the collapse mode, as a
#: share of the largest: bins (upper edges) and colours, light grey for joints that stay shut
MECHANISM_BINS: tuple[float, ...] = (0.05, 0.25, 0.5)
MECHANISM_LABELS: tuple[str, ...] = ("< 5 % (shut)", "5-25 %", "25-50 %", "> 50 % (crack)")
MECHANISM_COLOURS: tuple[tuple[int, int, int], ...] = (
    (205, 205, 205),
    (250, 200, 0),
    (250, 110, 0),
    (190, 0, 0),
)
#: what the colours of each palette measure (the title over the legend)
STATE_LEGEND_TITLE = "interface state"
MECHANISM_LEGEND_TITLE = "joint motion in the mode,\nshare of the largest joint's"
#: colour of an interface whose state code is unknown
UNKNOWN_STATE_COLOUR = (128, 128, 128)
BLOCK_COLOUR = (222, 214, 200)
SUPPORT_COLOUR = (105, 105, 105)
BACKGROUND = (255, 255, 255)

#: camera presets: direction from the wall towards the camera, view-up, parallel projection.
#: Axes: e1 along the wall, e2 up, e3 out of plane (the front face looks along +e3).
VIEWS: dict[str, dict[str, Any]] = {
    "front": {"direction": (0.0, 0.0, 1.0), "up": (0.0, 1.0, 0.0), "parallel": True},
    "back": {"direction": (0.0, 0.0, -1.0), "up": (0.0, 1.0, 0.0), "parallel": True},
    "oblique": {"direction": (0.75, 0.55, 1.0), "up": (0.0, 1.0, 0.0), "parallel": False},
    "side": {"direction": (1.0, 0.0, 0.0), "up": (0.0, 1.0, 0.0), "parallel": True},
}

#: legend box in normalised window coordinates (x0, y0, width, height), y from the bottom
LEGEND_BOX = (0.79, 0.015, 0.2, 0.2)
#: part of the window left to the wall: (x0, y0, x1, y1), normalised, y from the bottom
FREE_BOX = (0.01, 0.01, 0.78, 0.91)
#: largest displacement / largest wall dimension aimed at by the automatic scale
AUTO_SCALE_TARGET = 0.065
#: joint (gap) thickness as a fraction of the median smallest block dimension
GAP_FRACTION = 0.1

VTK_HEXAHEDRON, VTK_QUAD = 12, 9
# faces of a VTK hexahedron, outward normals
_HEX_FACES = np.array(
    [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
)
# a joint slab shows only its four thin sides: its two large faces always face a block
_JOINT_FACES = _HEX_FACES[2:]


# --------------------------------------------------------------------------- pyvista, lazily
def configure_offscreen() -> None:
    """With no display, pick a headless OpenGL window before VTK makes one (the VTK wheel
    would try X first and warn). Never overrides a user's ``VTK_DEFAULT_OPENGL_WINDOW``."""
    if not sys.platform.startswith("linux") or os.environ.get("VTK_DEFAULT_OPENGL_WINDOW"):
        return
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return
    if ctypes.util.find_library("EGL"):
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"
    elif ctypes.util.find_library("OSMesa"):
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkOSOpenGLRenderWindow"


def pyvista_offscreen():
    configure_offscreen()
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


# --------------------------------------------------------------------------- one step's geometry
@dataclass(frozen=True)
class StepData:
    """Blocks (nb, 8, 3) corners + displacements, fixed flags; interfaces (m, 4, 3) corners +
    displacements, normal axis and state (or any code the palette colours)."""

    block_points: np.ndarray
    block_disp: np.ndarray
    fixed: np.ndarray
    joint_points: np.ndarray | None
    joint_disp: np.ndarray | None
    joint_axis: np.ndarray | None
    state: np.ndarray | None
    load_factor: float | None
    #: (nb, 6) DOFs a support holds and (nb, 3) live force at lambda = 1 [N]; None when the
    #: results were written before these arrays existed
    restrained: np.ndarray | None = None
    live_load: np.ndarray | None = None


def read_cells(pv, path: Path, celltype: int, per_cell: int):
    grid = pv.read(str(path))
    n = grid.n_cells
    if n and not np.all(np.asarray(grid.celltypes) == celltype):
        raise ValueError(f"{path}: expected only VTK cell type {celltype}")
    conn = np.asarray(grid.cell_connectivity).reshape(n, per_cell)
    pts = np.asarray(grid.points, dtype=float)[conn]
    if "displacement" not in grid.point_data:
        raise ValueError(f"{path}: point data 'displacement' is missing")
    disp = np.asarray(grid.point_data["displacement"], dtype=float)[conn]
    return grid, pts, disp


def point_field(grid, path: Path, name: str, per_cell: int) -> np.ndarray:
    """Point data ``name`` of ``grid`` per cell corner (cells, per_cell, 3)."""
    if name not in grid.point_data:
        raise ValueError(f"{path}: point data {name!r} is missing")
    conn = np.asarray(grid.cell_connectivity).reshape(grid.n_cells, per_cell)
    return np.asarray(grid.point_data[name], dtype=float)[conn]


def block_supports_and_loads(
    grid: Any,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``fixed`` (nb,), ``restrained`` (nb, 6) and ``live_load`` (nb, 3) of a blocks grid;
    the last two None in results written before they were recorded."""
    n = grid.n_cells
    cd = grid.cell_data
    fixed = np.asarray(cd["fixed"]).astype(bool) if "fixed" in cd else np.zeros(n, dtype=bool)
    restrained = np.asarray(cd["restrained"]).astype(bool) if "restrained" in cd else None
    live = np.asarray(cd["live_load"], dtype=float) if "live_load" in cd else None
    return fixed, restrained, live


def read_step(series: ResultsSeries, index: int, interfaces: bool = True) -> StepData:
    pv = pyvista_offscreen()
    grid, bpts, bdisp = read_cells(pv, series.block_files[index], VTK_HEXAHEDRON, 8)
    fixed, restrained, live = block_supports_and_loads(grid)
    lam = None
    if "load_factor" in grid.field_data:  # written by newer writers; preferred when present
        lam = float(np.asarray(grid.field_data["load_factor"]).ravel()[0])
    jp = jd = axis = state = None
    if interfaces and series.interface_files is not None:
        igrid, jp, jd = read_cells(pv, series.interface_files[index], VTK_QUAD, 4)
        if "state" not in igrid.cell_data:
            raise ValueError(f"{series.interface_files[index]}: cell data 'state' is missing")
        state = np.asarray(igrid.cell_data["state"]).astype(int)
        if "normal_axis" in igrid.cell_data:
            axis = np.asarray(igrid.cell_data["normal_axis"]).astype(int)
        else:  # the axis along which the quad is flat
            axis = np.argmin(np.ptp(jp, axis=1), axis=1)
    return StepData(bpts, bdisp, fixed, jp, jd, axis, state, lam, restrained, live)


def wall_size(data: StepData) -> float:
    p = data.block_points.reshape(-1, 3)
    return float(np.max(p.max(axis=0) - p.min(axis=0)))


def max_displacement(data: StepData) -> float:
    return (
        float(np.sqrt(np.max(np.sum(data.block_disp**2, axis=2)))) if data.block_disp.size else 0.0
    )


#: the views the mechanism picture chooses among (the back view shows what the front does)
MECHANISM_VIEW_CHOICES: tuple[str, ...] = ("front", "side", "oblique")
#: walls deeper (e3) than this many times their median block depth are walls that meet (a U,
#: L or T plan) or several leaves: a front or side elevation hides some of them behind the
#: others, so their mechanism is drawn in the oblique view
DEEP_WALL_BLOCKS = 1.5


def motion_in_view(disp: np.ndarray, view: str) -> float:
    """How much of the displacements ``disp`` (..., 3) a camera of preset ``view`` sees: the
    sum of their squared components in its image plane (the part along its line of sight is
    invisible)."""
    d = np.asarray(check_view(view)["direction"], dtype=float)
    d /= np.linalg.norm(d)
    u = np.asarray(disp, dtype=float).reshape(-1, 3)
    return float(np.sum(u * u) - np.sum((u @ d) ** 2))


def view_of_motion(data: StepData) -> str:
    """The camera preset in which the displacements of ``data`` (a collapse mode) move the
    most: of :data:`MECHANISM_VIEW_CHOICES`, the one whose image plane holds the largest
    share of the moving blocks' corner displacements (:func:`motion_in_view`). A wall
    overturning out of its plane (e3) is drawn from the side, an in-plane mechanism (e1)
    from the front, a ``"front"`` on a tie. Walls that meet (deeper than
    :data:`DEEP_WALL_BLOCKS` of their blocks' depth) and a mode that moves nothing keep the
    oblique view."""
    moving = ~np.asarray(data.fixed, dtype=bool)
    if not moving.any():
        return "oblique"
    pts, disp = data.block_points[moving], data.block_disp[moving]
    block_depth = float(np.median(np.ptp(pts[..., 2], axis=1)))
    if np.ptp(pts[..., 2]) > DEEP_WALL_BLOCKS * block_depth:
        return "oblique"
    seen = {view: motion_in_view(disp, view) for view in MECHANISM_VIEW_CHOICES}
    best = max(seen.values())
    if not best > 0:
        return "oblique"
    return next(view for view in MECHANISM_VIEW_CHOICES if seen[view] >= (1 - 1e-9) * best)


def auto_scale(max_displacement: float, wall_size: float) -> float:
    """A round amplification (two significant figures, rounded down) making the largest
    displacement about :data:`AUTO_SCALE_TARGET` of the wall size; 1 when nothing moves."""
    if not (max_displacement > 0 and math.isfinite(max_displacement)) or wall_size <= 0:
        return 1.0
    raw = AUTO_SCALE_TARGET * wall_size / max_displacement
    mag = 10.0 ** (math.floor(math.log10(raw)) - 1)
    return float(math.floor(raw / mag) * mag)


def block_size(data: StepData) -> float:
    """The median smallest block dimension: the wall's own unit for joints and marks."""
    ext = data.block_points.max(axis=1) - data.block_points.min(axis=1)
    return float(np.median(ext.min(axis=1)))


def joint_gap(data: StepData, window_size: tuple[int, int]) -> float:
    """Joint thickness: GAP_FRACTION of the median smallest block dimension, at least about
    1.5 pixels (so the damage colours stay visible on large walls), at most 35 % of it."""
    dmin = block_size(data)
    pixel = wall_size(data) / (min(window_size) * (FREE_BOX[3] - FREE_BOX[1]))
    return float(min(max(GAP_FRACTION * dmin, 1.5 * pixel), 0.35 * dmin))


def _block_surface(data: StepData, scale: float, gap: float):
    """Points (nb*8, 3) of the shrunk, displaced blocks (faces are fixed)."""
    p, d = data.block_points, data.block_disp
    c = p.mean(axis=1)
    x = p - c[:, None, :]
    dc = d.mean(axis=1)
    # displacement field of a rigid (affine) motion fitted on the 8 corners: exact for blocks
    denom = np.einsum("nik,nik->nk", x, x)
    grad = (
        np.einsum("nij,nik->njk", d - dc[:, None, :], x) / np.where(denom > 0, denom, 1.0)[:, None]
    )
    half = np.abs(x).max(axis=1)
    shrunk_half = np.maximum(half - gap / 2, 0.5 * half)
    xs = np.sign(x) * shrunk_half[:, None, :]
    ds = dc[:, None, :] + np.einsum("njk,nik->nij", grad, xs)
    return (c[:, None, :] + xs + scale * ds).reshape(-1, 3)


def _joint_surface(data: StepData, scale: float, gap: float):
    """Points (m*8, 3) of the joint slabs: each interface quad thickened by ``gap``."""
    q, d, axis = data.joint_points, data.joint_disp, data.joint_axis
    assert q is not None and d is not None and axis is not None
    offset = np.zeros((q.shape[0], 3))
    offset[np.arange(q.shape[0]), axis] = gap / 2
    pts = np.concatenate([q - offset[:, None, :], q + offset[:, None, :]], axis=1)
    disp = np.concatenate([d, d], axis=1)
    return (pts + scale * disp).reshape(-1, 3)


def _hex_faces(n: int, faces: np.ndarray = _HEX_FACES) -> np.ndarray:
    return (8 * np.arange(n)[:, None, None] + faces[None]).reshape(-1, 4)


def state_colours(
    state: np.ndarray, colours: Sequence[tuple[int, int, int]] = STATE_COLOURS
) -> np.ndarray:
    """(m, 3) uint8 RGB of interface codes in the table ``colours`` (unknown codes grey)."""
    table = np.array(list(colours) + [UNKNOWN_STATE_COLOUR], dtype=np.uint8)
    code = np.asarray(state, dtype=int)
    code = np.where((code >= 0) & (code < len(colours)), code, len(colours))
    return table[code]


# --------------------------------------------------------------------------- the scene
def check_view(view: str) -> dict[str, Any]:
    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}: choose one of {', '.join(VIEWS)}")
    return VIEWS[view]


class Scene:
    """One plotter with the block mesh and the joint mesh, updated in place for each step."""

    def __init__(
        self,
        first: StepData,
        view: str,
        window_size: tuple[int, int],
        gap: float,
        legend: bool = True,
        palette: tuple[Sequence[str], Sequence[tuple[int, int, int]]] = (
            STATE_NAMES,
            STATE_COLOURS,
        ),
        legend_title: str = STATE_LEGEND_TITLE,
    ) -> None:
        pv = pyvista_offscreen()
        self.palette = palette
        self.pv = pv
        self.view = check_view(view)
        self.gap = gap
        self._title: Any = None
        #: the title's height as a fraction of the window (0 before a title is set): the
        #: camera keeps the wall below it
        self._title_height = 0.0
        # no multi-sampling: exact damage colours on screen, and 2-3x faster with Mesa
        theme = copy.deepcopy(pv.global_theme)
        theme.multi_samples = 0
        theme.anti_aliasing = None
        self.plotter = pv.Plotter(
            off_screen=True, window_size=list(window_size), lighting="three lights", theme=theme
        )
        p = self.plotter
        p.set_background([c / 255 for c in BACKGROUND])
        nb = first.block_points.shape[0]
        self.blocks = pv.PolyData.from_regular_faces(
            _block_surface(first, 0.0, gap), _hex_faces(nb)
        )
        colours = np.where(
            np.repeat(first.fixed, 6)[:, None],
            np.array(SUPPORT_COLOUR, dtype=np.uint8),
            np.array(BLOCK_COLOUR, dtype=np.uint8),
        ).astype(np.uint8)
        self.blocks.cell_data["rgb"] = colours
        p.add_mesh(
            self.blocks, scalars="rgb", rgb=True, show_scalar_bar=False, ambient=0.3, diffuse=0.75
        )
        self.joints = None
        if first.joint_points is not None and first.state is not None and first.joint_points.size:
            m = first.joint_points.shape[0]
            self.joints = pv.PolyData.from_regular_faces(
                _joint_surface(first, 0.0, gap), _hex_faces(m, _JOINT_FACES)
            )
            self.joints.cell_data["rgb"] = np.repeat(
                state_colours(first.state, palette[1]), 4, axis=0
            )
            p.add_mesh(self.joints, scalars="rgb", rgb=True, lighting=False, show_scalar_bar=False)
        if legend:
            box = p.add_legend(
                labels=[[name, [c / 255 for c in col]] for name, col in zip(*palette, strict=True)],
                bcolor=(1.0, 1.0, 1.0),
                border=True,
                face="rectangle",
            )
            box.SetPosition(LEGEND_BOX[0], LEGEND_BOX[1])
            box.SetPosition2(LEGEND_BOX[2], LEGEND_BOX[3])
        from masonry_dem.export.annotations import Annotations

        self.annotations = Annotations(
            pv,
            p,
            first,
            self.view,
            block_size(first),
            legend_title if legend else "",
            LEGEND_BOX,
        )

    def update(self, data: StepData, scale: float) -> None:
        self.blocks.points = _block_surface(data, scale, self.gap)
        self.annotations.update(data.block_disp.mean(axis=1), scale)
        if self.joints is not None and data.state is not None:
            self.joints.points = _joint_surface(data, scale, self.gap)
            self.joints.cell_data["rgb"] = np.repeat(
                state_colours(data.state, self.palette[1]), 4, axis=0
            )

    def frame_camera(self, points: np.ndarray) -> None:
        """Place the camera of the view preset so that ``points`` (k, 3) fill the picture."""
        v = self.view
        cam = self.plotter.camera
        points = np.concatenate([points, self.annotations.points()])
        lo, hi = points.min(axis=0), points.max(axis=0)
        centre = (lo + hi) / 2
        direction = np.asarray(v["direction"], dtype=float)
        direction /= np.linalg.norm(direction)
        up = np.asarray(v["up"], dtype=float)
        up = up - direction * (up @ direction)
        up /= np.linalg.norm(up)
        right = np.cross(up, direction)
        corners = (
            np.array(
                [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
            )
            - centre
        )
        half_w = float(np.max(np.abs(corners @ right))) or 1.0
        half_h = float(np.max(np.abs(corners @ up))) or 1.0
        depth = float(np.max(np.abs(corners @ direction)))
        w, h = self.plotter.window_size
        aspect = w / h
        # the wall goes in the free part of the window: below the title, left of the legend
        x0, y0, x1, y1 = FREE_BOX
        y1 = min(y1, 1.0 - self._title_height)  # a title of many lines takes more
        margin = 1.03 if v["parallel"] else 1.1
        half_view = margin * max(half_h / (y1 - y0), half_w / (aspect * (x1 - x0)))
        shift = ((x0 + x1) / 2 - 0.5) * 2 * half_view * aspect * right + (
            (y0 + y1) / 2 - 0.5
        ) * 2 * half_view * up
        focal = centre - shift
        radius = float(np.linalg.norm(hi - lo)) / 2 or 1.0
        cam.focal_point = tuple(focal)
        cam.up = tuple(up)
        if v["parallel"]:
            cam.enable_parallel_projection()
            cam.position = tuple(focal + direction * (depth + 4 * radius))
            cam.parallel_scale = half_view
            far = depth + 8 * radius
        else:
            cam.disable_parallel_projection()
            angle = 30.0
            cam.view_angle = angle
            dist = depth + half_view / math.tan(math.radians(angle) / 2)
            cam.position = tuple(focal + direction * dist)
            far = dist + 2 * radius
        cam.clipping_range = (1e-3 * far, 2 * far)

    def title(self, text: str) -> None:
        """Title at the top centre, wrapped to the window's width (never cut at its edges;
        one text actor, updated in place: cheap per frame). Set it before
        :meth:`frame_camera`, which keeps the wall and its labels below it."""
        w, h = self.plotter.window_size
        size = max(9, int(round(26 * min(w / 1200, h / 900))))
        text = fitted_title(text, w / 72.0, size)  # VTK's font size: pixels, as points at 72 dpi
        # VTK sets the lines about 0.9 font sizes apart, from max(4, h / 150) pixels below the
        # top; the load's label, centred on its point, needs half its own font below that
        lines = text.count("\n") + 1
        label = max(8, int(round(20 * min(w / 1200, h / 900))))  # Annotations' font
        self._title_height = (max(4, h // 150) + 0.9 * size * lines + 0.5 * label) / h
        if self._title is None:
            actor = self.pv.Text(text)
            prop = actor.GetTextProperty()
            prop.SetFontSize(size)
            prop.SetColor(0.0, 0.0, 0.0)
            prop.SetJustificationToCentered()
            prop.SetVerticalJustificationToTop()
            actor.SetDisplayPosition(w // 2, h - max(4, h // 150))
            self.plotter.add_actor(actor, reset_camera=False, name="title", pickable=False)
            self._title = actor
        else:
            self._title.SetInput(text)

    def image(self) -> np.ndarray:
        self.plotter.render()  # screenshot() reuses the last frame when nothing asked to render
        return self.plotter.screenshot(return_img=True)

    def save(self, path: Path) -> None:
        self.plotter.render()
        self.plotter.screenshot(str(path), return_img=False)

    def close(self) -> None:
        # pyvista runs the theme's before-close callback (image tests hook in there) in
        # show(), which an off-screen scene never calls
        callback = self.pv.global_theme.before_close_callback
        if callback is not None:
            callback(self.plotter)
        self.plotter.close()


def deformed_extent(data: StepData, scale: float, gap: float) -> np.ndarray:
    """Points (k, 3) the camera keeps in frame: the undeformed and the drawn blocks."""
    return np.concatenate([data.block_points.reshape(-1, 3), _block_surface(data, scale, gap)])
