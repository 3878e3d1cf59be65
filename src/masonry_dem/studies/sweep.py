"""Parameter sweeps of a case file on Dask: the spread of the collapse multiplier.

This module runs a sweep and owns its folder; :func:`sweep` is the entry point. A sweep varies
values of a case file by their path in it (``material.friction``, ``geometry.courses``,
``loads[1].direction``): on a grid (``0.5:0.9:9``, both ends included), as a list
(``0.5,0.6,0.8``), or drawn at random from a distribution with a seed (``lognormal(1e9,0.3)``,
``normal(mean,sd)``, ``uniform(lo,hi)``); :mod:`.sweep_plan` reads and checks them,
:mod:`.sweep_point` runs one point, :mod:`.sweep_table` writes the rows and
:mod:`.sweep_plots` draws them. Their public names are importable from here too.

Each run is one task of a ``dask.distributed`` client: a ``LocalCluster`` of one process per
core by default, or any running scheduler by address, so the same sweep runs on a laptop or a
cluster (whose workers need the package and, with ``keep``, the output folder). The rows are
appended to ``sweep.csv`` as the runs complete, so an interrupted sweep keeps them and
``resume`` runs only the missing ones; ``sweep.parquet`` (pyarrow) holds the same table, and
PNGs plot lambda against each varied value and, for samples, its histogram and empirical CDF.
A run that fails is a row with its status and reason; it never stops the sweep.

Folder layout::

    sweep.json          the plan: case, varied paths and values, distributions, seed
    sweep.csv           one row per run, appended as runs complete
    sweep.parquet       the same rows, typed (written at the end, also after an interrupt)
    lambda_vs_<path>.png, lambda_histogram.png, lambda_cdf.png
    runs/run_NNNN/      a run's files (keep="summary": summary.json and pushover.csv;
                        keep="all": the whole results folder of ``masonry-dem run``)
"""

from __future__ import annotations

import json
import logging
import os
import re
import shutil
import time
import uuid
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem._validation import plain
from masonry_dem.studies.sweep_plan import (
    DISTRIBUTIONS,
    Distribution,
    Plan,
    get_path,
    make_plan,
    parse_values,
    path_keys,
    set_path,
)
from masonry_dem.studies.sweep_plots import LAMBDA_LABEL, axis_label, write_plots
from masonry_dem.studies.sweep_point import MOVING, RESULT_COLUMNS, mechanism_summary, run_point
from masonry_dem.studies.sweep_table import (
    TABLE_CSV,
    TABLE_PARQUET,
    Journal,
    columns_of,
    read_rows,
    to_table,
    write_parquet,
    write_rows,
)

__all__ = [
    "DISTRIBUTIONS",
    "KEEP",
    "LAMBDA_LABEL",
    "MOVING",
    "PLAN",
    "RESULT_COLUMNS",
    "RUNS",
    "TABLE_CSV",
    "TABLE_PARQUET",
    "Distribution",
    "Plan",
    "SweepResult",
    "axis_label",
    "columns_of",
    "get_path",
    "make_plan",
    "mechanism_summary",
    "parse_values",
    "path_keys",
    "remove_own_files",
    "run_point",
    "set_path",
    "sweep",
    "to_table",
    "write_plots",
]

log = logging.getLogger(__name__)

PLAN = "sweep.json"
RUNS = "runs"
KEEP = ("none", "summary", "all")
#: runs from which a sweep's size, and a crossing of values that makes it, is a warning
MANY_RUNS = 10_000
#: seconds from which a sweep's time estimate is a warning
LONG_SECONDS = 3600.0
#: points whose walls the time estimate measures (evenly spread over the plan)
ESTIMATED_POINTS = 50
#: tasks in flight per worker thread
WINDOW_PER_WORKER = 4
#: seconds between two progress lines of the runs
PROGRESS_SECONDS = 10.0


@dataclass
class SweepResult:
    """What a sweep left in ``folder``: the rows (one per run, by run number), the table
    files, the plots, how many runs ran now and how many a resume found done."""

    folder: Path
    rows: list[dict[str, Any]]
    csv: Path
    parquet: Path
    plots: list[Path]
    ran: int
    resumed: int

    @property
    def lambdas(self) -> np.ndarray:
        """lambda of every run (nan where a run did not end in collapse or completion)."""
        return np.array([np.nan if r["lambda"] is None else r["lambda"] for r in self.rows])

    def table(self) -> Any:
        """The rows as a pyarrow Table (``.to_pandas()`` where pandas is installed)."""
        import pyarrow.parquet as pq

        return pq.read_table(self.parquet)


def sweep(
    case: str | Path | Mapping[str, Any] | None = None,
    vary: Mapping[str, str | Sequence[Any]] | None = None,
    sample: Mapping[str, str | Distribution] | None = None,
    samples: int = 0,
    seed: int | None = None,
    out: str | Path = "results/sweep",
    scheduler: Any = None,
    workers: int | None = None,
    keep: str = "none",
    resume: bool = False,
    overwrite: bool = False,
    plots: bool = True,
    progress: bool = False,
) -> SweepResult:
    """Run a case over varied values on Dask, writing one row per run to ``out``.

    Before anything starts, the number of runs and an estimate of their time are logged (a
    sweep of 10^4 runs or more, or of more than an hour, as a warning).

    Parameters
    ----------
    case : str or pathlib.Path or mapping, optional
        A TOML path, a parsed case dict, or None: the bundled default wall.
    vary : mapping, optional
        path -> values, or their text (``"0.5:0.9:9"`` a grid, ``"0.5,0.6,0.8"`` a list);
        several paths are crossed.
    sample : mapping, optional
        path -> distribution (``"lognormal(1e9,0.3)"``, ``normal(mean,sd)``,
        ``uniform(lo,hi)``), drawn ``samples`` times with ``seed``.
    samples : int, default 0
        Draws of ``sample``.
    seed : int, optional
        The seed of the draws (one is drawn and recorded in ``sweep.json`` when not given).
    out : str or pathlib.Path, default "results/sweep"
        The sweep's folder.
    scheduler : optional
        None for a LocalCluster of ``workers`` processes (default: the cores) with one
        thread each, an address (``"tcp://host:8786"``), or a ``distributed.Client``.
    workers : int, optional
        Processes of the LocalCluster, 1 to 4096 (None: the cores).
    keep : {"none", "summary", "all"}, default "none"
        "none" (rows only), "summary" (each run's summary.json and pushover.csv) or "all"
        (each run's whole results folder, VTU/PVD) under ``out/runs/run_NNNN``.
    resume : bool, default False
        Run only the rows ``out`` does not hold yet (same plan, else refused).
    overwrite : bool, default False
        Replace a sweep in ``out`` (its own files only); without ``resume`` or
        ``overwrite``, a folder that holds a sweep is refused.
    plots : bool, default True
        Write the sweep's plots (PNG) to ``out``.
    progress : bool, default False
        Log how many runs are done and how long the rest will take.

    Returns
    -------
    SweepResult
        What the sweep left in ``out``: the rows (one per run, by run number), the table
        files (CSV, Parquet), the plots, how many runs ran now and how many a resume found
        done.

    Raises
    ------
    ValueError
        If ``keep`` or ``workers`` is out of range, the plan is refused (a path, a value or a
        distribution), ``resume`` and ``overwrite`` are both given, or ``out`` holds a sweep
        and neither ``resume`` (with the same plan) nor ``overwrite`` is given.

    Examples
    --------
    Two runs of the bundled wall (about 10 s, most of it starting Dask):

    >>> import masonry_dem as md
    >>> result = md.sweep(
    ...     vary={"material.friction": "0.6,0.8"}, out="results/mu", workers=1, plots=False
    ... )  # doctest: +SKIP
    >>> result.lambdas.round(3).tolist()  # doctest: +SKIP
    [0.266, 0.298]
    """
    if keep not in KEEP:
        raise ValueError(f"keep = {plain(keep)}: must be one of {', '.join(KEEP)}")
    if workers is not None and (isinstance(workers, bool) or not 1 <= int(workers) <= 4096):
        raise ValueError(f"workers = {plain(workers)}: must be a whole number from 1 to 4096")
    folder = Path(out)
    if resume and sample and seed is None:  # the seed the sweep drew and recorded
        seed = _recorded(folder).get("seed")
    plan = make_plan(case, vary, sample, samples, seed)
    points = plan.points()
    _announce(plan, points, scheduler, workers)
    done = _prepare(folder, plan, resume, overwrite)
    columns = columns_of(plan)
    rows: dict[int, dict[str, Any]] = dict(done)
    todo = [i for i in range(len(points)) if i not in done]
    log.info(
        "sweep of %d runs in %s: %d to run, %d done", len(points), folder, len(todo), len(done)
    )
    journal = Journal(folder / TABLE_CSV, columns, [rows[i] for i in sorted(rows)])
    interrupted = True
    try:
        if todo:
            _compute(plan, points, todo, folder, keep, scheduler, workers, progress, rows, journal)
        interrupted = False
    finally:
        journal.close()
        ordered = [rows[i] for i in sorted(rows)]
        write_rows(folder / TABLE_CSV, columns, ordered)  # the runs' order, not their ends'
        write_parquet(folder / TABLE_PARQUET, ordered, columns)
        pngs = write_plots(folder, ordered, plan) if plots else []
        if interrupted:
            log.warning(
                "sweep in %s stopped after %d of %d runs; resume continues it",
                folder,
                len(rows),
                len(points),
            )
    return SweepResult(
        folder,
        ordered,
        folder / TABLE_CSV,
        folder / TABLE_PARQUET,
        pngs,
        ran=len(rows) - len(done),
        resumed=len(done),
    )


def _announce(
    plan: Plan, points: list[dict[str, Any]], scheduler: Any, workers: int | None
) -> None:
    """Log, before anything starts, how many runs the sweep makes (the crossing of values
    that makes a large one named) and how long they will take."""
    from masonry_dem.solvers.resources import SWEEP_RUN_FACTOR, estimate, sweep_time
    from masonry_dem.solvers.resources import blocks_of_geometry as blocks_of

    runs = len(points)
    some = points[:: max(1, runs // ESTIMATED_POINTS)][:ESTIMATED_POINTS]
    sizes = [blocks_of(plan.case_of(p).get("geometry") or {}) for p in some]
    known = [n for n in sizes if n is not None]
    if not known:  # a builder the estimate cannot count: no time said
        log.info("sweep of %d runs", runs)
        return
    run_seconds = float(np.mean([estimate(n).seconds for n in known]))
    if scheduler is None:
        seconds, text = sweep_time(runs, run_seconds, int(workers or os.cpu_count() or 1))
    else:  # the scheduler's workers, unknown here, share the work
        seconds = runs * run_seconds * SWEEP_RUN_FACTOR
        text = f"{seconds:.0f} s of work for the scheduler's workers"
    counts = [len(v) for v in plan.vary.values()] + ([plan.samples] if plan.sample else [])
    crossed = f" ({' x '.join(map(str, counts))} crossed)" if len(counts) > 1 else ""
    many = runs >= MANY_RUNS or seconds >= LONG_SECONDS
    log.log(
        logging.WARNING if many else logging.INFO,
        "sweep of %d runs%s: %s%s",
        runs,
        crossed,
        text,
        "; Ctrl-C stops it, resume continues it" if many else "",
    )


def _compute(
    plan: Plan,
    points: list[dict[str, Any]],
    todo: list[int],
    folder: Path,
    keep: str,
    scheduler: Any,
    workers: int | None,
    progress: bool,
    rows: dict[int, dict[str, Any]],
    journal: Journal,
) -> None:
    from distributed import as_completed

    runs = (folder / RUNS).resolve()
    with _client(scheduler, workers) as client:
        log.info("dask scheduler %s, dashboard %s", client.scheduler.address, client.dashboard_link)
        tag = uuid.uuid4().hex[:8]
        # a few tasks per worker in flight, not every run at once: 10^6 submitted tasks (each
        # with its case) filled the scheduler's memory until its workers were dropped
        window = max(8, WINDOW_PER_WORKER * max(sum(client.nthreads().values()), 1))
        waiting = iter(todo)
        futures: dict[Any, int] = {}

        def submit() -> Any:
            i = next(waiting, None)
            if i is None:
                return None
            future = client.submit(
                run_point,
                plan.case_of(points[i]),
                plan.source,
                keep,
                str(runs / f"run_{i:04d}"),
                key=f"masonry-run-{i}-{tag}",
            )
            futures[future] = i
            return future

        first = [f for f in (submit() for _ in range(window)) if f is not None]
        queue = as_completed(first)  # type: ignore[no-untyped-call]
        shown = _Shown(len(todo), progress)
        for future in queue:
            i = futures.pop(future)
            try:
                result = future.result()
            except Exception as exc:  # the worker died, or the task could not run
                text = " ".join(str(exc).split()) or type(exc).__name__
                result = dict.fromkeys(RESULT_COLUMNS)
                result.update(status="error", reason=f"{type(exc).__name__}: {text}")
            rows[i] = {"run": i, **points[i], **result}
            journal.append(rows[i])
            future.release()
            shown.step()
            following = submit()
            if following is not None:
                queue.add(following)  # type: ignore[no-untyped-call]


class _Shown:
    """Logs how many runs are done and how long the rest will take, every
    :data:`PROGRESS_SECONDS` (when ``shown``)."""

    def __init__(self, total: int, shown: bool) -> None:
        self.total, self.shown, self.done = total, shown, 0
        self.start = self.last = time.monotonic()

    def step(self) -> None:
        self.done += 1
        now = time.monotonic()
        if not self.shown or (now - self.last < PROGRESS_SECONDS and self.done < self.total):
            return
        self.last = now
        left = (now - self.start) / self.done * (self.total - self.done)
        log.info("%d of %d runs done, about %.0f s left", self.done, self.total, left)


@contextmanager
def _client(scheduler: Any, workers: int | None) -> Iterator[Any]:
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - the optional extra is missing
        raise ModuleNotFoundError(
            'a sweep needs dask.distributed and pyarrow: pip install "masonry_dem[sweep]"'
        ) from exc
    if scheduler is not None and not isinstance(scheduler, str):
        yield scheduler  # a Client of the caller's: theirs to close
        return
    if isinstance(scheduler, str):
        with Client(scheduler) as client:  # type: ignore[no-untyped-call]
            yield client
        return
    n = int(workers or os.cpu_count() or 1)
    # one run per core: the kernels' own threads would only compete with the other workers
    env = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    cluster = LocalCluster(  # type: ignore[no-untyped-call]
        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", env=env
    )
    try:
        with Client(cluster) as client:  # type: ignore[no-untyped-call]
            yield client
    finally:
        # a worker whose compiled kernels' threads outlast the nanny's wait is killed, as it
        # would be anyway: the nanny's "still alive ... killing" warning tells the user nothing
        nanny = logging.getLogger("distributed.nanny")
        level = nanny.level
        nanny.setLevel(logging.ERROR)
        try:
            cluster.close()
        finally:
            nanny.setLevel(level)


def _prepare(folder: Path, plan: Plan, resume: bool, overwrite: bool) -> dict[int, dict[str, Any]]:
    """Claim ``folder`` for the sweep; returns the rows a resume keeps."""
    if resume and overwrite:
        raise ValueError("resume and overwrite exclude each other")
    manifest = plan.manifest()
    plan_file = folder / PLAN
    if plan_file.is_file() or (folder / TABLE_CSV).is_file():
        if resume:
            same = json.loads(json.dumps(manifest))
            before = _recorded(folder)
            if {k: before.get(k) for k in same if k != "source"} != {
                k: v for k, v in same.items() if k != "source"
            }:
                raise ValueError(
                    f"{folder} holds a sweep of another plan (case, values, distributions or "
                    "seed differ): resume needs the same; use another folder or overwrite"
                )
            return read_rows(folder, plan)
        if not overwrite:
            raise ValueError(
                f"{folder} holds a sweep already: resume continues it, overwrite replaces it"
            )
        remove_own_files(folder)
    folder.mkdir(parents=True, exist_ok=True)
    tmp = plan_file.with_name(f".{PLAN}.{uuid.uuid4().hex}.tmp")
    tmp.write_text(json.dumps(manifest, indent=2))
    os.replace(tmp, plan_file)
    return {}


def _recorded(folder: Path) -> dict[str, Any]:
    """The plan a sweep in ``folder`` recorded ({} when there is none)."""
    try:
        data = json.loads((folder / PLAN).read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def remove_own_files(folder: Path) -> None:
    """Remove what a sweep writes in ``folder`` and nothing else."""
    for name in (PLAN, TABLE_CSV, TABLE_PARQUET):
        (folder / name).unlink(missing_ok=True)
    for png in folder.glob("lambda_*.png"):
        png.unlink()
    runs = folder / RUNS
    if runs.is_dir():
        for run in runs.iterdir():
            if run.is_dir() and re.fullmatch(r"run_\d+", run.name):
                shutil.rmtree(run)
        if not any(runs.iterdir()):
            runs.rmdir()
