"""The time series of a results folder as the pictures read it: the steps its PVD indexes
list (checked to be complete), the load multiplier of each, and the pushover table.

No pyvista here: the VTU files themselves are read by :mod:`masonry_dem.export.scene`.
"""

from __future__ import annotations

import csv
import io
import logging
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from masonry_dem.export import pushover_file as pf
from masonry_dem.export import results_folder as rf

log = logging.getLogger(__name__)

_STEP_FILE = re.compile(r"_(\d+)\.vtu$")


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


def recorded_in_pushover(folder: Path | str) -> pf.Recorded:
    """The block and DOF ``pushover.csv``'s header says its displacement is (None when the
    header does not name one: files written before it did, or no one DOF)."""
    with (Path(folder) / rf.PUSHOVER).open(newline="") as fh:
        header = next(csv.reader(fh), [])
    return pf.recorded_of_header(header[2]) if len(header) > 2 else None


def read_pushover(folder: Path | str) -> dict[str, np.ndarray]:
    """Columns of ``pushover.csv`` (step, lambda, control_displacement, and ``stage`` for a
    run in loading stages) as arrays, each found by its name (the third's header goes on
    with its unit and what it records)."""
    path = Path(folder) / rf.PUSHOVER
    if not path.is_file():
        raise FileNotFoundError(
            f"incomplete results folder {Path(folder)}: pushover.csv is missing"
        )
    text = path.read_text()
    if text and not text.endswith("\n"):  # a row cut short by a killed run: the whole ones
        text = text[: text.rfind("\n") + 1]
    rows = list(csv.reader(io.StringIO(text, newline="")))
    if not rows:
        raise ValueError(f"{path} is empty")
    header = [pf.pushover_column(h) for h in rows[0]]
    need = pf.PUSHOVER_COLUMNS
    if any(h not in header for h in need):
        raise ValueError(f"{path}: header must hold {', '.join(need)}, got {', '.join(header)}")
    try:
        data = np.array([[float(x) for x in r] for r in rows[1:] if r], dtype=float)
    except ValueError as exc:
        raise ValueError(f"{path}: non-numeric value ({exc})") from exc
    data = data.reshape(-1, len(header))
    # a run in loading stages adds each step's stage
    names = [*need, pf.STAGE_COLUMN] if pf.STAGE_COLUMN in header else need
    return {h: data[:, header.index(h)] for h in names}
