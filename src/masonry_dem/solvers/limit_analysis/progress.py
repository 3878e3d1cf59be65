"""What a limit analysis reports while it runs: each iteration of the normal-equation
interior point method (its primal and dual objectives, which close on lambda) and each solve
of the non-associative iteration (its lambda), handed to the callback that
:func:`~masonry_dem.solvers.limit_analysis.limit_analysis` was given (``progress``).

The callback is held in a context variable, as the budget is (``budget``): the solvers that
report run in the thread (or task) that called the analysis, at any depth, with no argument
passed down to them.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LimitProgress:
    """One iteration of a running limit analysis.

    Attributes:
        stage: ``"interior point"`` (an iteration of the normal-equation interior point
            method) or ``"non-associative"`` (a frozen-friction solve of the non-associative
            iteration).
        iteration: the iteration's number in its stage, from 1.
        lower, upper: the interior point iterate's dual objective and primal objective (they
            close on lambda from either side; certified only once the analysis ends), or the
            non-associative solve's lambda in both.
    """

    stage: str
    iteration: int
    lower: float
    upper: float


ProgressCallback = Callable[[LimitProgress], None]

_callback: ContextVar[ProgressCallback | None] = ContextVar("limit_progress", default=None)


@contextmanager
def reporting(callback: ProgressCallback | None) -> Iterator[None]:
    """Iterations inside are handed to ``callback`` (None: to nobody)."""
    token = _callback.set(callback)
    try:
        yield
    finally:
        _callback.reset(token)


def report(stage: str, iteration: int, lower: float, upper: float) -> None:
    """Hand one iteration to the analysis's callback, if it has one. A callback that raises
    is logged and dropped: what shows the progress never stops the analysis."""
    callback = _callback.get()
    if callback is None:
        return
    try:
        callback(LimitProgress(stage, iteration, float(lower), float(upper)))
    except Exception:  # noqa: BLE001 (a display's error is not the analysis's)
        log.warning("the progress callback failed; no more progress is reported", exc_info=True)
        _callback.set(None)
