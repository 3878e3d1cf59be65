"""Typed outcomes of the static solver: how a run ended (:class:`Status`), why its path
stopped (:class:`StopReason`) and why one equilibrium search failed (:class:`Failure`).

Callers branch on these enums, never on words of the reason texts (which are for people).
:class:`Status` and :class:`StopReason` are ``str`` enums: ``status == "collapse"`` holds
and ``json.dumps`` writes the plain value.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

    from masonry_dem.constitutive.law import LawResponse


class _Text(str, Enum):
    """A str enum that prints and formats as its value (``enum.StrEnum`` is 3.11+)."""

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)


class Status(_Text):
    """How a run ended. ``COLLAPSE`` only with a certificate that holds (see
    :mod:`masonry_dem.solvers.static.certificate`); a path that stops without one is
    ``FAILED``, with every step it converged kept."""

    RUNNING = "running"
    COMPLETED = "completed"
    COLLAPSE = "collapse"
    FAILED = "failed"


class StopReason(_Text):
    """Why the path of a run stopped (whatever the status that follows from it)."""

    NONE = "none"  # still running
    DEAD_LOAD = "no equilibrium under the dead load"
    NO_LIVE_LOAD = "no live load"
    MAX_LOAD_FACTOR = "max_load_factor reached"
    MAX_STEPS = "max_steps reached"
    LOAD_BRACKET = "load control: bracket refined"  # no equilibrium beyond the bracket
    CURVE_FLAT = "pushover curve flat"  # lambda stopped rising while w doubled
    STIFFNESS_LOST = "stiffness lost"  # three steps at < flat_slope of the elastic slope
    CREEPING = "work control creeps"  # three steps with no displacement to speak of
    DISPLACEMENT_LIMIT = "displacement limit"  # past the small-displacement range
    PATH_STUCK = "path stuck"  # no equilibrium for any step size (work control)
    LIMIT_POINT = "limit point"  # the pushover curve falls (work control)
    UNSTABLE = "unstable equilibrium"  # det K_t < 0 at a state of the path, the rule no rest
    CONTROL_REACHED = "control displacement reached"
    CONTROL_STUCK = "displacement control stuck"
    CONTROL_BUDGET = "displacement control: max_steps spent short of the target"
    SINGULAR_TANGENT = "singular tangent"  # no factorization, even with a stiffened floor
    NO_REST = "no rest"  # the reference analysis: the damped wall found no rest above lambda


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
