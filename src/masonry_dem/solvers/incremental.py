"""The static incremental solver: kept as a name for :mod:`masonry_dem.solvers.static`,
the package it became (problem, corrector, path followers, outcome, certificate)."""

from __future__ import annotations

from masonry_dem.solvers.static.outcome import Failure, Outcome, Status, StopReason
from masonry_dem.solvers.static.settings import CONTINUATION, DisplacementControl, StaticSettings
from masonry_dem.solvers.static.solver import StaticSolver, pushover

__all__ = [
    "CONTINUATION",
    "DisplacementControl",
    "Failure",
    "Outcome",
    "StaticSettings",
    "StaticSolver",
    "Status",
    "StopReason",
    "pushover",
]
