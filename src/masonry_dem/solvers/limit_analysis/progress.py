"""What a limit analysis reports while it runs: each iteration of the normal-equation
interior point method (its primal and dual objectives, which close on lambda) and each solve
of the non-associative iteration (its lambda), handed to the callback that
:func:`~masonry_dem.solvers.limit_analysis.limit_analysis` was given (``progress``).

The callback is held in the context variable of :mod:`masonry_dem._progress`: the solvers that
report run in the thread (or task) that called the analysis, at any depth, with no argument
passed down to them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from masonry_dem._progress import listening, reporting
from masonry_dem._progress import report as report_event

__all__ = ["LimitProgress", "ProgressCallback", "report", "reporting"]


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


def report(stage: str, iteration: int, lower: float, upper: float) -> None:
    """Hand one iteration to the analysis's callback (:func:`masonry_dem._progress.report`),
    if it has one."""
    if listening():
        report_event(LimitProgress(stage, iteration, float(lower), float(upper)))
