"""The searches that follow a motion of the wall, where Newton's corrections stop (at a fold
of the path, at kinks of the projection that no correction lowers the residual across):

* :meth:`Relaxations.pseudo_transient` - backward-Euler steps of an overdamped motion, which
  go round a fold of the path where no Newton correction lowers the residual;
* :meth:`Relaxations.implicit_relaxation` - implicit steps of the same motion that let the
  residual rise: the corner check, which tells a fold from a peak;
* :meth:`Relaxations.dynamic_rescue` - dynamic relaxation, polished by Newton.

Each starts from the :class:`~masonry_dem.solvers.static.corrector.Corrector`'s last
converged state and returns an :class:`~masonry_dem.solvers.static.outcome.Outcome`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Generator
from typing import TYPE_CHECKING

import numpy as np

from masonry_dem.model import Model
from masonry_dem.solvers.static.corrector import Corrector
from masonry_dem.solvers.static.outcome import Failure, Outcome
from masonry_dem.solvers.static.settings import StaticSettings

if TYPE_CHECKING:
    from masonry_dem.solvers.dynamic_relaxation import DynamicRelaxation, RelaxationStart

log = logging.getLogger(__name__)


class Relaxations(Corrector):
    """The corrector's state and Newton, with the relaxations that take over where Newton
    stops."""

    def __init__(self, model: Model, settings: StaticSettings | None = None) -> None:
        super().__init__(model, settings)
        self._dr: DynamicRelaxation | None = None  # kept while its budget is the same
        #: the last implicit check's motion, one row a step taken: (factorizations so far,
        #: largest translation from the start [m], residual), for benchmarks/creep_trace.py
        self.check_motion: list[tuple[int, float, float]] = []

    def pseudo_transient(self, target: float, start: np.ndarray | None = None) -> Outcome:
        """Pseudo-transient continuation to equilibrium at ``target`` from the last converged
        state (or from ``start``; displacements are measured from the last converged state): backward-Euler steps of the overdamped motion D dq/dt = R(q), with D the
        elastic stiffness of the joints (the floor of the tangent),

            (K_t + D / dt) dq = R(q),

        the pseudo time step dt grown as the residual falls (switched evolution relaxation,
        dt ~ 1 / |R|, grown faster while the residual falls) until the steps are Newton's.
        There is no line search: the residual may rise on the way.

        Work control stops where the equilibrium path folds at a kink of the law (a joint that
        changes state turns the path back in w, or a block between two sliding joints is left
        with almost no stiffness along a mode the load does not drive): no Newton correction
        lowers the residual from the last state, for any step. A damped motion goes round
        such a fold as dynamic relaxation does, to a stable equilibrium at the higher load,
        with few steps since each is implicit. Every accepted state meets the static
        tolerance on the exact residual. It fails when the displacements pass the limit
        (a mechanism), or the residual has not halved in ``transient_window`` steps, or the
        budget ``transient_steps`` runs out."""
        s = self.settings
        free = self.problem.asm.free_index
        q = (self.q if start is None else start).copy()
        residual, rnorm, response = self.residual(q, target)
        floor = s.transient_start
        best = [rnorm]
        for it in range(1, s.transient_steps + 1):
            if rnorm <= s.tolerance:
                self.last_increment = self.increment(q)
                return Outcome(True, q, target, response, it - 1)
            self.iterations += 1
            dq = self.problem.factor(response, floor).solve(residual)
            if not np.all(np.isfinite(dq)):
                floor = min(10.0 * floor, 1.0)
                continue
            size = float(np.abs(dq[self.problem.translation]).max(initial=0.0))
            if size > 0.1 * self.limit:  # no pseudo time step moves a block that far
                dq *= 0.1 * self.limit / size
            q_new = q.copy()
            q_new[free] += dq
            r_new, n_new, resp_new = self.residual(q_new, target)
            if not n_new < 10.0 * rnorm:
                if floor >= 1.0:
                    # the shortest time step fails: repeating it would factor the same
                    # matrix and fail the same way until the budget is spent
                    return Outcome(
                        False,
                        q,
                        target,
                        response,
                        it,
                        f"no rest: the shortest pseudo time step raises the residual "
                        f"{rnorm:.2e} to {n_new:.2e}",
                        failure=Failure.NO_REST,
                    )
                floor = min(10.0 * floor, 1.0)  # too long a time step: repeat it shorter
                continue
            ratio = n_new / rnorm
            q, residual, rnorm, response = q_new, r_new, n_new, resp_new
            if ratio < 1.0:
                ratio *= s.transient_shrink
            floor = min(max(floor * ratio, s.residual_stiffness), 1.0)
            umax = self.increment(q)
            if umax > self.limit:
                return self._past_limit(q, target, response, it)
            best.append(min(best[-1], rnorm))
            if len(best) > s.transient_window and best[-1] > 0.5 * best[-1 - s.transient_window]:
                return Outcome(
                    False,
                    q,
                    target,
                    response,
                    it,
                    f"no rest: the residual {rnorm:.2e} has not halved in "
                    f"{s.transient_window} pseudo time steps",
                    failure=Failure.NO_REST,
                )
        if rnorm <= s.tolerance:
            return Outcome(True, q, target, response, s.transient_steps)
        return Outcome(
            False,
            q,
            target,
            response,
            s.transient_steps,
            f"no rest in {s.transient_steps} pseudo time steps (residual {rnorm:.2e})",
            failure=Failure.NO_REST,
        )

    def implicit_relaxation(self, target: float, budget: int | None = None) -> Outcome:
        """The corner check's relaxation: from the last converged state to rest at
        ``target``, by linearly implicit Euler steps of the overdamped motion
        D dq/dt = R(q), D the joints' elastic stiffness (the tangent's floor),

            (K_t + D / dt) dq = R(q),

        one factorization a step, ``budget`` steps at most (``corner_check_steps``).

        What the check must resolve above a corner is the slow creep of a near-mechanism
        (a wall snapping through to the rest of a fold, or running off above a peak) beside
        the fast elastic modes: a stiff problem. Dynamic relaxation is explicit, its time
        step bounded by the stiffest joint, so the snap-through takes thousands of time
        steps; an implicit step damps the fast modes whatever its length. Unlike
        :meth:`pseudo_transient` (a step is refused when it raises the residual tenfold, and
        the search ends when the residual has not halved in ``transient_window`` steps),
        the residual is let rise: the wall is out of balance all the way to the rest above
        a fold, and a peak is told by its motion, not its residual. A step whose residual
        exceeds (1 + ``corner_check_rise``) times the last one's crossed kinks of the law
        its tangent did not see: it is taken again a quarter as long, down to the elastic
        relaxation time (D / dt = the elastic stiffness), which is always taken. After
        each step taken D / dt is halved (from ``corner_check_start``), so the steps grow
        to Newton's as the wall settles.

        Converged: the residual within ``tolerance`` at ``target`` (an equilibrium of the
        law, the path goes on from it: a fold). Failed: past the displacement limit
        (measured from the last converged state, as every search of the path), or no rest
        within the budget (a peak). A check: the trust radius of the path's searches is left
        as it was; the caller that goes on from its rest sets it."""
        motion = self.implicit_motion(target, budget)
        while (ended := _step(motion)) is None:
            pass
        return ended

    def implicit_motion(
        self, target: float, budget: int | None = None
    ) -> Generator[None, None, Outcome]:
        """:meth:`implicit_relaxation` as a resumable motion: yields after each
        factorization and returns its :class:`Outcome`."""
        s = self.settings
        budget = s.corner_check_steps if budget is None else budget
        free = self.problem.asm.free_index
        q = self.q.copy()
        residual, rnorm, response = self.residual(q, target)
        floor = s.corner_check_start
        self.check_motion = []
        for step in range(budget):
            if rnorm <= s.tolerance:
                return Outcome(True, q, target, response, step)
            self.iterations += 1
            self.implicit_steps += 1
            dq = self.problem.factor(response, floor).solve(residual)
            yield
            q_new = q.copy()
            q_new[free] += dq
            r_new, n_new, resp_new = self.residual(q_new, target)
            too_long = not (
                np.all(np.isfinite(dq)) and n_new <= (1.0 + s.corner_check_rise) * rnorm
            )
            if too_long and floor < 1.0:
                floor = min(4.0 * floor, 1.0)
                continue
            if not (np.all(np.isfinite(dq)) and math.isfinite(n_new)):
                return Outcome(
                    False,
                    q,
                    target,
                    response,
                    step + 1,
                    "the shortest implicit step has no finite residual",
                    failure=Failure.SINGULAR,
                )
            q, residual, rnorm, response = q_new, r_new, n_new, resp_new
            self.check_motion.append((step + 1, self.increment(q), rnorm))
            if self.check_motion[-1][1] > self.limit:
                return self._past_limit(q, target, response, step + 1)
            floor = max(0.5 * floor, s.residual_stiffness)
        if rnorm <= s.tolerance:
            return Outcome(True, q, target, response, budget)
        return Outcome(
            False,
            q,
            target,
            response,
            budget,
            f"no rest in {budget} implicit steps (residual {rnorm:.2e}, "
            f"{self.increment(q):.2e} m from the start)",
            failure=Failure.NO_REST,
        )

    def relaxation(self, budget: int) -> DynamicRelaxation:
        """The dynamic relaxation of this wall that a rescue or a stop check runs: the same
        law and displacement limit, ``budget`` time steps, stalled when its residual has not
        halved in a quarter of them."""
        from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation

        s = self.settings
        return DynamicRelaxation(
            self.model,
            DRSettings(
                tension=s.tension,
                memory=s.memory,
                tolerance=1e-6,
                max_cycles=budget,
                min_stall_window=budget // 4,
                displacement_limit=self.limit,
            ),
        )

    def _kept_relaxation(self, budget: int) -> DynamicRelaxation:
        """:meth:`relaxation` of ``budget`` time steps, kept while the budget is the same."""
        if self._dr is None or self._dr.settings.max_cycles != budget:
            self._dr = self.relaxation(budget)
        return self._dr

    def relaxation_start(self, last: float) -> RelaxationStart:
        """The state a dynamic relaxation starts from: the last converged one, at the load
        factor ``last``, at rest."""
        from masonry_dem.solvers.dynamic_relaxation import RelaxationStart

        free = self.problem.asm.free_index
        return RelaxationStart(
            self.q[free].copy(),
            self.plastic.copy(),
            self.cracked.copy(),
            last,
            np.ones((self.model.interfaces.count, 6)),
        )

    def newton_from(self, x: np.ndarray, target: float) -> Outcome:
        """Newton at ``target`` from a relaxation's state ``x``."""
        return self.equilibrate(target, start=self.state_of(x))

    def dynamic_rescue(
        self, target: float, last: float, budget: int, polish: bool = True
    ) -> Outcome | None:
        """Dynamic relaxation of ``budget`` time steps to ``target`` from the last converged
        state, then Newton from where it came to rest (so an accepted state meets the static
        tolerance). Newton stops at kinks of the projection (joints on the edge between two
        states) where no correction lowers the residual; the damped motion goes round them.
        ``polish=False``: only whether the relaxation came to rest (``ok``; the state
        returned is the last converged one). With ``fold_probe_every``, Newton is tried
        from the relaxation's states on the way (:meth:`Relaxation._relax`'s probe): Newton
        converges from states far short of the relaxation's own rest; with
        ``fold_creep_cos`` the motion along a converged creep is not damped between them
        (:meth:`Relaxation._relax`'s ``creep_cos``), so a wall snapping through to a fold's
        rest gets there in fewer time steps."""
        s = self.settings
        dr = self._kept_relaxation(budget)
        start = self.relaxation_start(last)
        # its displacement limit measured from the start state, as every search of the path
        # measures its step: from the unloaded wall a state already past the limit (a wall
        # whose path had moved that far) failed at the first time step
        found: list[Outcome] = []

        def probe(x: np.ndarray) -> bool:
            out = self.newton_from(x, target)
            if out.ok:
                found.append(out)
            return out.ok

        every = s.fold_probe_every if polish else 0
        relaxed = dr.relax_with_cuts(
            start,
            target,
            from_start=True,
            probe=probe if every else None,
            probe_every=every,
            creep_cos=s.fold_creep_cos if every else 0.0,
        )
        # time steps of an explicit relaxation are no Newton iterations (each costs a
        # residual, no factorization): counted apart, so that ``iterations`` compares paths
        self.time_steps += relaxed.cycles
        if not polish:
            return Outcome(relaxed.ok, self.q, target, self.residual(self.q, target)[2], 0)
        if not relaxed.ok:
            log.debug("dynamic rescue at lambda=%.6g failed: %s", target, relaxed.reason)
            return None
        if found:
            log.debug(
                "dynamic rescue at lambda=%.6g: Newton converged from the relaxation's state "
                "after %d time steps",
                target,
                relaxed.cycles,
            )
            return found[-1]
        polished = self.newton_from(relaxed.x, target)
        log.debug(
            "dynamic rescue at lambda=%.6g: %d time steps, Newton %s",
            target,
            relaxed.cycles,
            "ok" if polished.ok else polished.reason,
        )
        return polished if polished.ok else None


def _step(motion: Generator[None, None, Outcome]) -> Outcome | None:
    """One step of an implicit motion: None, or its outcome once it has ended."""
    try:
        next(motion)
    except StopIteration as done:
        return done.value
    return None
