"""What the path followers (:mod:`.paths`, :mod:`.steps`, :mod:`.displacement_control`) ask
of the solver that runs them, as a Protocol that :class:`.solver.StaticSolver` satisfies: the
followers name no class of the solver, not even in annotations, so the solver imports them
and nothing imports the solver back (no import cycle, tests/test_architecture.py).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    import numpy as np

    from masonry_dem.solvers.static.outcome import Outcome
    from masonry_dem.solvers.static.problem import DiscreteProblem
    from masonry_dem.solvers.static.settings import StaticSettings


class PathSolver(Protocol):
    """The last converged state of the path and the searches from it (the corrector's
    Newton iterations, the instability rule's damped motions)."""

    #: the step of the History from which the path measures its displacement limit
    limit_origin: int

    @property
    def problem(self) -> DiscreteProblem:
        """The discrete problem the searches solve."""
        ...

    @property
    def settings(self) -> StaticSettings:
        """The solver's settings."""
        ...

    @property
    def q(self) -> np.ndarray:
        """The displacements of the last converged state."""
        ...

    @property
    def plastic(self) -> np.ndarray:
        """The plastic part of the law state the path has reached."""
        ...

    @property
    def cracked(self) -> np.ndarray:
        """The cracked joints of the path."""
        ...

    @property
    def load_factor(self) -> float:
        """lambda of the last converged state."""
        ...

    @property
    def last_increment(self) -> float:
        """The size of the last converged search's increment [m]."""
        ...

    @property
    def instability(self) -> str:
        """The instability rule's verdict on the collapse."""
        ...

    @property
    def limit(self) -> float:
        """The displacement limit of the searches [m]."""
        ...

    @property
    def search_seed(self) -> float:
        """The trust radius of a search with no previous increment to go by [m]."""
        ...

    def residual(self, q: np.ndarray, lam: float, dead_factor: float = 1.0) -> Any:
        """R(q, lambda) with the plastic part and the cracked joints of the path."""
        ...

    def equilibrate(
        self,
        load_factor: float,
        *,
        control: tuple[np.ndarray, float, float] | None = ...,
        radius: float | None = ...,
        start: np.ndarray | None = ...,
    ) -> Outcome:
        """Newton iterations from the last converged state to equilibrium at ``load_factor``
        or, with ``control``, along a generalised displacement (the corrector's
        :meth:`~masonry_dem.solvers.static.corrector.Corrector.equilibrate`, as the
        followers call it)."""
        ...

    def damped_motion(
        self,
        target: float,
        dead: float = 1.0,
        held: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Outcome:
        """The instability rule where Newton finds no equilibrium (``held``: with a
        generalised displacement held, lambda free)."""
        ...

    def rule_at(self, top: float) -> Outcome:
        """The instability rule at a stop of the path whose highest lambda is ``top``."""
        ...

    def snapshot(self) -> tuple[Any, ...]:
        """The last converged state, to go back to (:meth:`resume`)."""
        ...

    def resume(self, kept: tuple[Any, ...]) -> None:
        """Go back to a state :meth:`snapshot` kept."""
        ...
