"""What the static solver reports while it runs, between two converged steps: its Newton
iterations and factorizations so far (a long step of a large wall takes minutes, and a
display shows that it moves). Reported through :mod:`masonry_dem._progress`, to whoever
listens (``masonry-dem run``'s progress bar)."""

from __future__ import annotations

from dataclasses import dataclass

from masonry_dem._progress import listening, report


@dataclass(frozen=True)
class NewtonProgress:
    """The static solver's work so far in a run.

    Attributes:
        iterations: Newton iterations (those of the damped motions included).
        factorizations: factorizations of the tangent.
    """

    iterations: int
    factorizations: int


def report_newton(iterations: int, factorizations: int) -> None:
    """Report one Newton iteration, if anybody listens."""
    if listening():
        report(NewtonProgress(iterations, factorizations))
