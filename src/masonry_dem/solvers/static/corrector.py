"""The equilibrium corrector: the state of a path, and Newton from its last converged state to
an equilibrium at a given lambda (load control) or at a given value of a controlled
displacement (lambda free).

* :meth:`Corrector.equilibrate` - Newton on the corrected actions with the consistent
  tangent, safeguarded by a trust region on the translations, a backtracking line search,
  chord steps while they converge fast and (under the dead load) a Levenberg-Marquardt
  floor.

Where Newton stops, the instability rule decides (the damped motion of
:mod:`masonry_dem.solvers.quasi_static`, :meth:`StaticSolver.damped_motion`).
A search returns an :class:`~masonry_dem.solvers.static.outcome.Outcome`: a converged state
is an exact equilibrium of the law at its lambda (whatever the safeguards did on the way);
a failed one carries a typed :class:`~masonry_dem.solvers.static.outcome.Failure`.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

import numpy as np

from masonry_dem._signals import check_stop
from masonry_dem.model import Model
from masonry_dem.solvers.factorization import Factors
from masonry_dem.solvers.static.outcome import Failure, Outcome
from masonry_dem.solvers.static.problem import DiscreteProblem
from masonry_dem.solvers.static.progress import report_newton
from masonry_dem.solvers.static.settings import StaticSettings

if TYPE_CHECKING:
    from masonry_dem.constitutive.law import LawResponse

log = logging.getLogger(__name__)

# The safeguards of Newton's method (a trust region on the translations and a backtracking
# line search: Dennis & Schnabel 1983, ch. 6; Conn, Gould & Toint 2000, ch. 6). They bound
# the effort of one search; none moves the equilibrium it converges to.
#: the trust radius of a search with no previous increment to go by, in elastic units of the
#: wall (``DiscreteProblem.displacement_scale``), so that a wall with kn and kt x f takes the
#: same iterates scaled by 1 / f
TRUST_SEED = 0.05
#: a search gives up after this many cuts (by 8) of its trust radius, or when the radius
#: falls below RADIUS_FLOOR elastic units
SEARCH_CUTS = 7
RADIUS_FLOOR = 1e-9
#: a search whose merit has not fallen by STALL_DECREASE over STALL_WINDOW iterations, with
#: no cut of the trust radius, has stalled: no equilibrium near the last converged state
STALL_WINDOW = 8
STALL_DECREASE = 0.5
#: the largest floor of the tangent (a fraction of the joints' elastic stiffness) of the
#: Levenberg-Marquardt fallback of the dead-load search
MAX_FLOOR = 1e-3
#: chord steps (modified Newton, Kelley 1995, 5.3): a factorized tangent is kept while each
#: full step divides the residual by at least 1 / CHORD_RATIO, and after a step shorter than
#: CREEP of the correction with no joint changing state (the tangent is then the same)
CHORD_RATIO = 0.25
CREEP = 1e-3


class Corrector:
    """The state of a path (q, plastic part, cracked joints) and the searches that move it
    to the next equilibrium of the :class:`DiscreteProblem`."""

    def __init__(
        self,
        model: Model,
        settings: StaticSettings | None = None,
        problem: DiscreteProblem | None = None,
    ) -> None:
        if settings is not None and not isinstance(settings, StaticSettings):
            raise TypeError(
                f"settings must be a StaticSettings (e.g. StaticSettings(max_steps=5)) or None, "
                f"got a {type(settings).__name__}"
            )
        self.model = model
        self.settings = settings or StaticSettings()
        s = self.settings
        # (``problem``: another solver's, whose state this one moves by the same law)
        self.problem = problem or DiscreteProblem(
            model,
            tangent=s.tangent,
            residual_stiffness=s.residual_stiffness,
            displacement_limit=s.displacement_limit,
        )
        self.law = self.problem.law
        m = model.interfaces.count
        self.plastic = np.zeros((m, 6))
        self.cracked = np.zeros(m, dtype=bool)
        self.q = np.zeros(model.n_dofs)
        self.iterations = 0  # Newton iterations (and those of the damped motions)
        self.time_steps = 0  # time steps of the damped motions the solver ran
        #: the largest translation of the last converged search's correction: the next
        #: search's trust radius starts at four times it
        self.last_increment = 0.0
        #: extra room of the displacement limit (the elastic displacement under the dead load)
        self._limit_allowance = 0.0

    @property
    def factorizations(self) -> int:
        return self.problem.factorizations

    @property
    def limit(self) -> float:
        """The displacement limit of the searches [m]."""
        return self.problem.limit + self._limit_allowance

    @property
    def search_seed(self) -> float:
        """The trust radius of a search with no previous increment to go by [m]:
        ``TRUST_SEED`` elastic units of the wall (:attr:`DiscreteProblem.displacement_scale`)."""
        return TRUST_SEED * self.problem.displacement_scale

    def restore(self, q: np.ndarray, cracked: np.ndarray | None = None) -> None:
        """Make (q, cracked) the last converged state (e.g. a state read from a History)."""
        self.q = np.asarray(q, dtype=float).reshape(-1).copy()
        if cracked is not None:
            self.cracked = np.asarray(cracked, dtype=bool).copy()

    # ------------------------------------------------------------------ one equilibrium
    def _past_limit(
        self, q: np.ndarray, lam: float, response: LawResponse, iterations: int
    ) -> Outcome:
        """The failed outcome of a state whose displacements passed :attr:`limit`."""
        return Outcome(
            False,
            q,
            lam,
            response,
            iterations,
            f"displacements exceed the limit {self.limit:.3g} m (a mechanism)",
            failure=Failure.DISPLACEMENT_LIMIT,
        )

    def state_of(self, x: np.ndarray) -> np.ndarray:
        """The displacements of the last converged state with its free DOFs set to ``x``."""
        q = self.q.copy()
        q[self.problem.asm.free_index] = x
        return q

    def increment(self, q: np.ndarray) -> float:
        """Largest translation of ``q`` away from the last converged state."""
        idx = self.problem.moving_translations
        return float(np.abs(q[idx] - self.q[idx]).max(initial=0.0))

    def residual(self, q: np.ndarray, lam: float, dead_factor: float = 1.0):
        """R(q, lambda) with the plastic part and the cracked joints of the path."""
        return self.problem.residual(q, lam, self.plastic, self.cracked, dead_factor)

    def equilibrate(
        self,
        load_factor: float,
        dead_factor: float = 1.0,
        control: tuple[np.ndarray, float, float] | None = None,
        radius: float | None = None,
        damped: bool = False,
        start: np.ndarray | None = None,
    ) -> Outcome:
        """Newton iterations from the last converged state to equilibrium at ``load_factor``
        (load control) or with the generalised displacement ``control[0] . q_free`` at
        ``control[1]`` (lambda free: displacement control of one DOF, or of the work-conjugate
        displacement of the live load), reached within ``control_tolerance`` x ``control[2]``
        (the size of the step asked for).

        Safeguards: the translation part of each correction is held within a trust radius
        (grown after full steps, cut by 8 when no step along the direction lowers the
        residual), and the step is backtracked until the residual decreases.
        """
        s = self.settings
        free = self.problem.asm.free_index
        q = (self.q if start is None else start).copy()
        lam = load_factor
        if radius is None:
            radius = max(4.0 * self.last_increment, self.search_seed)
        residual, rnorm, response = self.residual(q, lam, dead_factor)
        floor = s.residual_stiffness
        lu = None  # the factorized tangent, kept while it converges fast (chord steps)
        here = False  # lu was factorized at the current state
        history: list[tuple[float, float]]  # (merit, trust radius) of the iterates; set below
        budget: int
        cuts: int

        def regularise() -> bool:
            """Levenberg-Marquardt fallback: stiffen the tangent's floor (x1000, up to
            MAX_FLOOR x kbar). A near-mechanism of the yielded assembly (a joint at zero gap
            beside a sliding one) leaves the tangent almost singular along a direction the
            residual needs; the undamped Newton step along it is huge, the trust region cuts
            it to nothing and the search stalls far from an equilibrium that exists. The
            floor changes only the search direction, never the residual, so a converged
            state is still an exact equilibrium of the law."""
            nonlocal floor, history, budget, lu, cuts
            if not damped or floor >= MAX_FLOOR:
                return False
            assert radius is not None  # set above when not given
            floor = min(floor * 1e3, MAX_FLOOR)
            lu = None
            cuts = 0
            history = [(rnorm + constraint_error(q), radius)]
            budget = it + s.max_iterations  # a fresh budget for the damped search
            return True

        def constraint_error(qq: np.ndarray) -> float:
            if control is None:
                return 0.0
            return abs(float(control[0] @ qq[free]) - control[1]) / max(control[2], 1e-300)

        # the merit of the start includes the control's error: a controlled step starts at
        # an equilibrium (tiny residual) one whole step away from its goal
        history = [(rnorm + constraint_error(q), radius)]
        budget = s.max_iterations
        it = 0
        cuts = 0  # cuts of the trust radius in this search
        cut = False  # the last iteration cut the radius
        direction = (np.zeros(0), 0.0)  # (dq, dlam) of the search that was cut
        live_solved: tuple[Factors | None, np.ndarray] = (None, np.zeros(0))  # K^-1 F_live
        cerr = constraint_error(q)  # of the present iterate q, kept with it
        while it < budget:
            it += 1
            if rnorm <= s.tolerance and cerr <= s.control_tolerance:
                self.last_increment = self.increment(q)
                return Outcome(True, q, lam, response, it - 1)
            self.iterations += 1
            report_newton(self.iterations, self.factorizations)
            check_stop()  # a signal stops a long step here, not after it
            fresh = lu is None
            if lu is None:
                lu = self.problem.factor(response, floor)
                here = True  # the tangent of this state (False once a step is taken with it)
            repeat = cut and not fresh  # same state, same tangent: the same direction
            cut = False
            if repeat:
                dq, dlam = direction
            else:
                dq = lu.solve(residual)
                dlam = 0.0
            if control is not None and not repeat:
                c = control[0]
                if live_solved[0] is not lu:  # once per factorization: chord steps reuse it
                    live_solved = (lu, lu.solve(self.problem.F_live))
                a = live_solved[1]
                ca = float(c @ a)
                if abs(ca) < 1e-300:
                    return Outcome(
                        False,
                        q,
                        lam,
                        response,
                        it,
                        "the controlled displacement does not move under the live load",
                        failure=Failure.CONTROL_FIXED,
                    )
                dlam = (control[1] - float(c @ q[free]) - float(c @ dq)) / ca
                dq = dq + dlam * a
            if not np.all(np.isfinite(dq)):
                return Outcome(
                    False,
                    q,
                    lam,
                    response,
                    it,
                    "singular tangent stiffness",
                    failure=Failure.SINGULAR,
                )
            size = float(np.abs(dq[self.problem.translation]).max(initial=0.0))
            shrink = min(1.0, radius / size) if size > 0 else 1.0
            merit = rnorm + cerr
            accepted = None
            # after a cut the full step is the last backtrack of the search before it (x 1/8)
            for step in (0.5, 0.25, 0.125) if repeat else (1.0, 0.5, 0.25, 0.125):
                f = shrink * step
                q_try = q.copy()
                q_try[free] += f * dq
                lam_try = lam + f * dlam
                r_try, n_try, resp_try = self.residual(q_try, lam_try, dead_factor)
                c_try = constraint_error(q_try)
                if n_try + c_try < (1.0 - 1e-4 * f) * merit:
                    accepted = (q_try, lam_try, r_try, n_try, resp_try, c_try)
                    break
            if accepted is None and not here:  # a stale tangent: refactor before cutting
                lu = None
                continue
            if accepted is None:
                if not fresh:
                    # a search after a cut, with the tangent of this state: refactoring here
                    # would give the same matrix and the same failed search, so the radius is
                    # cut at once; that repeat still counts against the budget, which thus
                    # ends the same searches (a cut costs two iterations of it)
                    if it >= budget:
                        break
                    it += 1
                radius = min(radius, shrink * size) / 8.0
                cuts += 1
                exhausted = (
                    radius < RADIUS_FLOOR * self.problem.displacement_scale or cuts >= SEARCH_CUTS
                )
                if exhausted and regularise():
                    radius = max(4.0 * self.last_increment, self.search_seed)
                    continue
                if exhausted:
                    return Outcome(
                        False,
                        q,
                        lam,
                        response,
                        it,
                        f"no equilibrium found: no correction lowers the residual {rnorm:.2e}",
                        failure=Failure.NO_DESCENT,
                    )
                cut, direction = True, (dq, dlam)
                continue
            if step == 1.0 and shrink < 1.0:
                radius *= 2.0
            # keep the factorization (modified Newton) while a full step divides the residual
            # by CHORD_RATIO or more, and after a creep (a step too short to change the
            # tangent: under CREEP of the correction, no joint changing state); otherwise the
            # next iteration refactors
            crept = shrink * step < CREEP and np.array_equal(
                accepted[4].flags, response.flags
            )  # the same flags: the same states
            if not (crept or (step == 1.0 and shrink == 1.0 and accepted[3] < CHORD_RATIO * rnorm)):
                lu = None
            q, lam, residual, rnorm, response, cerr = accepted
            here = here and crept
            umax = self.increment(q)
            if not math.isfinite(umax) or umax > self.limit:
                return self._past_limit(q, lam, response, it)
            history.append((rnorm + cerr, radius))
            if len(history) > STALL_WINDOW:
                window = history[-1 - STALL_WINDOW :]
                steady = all(rad >= window[0][1] for _, rad in window)  # no cut in the window
                stalled = steady and history[-1][0] > (1.0 - STALL_DECREASE) * window[0][0]
            if len(history) > STALL_WINDOW and stalled and regularise():
                continue
            if len(history) > STALL_WINDOW and stalled:
                return Outcome(
                    False,
                    q,
                    lam,
                    response,
                    it,
                    f"no equilibrium found: the residual stalls at {rnorm:.2e} "
                    f"(displacement increment {umax:.2e} m)",
                    failure=Failure.STALL,
                )
        if rnorm <= s.tolerance and constraint_error(q) <= s.control_tolerance:
            self.last_increment = self.increment(q)
            return Outcome(True, q, lam, response, it)
        return Outcome(
            False,
            q,
            lam,
            response,
            it,
            f"no convergence in {it} iterations (residual {rnorm:.2e})",
            failure=Failure.NO_CONVERGENCE,
        )
