"""The pushover curve of a results folder (matplotlib): lambda against the displacement the
run recorded, with that displacement named (which block and DOF, in mm) and the collapse
multiplier marked.

``pushover.csv`` stores one displacement per step: the DOF a displacement control drives or
a ``monitor`` names, else the largest translation of any block. The file does not say which;
:func:`control_label` finds it from the steps' own block motions (``translation`` and
``rotation`` of the blocks VTU), so folders of any version are named correctly.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.export import results_folder as rf
from masonry_dem.export.picture_files import check_out, write_atomically
from masonry_dem.export.results_series import open_results, read_pushover

log = logging.getLogger(__name__)

_PLOT_SUFFIXES = (".png", ".svg", ".pdf")
DOF_NAMES = ("u1", "u2", "u3", "w1", "w2", "w3")
#: steps whose motion is compared with the recorded displacement to name it
_STEPS_CHECKED = 4
#: relative agreement for a block DOF to be the recorded one
_MATCH = 1e-6
LARGEST_TRANSLATION = "largest block translation (any block, u1-u3)"


def _block_motion(path: Path) -> np.ndarray | None:
    """(nb, 6) translations and rotations of a blocks VTU; None when not recorded."""
    import meshio

    mesh = meshio.read(path)
    data = mesh.cell_data
    if "translation" not in data or "rotation" not in data:
        return None
    return np.hstack([np.asarray(data["translation"][0]), np.asarray(data["rotation"][0])])


def control_dof(folder: Path | str) -> tuple[int, str] | str | None:
    """Which displacement ``pushover.csv`` records: ``(block, dof name)`` when one block DOF
    equals it at every step checked (a displacement control, a monitor, or the largest
    translation staying on one DOF), else :data:`LARGEST_TRANSLATION` (followed by the block
    and DOF where it is largest at the largest step) when it is that, else None when the steps written do not tell (no motion yet,
    or files of another layout)."""
    table = read_pushover(folder)
    try:
        series = open_results(folder)
    except (FileNotFoundError, ValueError):
        return None
    c = table["control_displacement"]
    file_of = dict(zip(series.steps.tolist(), series.block_files, strict=True))
    rows = [int(k) for k in np.argsort(-np.abs(c)) if abs(c[k]) > 0 and int(k) in file_of]
    motions = []
    for k in rows[:_STEPS_CHECKED]:
        q = _block_motion(file_of[k])
        if q is None:
            return None
        motions.append((c[k], q))
    if not motions:
        return None
    scale = max(abs(v) for v, _ in motions)
    tol = _MATCH * scale
    hit = np.ones(motions[0][1].shape, dtype=bool)
    for v, q in motions:
        hit &= np.abs(q - v) <= tol
    found = np.argwhere(hit)
    if not found.size:  # no one DOF: the largest translation, wherever it is
        if all(abs(np.abs(q[:, :3]).max() - v) <= tol for v, q in motions):
            block, dof = divmod(int(np.argmax(np.abs(motions[0][1][:, :3]))), 3)
            return f"{LARGEST_TRANSLATION}; at its largest block {block} {DOF_NAMES[dof]}"
        return None
    block, dof = (int(x) for x in found[0])
    return block, DOF_NAMES[dof]


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
    name = summary.get("name", folder.name)
    status = summary.get("status")
    ax.set_title(f"{name}" + (f" ({status})" if status else ""), fontsize=10)
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
