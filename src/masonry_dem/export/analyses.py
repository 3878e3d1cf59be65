"""The analyses of the public API that write a results folder: ``masonry_dem.pushover`` and
``masonry_dem.relax`` are the solvers' own functions with, for ``out``, a
:class:`~masonry_dem.export.writer.ResultsWriter` as their observer (the solvers compute and
import no writer; this module, above them, hands them one)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from masonry_dem.model import Model, Monitor
from masonry_dem.results import History, Observer, StepResult

if TYPE_CHECKING:
    from masonry_dem.solvers.dynamic_relaxation.settings import DRSettings
    from masonry_dem.solvers.static.certificate import Bound
    from masonry_dem.solvers.static.settings import DisplacementControl, StaticSettings

__all__ = ["pushover", "relax", "results_writer"]


def results_writer(
    model: Model,
    out: str | Path | None,
    write_every: int = 1,
    observer: Observer | None = None,
) -> Observer | None:
    """The observer of a run of ``model``: a results writer into ``out`` that writes every
    ``write_every``-th step (``out`` None: ``observer`` as given)."""
    if out is None:
        return observer
    if observer is not None:
        raise ValueError("give out (a results folder) or observer, not both")
    from masonry_dem.export.writer import ResultsWriter

    return ResultsWriter(out, model, every=write_every, background=True)


def pushover(
    model: Model,
    settings: StaticSettings | None = None,
    control: DisplacementControl | None = None,
    out: str | Path | None = None,
    monitor: Monitor | None = None,
    write_every: int = 1,
    callback: Callable[[StepResult], None] | None = None,
    bound: Bound = None,
    stream: bool | str | Path | None = None,
    observer: Observer | None = None,
) -> History:
    """Run the static incremental analysis; with ``out`` write VTU/PVD, pushover.csv and
    summary.json to that folder as the steps converge. ``callback(step)`` is called after
    each converged step (e.g. a progress bar); ``observer`` follows the run instead of a
    results folder (:class:`~masonry_dem.results.Observer`); ``bound`` see
    :class:`~masonry_dem.solvers.static.solver.StaticSolver`; ``stream`` (the History's
    steps on disk) see :meth:`~masonry_dem.solvers.static.solver.StaticSolver.run`."""
    from masonry_dem.model import check_bound, require_model
    from masonry_dem.solvers.static.solver import pushover as run

    require_model("pushover", model)  # before the folder is claimed
    check_bound(bound)
    return run(
        model,
        settings,
        control,
        monitor=monitor,
        callback=callback,
        bound=bound,
        stream=stream,
        observer=results_writer(model, out, write_every, observer),
    )


def relax(
    model: Model,
    settings: DRSettings | None = None,
    out: str | Path | None = None,
    monitor: Monitor | None = None,
    write_every: int = 1,
    callback: Callable[[StepResult], None] | None = None,
    observer: Observer | None = None,
) -> History:
    """Run dynamic relaxation; with ``out`` write VTU/PVD, pushover.csv and summary.json.
    ``callback(step)`` is called after each converged step (e.g. a progress bar);
    ``observer`` follows the run instead of a results folder
    (:class:`~masonry_dem.results.Observer`)."""
    from masonry_dem.model import require_model
    from masonry_dem.solvers.dynamic_relaxation.solver import relax as run

    require_model("relax", model)  # before the folder is claimed
    return run(
        model,
        settings,
        monitor=monitor,
        callback=callback,
        observer=results_writer(model, out, write_every, observer),
    )
