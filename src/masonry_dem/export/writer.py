"""Write an analysis to a results folder as it runs, so a failed or interrupted run keeps
every step it wrote and says how it ended.

The folder's layout, its lock and every write of its index files belong to
:mod:`masonry_dem.export.results_folder`; this module turns the solver's steps into them.
"""

from __future__ import annotations

import logging
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem._validation import is_count, plain
from masonry_dem.export import pushover_file as pf
from masonry_dem.export import results_folder as rf
from masonry_dem.export.pvd import write_pvd
from masonry_dem.export.vtu import write_mechanism_vtu, write_step_vtu
from masonry_dem.model import Model
from masonry_dem.results import History, StepResult

log = logging.getLogger(__name__)


#: a joint closing by more than this share of its blocks' size along its normal is outside
#: small displacements (a strain of 10 % is large by any convention)
LARGE_CLOSURE = 0.1


def warn_large_closure(model: Model, step: StepResult) -> float:
    """Log a warning when a joint of ``step`` (the first state of a run: the dead load)
    closes by more than :data:`LARGE_CLOSURE` of the smaller of its two blocks along its
    normal (the mean closure, -fn / (kn area)); return the largest such share. A wall too
    tall for its kn then fails short of its peak, its elastic drift past the displacement
    limit, with a reason about the tangent that does not say why."""
    its = model.interfaces
    if its.count == 0 or step.actions.shape[0] != its.count:
        return 0.0
    closure = np.maximum(-step.actions[:, 2], 0.0) / (model.kn * its.area)
    sizes = model.blocks.sizes
    depth = np.minimum(sizes[its.block_i, its.axis], sizes[its.block_j, its.axis])
    share = closure / depth
    k = int(np.argmax(share))
    if share[k] > LARGE_CLOSURE:
        log.warning(
            "at lambda = %s joint %d (blocks %d and %d) closes by %.3g m, %.0f %% of its "
            "blocks' %.3g m: outside small displacements, the analysis may stop short of the "
            "collapse; raise kn (now %.3g N/m^3) or check the units",
            f"{step.load_factor:.4g}",
            k,
            its.block_i[k],
            its.block_j[k],
            closure[k],
            100 * share[k],
            depth[k],
            model.kn[k],
        )
    return float(share[k])


class ResultsWriter:
    """Callback for the solvers: ``writer(step)`` writes one step and refreshes both PVDs
    together.

    Opening a writer claims the folder (:func:`results_folder.claim`): a folder in use by a
    live run is refused; one that holds a previous run is refused unless ``overwrite``
    (the default for the Python API, where a script re-runs into its folder; the command
    line asks for ``--overwrite``), which removes the package's own files first.
    ``summary.json`` says ``running`` from then on.

    ``background=True``: the steps are written in order by one thread while the solver goes
    on (zlib, which meshio compresses with, runs outside the GIL: a quarter of a run's time
    went into writing). A write that failed (full disk) is raised at the next step, so the
    solver does not go on for nothing. :meth:`flush` waits for the writes and raises a
    write's error; :meth:`finish` and leaving a ``with`` block flush first, so every step
    handed over is on disk, also when the solver raises. Leaving the block on an exception
    records the run as ``interrupted`` (Ctrl-C, SIGTERM) or ``failed``."""

    def __init__(
        self,
        folder: Path | str,
        model: Model,
        every: int = 1,
        background: bool = False,
        overwrite: bool = True,
        start: dict[str, Any] | None = None,
    ) -> None:
        self.folder = rf.folder_path(folder)
        self.model = model
        if not is_count(every, 1):
            raise ValueError(f"write_every must be a whole number >= 1, got {plain(every)}")
        self.every = int(every)
        self._start = {
            "name": model.name,
            "blocks": model.blocks.count,
            "interfaces": model.interfaces.count,
            **(start or {}),
        }
        self.block_files: list[str] = []
        self.interface_files: list[str] = []
        self.times: list[float] = []
        self.steps_written: list[int] = []
        self._curve: list[tuple[int, float, float, int]] = []
        #: a step of a later loading stage came: pushover.csv has its stage column
        self._staged = False
        self._recorded = pf.RecordedSoFar()
        self._count = 0
        self._failed: BaseException | None = None
        self._pending: list[Future] = []
        self._pool: ThreadPoolExecutor | None = None
        self._run = rf.claim(self.folder, overwrite, self._start)
        try:  # from here a signal or an error is recorded in summary.json (abort)
            self._start = rf.read_summary(self.folder) or self._start
            self._pool = ThreadPoolExecutor(1, "results-writer") if background else None
        except BaseException as exc:
            self.abort(exc)
            raise

    def __call__(self, step: StepResult, force: bool = False) -> None:
        self._raise_failed()
        if self._count == 0:
            warn_large_closure(self.model, step)
        self._count += 1
        if not force:
            self._add_to_curve(step)
        if not force and (self._count - 1) % self.every:
            return
        if self._pool is None:
            self._write(step)
        else:
            self._pending.append(self._pool.submit(self._write, step))

    def _add_to_curve(self, step: StepResult) -> None:
        """The step's row of ``pushover.csv``, appended; the whole file rewritten (atomically)
        when the step changes what the header says is recorded (block, DOF, unit: the one
        :meth:`finish` writes again at the end, :func:`pushover_file.recorded_dof_of`)."""
        index = len(self._curve)
        self._curve.append((step.step, step.load_factor, step.control_displacement, step.stage))
        changed = self._recorded.add(index, step.control_displacement, step.q)
        if step.stage and not self._staged:  # the first step of a later stage: a new column
            self._staged = changed = True
        if changed and index > 0:
            self._write_curve()
        else:
            pf.append_pushover_row(
                self.folder,
                index,
                step.load_factor,
                step.control_displacement,
                self._recorded.recorded,
                step.stage if self._staged else None,
            )

    def _write_curve(self) -> None:
        """``pushover.csv`` of every step handed over, at once."""
        steps, lams, disp, stages = (np.asarray(c) for c in zip(*self._curve, strict=True))
        pf.write_pushover(
            self.folder,
            np.arange(steps.size),
            lams,
            disp,
            self._recorded.recorded,
            stages if self._staged else None,
        )

    def _raise_failed(self) -> None:
        done = [f for f in self._pending if f.done()]
        self._pending = [f for f in self._pending if not f.done()]
        for future in done:
            future.result()

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

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc is None:
            try:
                # the background writes may lag the solver by hundreds of steps: a write that
                # fails, or a Ctrl-C while they finish, comes after the solver's last step
                self.close()
            except BaseException as err:  # else summary.json would say running for ever
                self.abort(err)
                raise
            return
        try:
            self.close()
        except OSError as err:  # the solver's exception goes on; this one is logged
            # (quietly when that exception is a write error too: the disk that refused the
            # curve refused the background writes as well, and one line says so)
            (log.debug if isinstance(exc, OSError) else log.warning)("%s", err)
        self.abort(exc)

    def _write(self, step: StepResult) -> None:
        if self._failed is not None:  # after a failed write nothing more: keep whole files
            return
        try:
            bfile, ifile = write_step_vtu(self.folder, self.model, step)
            self.block_files.append(bfile)
            self.interface_files.append(ifile)
            self.times.append(step.load_factor)
            self.steps_written.append(step.step)
            self._write_indexes()
        except BaseException as exc:
            self._failed = exc
            raise

    def _write_indexes(self) -> None:
        times = np.asarray(self.times)
        # ParaView needs increasing times; past a load peak lambda falls, so use step numbers.
        if times.size > 1 and np.any(np.diff(times) <= 0):
            times = np.asarray(self.steps_written, dtype=float)
        # both written first, then renamed back to back; blocks.pvd, the index readers start
        # from, last: a run killed between the two renames leaves interfaces.pvd one step
        # ahead, never behind, and the readers use the steps both list
        targets = {}
        if self.model.interfaces.count:
            targets[self.folder / rf.INTERFACES_PVD] = lambda tmp: write_pvd(
                tmp, self.interface_files, times, atomic=False
            )
        targets[self.folder / rf.BLOCKS_PVD] = lambda tmp: write_pvd(
            tmp, self.block_files, times, atomic=False
        )
        rf.replace_together(targets)

    def finish(self, history: History, release: bool = True, **summary_extra) -> dict:
        """Write the last step if skipped, pushover.csv, the collapse mechanism and the final
        summary.json (``summary_extra``: keys added to it); ``release``: unlock the folder
        (the command line keeps it while it renders). A write that fails (full disk) marks
        the run ``failed`` as far as the disk allows, and is raised."""
        try:
            self.close()
            if history.steps and (
                not self.steps_written or self.steps_written[-1] != history.last.step
            ):
                self(history.last, force=True)
        except OSError as exc:
            self.abort(exc)
            raise
        pf.write_history_pushover(self.folder, history)
        if history.status == "collapse" and history.steps:
            self._write_mechanism(history)
        summary = self.write_summary(
            history.summary(
                blocks=self.model.blocks.count,
                interfaces=self.model.interfaces.count,
                name=self.model.name,
                steps_written=len(self.steps_written),
            ),
            summary_extra,
        )
        log.info("results written to %s", self.folder)
        if release:
            self.release()
        return summary

    def write_summary(self, summary: dict, extra: dict | None = None) -> dict:
        """summary.json: what the run started with, ``summary`` and ``extra`` over it."""
        return rf.write_summary(self.folder, {**self._start, **summary}, extra)

    def abort(self, exc: BaseException) -> None:
        """Record a run stopped by ``exc``: pushover.csv of the steps handed over and
        summary.json ``interrupted`` (a signal) or ``failed``; then unlock the folder. A
        failing disk is logged: the exception that stopped the run is the one to report."""
        try:
            if self._curve:
                self._write_curve()
        except OSError as err:
            log.warning("%s: the run's curve is not rewritten (%s)", self.folder, err)
        try:
            end = rf.record_stopped(
                self.folder,
                exc,
                len(self._curve),
                steps=len(self._curve),
                **{
                    "lambda": float(self._curve[-1][1]) if self._curve else 0.0,
                    "lambda_bracket": None,
                    "steps_written": len(self.steps_written),
                },
            )
        finally:
            self.release()
        log.info("%s: %s", self.folder, end["reason"])  # the command line says it in one line

    def release(self) -> None:
        """Unlock the folder (another run may then claim it)."""
        self._run.release()

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
