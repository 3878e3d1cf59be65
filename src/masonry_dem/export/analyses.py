"""The analyses of the public API that write a results folder: ``masonry_dem.pushover`` and
``masonry_dem.relax`` are the solvers' own functions with, for ``out``, a
:class:`~masonry_dem.export.writer.ResultsWriter` as their observer (the solvers compute and
import no writer; this module, above them, hands them one)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from masonry_dem._docstrings import SHARED, fill
from masonry_dem.model import Model, Monitor
from masonry_dem.results import History, Observer, StepResult

if TYPE_CHECKING:
    from masonry_dem.solvers.dynamic_relaxation.settings import DRSettings
    from masonry_dem.solvers.static.certificate import Bound
    from masonry_dem.solvers.static.settings import DisplacementControl, StaticSettings
    from masonry_dem.solvers.static.stages import Stage

__all__ = ["pushover", "relax", "results_writer"]


#: the parameters pushover and relax share (:func:`masonry_dem._docstrings.fill`)
DOCS: dict[str, str] = {
    "output": """
        out : str or pathlib.Path, optional
            A results folder to write as the steps converge (None: nothing written; give
            ``out`` or ``observer``, not both).
        monitor : (int, str), optional
            (block, DOF name) whose displacement the pushover curve records (None: the
            largest block translation).
        write_every : int, default 1
            With ``out``: write every ``write_every``-th step (>= 1).
        callback : callable, optional
            ``callback(step)`` is called after each converged step (e.g. a progress bar).
    """,
    **SHARED,
}


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


@fill(DOCS)
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
    stages: Sequence[Stage | Mapping[str, Any]] | None = None,
) -> History:
    """Run the static incremental analysis (the pushover) of ``model``.

    Dead load, then lambda raised (load control, then work control) or a DOF driven
    (displacement control). With ``out``, VTU/PVD, pushover.csv and summary.json are written
    to that folder as the steps converge.

    Parameters
    ----------
    model : Model
        The wall.
    settings : StaticSettings, optional
        The solver's settings (None: the defaults).
    control : DisplacementControl, optional
        Drive one DOF to a target instead of raising lambda (None: load control).
    %(output)s
    bound : float or callable, optional
        An upper bound of the collapse multiplier (the associative limit-analysis multiplier
        of the model, a number or a function of the model) that a certified collapse may not
        exceed; None: the certificate says the bound was not checked
        (:class:`~masonry_dem.solvers.static.solver.StaticSolver`).
    stream : bool or str or pathlib.Path, optional
        Keep the History's steps on disk (:mod:`masonry_dem.streamed_history`): a folder,
        True (a temporary folder), False (in memory), None (on disk when the History would
        not fit in a quarter of the available memory;
        :meth:`~masonry_dem.solvers.static.solver.StaticSolver.run`).
    observer : Observer, optional
        Follows the run instead of a results folder (:class:`~masonry_dem.results.Observer`).
    stages : sequence of Stage, optional
        Loading stages run in turn, the state carried from one to the next
        (:class:`~masonry_dem.Stage`, or mappings of its fields; the model's own supports
        and loads are the first stage's); None: one stage, the model as it is. Each
        stage's steps are marked ``StepResult.stage``, with the reactions at the held DOFs.

    Returns
    -------
    History
        The converged steps and how the run ended: ``collapse`` only with a certificate that
        holds, else ``completed`` or ``failed``, with the stop and its reason.

    Raises
    ------
    ValueError
        If ``model`` is not a :class:`~masonry_dem.Model`, ``bound`` is neither a finite
        number, a function nor None, ``write_every`` is not a whole number >= 1, both
        ``out`` and ``observer`` are given, both ``control`` and ``stages`` are given, or
        a stage is bad (an empty list, an unknown field, a control on a held DOF: named).

    Examples
    --------
    %(sliding_block)s
    >>> history = md.pushover(model)
    >>> str(history.status), round(history.collapse_multiplier, 6)  # sliding: mu = 0.6
    ('collapse', 0.6)
    """
    from masonry_dem.model import check_bound, require_model
    from masonry_dem.solvers.static.solver import pushover as run

    require_model("pushover", model)  # before the folder is claimed
    check_bound(bound)
    if stages is not None:
        from masonry_dem.results import observed
        from masonry_dem.solvers.static.stages import as_stages, plan_stages, run_plans
        from masonry_dem.solvers.warmup import prepare

        if control is not None:
            raise ValueError(
                "give control or stages, not both: each stage names its own control "
                f"(Stage(control=...)), got control={control!r}"
            )
        plans = plan_stages(model, as_stages(stages))  # checked before the folder is claimed
        prepare(model.interfaces.count)
        return observed(
            lambda on_step: run_plans(
                model,
                plans,
                settings,
                monitor=monitor,
                callback=on_step,
                bound=bound,
                stream=stream,
            ),
            results_writer(model, out, write_every, observer),
            callback,
        )
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


@fill(DOCS)
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

    Parameters
    ----------
    model : Model
        The wall.
    settings : DRSettings, optional
        The knobs of dynamic relaxation (None: the defaults).
    %(output)s
    observer : Observer, optional
        Follows the run instead of a results folder (:class:`~masonry_dem.results.Observer`).

    Returns
    -------
    History
        The converged steps and how the run ended (``collapse`` with the bracket of the last
        converged and the first failed lambda).

    Raises
    ------
    ValueError
        If ``model`` is not a :class:`~masonry_dem.Model`, ``write_every`` is not a whole
        number >= 1, or both ``out`` and ``observer`` are given.

    Examples
    --------
    %(sliding_block)s
    >>> history = md.relax(model)
    >>> str(history.status), round(history.collapse_multiplier, 3)
    ('collapse', 0.6)
    """
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
