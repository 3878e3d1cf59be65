"""The static solver as a package, one role per module:

* :mod:`.problem` - the discrete problem: residual and consistent tangent of a Model under
  its interface law (shared with dynamic relaxation), the factorization behind one method;
* :mod:`.corrector` - one equilibrium: Newton with its safeguards, the pseudo-transient
  step, the robust and dynamic-relaxation fallbacks;
* :mod:`.paths` - path followers (load, work, displacement control) sharing one step rule;
* :mod:`.outcome` - typed outcomes: :class:`Status`, :class:`StopReason`, :class:`Failure`;
* :mod:`.certificate` - when a stop of the path is a collapse;
* :mod:`.settings` - every number that steers it; :mod:`.solver` - the solver, ``pushover``;
* :mod:`.branches` - load against displacement control on one model.

Names are imported lazily, so that :mod:`masonry_dem.results` can use the outcome enums.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

from masonry_dem.solvers.static.outcome import Failure, Outcome, Status, StopReason

_LAZY = {
    "StaticSettings": "settings",
    "DisplacementControl": "settings",
    "StaticSolver": "solver",
    "pushover": "solver",
    "Certificate": "certificate",
    "certify": "certificate",
    "DiscreteProblem": "problem",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(f"masonry_dem.solvers.static.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["Failure", "Outcome", "Status", "StopReason", *_LAZY]
