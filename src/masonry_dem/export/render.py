"""Off-screen pictures of a results folder: the deformed wall with its damage map at a step,
an animation of the whole analysis, the collapse mechanism, side-by-side sheets, and (from
:mod:`masonry_dem.export.plots`) the pushover curve.

The public entry points of the pictures live here; the scene (meshes, camera) is
:mod:`masonry_dem.export.scene`, what makes a picture explain itself (caption, triad, length
scale, load arrow, support marks, legend title) :mod:`masonry_dem.export.annotations`, the
results folder's series :mod:`masonry_dem.export.results_series`. Every file is written under a
temporary name and renamed into place: a reader never sees half a picture.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from masonry_dem.export import results_folder as rf
from masonry_dem.export.figure_text import method_of
from masonry_dem.export.picture_files import check_out, write_atomically
from masonry_dem.export.plots import plot_pushover
from masonry_dem.export.results_series import ResultsSeries, open_results, read_pushover
from masonry_dem.export.scene import (
    BACKGROUND,
    BLOCK_COLOUR,
    LEGEND_BOX,
    MECHANISM_BINS,
    MECHANISM_COLOURS,
    MECHANISM_LABELS,
    MECHANISM_LEGEND_TITLE,
    STATE_COLOURS,
    SUPPORT_COLOUR,
    VIEWS,
    VTK_HEXAHEDRON,
    VTK_QUAD,
    Scene,
    StepData,
    auto_scale,
    block_supports_and_loads,
    check_view,
    deformed_extent,
    joint_gap,
    max_displacement,
    point_field,
    pyvista_offscreen,
    read_cells,
    read_step,
    state_colours,
    view_of_motion,
    wall_size,
)

__all__ = [
    "BACKGROUND",
    "BLOCK_COLOUR",
    "LEGEND_BOX",
    "MECHANISM_BINS",
    "MECHANISM_COLOURS",
    "MECHANISM_LABELS",
    "STATE_COLOURS",
    "SUPPORT_COLOUR",
    "VIEWS",
    "ResultsSeries",
    "auto_scale",
    "open_results",
    "plot_pushover",
    "read_pushover",
    "mechanism_view",
    "render_animation",
    "render_mechanism",
    "render_side_by_side",
    "render_step",
    "state_colours",
]

log = logging.getLogger(__name__)

_IMAGE_SUFFIXES = (".png",)
_ANIMATION_SUFFIXES = (".gif", ".mp4")


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


def _save_and_close(scene: Scene, path: Path) -> None:
    """Write the scene to ``path`` atomically, then close it."""
    try:
        write_atomically(path, scene.save)
    finally:
        scene.close()


def caption(
    name: str,
    what: str,
    lam: float | None,
    status: str | None,
    amplification: str,
    method: str,
) -> str:
    """The picture's title: the case, then what is drawn and by which method, lambda, the
    run's status and the displacement amplification."""
    lam_txt = "n/a" if lam is None or not np.isfinite(lam) else f"{lam + 0.0:.4g}"  # no "-0"
    parts = [f"{what}, {method}", f"lambda = {lam_txt}"]
    if status:
        parts.append(str(status))
    parts.append(amplification)
    return f"{name}\n" + "   ".join(parts)


def _title(series: ResultsSeries, index: int, data: StepData, scale: float) -> str:
    lam = data.load_factor if data.load_factor is not None else series.load_factors[index]
    return caption(
        series.name,
        f"step {int(series.steps[index])}",
        lam,
        series.summary.get("status"),
        f"displacements x {scale:.3g}",
        method_of(series.summary),
    )


# --------------------------------------------------------------------------- public API
def _step_scene(
    series: ResultsSeries, index: int, view: str, scale: float | None, wsize: tuple[int, int]
) -> tuple[Scene, float]:
    """A scene of one step, camera and title set; the caller closes it."""
    data = read_step(series, index)
    s = auto_scale(max_displacement(data), wall_size(data)) if scale is None else scale
    gap = joint_gap(data, wsize)
    scene = Scene(data, view, wsize, gap)
    try:
        scene.update(data, s)
        scene.title(_title(series, index, data, s))
        scene.frame_camera(deformed_extent(data, s, gap))
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
    check_view(view)
    scale = _check_scale(scale)
    wsize = _check_window(window_size)
    series = open_results(folder)
    index = series.index_of(step)
    default = series.folder / f"render_{view}_{int(series.steps[index]):04d}.png"
    path = check_out(out, default, _IMAGE_SUFFIXES, "render_step")
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
        check_view(v)
    wsize = _check_window(window_size)
    ncol = len(dirs) if columns is None else int(columns)
    if ncol < 1:
        raise ValueError(f"columns must be >= 1, got {columns!r}")
    path = check_out(out, Path(out), _IMAGE_SUFFIXES, "render_side_by_side")
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

    write_atomically(path, lambda tmp: iio.imwrite(tmp, sheet, extension=".png"))
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
    check_view(view)
    scale = _check_scale(scale)
    wsize = _check_window(window_size)
    fps = float(fps)
    if not math.isfinite(fps) or not 0 < fps <= 100:
        raise ValueError(f"fps must be in (0, 100], got {fps!r}")
    series = open_results(folder)
    path = check_out(
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
    first = read_step(series, 0, interfaces=False)
    wall, gap = wall_size(first), joint_gap(first, wsize)
    dmax = 0.0
    p_lo, p_hi = first.block_points.min(axis=(0, 1)), first.block_points.max(axis=(0, 1))
    d_lo, d_hi = np.zeros(3), np.zeros(3)
    for k in range(n):
        blocks = first if k == 0 else read_step(series, k, interfaces=False)
        dmax = max(dmax, max_displacement(blocks))
        d_lo = np.minimum(d_lo, blocks.block_disp.min(axis=(0, 1)))
        d_hi = np.maximum(d_hi, blocks.block_disp.max(axis=(0, 1)))
    if scale is None:
        scale = auto_scale(dmax, wall)
    lo, hi = p_lo + scale * d_lo, p_hi + scale * d_hi
    # pass 2: one frame per step
    data = read_step(series, 0)
    scene = Scene(data, view, wsize, gap)
    frames = []
    try:
        # the longest title of the frames sets the room left below it
        scene.title(_title(series, n - 1, read_step(series, n - 1), scale))
        scene.frame_camera(np.array([lo, hi]))
        for k in range(n):
            data = data if k == 0 else read_step(series, k)
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

    write_atomically(path, write)
    log.info("animation of %d steps of %s written to %s", len(frames), series.folder, path)
    return path


def _read_mechanism(folder: Path, last_increment: bool) -> StepData:
    """The collapse mode of ``folder`` (or its last increment): blocks moved by it, joints
    coded by the relative motion across them (:data:`MECHANISM_BINS`)."""
    bfile, ifile = (folder / f for f in rf.MECHANISM_FILES)
    if not bfile.is_file():
        raise FileNotFoundError(
            f"no collapse mechanism in {folder}: {bfile.name} is missing (it is written when "
            "a run ends in collapse)"
        )
    pv = pyvista_offscreen()
    grid, bpts, bdisp = read_cells(pv, bfile, VTK_HEXAHEDRON, 8)
    field = "joint_motion_last_increment" if last_increment else "joint_motion"
    if last_increment:
        bdisp = point_field(grid, bfile, "last_increment", 8)
    fixed, restrained, live = block_supports_and_loads(grid)
    jp = jd = axis = code = None
    if ifile.is_file():
        igrid, jp, jd = read_cells(pv, ifile, VTK_QUAD, 4)
        if field not in igrid.cell_data:
            raise ValueError(f"{ifile}: cell data {field!r} is missing")
        if last_increment:
            jd = point_field(igrid, ifile, "last_increment", 4)
        motion = np.asarray(igrid.cell_data[field], dtype=float)
        code = np.searchsorted(np.asarray(MECHANISM_BINS), motion, side="right")
        axis = np.asarray(igrid.cell_data["normal_axis"]).astype(int)
    return StepData(bpts, bdisp, fixed, jp, jd, axis, code, None, restrained, live)


def mechanism_view(folder: Path | str, last_increment: bool = False) -> str:
    """The camera preset in which the collapse mode of a results folder moves the most
    (:func:`masonry_dem.export.scene.view_of_motion`): ``"side"`` for a wall overturning out
    of its plane, ``"front"`` for an in-plane mechanism, ``"oblique"`` for walls that meet."""
    return view_of_motion(_read_mechanism(Path(folder), last_increment))


def _mechanism_scene(
    folder: Path,
    view: str,
    scale: float | None,
    wsize: tuple[int, int],
    last_increment: bool,
    data: StepData | None = None,
) -> Scene:
    """A scene of the collapse mechanism of ``folder`` (``data``: as read already), camera
    and title set; the caller closes it."""
    if data is None:
        data = _read_mechanism(folder, last_increment)
    summary = rf.read_summary(folder)
    name, lam = str(summary.get("name", folder.name)), summary.get("lambda")
    s = auto_scale(max_displacement(data), wall_size(data)) if scale is None else scale
    gap = joint_gap(data, wsize)
    scene = Scene(
        data,
        view,
        wsize,
        gap,
        palette=(MECHANISM_LABELS, MECHANISM_COLOURS),
        legend_title=MECHANISM_LEGEND_TITLE,
    )
    try:
        scene.update(data, s)
        what = "mechanism, last increment" if last_increment else "mechanism (collapse mode)"
        amplification = f"displacements x {s:.3g}" if last_increment else f"unit mode x {s:.3g}"
        scene.title(
            caption(name, what, lam, summary.get("status"), amplification, method_of(summary))
        )
        scene.frame_camera(deformed_extent(data, s, gap))
    except BaseException:
        scene.close()
        raise
    return scene


def render_mechanism(
    folder: Path | str,
    view: str | None = None,
    scale: float | None = None,
    out: Path | str | None = None,
    window_size: Sequence[int] = (1200, 900),
    last_increment: bool = False,
) -> Path:
    """PNG of the collapse mechanism of a results folder: the blocks moved by the collapse
    mode (``mechanism_blocks.vtu``, written when a run ends in collapse) and every joint
    coloured by the relative motion across it, as a share of the largest
    (:data:`MECHANISM_BINS`): the cracks and hinges of the mechanism. ``view`` None: the view
    in which the mode moves the most (:func:`mechanism_view`: a wall overturning out of its
    plane from the side, an in-plane mechanism from the front). ``last_increment`` uses the
    last displacement increment of the run instead of the mode. Written to ``out`` or
    ``<folder>/mechanism_<view>.png``; returns the path."""
    folder = Path(folder)
    if view is not None:
        check_view(view)
    scale = _check_scale(scale)
    wsize = _check_window(window_size)
    data = _read_mechanism(folder, last_increment)
    view = view_of_motion(data) if view is None else view
    path = check_out(out, folder / f"mechanism_{view}.png", _IMAGE_SUFFIXES, "render_mechanism")
    scene = _mechanism_scene(folder, view, scale, wsize, last_increment, data)
    _save_and_close(scene, path)
    log.info("rendered the collapse mechanism of %s (%s view) to %s", folder, view, path)
    return path
