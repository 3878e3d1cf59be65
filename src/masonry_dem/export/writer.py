"""Write an analysis to a results folder as it runs, so a failed run keeps every step.

Folder layout: ``blocks.pvd``, ``interfaces.pvd``, ``steps/*.vtu``, ``pushover.csv``,
``summary.json``, the collapse mechanism ``mechanism_blocks.vtu`` / ``mechanism_interfaces.vtu``
when the run ends in collapse (and PNG renders next to them).
"""

from __future__ import annotations

import json
import logging
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import numpy as np

from masonry_dem.export.pvd import write_pvd
from masonry_dem.export.vtu import write_mechanism_vtu, write_step_vtu
from masonry_dem.model import Model
from masonry_dem.results import History, StepResult, write_pushover_csv

log = logging.getLogger(__name__)


class ResultsWriter:
    """Callback for the solvers: ``writer(step)`` writes one step and refreshes the PVDs.

    ``background=True``: the steps are written in order by one thread while the solver goes
    on (zlib, which meshio compresses with, runs outside the GIL: a quarter of a run's time
    went into writing). :meth:`flush` waits for them and raises a write's error;
    :meth:`finish`, :meth:`close` and leaving a ``with`` block flush first, so every step
    handed over is on disk, also when the solver raises."""

    def __init__(
        self, folder: Path | str, model: Model, every: int = 1, background: bool = False
    ) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.model = model
        self.every = max(1, int(every))
        self.block_files: list[str] = []
        self.interface_files: list[str] = []
        self.times: list[float] = []
        self.steps_written: list[int] = []
        self._count = 0
        self._pool = ThreadPoolExecutor(1, "results-writer") if background else None
        self._pending: list[Future] = []

    def __call__(self, step: StepResult, force: bool = False) -> None:
        self._count += 1
        if not force and (self._count - 1) % self.every:
            return
        if self._pool is None:
            self._write(step)
        else:
            self._pending.append(self._pool.submit(self._write, step))

    def flush(self) -> None:
        """Wait until every step handed over is written; raise the first write error."""
        pending, self._pending = self._pending, []
        for future in pending:
            future.result()

    def close(self) -> None:
        """Flush and stop the background thread (a no-op without one)."""
        try:
            self.flush()
        finally:
            if self._pool is not None:
                self._pool.shutdown(wait=True)
                self._pool = None

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _write(self, step: StepResult) -> None:
        bfile, ifile = write_step_vtu(self.folder, self.model, step)
        self.block_files.append(bfile)
        self.interface_files.append(ifile)
        self.times.append(step.load_factor)
        self.steps_written.append(step.step)
        self._write_indexes()

    def _write_indexes(self) -> None:
        times = np.asarray(self.times)
        # ParaView needs increasing times; past a load peak lambda falls, so use step numbers.
        if times.size > 1 and np.any(np.diff(times) <= 0):
            times = np.asarray(self.steps_written, dtype=float)
        write_pvd(self.folder / "blocks.pvd", self.block_files, times)
        if self.model.interfaces.count:
            write_pvd(self.folder / "interfaces.pvd", self.interface_files, times)

    def finish(self, history: History, **summary_extra) -> dict:
        """Write the last step if skipped, pushover.csv and summary.json."""
        self.close()
        if history.steps and (
            not self.steps_written or self.steps_written[-1] != history.last.step
        ):
            self(history.last, force=True)
        write_pushover_csv(self.folder / "pushover.csv", history)
        if history.status == "collapse" and history.steps:
            self._write_mechanism(history)
        summary = history.summary(
            blocks=self.model.blocks.count,
            interfaces=self.model.interfaces.count,
            name=self.model.name,
            steps_written=len(self.steps_written),
            **summary_extra,
        )
        (self.folder / "summary.json").write_text(json.dumps(summary, indent=2))
        log.info("results written to %s", self.folder)
        return summary

    def _write_mechanism(self, history: History) -> None:
        """The collapse mode at the last converged step (and the last increment) as VTU;
        a mode that cannot be computed is logged, never fatal: the steps are already on disk."""
        from masonry_dem.mechanism import collapse_mode

        try:
            mode = collapse_mode(self.model, history.last)
        except (ValueError, RuntimeError, ArithmeticError) as exc:
            log.warning("no collapse mechanism written to %s: %s", self.folder, exc)
            return
        increment = history.steps[-1].q - history.steps[-2].q if len(history.steps) > 1 else None
        write_mechanism_vtu(self.folder, self.model, history.last, mode, increment)
