"""The public entry point :func:`limit_analysis`: it checks the arguments, builds the problem,
solves it (associative: one solve; non-associative: the iteration), checks the mechanism, and
turns every outcome into a :class:`~.result.LimitAnalysisResult` with a status."""

from __future__ import annotations

import logging
import time
from dataclasses import replace
from typing import Any

import numpy as np

from masonry_dem._docstrings import SHARED, fill
from masonry_dem.model import Model, require_model

from .backends import solve_associative
from .budget import DEFAULT_TIME_LIMIT, budget
from .dead_load import check_dead_load
from .dem_domain import model_friction_scale
from .formulation import Problem
from .interface import ASSOCIATIVE_GRID, NON_ASSOCIATIVE_GRID, pyramid_edges
from .non_associative import non_associative
from .progress import ProgressCallback, reporting
from .result import _ADMISSIBILITY_TOLERANCE, LimitAnalysisResult, finish, mechanism_violation
from .settings import LimitSettings

log = logging.getLogger(__name__)

#: with no backend given: HiGHS (the friction pyramid's LP) below this many free DOFs,
#: Clarabel (the exact cone) from it. Measured (one process, running-bond walls of
#: 0.081 x 0.21 x 0.07 m blocks on a base, in and out of plane, held or not): HiGHS's
#: associative solve takes 0.36, 0.83, 2.6, 11 and 36 s of CPU at 53, 86, 158, 331 and
#: 586 blocks and does not end in 60 s at 1 007, against 0.02 to 0.4 s for Clarabel at
#: every size; 600 DOFs (100 free blocks) is where HiGHS passes about a second
#: (docs/limit_analysis.md, "Budgets")
EXACT_CONE_FROM = 600


# --------------------------------------------------------------------------- public entry
@fill(SHARED)
def limit_analysis(
    model: Model,
    *,
    associative: bool = True,
    grid: int | None = None,
    backend: str | None = None,
    cone: str | None = None,
    friction_sides: int = 8,
    tolerance: float = 1e-3,
    max_iterations: int = 50,
    relaxation: float = 0.5,
    friction_scale: float = 1.0,
    column_generation: bool = True,
    nearest_optimum: bool = False,
    time_limit: float = DEFAULT_TIME_LIMIT,
    start: str = "elastic",
    progress: ProgressCallback | None = None,
) -> LimitAnalysisResult:
    """The collapse multiplier of ``model``'s live load over its dead load, and the mechanism.

    Solver trouble is a status of the result, never an exception; bad arguments raise
    ValueError naming the argument.

    Parameters
    ----------
    model : Model
        The wall.
    associative : bool, default True, keyword-only
        True: the classical (associative) multiplier, an upper bound of the DEM's with the
        default cone; False: zero dilatancy (Gilbert et al. 2006).
    grid : int, optional, keyword-only
        Contact points per side of each interface (n x n, >= 2). None: 2 for the associative
        problem (exact, see the module docstring; a cohesion above mu ft dissipates on its
        own grid, at least ``NON_ASSOCIATIVE_GRID``: ``formulation.cohesive_grid``) and
        ``NON_ASSOCIATIVE_GRID`` for the frozen capacities of the non-associative one.
    backend : {"highs", "clarabel"}, optional, keyword-only
        "highs" (LP, friction pyramid) or "clarabel" (SOCP, the exact cone). None: the one
        ``cone`` names, else by size, HiGHS below ``EXACT_CONE_FROM`` free DOFs and Clarabel
        from it (HiGHS's time grows far faster).
    cone : {"circumscribed", "inscribed", "exact"}, optional, keyword-only
        "circumscribed" (default) or "inscribed" pyramid with "highs"; "exact" (the only
        one) with "clarabel".
    friction_sides : int, default 8, keyword-only
        Faces of the pyramid (>= 3). 8 by default: on the bundled wall (out of plane, held on
        one edge) the circumscribed pyramid of 4, 8 and 16 faces gives 0.587, 0.447 and
        0.434 against 0.429 with the exact cone, in 0.7, 1.2 and 2.4 s
        (docs/limit_analysis.md).
    tolerance : float, default 1e-3, keyword-only
        The non-associative iteration stops when its last three lambdas agree within
        ``tolerance``, relative; in (0, 1).
    max_iterations : int, default 50, keyword-only
        Solves of the non-associative iteration, >= 1.
    relaxation : float, default 0.5, keyword-only
        The non-associative iteration's starting under-relaxation of the frozen actions
        between solves, halved where lambda turns back and doubled back, to it at most, after
        three steps the same way; in (0, 1].
    friction_scale : float, default 1.0, keyword-only
        A factor (>= 1) on every joint's friction. ``dem_friction_scale`` of the model's
        alpha makes the LA domain contain the DEM's, so the associative multiplier is an
        upper bound of the pushover's by Radenkovic's theorem (the result's ``bound`` is then
        "upper"; ``dem_upper_bound`` does this).
    column_generation : bool, default True, keyword-only
        The non-associative iteration's LPs with "highs": True solves each by column
        generation (``columns``: the full LP's optimum to a relative 1e-7, or 1e-5 where
        HiGHS's tolerances stall it, certified by its duals, on a master of a few thousand
        columns), False the full LP (the same lambda per LP, tens of times slower:
        docs/limit_analysis.md). Ignored with "clarabel" and when associative.
    nearest_optimum : bool, default False, keyword-only
        The non-associative iteration with "highs": after each frozen LP, among its optimal
        force distributions, the one whose normal actions (fn, m1, m2) are nearest the frozen
        ones (``selection``: a convex QP by Clarabel at lambda held at the LP's optimum), so
        that the answer does not depend on which of the degenerate LP's optima the solver
        returns (the order of its columns). Ignored with "clarabel" and when associative.
    time_limit : float, default 600, keyword-only
        The analysis's wall-clock budget [s] (> 0): every solver is handed what is left of it
        as its own time limit, and each has an iteration limit too (``budget``); a solve they
        stop ends "failed", naming the limit, with no multiplier.
    start : {"elastic", "associative"}, default "elastic", keyword-only
        Where the non-associative iteration freezes its first capacities: "elastic", the
        joints' actions under the dead load of least complementary energy
        (``selection.elastic_state``: the state of the DEM's elastic joints, no
        self-stress), or "associative", the associative collapse (Gilbert et al. 2006), whose
        dilatant self-stress the iteration may keep. Ignored when associative.
    progress : callable, optional, keyword-only
        Called with a :class:`~masonry_dem.solvers.limit_analysis.LimitProgress` at each
        iteration of the normal-equation interior point method (walls of about 170 free
        blocks and more) and at each solve of the non-associative iteration: what a long
        analysis shows while it runs (``masonry-dem limit``'s progress line). A callback
        that raises is logged and dropped.

    Returns
    -------
    LimitAnalysisResult
        The status ("collapse", "no collapse" or "failed"), the multiplier, the mechanism and
        the interface actions at collapse.

    Raises
    ------
    ValueError
        If ``model`` is not a :class:`~masonry_dem.Model`, or an argument is out of its
        range (named).

    Examples
    --------
    %(sliding_block)s
    >>> result = md.limit_analysis(model)
    >>> result.status, round(result.load_factor, 6)
    ('collapse', 0.6)
    >>> result.block_velocities[0, :2].round(3).tolist()  # sliding, dilatant (associative)
    [1.0, 0.6]
    >>> round(md.limit_analysis(model, associative=False).load_factor, 6)
    0.6
    """
    t0 = time.perf_counter()
    require_model("limit_analysis", model)
    # every setting checked (a ValueError naming it and its range) where LimitSettings is
    LimitSettings(
        associative=associative,
        grid=grid,
        backend=backend,
        cone=cone,
        friction_sides=friction_sides,
        tolerance=tolerance,
        max_iterations=max_iterations,
        relaxation=relaxation,
        friction_scale=friction_scale,
        column_generation=column_generation,
        nearest_optimum=nearest_optimum,
        time_limit=time_limit,
        start=start,
    )
    if backend is None:
        backend = choose_backend(model, cone)
    if backend == "clarabel":
        cone = "exact"
        dirs = None
    else:
        cone = "circumscribed" if cone is None else cone
        dirs = pyramid_edges(friction_sides, cone)  # refuses the exact cone with HiGHS
    grid = (
        int(ASSOCIATIVE_GRID if associative else NON_ASSOCIATIVE_GRID)
        if grid is None
        else int(grid)
    )
    covers = friction_scale >= model_friction_scale(model) * (1 - 1e-9)
    if friction_scale != 1:
        scaled = model.friction * float(friction_scale)
        # the shear strength c - mu sigma scaled as a whole: the cohesion beyond mu ft too
        cohesion = scaled * model.tensile_strength + float(friction_scale) * (
            model.cohesion_beyond_friction
        )
        model = replace(model, friction=scaled, cohesion=cohesion)
    method = "associative" if associative else "non-associative"
    n, m = model.blocks.count, model.interfaces.count

    def result(status: str, lam: float, reason: str, **kw: Any) -> LimitAnalysisResult:
        kw.setdefault("block_velocities", np.zeros((n, 6)))
        kw.setdefault("interface_actions", np.zeros((m, 6)))
        out = LimitAnalysisResult(
            status,
            lam + 0.0 if status == "collapse" else float("nan"),  # never "-0"
            reason,
            method=method,
            grid=grid,
            backend=backend,
            seconds=time.perf_counter() - t0,
            cone=str(cone),
            friction_sides=int(friction_sides) if backend == "highs" else 0,
            friction_scale=float(friction_scale),
            covers_dem=bool(covers),
            **kw,
        )
        log.info("%s limit analysis of %s: %s (%s)", method, model.name, status, reason)
        return out

    standing = check_dead_load(model)
    if not standing.stands:
        # no multiplier for a wall that cannot carry its own weight: the associative one
        # would hold the hanging blocks by dilatancy alone (``dead_load``)
        return result(
            "failed",
            float("nan"),
            f"no equilibrium under the dead load: {standing.describe(model)}",
            hanging_blocks=tuple(int(b) for b in standing.hanging),
        )
    problem = Problem.of(model)
    if not np.any(problem.live):
        # the pushover's answer too (completed at the dead load): nothing pushes the wall
        return result(
            "no collapse",
            float("nan"),
            "no live load: nothing pushes the wall, there is no multiplier to find",
        )
    with budget(float(time_limit)), reporting(progress):  # every solver within them
        if associative:
            sol, size = solve_associative(problem, grid, dirs)
            out = finish(problem, sol, size, result, iterations=1, load_factors=(sol.lam,))
            if out.status == "collapse":
                violation = mechanism_violation(model, out.block_velocities, dirs)
                if violation > _ADMISSIBILITY_TOLERANCE:
                    return replace(
                        out,
                        status="failed",
                        load_factor=float("nan"),
                        reason=(
                            f"the solver's mechanism is not kinematically admissible (a corner "
                            f"closes or slides without dilating by {violation:.3g} of the largest "
                            f"relative velocity; {sol.detail}): lambda {sol.lam:.6g} is only "
                            "statically admissible, a lower bound of the multiplier"
                        ),
                    )
            return out
        return non_associative(
            problem,
            grid,
            dirs,
            tolerance,
            int(max_iterations),
            float(relaxation),
            result,
            bool(column_generation),
            bool(nearest_optimum),
            start,
        )


def choose_backend(model: Model, cone: str | None = None) -> str:
    """The backend of an analysis given none: the one ``cone`` needs, else HiGHS below
    ``EXACT_CONE_FROM`` free DOFs and Clarabel from it, and Clarabel for joints with a
    cohesion of their own at any size: the pyramid gives each of their cohesive points as
    many columns as sides and a row (2.6 to 3.0 s with HiGHS on a 24-block wall against
    0.12 s with Clarabel's cone, docs/limit_analysis.md)."""
    if cone == "exact":
        return "clarabel"
    if cone is not None:
        return "highs"
    if model.cohesion_beyond_friction.any():
        return "clarabel"
    return "highs" if int(np.count_nonzero(model.free)) < EXACT_CONE_FROM else "clarabel"


def dem_upper_bound(model: Model, **options: Any) -> LimitAnalysisResult:
    """The associative multiplier with the exact cone (Clarabel) and the friction enlarged by
    ``dem_friction_scale`` of the model's alpha: its domain contains the DEM's, so the
    multiplier is an upper bound of the pushover's by Radenkovic's theorem
    (``dem_domain``). The bound of ``masonry-dem run``'s certificate."""
    options.setdefault("backend", "clarabel")
    options.setdefault("friction_scale", model_friction_scale(model))
    return limit_analysis(model, associative=True, **options)
