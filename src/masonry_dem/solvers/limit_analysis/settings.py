"""The settings of a limit analysis as one object, checked when made: :class:`LimitSettings`
holds what :func:`~masonry_dem.solvers.limit_analysis.limit_analysis` takes as keyword
arguments, as ``StaticSettings`` and ``DRSettings`` hold the pushover's and the relaxation's
(``masonry_dem.analyze(model, "limit", LimitSettings(...))``)."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .budget import DEFAULT_TIME_LIMIT
from .interface import PYRAMIDS, lobatto_rule

#: the solvers: HiGHS (LP, the friction pyramid) and Clarabel (SOCP, the exact cone)
BACKENDS = ("highs", "clarabel")
#: where the non-associative iteration freezes its first friction capacities: the joints'
#: elastic state under the dead load (``selection.elastic_state``), or the associative
#: collapse (Gilbert et al. 2006)
STARTS = ("elastic", "associative")


def _boolean(name: str, value: Any) -> None:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")


@dataclass(frozen=True)
class LimitSettings:
    """The settings of one limit analysis.

    Each is the keyword argument of ``limit_analysis`` of the same name, documented there in
    full, and a value out of its range is a ValueError naming it when the settings are made.

    Parameters
    ----------
    associative : bool, default True
        The classical (associative) multiplier; False: zero dilatancy.
    grid : int, optional
        Contact points per side of each interface (>= 2; None: by the problem).
    backend : {"highs", "clarabel"}, optional
        The solver (None: by ``cone``, else by size).
    cone : {"circumscribed", "inscribed", "exact"}, optional
        The friction cone; only "exact" with "clarabel".
    friction_sides : int, default 8
        Faces of the pyramid, >= 3.
    tolerance : float, default 1e-3
        The non-associative iteration's convergence, relative; in (0, 1).
    max_iterations : int, default 50
        Solves of the non-associative iteration, >= 1.
    relaxation : float, default 0.5
        Its starting under-relaxation, in (0, 1].
    friction_scale : float, default 1.0
        A factor on every joint's friction, >= 1.
    column_generation : bool, default True
        The non-associative LPs by column generation.
    nearest_optimum : bool, default False
        Among a frozen LP's optima, the one nearest the frozen normal actions.
    time_limit : float, default 600
        The wall-clock budget [s], finite and > 0.
    start : {"elastic", "associative"}, default "elastic"
        Where the non-associative iteration freezes its first capacities.

    Raises
    ------
    ValueError
        If a setting is out of its range (named).

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.LimitSettings(associative=False, grid=3).keywords()["grid"]
    3
    >>> md.LimitSettings(friction_sides=2)
    Traceback (most recent call last):
    ...
    ValueError: friction_sides must be an integer >= 3, got 2
    """

    associative: bool = True
    grid: int | None = None
    backend: str | None = None
    cone: str | None = None
    friction_sides: int = 8
    tolerance: float = 1e-3
    max_iterations: int = 50
    relaxation: float = 0.5
    friction_scale: float = 1.0
    column_generation: bool = True
    nearest_optimum: bool = False
    time_limit: float = DEFAULT_TIME_LIMIT
    start: str = "elastic"

    def __post_init__(self) -> None:
        _boolean("associative", self.associative)
        if self.grid is not None:
            lobatto_rule(self.grid)  # names grid and its range
        if self.backend is not None and self.backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {self.backend!r}")
        if self.backend == "clarabel" and self.cone not in (None, "exact"):
            raise ValueError(f"cone must be 'exact' with backend 'clarabel', got {self.cone!r}")
        if self.cone is not None and self.cone not in (*PYRAMIDS, "exact"):
            raise ValueError(f"cone must be one of {(*PYRAMIDS, 'exact')}, got {self.cone!r}")
        sides = self.friction_sides
        if isinstance(sides, bool) or int(sides) != sides or sides < 3:
            raise ValueError(f"friction_sides must be an integer >= 3, got {sides!r}")
        if not (isinstance(self.tolerance, (int, float)) and 0 < self.tolerance < 1):
            raise ValueError(f"tolerance must be in (0, 1), got {self.tolerance!r}")
        its = self.max_iterations
        if isinstance(its, bool) or int(its) != its or its < 1:
            raise ValueError(f"max_iterations must be an integer >= 1, got {its!r}")
        if not (isinstance(self.relaxation, (int, float)) and 0 < self.relaxation <= 1):
            raise ValueError(f"relaxation must be in (0, 1], got {self.relaxation!r}")
        scale = self.friction_scale
        if not (isinstance(scale, (int, float)) and 1 <= scale < np.inf):
            raise ValueError(f"friction_scale must be a number >= 1, got {scale!r}")
        _boolean("column_generation", self.column_generation)
        _boolean("nearest_optimum", self.nearest_optimum)
        if self.start not in STARTS:
            raise ValueError(f"start must be one of {STARTS}, got {self.start!r}")
        limit = self.time_limit
        if (
            isinstance(limit, (bool, np.bool_))
            or not isinstance(limit, (int, float, np.integer, np.floating))
            or not 0 < limit < np.inf
        ):
            raise ValueError(f"time_limit must be a finite number of seconds > 0, got {limit!r}")

    def keywords(self) -> dict[str, Any]:
        """The settings as ``limit_analysis``'s keyword arguments.

        Returns
        -------
        dict
            Each field by its name.
        """
        return asdict(self)
