"""Where a mechanism to assess comes from, in memory: a pushover's :class:`History` that
ended in collapse (its collapse mode, :func:`masonry_dem.mechanism.collapse_mode`) or a limit
analysis's result (its block velocities). Each is turned into the rigid-block mechanism
(:func:`~masonry_dem.assessment.kinematics.hinged_mode`) and returned with alpha0, the
analysis's multiplier in the codes' terms (c lambda, c of the live load c P_i d). A results
folder is read by ``export/assessment_files.py``."""

from __future__ import annotations

from typing import Any

import numpy as np

from masonry_dem.assessment.kinematics import MOVING, Mechanism, hinged_mode
from masonry_dem.model import Model
from masonry_dem.results import History


def history_mechanism(
    model: Model, history: History, moving: float = MOVING
) -> tuple[Mechanism, float]:
    """The mechanism of a pushover that ended in collapse, and its alpha0."""
    from masonry_dem.mechanism import collapse_mode

    lam = history.collapse_multiplier
    if history.status.value != "collapse" or lam is None or not history.steps:
        raise ValueError(
            f"the run ended {history.status.value!r} with no collapse multiplier: there is "
            "no mechanism to assess"
        )
    mode, _ = hinged_mode(model, collapse_mode(model, history.steps[-1]))
    mech = Mechanism.of(model, mode, moving)
    return mech, float(lam) * mech.scale


def limit_mechanism(model: Model, result: Any, moving: float = MOVING) -> tuple[Mechanism, float]:
    """The mechanism of a limit analysis (``LimitAnalysisResult``) that found a collapse,
    and its alpha0."""
    if result.status != "collapse" or not np.isfinite(result.load_factor):
        raise ValueError(
            f"the limit analysis ended {result.status!r}: there is no mechanism to assess"
        )
    mode, _ = hinged_mode(model, np.asarray(result.block_velocities, dtype=float))
    mech = Mechanism.of(model, mode, moving)
    return mech, float(result.load_factor) * mech.scale
