"""The static solver as a package, one role per module:

* :mod:`.problem` - the discrete problem: residual and consistent tangent of a Model under
  its interface law (shared with dynamic relaxation), the factorization behind one method;
* :mod:`.corrector` - one equilibrium: Newton with its safeguards (where it finds none,
  the instability rule: the damped motion of :mod:`masonry_dem.solvers.quasi_static`);
* :mod:`.paths` - path followers (load, work, displacement control) sharing one step rule;
  :mod:`.path_solver` - what they ask of the solver that runs them;
* :mod:`.outcome` - typed outcomes: :class:`Status`, :class:`StopReason`, :class:`Failure`;
* :mod:`.certificate` - when a stop of the path is a collapse;
* :mod:`.settings` - every number that steers it; :mod:`.solver` - the solver, ``pushover``;
* :mod:`.branches` - load against displacement control on one model;
* :mod:`.stages` - loading stages: runs of the solver in turn, the state carried.

Names are imported lazily, so that :mod:`masonry_dem.results` can use the outcome enums.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from masonry_dem._lazy import lazy_names
from masonry_dem.solvers.static.outcome import Failure, Outcome, Status, StopReason

if TYPE_CHECKING:  # the names ``__getattr__`` imports, seen by type checkers as re-exports
    from masonry_dem.solvers.static.certificate import Certificate as Certificate
    from masonry_dem.solvers.static.certificate import certify as certify
    from masonry_dem.solvers.static.problem import DiscreteProblem as DiscreteProblem
    from masonry_dem.solvers.static.settings import DisplacementControl as DisplacementControl
    from masonry_dem.solvers.static.settings import StaticSettings as StaticSettings
    from masonry_dem.solvers.static.solver import StaticSolver as StaticSolver
    from masonry_dem.solvers.static.solver import pushover as pushover
    from masonry_dem.solvers.static.stages import Stage as Stage
    from masonry_dem.solvers.static.stages import run_stages as run_stages

_LAZY = {
    "StaticSettings": ".settings",
    "DisplacementControl": ".settings",
    "StaticSolver": ".solver",
    "pushover": ".solver",
    "Certificate": ".certificate",
    "certify": ".certificate",
    "DiscreteProblem": ".problem",
    "Stage": ".stages",
    "run_stages": ".stages",
}
__getattr__ = lazy_names(__name__, _LAZY)

__all__ = ["Failure", "Outcome", "Status", "StopReason", *_LAZY]
