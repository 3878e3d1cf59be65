"""The pushover curve of a results folder (matplotlib): lambda against the displacement the
run recorded, with that displacement named (which block and DOF, in mm) and the collapse
multiplier marked.

``pushover.csv`` stores one displacement per step: the DOF a displacement control drives or
a ``monitor`` names, else the largest translation of any block. Its header names the block
and DOF; for files whose header does not, :func:`control_dof` finds them from the steps' own
block motions (``translation`` and ``rotation`` of the blocks VTU), so folders of any version
are named correctly.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.export import pushover_file as pf
from masonry_dem.export import results_folder as rf
from masonry_dem.export.figure_text import frame_level, level, method_of, plain_axes, set_title
from masonry_dem.export.picture_files import check_out, write_atomically
from masonry_dem.export.results_series import open_results, read_pushover, recorded_in_pushover

log = logging.getLogger(__name__)

_PLOT_SUFFIXES = (".png", ".svg", ".pdf")
DOF_NAMES = pf.DOF_NAMES
LARGEST_TRANSLATION = pf.LARGEST_TRANSLATION


def _block_motion(path: Path) -> np.ndarray | None:
    """(nb, 6) translations and rotations of a blocks VTU; None when not recorded."""
    import meshio

    mesh = meshio.read(path)
    data = mesh.cell_data
    if "translation" not in data or "rotation" not in data:
        return None
    return np.hstack([np.asarray(data["translation"][0]), np.asarray(data["rotation"][0])])


def control_dof(folder: Path | str) -> pf.Recorded:
    """Which displacement ``pushover.csv`` records: the block and DOF its header names, else
    (files written before it named them) :func:`pushover_file.recorded_dof` of the steps'
    block motions; None when neither tells."""
    named = recorded_in_pushover(folder)
    if named is not None:
        return named
    table = read_pushover(folder)
    try:
        series = open_results(folder)
    except (FileNotFoundError, ValueError):
        return None
    c = table["control_displacement"]
    file_of = dict(zip(series.steps.tolist(), series.block_files, strict=True))
    rows = [int(k) for k in np.argsort(-np.abs(c)) if abs(c[k]) > 0 and int(k) in file_of]
    motions = []
    for k in rows[: pf.STEPS_CHECKED]:
        q = _block_motion(file_of[k])
        if q is None:
            return None
        motions.append((float(c[k]), q))
    return pf.recorded_dof(motions)


def control_label(which: tuple[int, str] | str | None) -> tuple[str, float]:
    """Axis label (with its unit) of the recorded displacement and the factor from the
    stored SI value (m, rad) to that unit (mm, mrad)."""
    if isinstance(which, tuple):
        block, dof = which
        unit = "mrad" if dof.startswith("w") else "mm"
        return f"block {block}, {dof} [{unit}]", 1e3
    if isinstance(which, str) and which.startswith(LARGEST_TRANSLATION):
        return f"{which} [mm]", 1e3
    return "control displacement [mm]", 1e3


def pushover_figure(folder: Path | str) -> Any:
    """The pushover curve of ``folder`` as a matplotlib Figure (Agg canvas, no pyplot)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"results folder not found: {folder}")
    table = read_pushover(folder)
    if table["lambda"].size == 0:
        raise ValueError(f"{folder / 'pushover.csv'} holds no step")
    summary = rf.read_summary(folder)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.4), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    x, lam = table["control_displacement"], table["lambda"]
    if np.any(x != 0):
        label, factor = control_label(control_dof(folder))
        ax.plot(factor * x, lam, "o-", ms=3, lw=1.4, color="#1f4e9c")
        ax.set_xlabel(label)
    else:
        ax.plot(table["step"], lam, "o-", ms=3, lw=1.4, color="#1f4e9c")
        ax.set_xlabel("step (no displacement recorded)")
    ax.set_ylabel("load multiplier $\\lambda$ [-]")
    collapse = summary.get("lambda") if summary.get("status") == "collapse" else None
    if isinstance(collapse, (int, float)):
        ax.axhline(
            collapse, ls="--", color="#c0392b", lw=1, label=f"collapse $\\lambda$ = {collapse:.4g}"
        )
        ax.legend(loc="lower right")
    ax.grid(True, alpha=0.3)
    plain_axes(ax)
    flat = level(lam)
    if flat is not None:
        frame_level(ax, flat)
    name = summary.get("name", folder.name)
    status = summary.get("status")
    method = method_of(summary)
    set_title(ax, f"{name}\n{method}" + (f": {status}" if status else ""))
    fig.tight_layout()
    return fig


def plot_pushover(folder: Path | str, out: Path | str | None = None, dpi: int = 150) -> Path:
    """The pushover curve (lambda against the recorded displacement, named by
    :func:`control_dof`, in mm; against the step when no displacement was recorded), with
    the collapse multiplier when the summary gives one. Written to ``out`` or
    ``<folder>/pushover.png``; returns the path."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"results folder not found: {folder}")
    path = check_out(out, folder / "pushover.png", _PLOT_SUFFIXES, "plot_pushover")
    fig = pushover_figure(folder)
    write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=dpi))
    log.info("pushover curve of %s written to %s", folder, path)
    return path
