"""The reference quasi-static analysis: a wall loaded slowly, with dashpots beside its
joints, moved by implicit time steps to rest after every small increment of load, up to the
first load at which it finds no rest. Slow, with no rule of its own about folds, corners or
stops: the judge of the path follower's answer (``benchmarks/agreement.py``).

The motion
----------
Each joint is a Kelvin-Voigt element: its elastic-plastic spring (the paper's law) beside a
dashpot of viscosity ``kbar x t_r`` (t_r, the unit of time, cancels), so the wall moves by

    K_e dq/dt = R(q, lambda) = F_D + lambda F_L - f(q),

K_e the elastic stiffness of the bonded assembly: an overdamped motion whose rests are the
equilibria of the wall. It is integrated by backward Euler, each step solved by Newton on

    G(q) = R(q, lambda) - K_e (q - q_n) / dt = 0,   (K_t + K_e / dt) dq = G,

with the law's state (plastic slip kept where the material's ``memory`` asks for it, joints
cracked in tension) carried from one time step to the next as an incremental law carries it.
This is the viscous stabilisation of Abaqus/Standard (``*STATIC, STABILIZE``) run to rest,
and the pseudo-transient continuation of Kelley & Keyes (1998, SIAM J. Numer. Anal. 35) with
a time step that follows the motion instead of the residual. The time step is set by the
local error of backward Euler (Hairer & Wanner, *Solving ODEs II*, IV.8): half the change of
the velocity over a step, within ``motion_tolerance`` elastic units of the wall plus that
fraction of the distance travelled since the last rest. A step never blows up: K_e / dt
keeps the matrix positive definite however the joints have yielded.

The selection rule
------------------
Loading is raised in increments of at most ``load_increment`` x lambda (and
``first_increment`` load scales while lambda is small), each held until the wall is at rest
again. A damped, slowly loaded wall follows the stable branch it is on; where that branch
ends (a limit point or a bifurcation), it moves, at the same load, to whichever rest the
damped motion reaches from there (a snap-through, after which loading goes on), or it runs
past the displacement limit: no rest. The collapse multiplier is the highest load at which
the wall rested, refined by halving the last increment from the last rest until the bracket
[rest, no rest] is within ``bracket_tolerance``.

A motion that spends ``max_time_steps`` at one load without a verdict ends the analysis
``failed``, saying so.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from masonry_dem._docstrings import SHARED, fill
from masonry_dem._threads import kernel_threads_for
from masonry_dem._validation import (
    at_least,
    check_fields,
    checked,
    count,
    is_number,
    positive,
    positive_or_none,
)
from masonry_dem.constitutive.law import LawResponse
from masonry_dem.model import Model
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.static.corrector import Corrector
from masonry_dem.solvers.static.outcome import Status, StopReason
from masonry_dem.solvers.static.problem import DiscreteProblem
from masonry_dem.solvers.static.settings import StaticSettings

log = logging.getLogger(__name__)

#: a factorized matrix is reused (a chord step) while each step divides the residual of the
#: time step by at least 1 / CHORD_RATIO (modified Newton, Kelley 1995, 5.3)
CHORD_RATIO = 0.25
#: after a time step whose Newton fails it is taken again this much shorter; the step after
#: it is not longer than the one before (no growth right after a rejection: Hairer & Wanner
#: 1996, IV.8, RADAU5's step control; CVODE's, Hindmarsh et al. 2005); and the following ones
#: stay below FAILED_CEILING x the shortest failed time step of the motion, a ceiling that
#: rises by CEILING_GROWTH with each accepted step. Without that memory a steady run-off
#: alternates an accepted step with a failed one 4x as long (each ~10 factorizations).
NEWTON_FAILURE_CUT = 0.25
FAILED_CEILING = 0.7
CEILING_GROWTH = 1.25
#: a time step's Newton stops once |G| <= NEWTON_FORCING x |R| (or the rest tolerance): the
#: dashpot force K_e (q - q_n) / dt = R - G is then right to 1 %, and so is the step, well
#: within its local error (the stopping test of implicit ODE codes solves the step's equation
#: to a fraction kappa ~ 0.01-0.1 of the local error tolerance, not to round-off: Hairer &
#: Wanner 1996, IV.8, (8.10)-(8.11); an inexact Newton's forcing term, Dembo, Eisenstat &
#: Steihaug 1982). A rest (|R| <= tolerance) is still an exact equilibrium of the law.
NEWTON_FORCING = 1e-2


@fill(SHARED)
@dataclass(frozen=True)
class QuasiStaticSettings:
    """How finely the reference analysis loads and moves the wall.

    A value out of range is refused at construction, by the field's name.

    Parameters
    ----------
    first_increment : float, default 0.01
        The load increment while lambda is small, in load scales ``|F_D| / |F_L|`` (1 for a tilt
        table), > 0.
    load_increment : float, default 0.02
        The largest load increment, relative to lambda (the loading rate), > 0.
    growth : float, default 1.5
        An increment after which the wall came to rest in a few time steps (an elastic or
        nearly elastic response) makes the next one this many times longer, up to the cap of
        ``load_increment``; >= 1.
    bracket_tolerance : float, default 1e-3
        The width of the collapse bracket, relative to lambda, > 0.
    tolerance : float, default 1e-8
        The force residual ``|R| / |F_D + lambda F_L|`` of a rest (moments as forces at the
        median block size), as the static solver's ``tolerance``; > 0.
    motion_tolerance : float, default 0.01
        The local error of a time step, in elastic units of the wall (its largest
        translation under the dead load) and as a fraction of the distance moved since the
        last rest; > 0.
    max_time_steps : int, default 20000
        Time steps at one load before the analysis gives up without a verdict, >= 1.
    max_newton : int, default 25
        Newton iterations of one time step before it is taken again half as long, >= 1.
    displacement_limit : float, optional
        A motion at one load that runs this far from the last rest [m] is a mechanism: no
        rest (None: half the smallest dimension of the moving blocks, as the static solver);
        under the dead load, from the unloaded wall, with the elastic displacement of the
        bonded wall under its weight added. The model is geometrically linear: an elastic
        deflection that grows with the load is no mechanism, however large (the collapse's
        reason says when the last rest lies past the limit).
    max_load_factor : float, default inf
        The analysis ends ``completed`` when lambda reaches it, > 0 (inf: no cap).
    newton_steps : bool, default False
        Each increment is first tried by the static solver's safeguarded Newton corrector
        from the last rest (:meth:`QuasiStatic.newton`), the damped motion running only
        where Newton does not converge, and the increments follow the iteration rule of
        Crisfield (1981): times (``target_iterations`` / I) ** 1/2 after a step of I
        iterations, within [1/2, ``growth``], up to ``max_step`` load scales and the loading
        rate of ``load_increment``, and never below ``bracket_tolerance`` x lambda. False
        (the reference): every increment by the damped motion.
    target_iterations : int, default 4
        The iteration rule's target, with ``newton_steps``; >= 1.
    max_step : float, default 1.0
        The iteration rule's largest increment (load scales), with ``newton_steps``; > 0.

    %(field_errors)s

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.QuasiStaticSettings(load_increment=0.05).bracket_tolerance
    0.001
    """

    first_increment: float = positive(0.01)
    load_increment: float = positive(0.02)
    growth: float = at_least(1.5, 1.0)
    bracket_tolerance: float = positive(1e-3)
    tolerance: float = positive(1e-8)
    motion_tolerance: float = positive(0.01)
    max_time_steps: int = count(20_000, least=1)
    max_newton: int = count(25, least=1)
    displacement_limit: float | None = positive_or_none()
    max_load_factor: float = checked(
        math.inf, lambda v: is_number(v) and v > 0, "a number > 0 (inf: no cap)"
    )

    newton_steps: bool = False
    target_iterations: int = count(4, least=1)
    max_step: float = positive(1.0)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass
class Motion:
    """The verdict of one load level: at rest (``rest``), or why not."""

    rest: bool
    time_steps: int
    reason: str = ""
    past_limit: bool = False
    undecided: bool = False  # neither a rest nor a run past the limit: no verdict
    #: where a motion past the displacement limit ended (its direction is the mechanism)
    end: np.ndarray | None = None
    #: the load factor at its end: the load of the motion, or, in a motion with a
    #: displacement held (``move_to_rest(held=...)``), the reaction it came to
    load_factor: float | None = None


class QuasiStatic:
    """The reference analysis of one model: the wall's state (q, plastic slip, cracked
    joints) at its last rest, and the damped motion that takes it to the next one."""

    def __init__(
        self,
        model: Model,
        settings: QuasiStaticSettings | None = None,
        problem: DiscreteProblem | None = None,
    ) -> None:
        if settings is not None and not isinstance(settings, QuasiStaticSettings):
            raise TypeError(
                f"settings must be a QuasiStaticSettings or None, got a {type(settings).__name__}"
            )
        self.model = model
        self.settings = settings or QuasiStaticSettings()
        # (``problem``: another analysis's of the same model and displacement limit, whose
        # assembly, factorizer and count of factorizations this one shares)
        self.problem = problem or DiscreteProblem(
            model, displacement_limit=self.settings.displacement_limit
        )
        self.law = self.problem.law
        m = model.interfaces.count
        self.q = np.zeros(model.n_dofs)
        self.plastic = np.zeros((m, 6))
        self.cracked = np.zeros(m, dtype=bool)
        self._corrector = Corrector(
            model,
            StaticSettings(
                tolerance=self.settings.tolerance,
                displacement_limit=self.settings.displacement_limit,
            ),
            problem=self.problem,
        )
        #: K_e: the dashpots' viscosity per unit of time (the bonded assembly's stiffness)
        self.viscosity = self.problem.tangent_assembler.matrix(self.problem.elastic_tangents())
        self.time_steps = 0
        #: factorizations of the whole analysis after which a motion gives no verdict (None:
        #: no budget but ``max_time_steps`` a motion)
        self.budget: int | None = None
        self.iterations = 0
        #: the law's response at the wall's state (None before the first rest)
        self.response: LawResponse | None = None
        #: the law state (plastic slip, cracked joints) the last rest was found with: the one
        #: carried to the time step before it, which under the incremental law is not the one
        #: the last rest before it stored
        self.found_with = (self.plastic, self.cracked)
        #: the lowest load with no rest and its motion, once the analysis has found it
        self.no_rest: tuple[float, Motion] | None = None
        #: the dead-load rest (None before it is found)
        self.origin: np.ndarray | None = None
        self._dt = 1.0  # the last time step taken, in units of the dashpots' relaxation time

    @property
    def factorizations(self) -> int:
        return self.problem.factorizations

    # ------------------------------------------------------------------ one time step
    def _time_step(
        self,
        q_n: np.ndarray,
        lam: float,
        dead: float,
        dt: float,
        start: np.ndarray,
        held: tuple[np.ndarray, float] | None = None,
    ) -> tuple[np.ndarray, LawResponse, float, float] | None:
        """Backward Euler from ``q_n`` over ``dt``: Newton on G(q) = 0 from ``start``, with a
        backtracking line search on |G|. (q, the law's response, the static residual |R|,
        lambda), or None when Newton does not converge. With ``held`` = (c over the free
        DOFs, value) c.q is held at the value (``start`` moved onto it along c) and lambda is
        free: the bordered Newton step of the static corrector, on the matrix of the time
        step."""
        s = self.settings
        free = self.problem.asm.free_index
        q = start.copy()
        rate = 1.0 / dt
        if held is not None:
            c, goal = held
            q[free] += (goal - float(c @ q[free])) / float(c @ c) * c

        def balance(qq: np.ndarray, ll: float) -> tuple[np.ndarray, float, LawResponse, float]:
            residual, rnorm, response = self.problem.residual(
                qq, ll, self.plastic, self.cracked, dead
            )
            g = residual - rate * (self.viscosity @ (qq[free] - q_n[free]))
            return g, self.problem.relative_norm(g, ll, dead), response, rnorm

        def solved(gn: float, rn: float) -> bool:
            """The stopping test (NEWTON_FORCING); a residual that overflowed solves nothing."""
            return math.isfinite(rn) and gn <= max(s.tolerance, NEWTON_FORCING * rn)

        g, gnorm, response, rnorm = balance(q, lam)
        factors = None  # the matrix factorized at an earlier iterate, kept while it converges
        live = np.zeros(0)  # the factorized matrix's response to the live load (held only)
        for _ in range(s.max_newton):
            if solved(gnorm, rnorm):
                return q, response, rnorm, lam
            self.iterations += 1
            chord = factors is not None
            if factors is None:
                factors = self.problem.factor(response, rate)
                if held is not None:
                    live = factors.solve(self.problem.F_live)
            dq = factors.solve(g)
            dlam = 0.0
            if held is not None:
                dlam = (goal - float(c @ q[free]) - float(c @ dq)) / float(c @ live)
                dq = dq + dlam * live
            if not np.all(np.isfinite(dq)) or not math.isfinite(dlam):
                return None
            if chord:  # a kept matrix: its step is taken only while it converges fast
                trial = q.copy()
                trial[free] += dq
                lam_t = lam + dlam
                g_t, n_t, resp_t, r_t = balance(trial, lam_t)
                if n_t > CHORD_RATIO * gnorm and not solved(n_t, r_t):
                    factors = None  # factor anew at q
                    continue
            else:  # Newton's step, backtracked until |G| falls
                length = 1.0
                for _cut in range(12):
                    trial = q.copy()
                    trial[free] += length * dq
                    lam_t = lam + length * dlam
                    g_t, n_t, resp_t, r_t = balance(trial, lam_t)
                    if n_t < gnorm or solved(n_t, r_t):
                        break
                    length *= 0.5
                else:
                    return None
            if n_t > CHORD_RATIO * gnorm:
                factors = None  # slow convergence: the next iteration factors
            q, g, gnorm, response, rnorm, lam = trial, g_t, n_t, resp_t, r_t, lam_t
        return (q, response, rnorm, lam) if solved(gnorm, rnorm) else None

    # ------------------------------------------------------------------ one load level
    def move_to_rest(
        self,
        lam: float,
        dead: float = 1.0,
        held: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Motion:
        """The damped motion from the last rest at load (``dead`` F_D + ``lam`` F_L) until it
        is at rest (the wall's state becomes that rest), runs past the displacement limit,
        or spends ``max_time_steps``.

        ``held`` = (c, start): the motion of a displacement-controlled test instead, the
        generalised displacement c.q of the free DOFs held at its value at ``start`` (the
        first time step's start, c.q moved there from the last rest as the test's machine
        moves it) and lambda free, the reaction of the held displacement; ``lam`` is where
        it starts. Its end: ``Motion.load_factor``."""
        s = self.settings
        free = self.problem.asm.free_index
        moving = self.problem.moving_translations
        unit = self.problem.displacement_scale
        weight = self.problem.displacement_weight
        # under the dead load, elastic shortening is no mechanism (a tall column shortens
        # by more than half a block under its own weight)
        limit = self.problem.limit + (unit if self.origin is None else 0.0)
        rest_q = self.q.copy()
        fixed = None if held is None else (held[0], float(held[0] @ held[1][free]))
        _, rnorm, response = self.problem.residual(self.q, lam, self.plastic, self.cracked, dead)
        if rnorm <= s.tolerance and held is None:
            self.response = response
            self.found_with = (self.plastic, self.cracked)
            return Motion(True, 0)
        q = self.q.copy()
        velocity = np.zeros_like(q)  # over the last step taken
        dt = self._dt
        taken = 0
        failed: float | None = None  # the ceiling's failed time step (None: none failed)
        rejected = False  # the last attempt was rejected: the next step is no longer
        for _ in range(s.max_time_steps):
            if self.budget is not None and self.factorizations >= self.budget:
                return Motion(
                    False,
                    taken,
                    f"the budget of {self.budget} factorizations is spent",
                    undecided=True,
                )
            if failed is not None:
                dt = min(dt, FAILED_CEILING * failed)
            # (the velocity predictor; retaking a failed step from q instead is no help: its
            # zero increment leaves the yielded joints' flags to round-off, and that Newton
            # fails at its first iteration)
            start = held[1] if held is not None and taken == 0 else q + velocity * dt
            stepped = self._time_step(q, lam, dead, dt, start, fixed)
            if stepped is None:
                failed = dt if failed is None else min(failed, dt)
                rejected = True
                dt *= NEWTON_FAILURE_CUT
                if dt < 1e-12:
                    return Motion(
                        False, taken, "no time step converges (dt < 1e-12)", undecided=True
                    )
                continue
            q_new, response, rnorm, lam_new = stepped
            new_velocity = (q_new - q) / dt
            # local error of backward Euler: dt^2 / 2 |q''| ~ dt / 2 |v_new - v_old|
            # (rotations as displacements at the median block size)
            change = 0.5 * dt * float(np.abs(weight * (new_velocity - velocity)[free]).max())
            moved = float(np.abs(weight * (q_new - rest_q)[free]).max())
            travelled = float(np.abs(q_new[moving] - rest_q[moving]).max(initial=0.0))
            allowed = s.motion_tolerance * (unit + moved)
            error = change / allowed
            if error > 1.0 and taken > 0:
                rejected = True
                dt *= max(0.2, 0.9 / math.sqrt(error))
                continue
            taken += 1
            self.time_steps += 1
            lam = lam_new
            if failed is not None:
                failed *= CEILING_GROWTH
            # the law's state moves with the wall: an incremental law, one time step at a time
            self.found_with = (self.plastic, self.cracked)
            self._carry(q_new, response)
            q, velocity = q_new, new_velocity
            if travelled > limit:
                return Motion(
                    False,
                    taken,
                    f"the wall ran {travelled:.3g} m from its last rest at this load, past "
                    f"the displacement limit {limit:.3g} m (a mechanism)",
                    past_limit=True,
                    end=q_new,
                    load_factor=lam,
                )
            if rnorm <= s.tolerance:
                self._dt = min(dt, 1.0)
                return Motion(True, taken, load_factor=lam)
            dt *= min(1.0 if rejected else 4.0, 0.9 / math.sqrt(max(error, 1e-12)))
            dt = min(dt, 1e15)
            rejected = False
        return Motion(
            False,
            taken,
            undecided=True,
            reason=f"no verdict in {s.max_time_steps} time steps at lambda {lam:.6g} "
            f"(residual {rnorm:.2e}, {float(np.abs(q[moving] - rest_q[moving]).max()):.3g} m "
            f"from the last rest)",
        )

    def newton(self, lam: float) -> int | None:
        """The static solver's safeguarded Newton corrector (a trust region on the
        translations, a line search, chord steps) from the last rest to an equilibrium at
        ``lam``: the iterations it took, the wall's state moved there; None where it finds
        none (the state is then left as it was)."""
        corrector = self._corrector
        corrector.q, corrector.plastic, corrector.cracked = self.q, self.plastic, self.cracked
        out = corrector.equilibrate(lam)
        self.iterations += out.iterations
        if not out.ok:
            return None
        moving = self.problem.moving_translations
        if np.abs(out.q[moving] - self.q[moving]).max(initial=0.0) > self.problem.limit:
            return None  # as far as a mechanism runs: the motion decides
        self._carry(out.q, out.response)
        return max(out.iterations, 1)

    def _carry(self, q: np.ndarray, response: LawResponse) -> None:
        """Make ``q`` the wall's state, the law's state (plastic slip, cracked joints)
        carried to it from the last one."""
        relative = np.asarray(self.problem.asm.H @ q).reshape(-1, 6)
        self.plastic = self.law.plastic_part(relative, response.actions)
        self.cracked = self.law.cracked_after(self.cracked, response)
        self.q = q
        self.response = response

    def moved_from_dead_load(self) -> float:
        """The largest translation of the wall's state from its dead-load rest (0 before
        that rest is found)."""
        if self.origin is None:
            return 0.0
        moving = self.problem.moving_translations
        return float(np.abs(self.q[moving] - self.origin[moving]).max(initial=0.0))

    def past_range(self) -> bool:
        """Does the wall's state lie past the small-displacement range (the displacement
        limit) from its dead-load rest?"""
        return self.moved_from_dead_load() > self.problem.limit

    def _range_note(self) -> str:
        """A note when the last rest lies past the displacement limit from the dead-load
        rest: an equilibrium of the geometrically linear model, outside its range."""
        if not self.past_range():
            return ""
        total = self.moved_from_dead_load()
        return (
            f", {total:.3g} m from the dead-load rest, past the small-displacement range "
            f"({self.problem.limit:.3g} m): joints this soft deflect beyond it before the wall "
            f"collapses"
        )

    def snapshot(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.q.copy(), self.plastic.copy(), self.cracked.copy()

    def restore(self, kept: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
        self.q, self.plastic, self.cracked = (a.copy() for a in kept)

    def _step_result(self, step: int, lam: float) -> StepResult:
        response = self.problem.residual(self.q, lam, self.plastic, self.cracked)[2]
        util = self.law.utilisation(response)
        return StepResult(
            step=step,
            load_factor=float(lam),
            q=self.q.reshape(-1, 6).copy(),
            actions=response.actions.copy(),
            state=response.state.astype(np.int32),
            utilisation=np.minimum(util, 1.0),
            flags=response.flags.astype(np.int32),
            control_displacement=float(np.abs(self.q.reshape(-1, 6)[:, :3]).max(initial=0.0)),
        )

    # ------------------------------------------------------------------ the analysis
    def run(self, callback: Callable[[StepResult], None] | None = None) -> History:
        """Dead load, then lambda raised slowly; one step of the History per rest."""
        with kernel_threads_for(self.model.interfaces.count):
            return self._run(callback)

    def _run(self, callback: Callable[[StepResult], None] | None) -> History:
        s = self.settings
        t0 = time.perf_counter()
        hist = History()

        def record(lam: float) -> None:
            step = self._step_result(len(hist.steps), lam)
            hist.steps.append(step)
            if callback is not None:
                callback(step)

        def finish(status: Status, stop: StopReason, reason: str) -> History:
            hist.end(status, stop, reason)
            hist.seconds = time.perf_counter() - t0
            hist.iterations = self.iterations
            hist.factorizations = self.factorizations
            log.info(
                "%s: reference %s at lambda %.6g after %d rests, %d time steps (%s)",
                self.model.name,
                hist.status,
                hist.final_load_factor,
                len(hist.steps),
                self.time_steps,
                reason,
            )
            return hist

        unloaded = self.snapshot()
        dead = self.move_to_rest(0.0)
        if not dead.rest:
            self.restore(unloaded)  # the History keeps rests only: the unloaded wall
            record(0.0)
            return finish(
                Status.FAILED,
                StopReason.DEAD_LOAD,
                f"the wall finds no rest under its dead load: {dead.reason}",
            )
        record(0.0)
        self.origin = self.q.copy()
        if not np.any(self.problem.F_live):
            return finish(Status.COMPLETED, StopReason.NO_LIVE_LOAD, "no live load")
        return self.raise_load(
            0.0, s.first_increment * self.problem.load_scale, hist, record, finish
        )

    def start_from(
        self,
        q: np.ndarray,
        plastic: np.ndarray,
        cracked: np.ndarray,
        origin: np.ndarray | None,
    ) -> None:
        """Make a state found by another method (a state of a pushover, its law state, and
        its dead-load rest ``origin``; None: the dead load is not carried yet) the wall's
        state, to move or load it from there."""
        self.q = np.asarray(q, dtype=float).reshape(-1).copy()
        self.plastic = np.asarray(plastic, dtype=float).copy()
        self.cracked = np.asarray(cracked, dtype=bool).copy()
        self.origin = None if origin is None else np.asarray(origin, dtype=float).reshape(-1).copy()
        self.no_rest = None

    def raise_load(
        self,
        lam: float,
        increment: float,
        hist: History,
        record: Callable[[float], None],
        finish: Callable[[Status, StopReason, str], History],
    ) -> History:
        """Raise the load from a rest at ``lam`` (the wall's state), the first increment
        ``increment``, recording each rest, up to the first load with no rest (bracketed
        by halving), ``max_load_factor``, or a motion with no verdict."""
        s = self.settings
        scale = self.problem.load_scale
        kept = self.snapshot()
        failed: tuple[float, Motion] | None = None  # the lowest load with no rest
        while True:
            target = min(lam + increment, s.max_load_factor)
            newton = self.newton(target) if s.newton_steps else None
            if newton is None:  # (a failed Newton search leaves the last rest as it was)
                motion = self.move_to_rest(target)
            else:
                motion = Motion(True, 0)
            if motion.rest:
                lam = target
                kept = self.snapshot()
                record(lam)
                if lam >= s.max_load_factor:
                    return finish(
                        Status.COMPLETED, StopReason.MAX_LOAD_FACTOR, "max_load_factor reached"
                    )

                # the loading rate; with newton_steps too, where Newton is only a faster way
                # to the next rest, so that the two are told apart by the rest reached alone
                rate = max(s.load_increment * lam, s.first_increment * scale)
                if failed is None and s.newton_steps:
                    if newton is not None:  # Crisfield's rule
                        factor = math.sqrt(s.target_iterations / max(newton, 1))
                        increment *= min(max(factor, 0.5), s.growth)
                    least = s.bracket_tolerance * lam
                    increment = min(max(increment, least), s.max_step * scale, rate)
                elif failed is None:
                    grown = increment * (s.growth if motion.time_steps <= 3 else 1.0)
                    increment = min(grown, rate)
            else:
                self.restore(kept)
                if motion.undecided:
                    hist.collapse_bracket = None
                    return finish(Status.FAILED, StopReason.MAX_STEPS, motion.reason)
                failed = (target, motion)
            if failed is not None:
                if failed[0] - lam <= s.bracket_tolerance * max(lam, 1e-300):
                    hist.collapse_bracket = (lam, failed[0])
                    self.no_rest = failed
                    return finish(
                        Status.COLLAPSE,
                        StopReason.NO_REST,
                        f"no rest at lambda {failed[0]:.6g} ({failed[1].reason}); at rest at "
                        f"{lam:.6g}{self._range_note()}",
                    )
                increment = 0.5 * (failed[0] - lam)


@fill(SHARED)
def quasi_static(
    model: Model,
    settings: QuasiStaticSettings | None = None,
    callback: Callable[[StepResult], None] | None = None,
) -> History:
    """The reference quasi-static analysis of ``model``.

    The wall, with dashpots beside its joints, is loaded slowly and moved to rest after every
    increment (see :mod:`masonry_dem.solvers.quasi_static`); the collapse multiplier is the
    highest load at which it rests.

    Parameters
    ----------
    model : Model
        The wall.
    settings : QuasiStaticSettings, optional
        How finely it is loaded and moved (None: the defaults).
    callback : callable, optional
        Called with each rest (a :class:`~masonry_dem.StepResult`) as it is found.

    Returns
    -------
    History
        The rests, the status (``collapse`` with the bracket of the last rest and the first
        load with no rest), the stop and its reason.

    Raises
    ------
    ValueError
        If ``model`` is not a :class:`~masonry_dem.Model`.

    Examples
    --------
    %(sliding_block)s
    >>> history = md.quasi_static(model)
    >>> print(history.status, round(history.collapse_multiplier, 3))
    collapse 0.6
    """
    return QuasiStatic(model, settings).run(callback)
