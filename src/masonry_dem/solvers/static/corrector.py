"""The equilibrium corrector: the state of a path, and Newton from its last converged state to
an equilibrium at a given lambda (load control) or at a given value of a controlled
displacement (lambda free).

* :meth:`Corrector.equilibrate` - Newton on the corrected actions with the consistent
  tangent, safeguarded by a trust region on the translations, a backtracking line search,
  chord steps while they converge fast and (under the dead load) a Levenberg-Marquardt
  floor;
* :meth:`Corrector.robust` - initial-stiffness iterations with Anderson acceleration.

The searches that follow a motion of the wall where Newton stops (pseudo-transient and
implicit relaxations, dynamic relaxation) are :mod:`~masonry_dem.solvers.static.relaxations`'.
Each returns an :class:`~masonry_dem.solvers.static.outcome.Outcome`: a converged state
is an exact equilibrium of the law at its lambda (whatever the safeguards did on the way);
a failed one carries a typed :class:`~masonry_dem.solvers.static.outcome.Failure`.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

import numpy as np

from masonry_dem.model import Model
from masonry_dem.solvers.factorization import Factors
from masonry_dem.solvers.static.outcome import Failure, Outcome
from masonry_dem.solvers.static.problem import DiscreteProblem
from masonry_dem.solvers.static.settings import StaticSettings

if TYPE_CHECKING:
    from masonry_dem.constitutive.law import LawResponse

log = logging.getLogger(__name__)


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
            tension=s.tension,
            memory=s.memory,
            tangent=s.tangent,
            residual_stiffness=s.residual_stiffness,
            displacement_limit=s.displacement_limit,
        )
        self.law = self.problem.law
        m = model.interfaces.count
        self.plastic = np.zeros((m, 6))
        self.cracked = np.zeros(m, dtype=bool)
        self.q = np.zeros(model.n_dofs)
        self.iterations = 0  # Newton (and pseudo-transient, robust) iterations
        self.time_steps = 0  # time steps of the dynamic relaxations the solver ran
        self.implicit_steps = 0  # steps of the implicit relaxations (corner checks) it ran
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
        ``trust_seed`` elastic units of the wall (:attr:`DiscreteProblem.displacement_scale`)."""
        return self.settings.trust_seed * self.problem.displacement_scale

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
            s.max_floor x kbar). A near-mechanism of the yielded assembly (a joint at zero gap
            beside a sliding one) leaves the tangent almost singular along a direction the
            residual needs; the undamped Newton step along it is huge, the trust region cuts
            it to nothing and the search stalls far from an equilibrium that exists. The
            floor changes only the search direction, never the residual, so a converged
            state is still an exact equilibrium of the law."""
            nonlocal floor, history, budget, lu, cuts
            if not damped or floor >= s.max_floor:
                return False
            assert radius is not None  # set above when not given
            floor = min(floor * 1e3, s.max_floor)
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
                    radius < s.radius_floor * self.problem.displacement_scale
                    or cuts >= s.search_cuts
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
            # by s.chord_ratio or more, and after a creep (a step too short to change the
            # tangent: under s.creep of the correction, no joint changing state); otherwise the
            # next iteration refactors
            crept = shrink * step < s.creep and np.array_equal(
                accepted[4].flags, response.flags
            )  # the same flags: the same states
            if not (
                crept or (step == 1.0 and shrink == 1.0 and accepted[3] < s.chord_ratio * rnorm)
            ):
                lu = None
            q, lam, residual, rnorm, response, cerr = accepted
            here = here and crept
            umax = self.increment(q)
            if not math.isfinite(umax) or umax > self.limit:
                return self._past_limit(q, lam, response, it)
            history.append((rnorm + cerr, radius))
            if len(history) > s.stall_window:
                window = history[-1 - s.stall_window :]
                steady = all(rad >= window[0][1] for _, rad in window)  # no cut in the window
                stalled = steady and history[-1][0] > (1.0 - s.stall_decrease) * window[0][0]
            if len(history) > s.stall_window and stalled and regularise():
                continue
            if len(history) > s.stall_window and stalled:
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

    def robust(
        self, load_factor: float, start: np.ndarray | None = None, budget: int | None = None
    ) -> Outcome:
        """Second strategy for a load step Newton could not solve: initial-stiffness
        iterations (the elastic matrix of the assembly, factorized once per analysis) with
        Anderson acceleration over the last ``anderson`` corrections, no line search, at most
        ``budget`` of them (None: ``zero_load_robust_iterations``).

        Newton stalls where the yielded tangent is nearly singular or flips between contact
        states of zero-gap joints; the fixed point of q <- q + K0^-1 R(q) does not depend on
        the tangent, so it converges (slowly, hence the larger budget) wherever an equilibrium
        is near. It gives up when the displacements pass the limit (a mechanism) or when the
        residual has not decreased by a tenth over ``divergence_window`` iterations while the
        corrections do not shrink (the iterates drift: no equilibrium)."""
        out = self._robust(load_factor, start, budget)
        log.debug("robust at lambda=%.6g: %s", load_factor, "ok" if out.ok else out.reason)
        return out

    def _robust(self, load_factor: float, start: np.ndarray | None, budget: int | None) -> Outcome:
        s = self.settings
        free = self.problem.asm.free_index
        lu = self.problem.elastic_factor()
        x = (self.q if start is None else start)[free].copy()
        q = self.q.copy()

        def g(xx):
            q[free] = xx
            r, n, resp = self.residual(q, load_factor)
            return lu.solve(r), n, resp

        f, rnorm, response = g(x)
        xs, fs = [x.copy()], [f.copy()]
        best = (rnorm, x.copy(), response)
        hist: list[tuple[float, float]] = []
        budget = s.zero_load_robust_iterations if budget is None else budget
        for it in range(1, budget + 1):
            self.iterations += 1
            if len(xs) > 1:
                dX = np.diff(np.array(xs), axis=0).T
                dF = np.diff(np.array(fs), axis=0).T
                gamma = np.linalg.lstsq(dF, f, rcond=1e-10)[0]
                x_new = x + f - (dX + dF) @ gamma
            else:
                x_new = x + f
            if not np.all(np.isfinite(x_new)):
                xs, fs = [x.copy()], [f.copy()]
                x_new = x + f
            x = x_new
            f, rnorm, response = g(x)
            xs.append(x.copy())
            fs.append(f.copy())
            if len(xs) > s.anderson + 1:
                xs.pop(0)
                fs.pop(0)
            if rnorm < best[0]:
                best = (rnorm, x.copy(), response)
            q_now = self.state_of(x)
            umax = self.increment(q_now)
            if rnorm <= s.tolerance:
                self.last_increment = umax
                return Outcome(True, q_now, load_factor, response, it)
            if not math.isfinite(umax) or umax > self.limit:
                return self._past_limit(q_now, load_factor, response, it)
            step = float(np.abs(f[self.problem.translation]).max(initial=0.0))
            hist.append((rnorm, step))
            if len(hist) > s.divergence_window:
                r0, s0 = hist[-1 - s.divergence_window]
                if best[0] > 0.1 * r0 and step >= s0:
                    return Outcome(
                        False,
                        q_now,
                        load_factor,
                        response,
                        it,
                        f"no equilibrium found: the robust iterations drift (residual "
                        f"{rnorm:.2e}, correction {step:.2e} m not shrinking)",
                        failure=Failure.DRIFT,
                    )
        q_best = self.state_of(best[1])
        return Outcome(
            False,
            q_best,
            load_factor,
            best[2],
            budget,
            f"no convergence in {budget} robust iterations (residual {best[0]:.2e})",
            failure=Failure.NO_CONVERGENCE,
        )
