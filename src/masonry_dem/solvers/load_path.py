"""The settings of a load path that the static and the dynamic-relaxation solvers share:
:class:`LoadPathSettings`, the base of both solvers' settings. Each field states its range
where it is declared (the specifiers of :mod:`masonry_dem._validation`), and one check at
construction refuses a value out of range by the field's name."""

from __future__ import annotations

import math
from dataclasses import dataclass

from masonry_dem._docstrings import SHARED, fill
from masonry_dem._validation import (
    at_least,
    check_fields,
    checked,
    count,
    is_number,
    positive,
    positive_or_none,
)

#: the fields of :class:`LoadPathSettings` that a subclass documents as they are, filled into
#: the docstrings (:func:`masonry_dem._docstrings.fill`)
DOCS: dict[str, str] = {
    "load_path_fields": """
        growth : float, default 1.5
            An easy step makes the next one ``growth`` times longer, >= 1.
        bracket_tolerance : float, default 0.005
            Width of the collapse bracket, relative to lambda, > 0.
        refine : bool, default True
            Halve a failed load step (False: stop at the first failure, an upper bracket
            only).
        max_steps : int, default 1000
            Converged steps of a run, >= 1.
        max_load_factor : float, default inf
            The run ends ``completed`` when lambda reaches it, > 0 (inf: no cap).
        displacement_limit : float, optional
            Largest translation [m] still in the small-displacement range, > 0 (None: the
            solver's own, from the size of the blocks).
    """,
    **SHARED,
}


@fill(DOCS)
@dataclass(frozen=True)
class LoadPathSettings:
    """How a solver steps lambda from the dead-load state to a collapse.

    Step sizes are in units of the load scale ``|F_D| / |F_L|``: 1 for a tilt table, where
    the live load is the weight turned horizontal. A subclass declares its own fields with
    their ranges in the same way, and documents every field, its base's too.

    Parameters
    ----------
    initial_step, max_step : float, default 0.02 and 1.0
        The first and the largest lambda increment, > 0.
    %(load_path_fields)s

    %(field_errors)s
    """

    initial_step: float = positive(0.02)
    max_step: float = positive(1.0)
    growth: float = at_least(1.5, 1.0)
    bracket_tolerance: float = positive(0.005)
    refine: bool = True
    max_steps: int = count(1000, least=1)
    # NaN fails the test too
    max_load_factor: float = checked(
        math.inf, lambda v: is_number(v) and v > 0, "a number > 0 (inf: no cap)"
    )
    displacement_limit: float | None = positive_or_none()

    def __post_init__(self) -> None:
        check_fields(self)
