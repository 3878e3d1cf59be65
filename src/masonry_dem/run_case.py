"""One case run into a results folder, as ``masonry-dem run`` runs it: the memory estimate
checked before anything is built (:func:`estimate_run`), the pushover run through
:func:`~masonry_dem.analysis.analyze` and written step by step (:func:`run_case`: Ctrl-C or
SIGTERM stop it between steps, every step written), the associative limit-analysis bound
computed only when a collapse is to be certified (:class:`LazyBound`), the summary and the
PNGs. The command line adds the progress bar (a :class:`Progress`) and prints.

It sits on top of the data flow with ``analysis.py``, whose entry point it runs.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from masonry_dem.cases.casefile import Case
    from masonry_dem.export.writer import ResultsWriter
    from masonry_dem.model import Model
    from masonry_dem.results import AnalysisResult, StepResult
    from masonry_dem.solvers.resources import Estimate

log = logging.getLogger(__name__)

#: seconds between two progress ticks within a step (Newton iterations, factorizations)
TICK_SECONDS = 2.0


class LazyBound:
    """The associative limit-analysis bound, computed the first time the certificate of a
    collapse asks for it and never otherwise: a run that ends ``completed`` or ``failed``
    before a collapse is checked costs no limit analysis (at 10^4 blocks it took longer
    than the pushover). :meth:`summary` gives the ``limit_analysis_*`` fields."""

    def __init__(self, enabled: bool = True) -> None:
        self.enabled = enabled
        self.result: dict[str, Any] | None = None

    def __call__(self, model: Model) -> float | None:
        if not self.enabled:
            return None
        if self.result is None:
            self.result = limit_analysis_bound(model)
        bound: float | None = self.result["limit_analysis_bound"]
        return bound

    def summary(self) -> dict[str, Any]:
        if self.result is not None:
            return self.result
        why = (
            "not computed (--no-bound)"
            if not self.enabled
            else "not computed (no collapse to certify)"
        )
        return {
            "limit_analysis_bound": None,
            "limit_analysis_status": why,
            "limit_analysis_seconds": 0.0,
        }


def limit_analysis_bound(model: Model) -> dict[str, Any]:
    """The associative limit-analysis multiplier of the model, an upper bound of the
    pushover's (``limit_analysis_bound``: None unless the LA finds a collapse), and its
    status and time: the exact cone (Clarabel) with the friction enlarged by kappa(alpha),
    whose domain contains the DEM's (``solvers.limit_analysis.dem_upper_bound``); a
    cohesion of its own included."""
    from masonry_dem.solvers.limit_analysis import dem_upper_bound

    la = dem_upper_bound(model)
    return {
        "limit_analysis_bound": la.load_factor if la.status == "collapse" else None,
        "limit_analysis_status": la.status,
        "limit_analysis_seconds": round(la.seconds, 4),
    }


#: the ``stop`` of a run whose live load cannot drive a collapse (:func:`cannot_collapse`)
HOPELESS = "live load cannot drive a collapse"
#: a live load pushes sideways when a horizontal force (or a moment over the median block
#: size) on a free DOF exceeds this share of its largest vertical force
SIDEWAYS = 1e-9


def cannot_collapse(model: Model) -> dict[str, Any] | None:
    """The associative limit analysis of a live load that pushes nothing sideways (every
    force on a free DOF along -e2, no moment), when it finds no mechanism: such a load
    cannot drive the pushover to a collapse either (the associative multiplier is an upper
    bound of the pushover's), which would climb to max_steps writing every step. None for
    any other live load (the limit analysis is not run) or one it finds a collapse for."""
    import numpy as np

    free = ~model.fixed
    live = np.where(free, model.live, 0.0)
    down = -live[:, 1]
    if not live.any() or down.min() < 0:
        return None
    length = float(np.median(model.blocks.sizes))
    sideways = max(np.abs(live[:, [0, 2]]).max(), np.abs(live[:, 3:]).max() / length)
    if sideways > SIDEWAYS * down.max():
        return None
    bound = limit_analysis_bound(model)
    return bound if bound["limit_analysis_status"] == "no collapse" else None


#: the PNGs a run writes: the last step and, after a collapse, the mechanism
RUN_PICTURES = 2


def estimate_run(
    case: str | Path | Model | None, max_memory: str | None = None, render: bool = True
) -> Estimate | None:
    """The memory and time a run needs: of a case file, counted from its ``[geometry]``
    without building it (None for the bundled wall, a builder that cannot be counted, or a
    file that does not parse: loading the case then names the fault), or of a built model,
    whose time is the whole run's (:func:`~masonry_dem.solvers.resources.run_time`: the
    kernels compiled when numba's cache lacks them, the analysis, the pictures with
    ``render``, on this machine's load). Raises
    :class:`~masonry_dem.solvers.resources.TooLarge` when it is above ``max_memory`` (a size
    such as ``16G``; default: the machine's available memory)."""
    from masonry_dem.solvers import resources

    if case is None or isinstance(case, (str, Path)):
        geometry = _geometry_of(case)
        try:
            blocks = None if geometry is None else resources.blocks_of_geometry(geometry)
        except (TypeError, ValueError, OverflowError):
            blocks = None  # not a geometry the schema accepts: load_case names the fault
        if blocks is None:
            return None
        est = resources.estimate(blocks)
    else:
        from masonry_dem import jit
        from masonry_dem.solvers import warmup  # noqa: F401 - every kernel in jit's catalogue

        est = resources.estimate(case.blocks.count, case.interfaces.count, case.n_dofs)
        est = resources.run_time(
            est,
            compile_seconds=jit.compile_seconds(case.interfaces.count, processes=2),
            pictures=RUN_PICTURES if render else 0,
        )
    limit = None if max_memory is None else resources.parse_memory(max_memory)
    resources.check_fits(est, limit)
    return est


def _geometry_of(case: str | Path | None) -> dict[str, Any] | None:
    """The ``[geometry]`` table of a case file, read and checked by the schema without
    building anything (None for the bundled wall, a file that does not parse or a case the
    schema refuses: loading the case then names the fault, where counting blocks from a
    negative ``courses`` named none)."""
    from masonry_dem.cases.casefile import check_case_data, read_case_data

    if case is None:
        return None
    try:
        data, source = read_case_data(case)
        check_case_data(data, source, warn=False)  # load_case warns
    except (OSError, ValueError):  # CaseError is a ValueError: load_case raises it again
        return None
    return dict(data["geometry"])


class Progress:
    """What the caller of :func:`run_case` sees while it runs (the command line's progress
    bar; this base shows nothing). Entered once the folder is claimed and left when the
    pushover stops; :meth:`step` after each step handed to the writer, :meth:`tick` every
    :data:`TICK_SECONDS` within long steps."""

    def __enter__(self) -> Progress:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        return None

    def step(self, step: StepResult) -> None:
        """A step is done and handed to the writer."""

    def tick(self, iterations: int, factorizations: int) -> None:
        """The solver's Newton iterations and factorizations so far."""


def run_case(
    case: Case,
    out: str | Path,
    overwrite: bool = False,
    bound: bool = True,
    render: bool = True,
    progress: Progress | None = None,
) -> dict[str, Any]:
    """Run the pushover of a loaded case into the results folder ``out`` and return its
    summary (what ``summary.json`` holds).

    The folder is claimed first: refused if it holds another run (unless ``overwrite``,
    which removes the package's own files there) or is in use. Ctrl-C or SIGTERM stop the
    run between steps; an exception (a signal, a full disk) leaves the folder marked
    interrupted or failed with every step written. ``bound``: the certificate of a collapse
    checks lambda against the associative limit-analysis bound, computed then and only then
    (:class:`LazyBound`). ``render``: PNGs of the last step and of the collapse mechanism,
    named in the summary."""
    from masonry_dem._signals import (
        Interrupted,
        check_stop,
        deferred_signals,
        run_interruptible,
        stop_on_signals,
    )
    from masonry_dem.analysis import analyze
    from masonry_dem.export.results_folder import MECHANISM_FILES
    from masonry_dem.export.writer import ResultsWriter
    from masonry_dem.solvers.warmup import prepare

    out = Path(out)
    shown = progress or Progress()
    lazy = LazyBound(enabled=bound)
    model, stopped = case.model, None
    # a run in loading stages pushes with its stages' loads, not the model's live load
    hopeless = None if case.stages is not None else cannot_collapse(case.model)
    if hopeless is not None:
        stopped = (
            "the live load cannot drive a collapse: it pushes nothing sideways and the "
            "associative limit analysis, an upper bound of the pushover, finds no mechanism; "
            "the dead-load state is the answer"
        )
        log.warning("%s (the pushover stops after the dead load)", stopped)
        lazy.result = hopeless
        model = replace(case.model, live=0.0 * case.model.live)
    prepare(case.model.interfaces.count)  # says "compiling kernels ..." first, if it must
    t0 = time.perf_counter()
    writer = ResultsWriter(
        out, case.model, background=True, overwrite=overwrite, start={"case": case.source}
    )
    try:
        # the solver runs in a worker thread (run_interruptible), so that a second signal
        # stops the run at once even inside a long factorization; once the main thread has
        # stopped it, the worker hands no more steps to the writer
        handing, abandoned = threading.Lock(), threading.Event()

        def on_step(step: StepResult) -> None:
            with handing:
                if abandoned.is_set():
                    raise Interrupted()
                writer(step)
            shown.step(step)
            check_stop()  # Ctrl-C or SIGTERM: stop here, between steps, all of them written

        # from the claim on, a signal (or an error) while the solver is set up is recorded by
        # the writer's exit as it is during the steps
        with writer, shown, stop_on_signals():
            try:
                result = run_interruptible(
                    lambda: _reporting_ticks(
                        shown,
                        lambda: analyze(
                            model,
                            "pushover",
                            case.settings,
                            control=case.control,
                            stages=case.stages,
                            bound=lazy,
                            monitor=case.monitor,
                            progress=on_step,
                        ),
                    )
                )
            except BaseException:
                with handing:
                    abandoned.set()
                raise
        history = result.history
        assert history is not None  # a pushover's result has its history
        with deferred_signals():  # pushover.csv, the mechanism and summary.json agree
            summary: dict[str, Any] = writer.finish(
                history,
                release=False,
                case=case.source,
                wall_seconds=round(time.perf_counter() - t0, 4),
                **lazy.summary(),
                **(
                    {} if stopped is None else {"reason": stopped, "stop": HOPELESS, "lambda": None}
                ),
            )
        if render:
            summary = _render(out, summary, writer, MECHANISM_FILES[0])
    finally:
        writer.release()
    return summary


def _reporting_ticks(shown: Progress, work: Callable[[], AnalysisResult]) -> AnalysisResult:
    """``work()`` with the static solver's Newton progress shown by ``shown.tick``, at most
    once every :data:`TICK_SECONDS` (it runs in the thread that does the work: the
    progress channel is that thread's)."""
    from masonry_dem._progress import reporting
    from masonry_dem.solvers.static.progress import NewtonProgress

    last = [time.monotonic()]

    def listen(event: object) -> None:
        now = time.monotonic()
        if isinstance(event, NewtonProgress) and now - last[0] >= TICK_SECONDS:
            last[0] = now
            shown.tick(event.iterations, event.factorizations)

    with reporting(listen):
        return work()


def _render(
    out: Path, summary: dict[str, Any], writer: ResultsWriter, mechanism_file: str
) -> dict[str, Any]:
    """PNGs of the last step and, after a collapse, of the mechanism, named in summary.json."""
    try:
        from masonry_dem.export.render import render_mechanism, render_step
    except ImportError as exc:  # rendering is optional for the analysis itself
        log.warning("no PNG: the render module is unavailable (%s)", exc)
        return summary
    pngs = {"png": Path(render_step(out, step="last")).name}
    if (out / mechanism_file).is_file():  # the run ended in collapse
        pngs["mechanism_png"] = render_mechanism(out).name
    return writer.write_summary(summary, pngs)
