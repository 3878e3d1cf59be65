"""What a limit analysis returns (:class:`LimitAnalysisResult`: status, multiplier, mechanism,
actions) and the independent check of its mechanism (:func:`mechanism_violation`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from masonry_dem._docstrings import SHARED, fill
from masonry_dem.assembly.compatibility import compatibility_matrix
from masonry_dem.model import Model

from .formulation import Problem, Solution
from .interface import grid_points

STATUSES = ("collapse", "no collapse", "failed")


@fill(SHARED)
@dataclass(frozen=True)
class LimitAnalysisResult:
    """Outcome of :func:`limit_analysis`.

    Parameters
    ----------
    status : {"collapse", "no collapse", "failed"}
        "collapse"; "no collapse" (no mechanism is possible: the LP is unbounded, or lambda
        reaches ``LAMBDA_CAP x max(1, |dead| / |live|)``); or "failed" (``reason`` says why,
        with the solver's own status).
    load_factor : float
        The collapse multiplier (nan unless "collapse").
    reason : str
        Why the analysis ended as it did, for people.
    block_velocities : numpy.ndarray, shape (n, 6)
        The collapse mechanism (zeros unless "collapse"), scaled so that the largest
        translation is 1 and the live load does positive work.
    interface_actions : numpy.ndarray, shape (m, 6)
        Local actions [f1, f2, fn, m1, m2, m3] at collapse.
    method : {"associative", "non-associative"}
        The problem solved.
    grid : int
        Contact points per side of each interface.
    backend : {"highs", "clarabel"}
        The solver.
    seconds : float
        Wall-clock time of the analysis.
    cone : str, default "circumscribed"
        The friction cone: "circumscribed" or "inscribed" pyramid, or "exact".
    friction_sides : int, default 8
        Faces of the pyramid (0 with the exact cone).
    iterations : int, default 1
        Solves of the analysis.
    load_factors : tuple of float, default ()
        One per solve (the non-associative iterations).
    variables, constraints : int, default 0
        Size of the (last) problem solved.
    info : dict, optional
        More about the run (e.g. ``start``, the associative multiplier that bounds the
        non-associative one).
    friction_scale : float, default 1.0
        The factor on every joint's friction.
    covers_dem : bool, default False
        ``friction_scale`` >= kappa(alpha): the LA domain holds the DEM's.
    bracket : (float, float), optional
        Where the solver certifies lambda both ways, (lower, upper) (statically admissible
        forces, an admissible mechanism) with ``load_factor`` = upper (``normal_ipm``); None
        where the solver gives no such bracket.
    hanging_blocks : tuple of int, default ()
        The blocks the dead load alone cannot hold with zero dilatancy (``dead_load``): the
        analysis then ends "failed" with no multiplier.

    Examples
    --------
    %(sliding_block)s
    >>> result = md.limit_analysis(model)
    >>> result.summary()["status"], result.bound, result.method
    ('collapse', 'estimate', 'associative')
    """

    status: str
    load_factor: float
    reason: str
    block_velocities: np.ndarray
    interface_actions: np.ndarray
    method: str  # "associative" or "non-associative"
    grid: int
    backend: str
    seconds: float
    cone: str = "circumscribed"
    friction_sides: int = 8
    iterations: int = 1
    load_factors: tuple[float, ...] = ()  # one per solve (the non-associative iterations)
    variables: int = 0
    constraints: int = 0
    info: dict[str, Any] = field(default_factory=dict)
    friction_scale: float = 1.0
    covers_dem: bool = False  # friction_scale >= kappa(alpha): the LA domain holds the DEM's
    #: (lower, upper): lambda certified from both sides (statically admissible forces, an
    #: admissible mechanism; ``normal_ipm``), None where the solver gives no such bracket
    bracket: tuple[float, float] | None = None
    #: the blocks the dead load alone cannot hold with zero dilatancy (``dead_load``): the
    #: analysis then ends "failed" with no multiplier
    hanging_blocks: tuple[int, ...] = ()

    @property
    def bound(self) -> str:
        """What the multiplier is to the DEM's: "upper" or "estimate".

        An "upper" bound: associative, with a cone and a friction whose domain contains the
        DEM's (``friction_scale`` >= kappa(alpha), ``dem_domain``); an "estimate":
        non-associative, an inscribed cone, or a DEM alpha the friction does not cover.
        """
        upper = (
            self.method == "associative"
            and self.cone in ("circumscribed", "exact")
            and self.covers_dem
        )
        return "upper" if upper else "estimate"

    def summary(self) -> dict[str, Any]:
        """What summary.json holds of the analysis.

        Returns
        -------
        dict
            status, reason, lambda (None unless finite), lambda_bracket, method, bound, grid,
            backend, cone, friction_sides, friction_scale, iterations, load_factors,
            variables, constraints, seconds, hanging_blocks, and for the non-associative
            analysis its ``start`` and the associative multiplier of the same cone that
            bounds it from above (``associative_lambda``).
        """
        lam = self.load_factor if np.isfinite(self.load_factor) else None
        return {
            "status": self.status,
            "reason": self.reason,
            "lambda": lam,
            "lambda_bracket": None if self.bracket is None else [float(x) for x in self.bracket],
            "method": self.method,
            "bound": self.bound,
            "grid": self.grid,
            "backend": self.backend,
            "cone": self.cone,
            "friction_sides": self.friction_sides,
            "friction_scale": self.friction_scale,
            "iterations": self.iterations,
            "load_factors": [float(x) for x in self.load_factors],
            "variables": self.variables,
            "constraints": self.constraints,
            "seconds": round(self.seconds, 4),
            "hanging_blocks": list(self.hanging_blocks),
            # the non-associative iteration's starting state and the associative multiplier
            # of the same cone that bounds it from above (None for the associative analysis)
            "start": self.info.get("start") if self.method != "associative" else None,
            "associative_lambda": _finite_or_none(self.info.get("associative")),
        }


def _finite_or_none(value: Any) -> float | None:
    return float(value) if value is not None and np.isfinite(value) else None


#: largest violation of the kinematic admissibility of a returned mechanism, relative to its
#: largest relative velocity (interior point solutions are accurate to about 1e-8)
_ADMISSIBILITY_TOLERANCE = 1e-5


def mechanism_violation(model: Model, velocities: np.ndarray, dirs: np.ndarray | None) -> float:
    """How far a mechanism is from kinematically admissible for the associative problem:
    the largest ``mu g(v_t) - v_n`` over the corners of every interface (g: the pyramid's
    gauge, or |v_t| for the exact cone, ``dirs`` None), divided by the largest relative
    velocity; 0 when admissible. The corners suffice (module docstring). An independent
    check of the solver's dual: on a 3 053-block wall Clarabel reported "Solved" with a
    mechanism 0.7 off."""
    its = model.interfaces
    if its.count == 0:
        return 0.0
    H = compatibility_matrix(model.blocks, its)
    d = (H @ np.asarray(velocities, dtype=float).reshape(-1)).reshape(-1, 6)
    scale = float(np.abs(d).max(initial=0.0))
    if scale == 0:
        return 0.0
    y, _ = grid_points(its.l1, its.l2, 2)
    vt1 = d[:, None, 0] - d[:, None, 5] * y[:, :, 1]
    vt2 = d[:, None, 1] + d[:, None, 5] * y[:, :, 0]
    vn = d[:, None, 2] + d[:, None, 3] * y[:, :, 1] - d[:, None, 4] * y[:, :, 0]
    if dirs is None:
        gauge = np.hypot(vt1, vt2)
    else:
        gauge = (vt1[..., None] * dirs[:, 0] + vt2[..., None] * dirs[:, 1]).max(axis=-1)
    gap = model.friction[:, None] * gauge - vn
    return max(float(gap.max()) / scale, 0.0)


def finish(problem: Problem, sol: Solution, size: tuple[int, int], result, **kw):
    """The result of a solve: its status word turned into the analysis's status and reason."""
    variables, constraints = size
    kw = dict(kw, variables=variables, constraints=constraints)
    if sol.status == "unbounded":
        return result(
            "no collapse",
            float("nan"),
            f"no mechanism: rigid blocks carry the live load at any lambda ({sol.detail}); "
            "blocks of unlimited stiffness and compressive strength can, e.g. by arching "
            "between supports, which joints of finite stiffness flatten and masonry of finite "
            "strength crushes: no proof that the wall stands (its pushover answers that)",
            **kw,
        )
    if sol.status == "dead load":
        return result(
            "failed",
            float("nan"),
            f"no equilibrium under the dead load ({sol.detail})",
            **kw,
        )
    if sol.status == "budget":
        return result(
            "failed",
            float("nan"),
            f"stopped by the solver's time or iteration limit ({sol.detail}): no "
            "multiplier; a larger time_limit (--time-limit) or the other backend may reach one",
            **kw,
        )
    if sol.status != "optimal":
        return result("failed", float("nan"), f"solver trouble: {sol.detail}", **kw)
    actions = sol.info_actions if hasattr(sol, "info_actions") else None
    return result(
        "collapse",
        sol.lam,
        f"collapse mechanism at lambda = {sol.lam:.6g} ({sol.detail})",
        block_velocities=problem.velocities(sol.duals),
        bracket=sol.bracket,
        interface_actions=actions,
        **kw,
    )
