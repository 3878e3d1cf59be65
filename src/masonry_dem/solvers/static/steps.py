"""How long the next step of a path is and where it starts: the step rule shared by the path
followers (:class:`StepController`), work control's secant start (:class:`SecantPredictor`),
the first live step's length from the wall's elastic solution (:func:`elastic_range`) and
the longest work step near the peak (:func:`tail_cap`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from masonry_dem.constitutive.law import CONTACT_BAND

if TYPE_CHECKING:
    from masonry_dem.solvers.static.path_solver import PathSolver

__all__ = [
    "ElasticRange",
    "SecantPredictor",
    "StepController",
    "elastic_range",
    "tail_cap",
]


@dataclass
class StepController:
    """The step length of a path follower, at most ``cap``; halved after a failure, counting
    the halvings in a row (``cuts``). After a converged step (:meth:`grow`) ``growth`` times
    longer after an easy step (at most ``easy_iterations`` corrector iterations; None: after
    every converged step), else kept.
    """

    size: float
    growth: float
    cap: float = math.inf
    easy_iterations: int | None = None
    cuts: int = 0

    def factor(self, iterations: int) -> float:
        """How much longer the next step is than the one that converged in ``iterations``."""
        easy = self.easy_iterations is None or iterations <= self.easy_iterations
        return self.growth if easy else 1.0

    def grow(self, iterations: int) -> None:
        self.size = min(self.size * self.factor(iterations), self.cap)

    def cut(self) -> None:
        self.size /= 2
        self.cuts += 1


@dataclass
class SecantPredictor:
    """The start of the next search of work control: the line through the last two converged
    states of the path, extended by the next step. Along a smooth
    stretch of the path Newton then starts within a fraction of the step of the answer
    instead of a whole step away; a state reached by a jump (the damped motion past a
    fold) starts a new line. The parameter ``t`` is what the
    follower prescribes (lambda under load control, w under work control)."""

    states: list[tuple[float, np.ndarray, float]] = field(
        default_factory=list
    )  # (t, q, lambda), at most two

    def add(self, t: float, q: np.ndarray, lam: float) -> None:
        self.states = [*self.states[-1:], (t, q, lam)]

    def restart(self, t: float, q: np.ndarray, lam: float) -> None:
        self.states = [(t, q, lam)]

    def start(self, t: float) -> tuple[np.ndarray | None, float | None]:
        """(q, lambda) on the line at ``t``; (None, None) without two states on it."""
        if len(self.states) < 2:
            return None, None
        (t0, q0, lam0), (t1, q1, lam1) = self.states[-2:]
        if t1 == t0:
            return None, None
        f = (t - t1) / (t1 - t0)
        return q1 + f * (q1 - q0), lam1 + f * (lam1 - lam0)


@dataclass(frozen=True)
class ElasticRange:
    """The elastic range of the live load from the last converged state (the dead-load
    state): the tangent response ``rate`` = K_t^-1 F_L of the free DOFs, and the largest
    ``load_factor`` up to which every joint that carries load stays inside its strength
    domain along it (inf: none reaches it below ``cap``)."""

    load_factor: float
    rate: np.ndarray


def elastic_range(solver: PathSolver, cap: float) -> ElasticRange | None:
    """The load factor at which the first joint that carries load reaches its strength
    domain along the tangent response to the live load from the last converged state, in
    closed form up to a bisection: along q + lambda K_t^-1 F_L the trial actions of each
    joint are affine in lambda, and the strength domain is convex, so the lambdas at which
    every joint stays inside form one interval [0, lambda_e] (found to 1e-6 of itself).

    Joints with no tensile strength at zero compression (within the law's contact band, the
    head joints of a dry wall under its own weight) carry no load and have no elastic range:
    they are left out, as the tangent leaves them out (``DiscreteProblem.joint_tangents``);
    so are joints already yielded (a criterion of the law violated: non-zero flags). None
    when the tangent gives no response (a singular tangent) or when some joint that carries
    load has no elastic range at all."""
    problem = solver.problem
    law = problem.law
    _, _, response = solver.residual(solver.q, solver.load_factor)
    rate = problem.factor(response).solve(problem.F_live)
    if not np.all(np.isfinite(rate)):
        return None
    moved = np.zeros_like(solver.q)
    moved[problem.free] = rate
    base = problem.asm.relative_displacements(solver.q)
    per_unit = problem.asm.relative_displacements(moved)
    normal = np.abs(response.trial[:, 2])
    no_load = (response.strength_at_zero <= 0.0) & (
        normal <= CONTACT_BAND * normal.max(initial=0.0)
    )
    # the law's own test: a joint is inside its domain where no criterion is violated (its
    # flags are zero); one at capacity under the dead load has yielded already
    inside = law.respond(base, solver.plastic, solver.cracked, utilisation=False).flags == 0
    rows = inside & ~no_load
    if not rows.any():
        return None

    def over(lam: float) -> bool:
        # the law is row by row: the joints left out change no flag of the others
        trial = law.respond(base + lam * per_unit, solver.plastic, solver.cracked, False)
        return bool(np.any(trial.flags[rows] != 0))

    hi = cap
    if not over(hi):
        return ElasticRange(math.inf, rate)
    lo = 0.0
    for _ in range(60):  # to 1e-6 of lambda_e from a cap up to 2^40 times larger
        if hi - lo <= 1e-6 * hi:
            break
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if over(mid) else (mid, hi)
    return ElasticRange(lo, rate) if lo > 0.0 else None


def tail_cap(
    lam: float,
    elastic_slope: float,
    flat_slope: float,
    resolution: float,
    slope: float = math.nan,
    to_limit: float = math.inf,
) -> float:
    """The longest work step that gains at most ``resolution`` x |lambda| where it may end
    the path: inf when off (``resolution`` or ``flat_slope`` 0) or without an elastic slope.

    * At the slope of the stop (``flat_slope`` of the elastic slope d lambda / d w): on a
      curve whose slope fades (a mechanism forming joint by joint) the path stops three
      steps after its slope fell below ``flat_slope`` and reports the highest lambda it
      reached. Those steps are ``growth`` - 1 times the distance travelled, so the answer
      carries their gain, an error of first order in the step and always upward. Bounded
      by the gain they can make at the stop's slope, the stop is located to within a few
      ``resolution`` of lambda whatever ``growth``. The bound is (``resolution`` /
      ``flat_slope``) x lambda / elastic slope: for equal fractions, the elastic
      displacement at lambda, which the steps of the rising path rarely reach.
    * At the displacement limit, ``to_limit`` ahead in w (by the secant of the last two
      states): a step that may pass it goes no further than it, or no longer than its gain
      at the last step's ``slope`` (relative to the elastic one) allows, whichever is longer.
      The state past the limit is the last of the path, and its lambda counts.
    """
    if resolution <= 0 or flat_slope <= 0 or not elastic_slope > 0:
        return math.inf
    cap = resolution * abs(lam) / (flat_slope * elastic_slope)
    if to_limit < cap:
        steep = max(slope, flat_slope) if math.isfinite(slope) else flat_slope
        cap = max(to_limit, resolution * abs(lam) / (steep * elastic_slope))
    return cap
