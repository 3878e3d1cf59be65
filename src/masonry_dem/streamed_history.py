"""The steps of a History kept on disk instead of in memory.

A converged step holds the displacements of every block and the actions, state and
utilisation of every interface: about 48 bytes a block and 66 an interface, 25 MB a step at
10^5 blocks, so a History of 70 steps would hold 1.7 GB that the solver never reads again.
:class:`StreamedSteps` takes the place of the History's list of steps: each appended step is
written at once to its own ``.npz`` file (exact arrays) and only the dead-load state (the
path measures displacements from it) and the last ``keep`` steps stay in memory; the
scalars of every step (lambda, the control displacement, iterations) stay in memory too, so
the pushover curve is read without touching the disk. Indexing reads a step back, equal to
the step that was appended.

``History(steps=StreamedSteps(folder))``, or ``StaticSolver.run(stream=...)`` /
``pushover(..., stream=...)``, which stream by default when the History would not fit in a
quarter of the machine's available memory (:func:`masonry_dem.solvers.resources.should_stream`).
"""

from __future__ import annotations

import logging
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import overload

import numpy as np

from masonry_dem.results import STEP_ARRAYS, StepResult

log = logging.getLogger(__name__)

_ARRAYS = STEP_ARRAYS


class StreamedSteps(Sequence[StepResult]):
    """A list of :class:`StepResult` whose steps live in ``folder`` (None: a temporary
    folder removed when this object goes), one ``step_NNNNNN.npz`` a step."""

    def __init__(self, folder: str | Path | None = None, keep: int = 2) -> None:
        if keep < 1:
            raise ValueError(f"keep must be at least 1 step, got {keep}")
        self._tmp = None
        if folder is None:
            self._tmp = tempfile.TemporaryDirectory(prefix="masonry-dem-history-")
            folder = self._tmp.name
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.keep = keep
        self._count = 0
        self._first: StepResult | None = None
        self._recent: dict[int, StepResult] = {}
        self.load_factors: list[float] = []
        self.control_displacements: list[float] = []
        self.stages: list[int] = []

    def _path(self, index: int) -> Path:
        return self.folder / f"step_{index:06d}.npz"

    def append(self, step: StepResult) -> None:
        """Write ``step`` (the next one) to disk; keep it in memory while it is recent."""
        arrays = {k: getattr(step, k) for k in _ARRAYS if getattr(step, k) is not None}
        values = [step.step, step.load_factor, step.control_displacement, step.iterations]
        if step.stage:  # a later loading stage (the first keeps the four scalars)
            values.append(step.stage)
        scalars = np.array(values, dtype=float)
        path = self._path(self._count)
        tmp = path.with_suffix(".part")
        with open(tmp, "wb") as f:  # a reader never sees half a step
            np.savez(f, scalars=scalars, **arrays)
        tmp.replace(path)
        if self._count == 0:
            self._first = step
        self._recent[self._count] = step
        self._recent.pop(self._count - self.keep, None)
        self._count += 1
        self.load_factors.append(float(step.load_factor))
        self.control_displacements.append(float(step.control_displacement))
        self.stages.append(int(step.stage))

    def _read(self, index: int) -> StepResult:
        with np.load(self._path(index)) as data:
            scalars = data["scalars"]
            arrays = {k: data[k] for k in _ARRAYS if k in data.files}
        return StepResult(
            step=int(scalars[0]),
            load_factor=float(scalars[1]),
            control_displacement=float(scalars[2]),
            iterations=int(scalars[3]),
            q=arrays["q"],
            actions=arrays["actions"],
            state=arrays["state"],
            utilisation=arrays["utilisation"],
            flags=arrays.get("flags"),
            found_plastic=arrays.get("found_plastic"),
            found_cracked=arrays.get("found_cracked"),
            stage=int(scalars[4]) if scalars.size > 4 else 0,
            reactions=arrays.get("reactions"),
        )

    def __len__(self) -> int:
        return self._count

    @overload
    def __getitem__(self, index: int) -> StepResult: ...

    @overload
    def __getitem__(self, index: slice) -> list[StepResult]: ...

    def __getitem__(self, index: int | slice) -> StepResult | list[StepResult]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self._count))]
        i = index + self._count if index < 0 else index
        if not 0 <= i < self._count:
            raise IndexError(f"step {index} of a History of {self._count} steps")
        if i == 0 and self._first is not None:
            return self._first
        if i in self._recent:
            return self._recent[i]
        return self._read(i)

    def __iter__(self) -> Iterator[StepResult]:
        return (self[i] for i in range(self._count))
