"""Dynamic relaxation (DR): the explicit baseline the paper's static method is measured
against, one role per module:

* :mod:`.settings` - :class:`DRSettings` (every knob, the choices as ``Literal`` types) and
  :class:`DRStats` (what a run cost);
* :mod:`.integrator` - one relaxation: masses, stable time step, damped central differences
  until the motion dies out, blow-up checks and cuts of the step;
* :mod:`.solver` - the load path: dead load, load steps or a ramp, the collapse bracket,
  :class:`DynamicRelaxation` and :func:`relax`.

It answers the static solver's discrete problem (same law, loads, residual norm and
displacement limit), so both must find the same collapse multiplier.
"""

from __future__ import annotations

from masonry_dem.solvers.dynamic_relaxation.integrator import RelaxationStart
from masonry_dem.solvers.dynamic_relaxation.settings import DRSettings, DRStats
from masonry_dem.solvers.dynamic_relaxation.solver import DynamicRelaxation, relax

__all__ = ["DRSettings", "DRStats", "DynamicRelaxation", "RelaxationStart", "relax"]
