"""``pushover.csv`` of a results folder: the pushover curve, one row per step (step, lambda,
the control displacement), written row by row as the steps come (readable after a kill) and
whole at the end, and the name of what its third column records (a block's DOF, or the
largest translation).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.export.results_folder import PUSHOVER, write_atomic, write_error

#: the first columns of ``pushover.csv``; the third's name goes on with what it records
PUSHOVER_COLUMNS = ("step", "lambda", "control_displacement")
#: the fourth column of the ``pushover.csv`` of a run in loading stages: each step's stage
STAGE_COLUMN = "stage"
DOF_NAMES = ("u1", "u2", "u3", "w1", "w2", "w3")
#: what the third column records when no one block DOF equals it at every step
LARGEST_TRANSLATION = "largest block translation (any block, u1-u3)"
#: steps whose motion is compared with the recorded displacement to name it
STEPS_CHECKED = 4
#: relative agreement for a block DOF to be the recorded one
_MATCH = 1e-6

#: what ``pushover.csv``'s third column records: (block, DOF name), a description, or None
Recorded = tuple[int, str] | str | None


def recorded_dof(motions: list[tuple[float, np.ndarray]]) -> Recorded:
    """Which displacement a pushover recorded, from ``(recorded value, (nb, 6) block motion)``
    of its steps with the largest values: ``(block, DOF name)`` when one block DOF equals it
    at every step given (a displacement control, a monitor, or the largest translation
    staying on one DOF), else :data:`LARGEST_TRANSLATION` (followed by the block and DOF
    where it is largest at the first step given) when it is that, else None (no motion, or
    a displacement of no block DOF)."""
    motions = [(v, q) for v, q in motions if v != 0][:STEPS_CHECKED]
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


def recorded_dof_of(steps: Any, displacements: np.ndarray) -> Recorded:
    """:func:`recorded_dof` of a run's steps (each with its ``q``) and their recorded
    displacements, checked at the steps where these are largest (of equal ones, the
    earlier: :class:`RecordedSoFar` finds the same steps as they arrive)."""
    displacements = np.asarray(displacements, dtype=float)
    order = [
        int(k)
        for k in np.argsort(-np.abs(displacements), kind="stable")
        if displacements[k] != 0 and np.isfinite(displacements[k])
    ]
    return recorded_dof(
        [(float(displacements[k]), np.asarray(steps[k].q)) for k in order[:STEPS_CHECKED]]
    )


class RecordedSoFar:
    """:func:`recorded_dof_of` of a run's steps as they arrive, one by one: it keeps the
    motions of the :data:`STEPS_CHECKED` steps with the largest recorded displacements so
    far, so that after the last step :attr:`recorded` is what :func:`recorded_dof_of` says
    of the whole run (the header ``pushover.csv`` is written with row by row, and again at
    the end)."""

    def __init__(self) -> None:
        self._top: list[tuple[float, int, float, np.ndarray]] = []
        self.recorded: Recorded = None

    def add(self, index: int, value: float, q: Any) -> bool:
        """Take step ``index`` (its recorded displacement ``value`` and block motion ``q``);
        True when what the run is found to record changed with it."""
        value = float(value)
        if value == 0 or not np.isfinite(value):
            return False
        key = (-abs(value), int(index))
        if len(self._top) >= STEPS_CHECKED and key >= self._top[-1][:2]:
            return False  # not among the largest: it never will be
        self._top.append((*key, value, np.array(q, dtype=float)))
        self._top.sort(key=lambda t: t[:2])
        del self._top[STEPS_CHECKED:]
        found = recorded_dof([(v, q) for _, _, v, q in self._top])
        changed = found != self.recorded
        self.recorded = found
        return changed


def displacement_column(recorded: Recorded) -> str:
    """The header of ``pushover.csv``'s third column: ``control_displacement``, its unit and
    what it records, e.g. ``control_displacement [m] block 125 u3``."""
    name = PUSHOVER_COLUMNS[2]
    if isinstance(recorded, tuple):
        block, dof = recorded
        return f"{name} [{'rad' if dof.startswith('w') else 'm'}] block {block} {dof}"
    if isinstance(recorded, str):  # a CSV header holds no comma
        return f"{name} [m] largest block translation"
    return f"{name} [m]"


def write_pushover(
    folder: Path | str,
    steps,
    load_factors,
    control_displacements,
    recorded: Recorded = None,
    stages=None,
) -> None:
    """``pushover.csv``: one row per step (step, lambda, control_displacement, and with
    ``stages`` each step's loading stage), the third column's header naming what it records
    (:func:`displacement_column`)."""
    columns = [np.asarray(steps, dtype=float), np.asarray(load_factors), control_displacements]
    if stages is not None:
        columns.append(np.asarray(stages, dtype=float))
    rows = np.column_stack(columns).reshape(-1, len(columns))
    write_atomic(Path(folder) / PUSHOVER, lambda tmp: save_pushover_rows(tmp, rows, recorded))


def append_pushover_row(
    folder: Path | str,
    step: int,
    load_factor: float,
    control: float,
    recorded: Recorded = None,
    stage: int | None = None,
) -> None:
    """One row of ``pushover.csv`` as its step is handed over (the header with the first,
    ``step`` 0, naming ``recorded`` as :func:`save_pushover_rows` does), each in one
    ``write`` of a whole line to a file opened for appending: a run killed outright leaves
    the curve up to its last whole row, which the readers take. ``stage``: the step's
    loading stage, a fourth column (None: none)."""
    path = Path(folder) / PUSHOVER
    line = f"{int(step)},{float(load_factor):.10g},{float(control):.10g}"
    line += "\n" if stage is None else f",{int(stage)}\n"
    flags = os.O_WRONLY | os.O_CREAT | (os.O_TRUNC if step == 0 else os.O_APPEND)
    if step == 0:
        line = pushover_header(recorded, stage is not None) + "\n" + line
    try:
        fd = os.open(path, flags, 0o644)
        try:
            os.write(fd, line.encode())
        finally:
            os.close(fd)
    except OSError as exc:
        raise write_error(path, exc) from exc


def write_history_pushover(folder: Path | str, history: Any) -> None:
    """``pushover.csv`` of a :class:`~masonry_dem.results.History`: every step's lambda and
    recorded displacement, named by :func:`recorded_dof_of` its steps (and each step's
    loading stage, for a run in stages)."""
    displacements = history.control_displacements
    stages = history.stages
    write_pushover(
        folder,
        np.arange(len(history.steps)),
        history.load_factors,
        displacements,
        recorded_dof_of(history.steps, displacements),
        stages if stages.any() else None,
    )


def pushover_header(recorded: Recorded = None, staged: bool = False) -> str:
    """The header line of ``pushover.csv``: step, lambda and :func:`displacement_column`
    (and ``stage``, for a run in loading stages)."""
    names = [*PUSHOVER_COLUMNS[:2], displacement_column(recorded)]
    return ",".join([*names, STAGE_COLUMN] if staged else names)


def save_pushover_rows(path: Path, rows: np.ndarray, recorded: Recorded = None) -> None:
    """The one layout of ``pushover.csv``: one header line, then rows of (step, lambda,
    control_displacement), and the stage for rows of four columns."""
    staged = rows.ndim == 2 and rows.shape[1] == 4
    np.savetxt(
        path,
        rows,
        delimiter=",",
        header=pushover_header(recorded, staged),
        comments="",
        fmt=["%d", "%.10g", "%.10g", "%d"] if staged else ["%d", "%.10g", "%.10g"],
    )


def pushover_column(header: str) -> str:
    """The column a header of ``pushover.csv`` names: ``control_displacement [m] block 3 u3``
    -> ``control_displacement`` (older files name it bare)."""
    return header.strip().split(" [")[0]


def recorded_of_header(header: str) -> Recorded:
    """What a third-column header of :func:`displacement_column` says it records (None for
    a bare or unknown one)."""
    parts = header.split("] ", 1)
    if len(parts) != 2:
        return None
    words = parts[1].split()
    if len(words) == 3 and words[0] == "block" and words[2] in DOF_NAMES and words[1].isdigit():
        return int(words[1]), words[2]
    return None


# ------------------------------------------------------------------------------ reading
