"""Off-screen pictures of a results folder: the deformed wall with its damage map, an animation
of the whole analysis, and the pushover curve.

This is the only module of the package that imports pyvista, and it does so lazily (inside the
functions), so ``import masonry_dem`` and the command line stay light. Rendering is always
off-screen: with no ``DISPLAY`` the VTK wheel renders through EGL (or OSMesa).

The picture (Figures 20-21 of the paper): blocks are drawn slightly shrunk about their centres
and every interface as a thin slab ("joint") filling the gap, coloured by its state with flat,
unlit colours (:data:`STATE_COLOURS`): green elastic, red sliding (shear or torsion), magenta
rocking (flexural), orange sliding and rocking, blue detached. Support blocks are dark grey.
Points move by ``scale`` times their displacement; the scale is chosen automatically (a round
number making the largest displacement about 6 % of the wall's largest dimension) unless
given, and stated in the title with the load multiplier.

Everything is batched: one mesh for all blocks and one for all joints, built with numpy.
"""

from __future__ import annotations

import copy
import csv
import ctypes.util
import logging
import math
import os
import re
import sys
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.constitutive.states import STATE_NAMES
from masonry_dem.export import results_folder as rf

log = logging.getLogger(__name__)

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
# part of the window left to the wall: (x0, y0, x1, y1), normalised, y from the bottom
_FREE_BOX = (0.01, 0.01, 0.78, 0.91)
#: largest displacement / largest wall dimension aimed at by the automatic scale
AUTO_SCALE_TARGET = 0.065
#: joint (gap) thickness as a fraction of the median smallest block dimension
GAP_FRACTION = 0.1

_IMAGE_SUFFIXES = (".png",)
_ANIMATION_SUFFIXES = (".gif", ".mp4")
_PLOT_SUFFIXES = (".png", ".svg", ".pdf")
_STEP_FILE = re.compile(r"_(\d+)\.vtu$")
_VTK_HEXAHEDRON, _VTK_QUAD = 12, 9
# faces of a VTK hexahedron, outward normals
_HEX_FACES = np.array(
    [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
)
# a joint slab shows only its four thin sides: its two large faces always face a block
_JOINT_FACES = _HEX_FACES[2:]


# --------------------------------------------------------------------------- pyvista, lazily
def _configure_offscreen() -> None:
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


def _pyvista():
    _configure_offscreen()
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


# --------------------------------------------------------------------------- the results folder
@dataclass(frozen=True)
class ResultsSeries:
    """The time series of a results folder, checked to be complete.

    steps: step numbers (from the file names); load_factors: lambda of each step;
    block_files / interface_files: absolute paths (interface_files is None when the model has
    no interface).
    """

    folder: Path
    steps: np.ndarray
    times: np.ndarray
    load_factors: np.ndarray
    block_files: tuple[Path, ...]
    interface_files: tuple[Path, ...] | None
    name: str
    summary: dict

    def index_of(self, step: int | str) -> int:
        """Position in the series of step ``step`` (a step number, or ``"last"``/``"first"``)."""
        if isinstance(step, str):
            key = step.strip().lower()
            if key == "last":
                return len(self.steps) - 1
            if key == "first":
                return 0
            if not re.fullmatch(r"[+-]?\d+", key):
                raise ValueError(f"step must be a step number, 'first' or 'last', got {step!r}")
            step = int(key)
        if isinstance(step, bool) or not isinstance(step, (int, np.integer)):
            raise ValueError(f"step must be a step number, 'first' or 'last', got {step!r}")
        hits = np.flatnonzero(self.steps == int(step))
        if hits.size == 0:
            raise ValueError(
                f"step {int(step)} is not in {self.folder}: it holds {len(self.steps)} step(s), "
                f"numbers {_ranges(self.steps)}"
            )
        return int(hits[0])


def _ranges(values: np.ndarray) -> str:
    v = np.asarray(values, dtype=int)
    if v.size and np.array_equal(v, np.arange(v[0], v[0] + v.size)):
        return f"{v[0]}..{v[-1]}"
    return ", ".join(str(x) for x in v[:20]) + (" ..." if v.size > 20 else "")


def _read_pvd(path: Path) -> list[tuple[float, str]]:
    from masonry_dem.export.pvd import read_pvd

    try:
        return read_pvd(path)
    except Exception as exc:  # xml.etree.ElementTree.ParseError and friends
        raise ValueError(f"{path} is not a readable PVD file: {exc}") from exc


def open_results(folder: Path | str) -> ResultsSeries:
    """Check that ``folder`` is a complete results folder and index its steps.

    Raises FileNotFoundError (folder, ``blocks.pvd`` or a listed VTU file missing) or
    ValueError (empty or inconsistent index)."""
    folder = Path(folder)
    if not folder.exists():
        raise FileNotFoundError(f"results folder not found: {folder}")
    if not folder.is_dir():
        raise FileNotFoundError(f"not a results folder (not a directory): {folder}")
    bpvd, ipvd = folder / rf.BLOCKS_PVD, folder / rf.INTERFACES_PVD
    if not bpvd.is_file():
        raise FileNotFoundError(
            f"incomplete results folder {folder}: blocks.pvd is missing "
            "(a results folder holds blocks.pvd, interfaces.pvd, steps/, pushover.csv, "
            "summary.json)"
        )
    blocks = _read_pvd(bpvd)
    if not blocks:
        raise ValueError(f"incomplete results folder {folder}: blocks.pvd lists no step")
    interfaces: list[tuple[float, str]] | None = None
    if ipvd.is_file():
        interfaces = _read_pvd(ipvd)
        if len(interfaces) != len(blocks) and rf.state(folder).kind in rf.UNFINISHED:
            # a run killed between the renames of its two indexes: the steps both list
            common = min(len(blocks), len(interfaces))
            log.warning(
                "%s: blocks.pvd lists %d steps and interfaces.pvd %d (the run stopped "
                "between them): using the first %d",
                folder,
                len(blocks),
                len(interfaces),
                common,
            )
            blocks, interfaces = blocks[:common], interfaces[:common]
        if len(interfaces) != len(blocks):
            raise ValueError(
                f"inconsistent results folder {folder}: blocks.pvd lists {len(blocks)} steps "
                f"but interfaces.pvd {len(interfaces)}"
            )
    elif any((folder / "steps").glob("interfaces_*.vtu")):
        raise FileNotFoundError(f"incomplete results folder {folder}: interfaces.pvd is missing")
    files = [folder / f for _, f in blocks]
    ifiles = None if interfaces is None else [folder / f for _, f in interfaces]
    for f in files + (ifiles or []):
        if not f.is_file():
            raise FileNotFoundError(f"incomplete results folder {folder}: {f} is missing")
    steps = []
    for k, f in enumerate(files):
        m = _STEP_FILE.search(f.name)
        steps.append(int(m.group(1)) if m else k)
    steps_a = np.asarray(steps, dtype=int)
    times = np.asarray([t for t, _ in blocks], dtype=float)
    summary = rf.read_summary(folder)
    return ResultsSeries(
        folder=folder,
        steps=steps_a,
        times=times,
        load_factors=_load_factors(folder, steps_a, times),
        block_files=tuple(files),
        interface_files=None if ifiles is None else tuple(ifiles),
        name=str(summary.get("name", folder.name)),
        summary=summary,
    )


def _load_factors(folder: Path, steps: np.ndarray, times: np.ndarray) -> np.ndarray:
    """lambda of each step: the PVD times, unless the writer replaced them by step numbers
    (lambda not increasing), in which case pushover.csv gives them."""
    if not (steps.size > 1 and np.array_equal(times, steps.astype(float))):
        return times
    try:
        table = read_pushover(folder)
    except (FileNotFoundError, ValueError):
        log.warning("%s: PVD times are step numbers and pushover.csv is unusable", folder)
        return np.full(steps.size, np.nan)
    lookup = dict(zip(table["step"].astype(int).tolist(), table["lambda"].tolist(), strict=True))
    return np.array([lookup.get(int(s), np.nan) for s in steps])


def read_pushover(folder: Path | str) -> dict[str, np.ndarray]:
    """Columns of ``pushover.csv`` (step, lambda, control_displacement) as arrays."""
    path = Path(folder) / rf.PUSHOVER
    if not path.is_file():
        raise FileNotFoundError(
            f"incomplete results folder {Path(folder)}: pushover.csv is missing"
        )
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise ValueError(f"{path} is empty")
    header = [h.strip() for h in rows[0]]
    need = ("step", "lambda", "control_displacement")
    if any(h not in header for h in need):
        raise ValueError(f"{path}: header must hold {', '.join(need)}, got {', '.join(header)}")
    try:
        data = np.array([[float(x) for x in r] for r in rows[1:] if r], dtype=float)
    except ValueError as exc:
        raise ValueError(f"{path}: non-numeric value ({exc})") from exc
    data = data.reshape(-1, len(header))
    return {h: data[:, header.index(h)] for h in need}


# --------------------------------------------------------------------------- one step's geometry
@dataclass(frozen=True)
class _StepData:
    """Blocks (nb, 8, 3) corners + displacements, fixed flags; interfaces (m, 4, 3) corners +
    displacements, normal axis and state."""

    block_points: np.ndarray
    block_disp: np.ndarray
    fixed: np.ndarray
    joint_points: np.ndarray | None
    joint_disp: np.ndarray | None
    joint_axis: np.ndarray | None
    state: np.ndarray | None
    load_factor: float | None


def _read_cells(pv, path: Path, celltype: int, per_cell: int):
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


def _point_field(grid, path: Path, name: str, per_cell: int) -> np.ndarray:
    """Point data ``name`` of ``grid`` per cell corner (cells, per_cell, 3)."""
    if name not in grid.point_data:
        raise ValueError(f"{path}: point data {name!r} is missing")
    conn = np.asarray(grid.cell_connectivity).reshape(grid.n_cells, per_cell)
    return np.asarray(grid.point_data[name], dtype=float)[conn]


def _read_step(series: ResultsSeries, index: int, interfaces: bool = True) -> _StepData:
    pv = _pyvista()
    grid, bpts, bdisp = _read_cells(pv, series.block_files[index], _VTK_HEXAHEDRON, 8)
    fixed = (
        np.asarray(grid.cell_data["fixed"]).astype(bool)
        if "fixed" in grid.cell_data
        else np.zeros(grid.n_cells, dtype=bool)
    )
    lam = None
    if "load_factor" in grid.field_data:  # written by newer writers; preferred when present
        lam = float(np.asarray(grid.field_data["load_factor"]).ravel()[0])
    jp = jd = axis = state = None
    if interfaces and series.interface_files is not None:
        igrid, jp, jd = _read_cells(pv, series.interface_files[index], _VTK_QUAD, 4)
        if "state" not in igrid.cell_data:
            raise ValueError(f"{series.interface_files[index]}: cell data 'state' is missing")
        state = np.asarray(igrid.cell_data["state"]).astype(int)
        if "normal_axis" in igrid.cell_data:
            axis = np.asarray(igrid.cell_data["normal_axis"]).astype(int)
        else:  # the axis along which the quad is flat
            axis = np.argmin(np.ptp(jp, axis=1), axis=1)
    return _StepData(bpts, bdisp, fixed, jp, jd, axis, state, lam)


def _wall_size(data: _StepData) -> float:
    p = data.block_points.reshape(-1, 3)
    return float(np.max(p.max(axis=0) - p.min(axis=0)))


def _max_displacement(data: _StepData) -> float:
    return (
        float(np.sqrt(np.max(np.sum(data.block_disp**2, axis=2)))) if data.block_disp.size else 0.0
    )


def auto_scale(max_displacement: float, wall_size: float) -> float:
    """A round amplification (two significant figures, rounded down) making the largest
    displacement about :data:`AUTO_SCALE_TARGET` of the wall size; 1 when nothing moves."""
    if not (max_displacement > 0 and math.isfinite(max_displacement)) or wall_size <= 0:
        return 1.0
    raw = AUTO_SCALE_TARGET * wall_size / max_displacement
    mag = 10.0 ** (math.floor(math.log10(raw)) - 1)
    return float(math.floor(raw / mag) * mag)


def _gap(data: _StepData, window_size: tuple[int, int]) -> float:
    """Joint thickness: GAP_FRACTION of the median smallest block dimension, at least about
    1.5 pixels (so the damage colours stay visible on large walls), at most 35 % of it."""
    ext = data.block_points.max(axis=1) - data.block_points.min(axis=1)
    dmin = float(np.median(ext.min(axis=1)))
    pixel = _wall_size(data) / (min(window_size) * (_FREE_BOX[3] - _FREE_BOX[1]))
    return float(min(max(GAP_FRACTION * dmin, 1.5 * pixel), 0.35 * dmin))


def _block_surface(data: _StepData, scale: float, gap: float):
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


def _joint_surface(data: _StepData, scale: float, gap: float):
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
def _check_view(view: str) -> dict[str, Any]:
    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}: choose one of {', '.join(VIEWS)}")
    return VIEWS[view]


def _check_scale(scale: float | None) -> float | None:
    if scale is None:
        return None
    s = float(scale)
    if not math.isfinite(s) or s < 0:
        raise ValueError(f"scale must be a finite number >= 0, got {scale!r}")
    return s


def _check_window(window_size: Sequence[int]) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in window_size)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"window_size must be (width, height), got {window_size!r}") from exc
    if w < 64 or h < 64 or w > 8192 or h > 8192:
        raise ValueError(f"window_size must be between 64 and 8192 pixels, got {window_size!r}")
    return w, h


def _check_out(out: Path | str | None, default: Path, suffixes: tuple[str, ...], what: str) -> Path:
    path = default if out is None else Path(out)
    if path.suffix.lower() not in suffixes:
        raise ValueError(f"{what} must be written to a {' or '.join(suffixes)} file, got {path}")
    if path.exists() and path.is_dir():
        raise ValueError(f"{what}: {path} is a directory")
    return path


def _atomic_target(path: Path) -> Path:
    """A temporary name beside ``path`` (same suffix) to be renamed over it when complete,
    so a failed render never leaves a half-written file or destroys the previous one."""
    path.parent.mkdir(parents=True, exist_ok=True)
    return path.with_name(f".{path.stem}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp{path.suffix}")


class _Scene:
    """One plotter with the block mesh and the joint mesh, updated in place for each step."""

    def __init__(
        self,
        first: _StepData,
        view: str,
        window_size: tuple[int, int],
        gap: float,
        legend: bool = True,
        palette: tuple[Sequence[str], Sequence[tuple[int, int, int]]] = (
            STATE_NAMES,
            STATE_COLOURS,
        ),
    ) -> None:
        pv = _pyvista()
        self.palette = palette
        self.pv = pv
        self.view = _check_view(view)
        self.gap = gap
        self._title: Any = None
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

    def update(self, data: _StepData, scale: float) -> None:
        self.blocks.points = _block_surface(data, scale, self.gap)
        if self.joints is not None and data.state is not None:
            self.joints.points = _joint_surface(data, scale, self.gap)
            self.joints.cell_data["rgb"] = np.repeat(
                state_colours(data.state, self.palette[1]), 4, axis=0
            )

    def frame_camera(self, points: np.ndarray) -> None:
        """Place the camera of the view preset so that ``points`` (k, 3) fill the picture."""
        v = self.view
        cam = self.plotter.camera
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
        x0, y0, x1, y1 = _FREE_BOX
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
        """Title at the top centre (one text actor, updated in place: cheap per frame)."""
        if self._title is None:
            w, h = self.plotter.window_size
            actor = self.pv.Text(text)
            prop = actor.GetTextProperty()
            prop.SetFontSize(max(9, int(round(26 * min(w / 1200, h / 900)))))
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
        self.plotter.close()


def _write_atomically(path: Path, write) -> None:
    """``write(tmp)`` to a temporary file next to ``path``, then move it onto ``path``: a
    reader never sees a half-written picture, and a failed write leaves nothing behind."""
    tmp = _atomic_target(path)
    try:
        write(tmp)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)


def _save_and_close(scene: _Scene, path: Path) -> None:
    """Write the scene to ``path`` atomically, then close it."""
    try:
        _write_atomically(path, scene.save)
    finally:
        scene.close()


def _title(series: ResultsSeries, index: int, data: _StepData, scale: float) -> str:
    lam = data.load_factor if data.load_factor is not None else series.load_factors[index]
    lam_txt = "n/a" if lam is None or not np.isfinite(lam) else f"{lam:.4g}"
    return (
        f"{series.name}: step {int(series.steps[index])}\n"
        f"lambda = {lam_txt}   displacements x {scale:.3g}"
    )


def _deformed_extent(data: _StepData, scale: float, gap: float) -> np.ndarray:
    return np.concatenate([data.block_points.reshape(-1, 3), _block_surface(data, scale, gap)])


# --------------------------------------------------------------------------- public API
def _step_scene(
    series: ResultsSeries, index: int, view: str, scale: float | None, wsize: tuple[int, int]
) -> tuple[_Scene, float]:
    """A scene of one step, camera and title set; the caller closes it."""
    data = _read_step(series, index)
    s = auto_scale(_max_displacement(data), _wall_size(data)) if scale is None else scale
    gap = _gap(data, wsize)
    scene = _Scene(data, view, wsize, gap)
    try:
        scene.update(data, s)
        scene.frame_camera(_deformed_extent(data, s, gap))
        scene.title(_title(series, index, data, s))
    except BaseException:
        scene.close()
        raise
    return scene, s


def render_step(
    folder: Path | str,
    step: int | str = "last",
    view: str = "oblique",
    scale: float | None = None,
    out: Path | str | None = None,
    window_size: Sequence[int] = (1200, 900),
) -> Path:
    """PNG of the deformed wall at ``step`` (a step number or ``"last"``), damage colours on
    the interfaces, in camera preset ``view`` (:data:`VIEWS`). ``scale`` amplifies the
    displacements (None: automatic). Written to ``out`` or ``<folder>/render_<view>_<step>.png``;
    returns the path."""
    _check_view(view)
    scale = _check_scale(scale)
    wsize = _check_window(window_size)
    series = open_results(folder)
    index = series.index_of(step)
    default = series.folder / f"render_{view}_{int(series.steps[index]):04d}.png"
    path = _check_out(out, default, _IMAGE_SUFFIXES, "render_step")
    scene, s = _step_scene(series, index, view, scale, wsize)
    _save_and_close(scene, path)
    log.info(
        "rendered step %d of %s (%s view, scale %g) to %s",
        int(series.steps[index]),
        series.folder,
        view,
        s,
        path,
    )
    return path


def render_side_by_side(
    folders: Sequence[Path | str],
    out: Path | str,
    view: str | Sequence[str] = "oblique",
    step: int | str = "last",
    columns: int | None = None,
    window_size: Sequence[int] = (600, 450),
    mechanism: bool = False,
) -> Path:
    """One PNG with several results folders (or several views of one: repeat the folder and
    give a list of views) rendered side by side, ``columns`` per row (default: all in one
    row), each panel ``window_size`` with its own title and automatic scale. For galleries
    such as the paper's collapse mechanisms (``mechanism=True``: the collapse mode of each
    folder, as :func:`render_mechanism`, instead of ``step``)."""
    dirs = [Path(f) for f in folders]
    if not dirs:
        raise ValueError("render_side_by_side needs at least one results folder")
    views = [view] * len(dirs) if isinstance(view, str) else list(view)
    if len(views) != len(dirs):
        raise ValueError(f"{len(dirs)} folders but {len(views)} views")
    for v in views:
        _check_view(v)
    wsize = _check_window(window_size)
    ncol = len(dirs) if columns is None else int(columns)
    if ncol < 1:
        raise ValueError(f"columns must be >= 1, got {columns!r}")
    path = _check_out(out, Path(out), _IMAGE_SUFFIXES, "render_side_by_side")
    # generators: each scene is made only when the previous one is closed
    if mechanism:
        scenes = (
            _mechanism_scene(f, v, None, wsize, False) for f, v in zip(dirs, views, strict=True)
        )
    else:
        series = [open_results(f) for f in dirs]
        indices = [s.index_of(step) for s in series]
        scenes = (
            _step_scene(ser, idx, v, None, wsize)[0]
            for ser, idx, v in zip(series, indices, views, strict=True)
        )
    panels = []
    for scene in scenes:
        try:
            panels.append(np.asarray(scene.image())[..., :3])
        finally:
            scene.close()
    nrow = -(-len(panels) // ncol)
    h, w = panels[0].shape[:2]
    sheet = np.full((nrow * h, ncol * w, 3), 255, dtype=np.uint8)
    for k, img in enumerate(panels):
        r, c = divmod(k, ncol)
        sheet[r * h : (r + 1) * h, c * w : (c + 1) * w] = img
    import imageio.v3 as iio

    _write_atomically(path, lambda tmp: iio.imwrite(tmp, sheet, extension=".png"))
    log.info("%d panels written to %s", len(panels), path)
    return path


def render_animation(
    folder: Path | str,
    out: Path | str | None = None,
    fps: float = 8.0,
    view: str = "oblique",
    scale: float | None = None,
    window_size: Sequence[int] = (800, 600),
) -> Path:
    """Animation (GIF; MP4 when imageio-ffmpeg is installed) of every step of a results folder,
    one frame per step, with one displacement scale and one camera for the whole run
    (automatic scale: from the largest displacement of all steps). Written to ``out`` or
    ``<folder>/animation_<view>.gif``; returns the path."""
    _check_view(view)
    scale = _check_scale(scale)
    wsize = _check_window(window_size)
    fps = float(fps)
    if not math.isfinite(fps) or not 0 < fps <= 100:
        raise ValueError(f"fps must be in (0, 100], got {fps!r}")
    series = open_results(folder)
    path = _check_out(
        out, series.folder / f"animation_{view}.gif", _ANIMATION_SUFFIXES, "render_animation"
    )
    import imageio.v3 as iio

    if path.suffix.lower() == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError as exc:
            raise ValueError(
                "an MP4 animation needs the imageio-ffmpeg package; write a .gif"
            ) from exc
    # pass 1, blocks only, one step in memory at a time: one scale (the largest displacement
    # of the run) and one camera (a box holding every deformed step) for the whole animation
    n = len(series.steps)
    first = _read_step(series, 0, interfaces=False)
    wall, gap = _wall_size(first), _gap(first, wsize)
    dmax = 0.0
    p_lo, p_hi = first.block_points.min(axis=(0, 1)), first.block_points.max(axis=(0, 1))
    d_lo, d_hi = np.zeros(3), np.zeros(3)
    for k in range(n):
        blocks = first if k == 0 else _read_step(series, k, interfaces=False)
        dmax = max(dmax, _max_displacement(blocks))
        d_lo = np.minimum(d_lo, blocks.block_disp.min(axis=(0, 1)))
        d_hi = np.maximum(d_hi, blocks.block_disp.max(axis=(0, 1)))
    if scale is None:
        scale = auto_scale(dmax, wall)
    lo, hi = p_lo + scale * d_lo, p_hi + scale * d_hi
    # pass 2: one frame per step
    data = _read_step(series, 0)
    scene = _Scene(data, view, wsize, gap)
    frames = []
    try:
        scene.frame_camera(np.array([lo, hi]))
        for k in range(n):
            data = data if k == 0 else _read_step(series, k)
            scene.update(data, scale)
            scene.title(_title(series, k, data, scale))
            frames.append(np.asarray(scene.image()))
    finally:
        scene.close()

    def write(tmp: Path) -> None:
        if path.suffix.lower() == ".gif":
            iio.imwrite(tmp, np.stack(frames), extension=".gif", duration=1000.0 / fps, loop=0)
        else:
            iio.imwrite(tmp, np.stack(frames), extension=".mp4", fps=fps)

    _write_atomically(path, write)
    log.info("animation of %d steps of %s written to %s", len(frames), series.folder, path)
    return path


def plot_pushover(folder: Path | str, out: Path | str | None = None) -> Path:
    """The pushover curve (lambda against the control displacement; against the step when
    no control displacement was recorded), with the collapse multiplier when the summary
    gives one. Written to ``out`` or ``<folder>/pushover.png``; returns the path."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"results folder not found: {folder}")
    table = read_pushover(folder)
    if table["lambda"].size == 0:
        raise ValueError(f"{folder / 'pushover.csv'} holds no step")
    path = _check_out(out, folder / "pushover.png", _PLOT_SUFFIXES, "plot_pushover")
    summary = rf.read_summary(folder)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.4), dpi=150)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    x, lam = table["control_displacement"], table["lambda"]
    if np.any(x != 0):
        ax.plot(x, lam, "o-", ms=3, lw=1.4, color="#1f4e9c")
        ax.set_xlabel("control displacement")
    else:
        ax.plot(table["step"], lam, "o-", ms=3, lw=1.4, color="#1f4e9c")
        ax.set_xlabel("step")
    ax.set_ylabel("load multiplier $\\lambda$")
    collapse = summary.get("lambda") if summary.get("status") == "collapse" else None
    if isinstance(collapse, (int, float)):
        ax.axhline(
            collapse, ls="--", color="#c0392b", lw=1, label=f"collapse $\\lambda$ = {collapse:.4g}"
        )
        ax.legend(loc="lower right")
    ax.grid(True, alpha=0.3)
    name = summary.get("name", folder.name)
    status = summary.get("status")
    ax.set_title(f"{name}" + (f" ({status})" if status else ""))
    fig.tight_layout()
    _write_atomically(path, fig.savefig)
    log.info("pushover curve of %s written to %s", folder, path)
    return path


def _mechanism_scene(
    folder: Path, view: str, scale: float | None, wsize: tuple[int, int], last_increment: bool
) -> _Scene:
    """A scene of the collapse mechanism of ``folder``, camera and title set; the caller
    closes it."""
    bfile, ifile = (folder / f for f in rf.MECHANISM_FILES)
    if not bfile.is_file():
        raise FileNotFoundError(
            f"no collapse mechanism in {folder}: {bfile.name} is missing (it is written when "
            "a run ends in collapse)"
        )
    pv = _pyvista()
    grid, bpts, bdisp = _read_cells(pv, bfile, _VTK_HEXAHEDRON, 8)
    field = "joint_motion_last_increment" if last_increment else "joint_motion"
    if last_increment:
        bdisp = _point_field(grid, bfile, "last_increment", 8)
    fixed = np.asarray(grid.cell_data["fixed"]).astype(bool)
    jp = jd = axis = code = None
    if ifile.is_file():
        igrid, jp, jd = _read_cells(pv, ifile, _VTK_QUAD, 4)
        if field not in igrid.cell_data:
            raise ValueError(f"{ifile}: cell data {field!r} is missing")
        if last_increment:
            jd = _point_field(igrid, ifile, "last_increment", 4)
        motion = np.asarray(igrid.cell_data[field], dtype=float)
        code = np.searchsorted(np.asarray(MECHANISM_BINS), motion, side="right")
        axis = np.asarray(igrid.cell_data["normal_axis"]).astype(int)
    data = _StepData(bpts, bdisp, fixed, jp, jd, axis, code, None)
    summary = rf.read_summary(folder)
    name, lam = str(summary.get("name", folder.name)), summary.get("lambda")
    s = auto_scale(_max_displacement(data), _wall_size(data)) if scale is None else scale
    gap = _gap(data, wsize)
    scene = _Scene(data, view, wsize, gap, palette=(MECHANISM_LABELS, MECHANISM_COLOURS))
    try:
        scene.update(data, s)
        scene.frame_camera(_deformed_extent(data, s, gap))
        what = "last increment" if last_increment else "collapse mode"
        lam_txt = "" if lam is None else f" at lambda = {lam:.4g}"
        scene.title(f"{name}: mechanism{lam_txt}\n{what}; joints by relative motion")
    except BaseException:
        scene.close()
        raise
    return scene


def render_mechanism(
    folder: Path | str,
    view: str = "oblique",
    scale: float | None = None,
    out: Path | str | None = None,
    window_size: Sequence[int] = (1200, 900),
    last_increment: bool = False,
) -> Path:
    """PNG of the collapse mechanism of a results folder: the blocks moved by the collapse
    mode (``mechanism_blocks.vtu``, written when a run ends in collapse) and every joint
    coloured by the relative motion across it, as a share of the largest
    (:data:`MECHANISM_BINS`): the cracks and hinges of the mechanism. ``last_increment``
    uses the last displacement increment of the run instead of the mode. Written to ``out``
    or ``<folder>/mechanism_<view>.png``; returns the path."""
    _check_view(view)
    scale = _check_scale(scale)
    wsize = _check_window(window_size)
    folder = Path(folder)
    path = _check_out(out, folder / f"mechanism_{view}.png", _IMAGE_SUFFIXES, "render_mechanism")
    scene = _mechanism_scene(folder, view, scale, wsize, last_increment)
    _save_and_close(scene, path)
    log.info("rendered the collapse mechanism of %s (%s view) to %s", folder, view, path)
    return path
