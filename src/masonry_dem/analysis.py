"""One way in: :func:`analyze` runs any of the package's three analyses of a model (the
pushover, dynamic relaxation, limit analysis), each with its own settings object, and returns
one :class:`~masonry_dem.results.AnalysisResult` with the same core fields for every method.
``pushover``, ``relax`` and ``limit_analysis`` stay as the methods' own public names; the
studies (speed-accuracy, size ladder, sweeps) run through this one.

It sits on top of the data flow, beside ``cli/`` and ``studies/``: it calls the solvers, reads
the collapse mechanism (``mechanism.py``) and, given a folder, writes it (``export/``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.model import Model, Monitor, require_model
from masonry_dem.results import AnalysisResult, History

#: the methods, and the other names each answers to (the studies' and the CLI's words)
METHODS = ("pushover", "relaxation", "limit")
ALIASES = {
    "static": "pushover",
    "dynamic_relaxation": "relaxation",
    "relax": "relaxation",
    "limit_analysis": "limit",
}


def method_name(method: str) -> str:
    """The method's name in :data:`METHODS` (an alias resolved); a ValueError naming the
    allowed values otherwise."""
    name = ALIASES.get(str(method), str(method))
    if name not in METHODS:
        allowed = ", ".join([*METHODS, *ALIASES])
        raise ValueError(f"method = {method!r}: must be one of {allowed}")
    return name


def analyze(
    model: Model,
    method: str = "pushover",
    settings: Any = None,
    *,
    control: Any = None,
    bound: Any = None,
    monitor: Monitor | None = None,
    out: str | Path | None = None,
    progress: Callable[[Any], None] | None = None,
    stages: Any = None,
) -> AnalysisResult:
    """Run one analysis of ``model`` and return its :class:`~masonry_dem.results.AnalysisResult`.

    Parameters
    ----------
    model : Model
        The wall (``Model.build`` or ``load_case(path).model``).
    method : str, default "pushover"
        ``"pushover"`` (the static incremental analysis), ``"relaxation"`` (dynamic
        relaxation) or ``"limit"`` (rigid-block limit analysis); ``"static"``,
        ``"dynamic_relaxation"``, ``"relax"`` and ``"limit_analysis"`` name them too.
    settings : StaticSettings, DRSettings, LimitSettings, mapping or None
        The method's settings: a ``StaticSettings`` (pushover), a ``DRSettings``
        (relaxation), a ``LimitSettings`` or a mapping of its fields (limit); None: the
        method's defaults.
    control : DisplacementControl, optional
        Pushover only: displacement control (None: load control).
    bound : float or callable, optional
        Pushover only: the multiplier its collapse must not pass (a number, or a function
        of the model), see ``pushover``.
    monitor : tuple of (int, str), optional
        Pushover and relaxation: the (block, DOF) whose displacement the pushover curve
        records (None: the one the live load drives most).
    out : str or Path, optional
        A results folder to write (VTU/PVD, pushover.csv, summary.json; for limit analysis
        summary.json and the mechanism); None: nothing is written.
    progress : callable, optional
        Called as the analysis goes: with each converged ``StepResult`` (pushover,
        relaxation) or each ``LimitProgress`` (limit analysis).
    stages : sequence of Stage, optional
        Pushover only: loading stages run in turn, the state carried from one to the next
        (:class:`~masonry_dem.Stage`; not with ``control``); None: one stage.

    Returns
    -------
    AnalysisResult
        The same core fields for every method (status, reason, lambda, bracket, stop,
        certificate or bound, mechanism, history, seconds, cost) and ``details``, the
        method's own result. A solver's trouble is a status, never an exception.

    Raises
    ------
    ValueError
        A method, setting or argument out of its range, named with what is allowed.
    TypeError
        Settings of another method.

    Examples
    --------
    >>> import masonry_dem as md
    >>> result = md.analyze(md.load_case().model, "limit")
    >>> result.status, round(result.load_factor, 4), result.bound
    ('collapse', 0.4471, 'estimate')
    """
    require_model("analyze", model)
    name = method_name(method)
    if name != "pushover":
        for key, value in (("control", control), ("bound", bound), ("stages", stages)):
            if value is not None:
                raise ValueError(f"{key} is a setting of the pushover, not of method {name!r}")
    if name == "limit" and monitor is not None:
        raise ValueError("monitor is a setting of the pushover and the relaxation, not of 'limit'")
    t0 = time.perf_counter()
    if name == "pushover":
        return _pushover(model, settings, control, bound, monitor, out, progress, t0, stages)
    if name == "relaxation":
        return _relaxation(model, settings, monitor, out, progress, t0)
    return _limit(model, settings, out, progress, t0)


def collapse_lambda(history: History) -> float | None:
    """The collapse multiplier of a run; None unless it ended in a (finite) collapse."""
    lam = history.collapse_multiplier
    if history.status != "collapse" or lam is None or not math.isfinite(lam):
        return None
    return float(lam)


def _check_settings(name: str, settings: Any, kind: type) -> None:
    if settings is not None and not isinstance(settings, kind):
        raise TypeError(
            f"settings of method {name!r} must be a {kind.__name__} or None, "
            f"got {type(settings).__name__}"
        )


def _pushover(
    model, settings, control, bound, monitor, out, progress, t0, stages=None
) -> AnalysisResult:
    from masonry_dem.export.analyses import pushover
    from masonry_dem.solvers.incremental import StaticSettings

    _check_settings("pushover", settings, StaticSettings)
    history = pushover(
        model,
        settings,
        control=control,
        out=out,
        monitor=monitor,
        callback=progress,
        bound=bound,
        stages=stages,
    )
    cost = {"iterations": history.iterations, "factorizations": history.factorizations}
    return _of_history("pushover", model, history, time.perf_counter() - t0, cost)


def _relaxation(model, settings, monitor, out, progress, t0) -> AnalysisResult:
    from masonry_dem.export.analyses import results_writer
    from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation
    from masonry_dem.solvers.dynamic_relaxation.solver import relax_with

    _check_settings("relaxation", settings, DRSettings)
    solver = DynamicRelaxation(model, settings)
    writer = results_writer(model, out)
    history = relax_with(solver, monitor, callback=progress, observer=writer)
    cost = {
        "time_steps": solver.stats.time_steps,
        "law_evaluations": solver.stats.law_evaluations,
        "dt_cuts": solver.stats.cuts,
    }
    return _of_history("relaxation", model, history, time.perf_counter() - t0, cost)


def _of_history(
    method: str, model: Model, history: History, seconds: float, cost: dict[str, int]
) -> AnalysisResult:
    from masonry_dem.mechanism import collapse_mode

    status = str(history.status)
    lam = collapse_lambda(history)
    collapse = lam is not None
    return AnalysisResult(
        method=method,
        status=status,
        reason=history.reason,
        load_factor=lam,
        bracket=history.collapse_bracket,
        stop=str(history.stop),
        certificate=None if history.certificate is None else history.certificate.as_dict(),
        bound=None,
        bound_reason=None,
        history=history,
        seconds=seconds,
        cost=cost,
        details=history,
        mechanism_of=(lambda: collapse_mode(model, history.last))
        if collapse and history.steps
        else None,
    )


def _limit(model, settings, out, progress, t0) -> AnalysisResult:
    from masonry_dem.export.limit_results import bound_of
    from masonry_dem.solvers.limit_analysis import LimitSettings, limit_analysis

    if isinstance(settings, Mapping):
        allowed = [f.name for f in fields(LimitSettings)]
        for key in settings:
            if key not in allowed:
                raise ValueError(
                    f"settings[{key!r}] is not a setting of limit analysis: allowed "
                    f"{', '.join(allowed)}"
                )
        settings = LimitSettings(**settings)
    if settings is not None and not isinstance(settings, LimitSettings):
        raise TypeError(
            "settings of method 'limit' must be a LimitSettings, a mapping of its fields or "
            f"None, got {type(settings).__name__}"
        )
    options = (settings or LimitSettings()).keywords()
    result = limit_analysis(model, progress=progress, **options)
    seconds = time.perf_counter() - t0
    if out is not None:
        _write_limit(out, model, result, seconds)
    collapse = result.status == "collapse" and bool(np.isfinite(result.load_factor))
    bound, bound_reason = bound_of(model, result)
    return AnalysisResult(
        method="limit",
        status=str(result.status),
        reason=result.reason,
        load_factor=float(result.load_factor) if collapse else None,
        bracket=None if result.bracket is None else tuple(map(float, result.bracket)),  # type: ignore[arg-type]
        stop=None,
        certificate=None,
        bound=bound,
        bound_reason=bound_reason,
        history=None,
        seconds=seconds,
        cost={"iterations": int(result.iterations)},
        details=result,
        mechanism_of=(lambda: result.block_velocities) if collapse else None,
    )


def _write_limit(out: str | Path, model: Model, result: Any, seconds: float) -> None:
    """The limit analysis's results folder, claimed as a run claims it."""
    from masonry_dem.export.limit_results import write_limit_results
    from masonry_dem.export.results_folder import claim

    folder = claim(out, False, {"name": model.name, "analysis": "limit"})
    try:
        write_limit_results(out, model, result, wall_seconds=round(seconds, 4))
    finally:
        folder.release()
