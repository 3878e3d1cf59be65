"""Typed outcomes of the static solver: how a run ended (:class:`Status`), why its path
stopped (:class:`StopReason`) and why one equilibrium search failed (:class:`Failure`).

Callers branch on these enums, never on words of the reason texts (which are for people).
:class:`Status` and :class:`StopReason` are ``str`` enums: ``status == "collapse"`` holds
and ``json.dumps`` writes the plain value. The two are defined in :mod:`masonry_dem.results`,
beside the History they end, and named here too.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from masonry_dem.results import Status as Status
from masonry_dem.results import StopReason as StopReason

if TYPE_CHECKING:
    import numpy as np

    from masonry_dem.constitutive.law import LawResponse


class Failure(Enum):
    """Why one equilibrium search (Newton, or the damped motion) failed."""

    NONE = "none"
    DISPLACEMENT_LIMIT = "displacements exceed the limit"
    NO_DESCENT = "no correction lowers the residual"
    STALL = "the residual stalls"
    NO_CONVERGENCE = "iteration budget spent"
    SINGULAR = "singular tangent"
    CONTROL_FIXED = "the controlled displacement does not move under the live load"
    NO_REST = "no rest"


@dataclass
class Outcome:
    """One equilibrium search: the state it ended in and whether it is an equilibrium."""

    ok: bool
    q: np.ndarray
    load_factor: float
    response: LawResponse
    iterations: int
    reason: str = ""
    failure: Failure = Failure.NONE
    #: the law state (plastic part, cracked joints) a rest of the damped motion was found
    #: with, where it differs from the one carried from the last converged state
    found_with: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def past_limit(self) -> bool:
        """The search left the small-displacement range."""
        return self.failure is Failure.DISPLACEMENT_LIMIT
