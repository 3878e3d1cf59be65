"""The static solver (Section 2.3 of the paper): the dead load, then the live load raised
by a path follower (:mod:`.paths`), each equilibrium found by the corrector
(:mod:`.corrector`) on the discrete problem (:mod:`.problem`), and a stop of the path
reported as a collapse only with a certificate (:mod:`.certificate`).

Loads are F = F_D + lambda F_L. The collapse multiplier is the peak of the pushover curve
that the path followers trace (docs/solvers.md).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from masonry_dem._threads import kernel_threads_for
from masonry_dem.model import Model, Monitor
from masonry_dem.results import History, Observer, StepResult, observed
from masonry_dem.solvers.factorization import SingularMatrix
from masonry_dem.solvers.resources import should_stream
from masonry_dem.solvers.static import paths
from masonry_dem.solvers.static.certificate import (
    NOT_CHECKED,
    ZERO_LOAD,
    Bound,
    certify,
    moved_from_dead_load,
)
from masonry_dem.solvers.static.corrector import Corrector
from masonry_dem.solvers.static.displacement_control import displacement_control
from masonry_dem.solvers.static.outcome import Failure, Outcome, Status, StopReason
from masonry_dem.solvers.static.settings import DisplacementControl, StaticSettings
from masonry_dem.streamed_history import StreamedSteps

if TYPE_CHECKING:
    from masonry_dem.solvers.quasi_static import QuasiStatic

log = logging.getLogger(__name__)

#: the instability rule's damped motion: its local error in elastic units of the wall, and
#: Newton iterations of one of its time steps (the reference's are 0.01 and 25; these, with
#: the pushover's bracket, agree with it on the corpus of benchmarks/agreement.py)
JUDGE_MOTION_TOLERANCE = 0.05
JUDGE_NEWTON = 10
#: time steps of one motion, and factorizations of the whole rule, before it gives no
#: verdict (a motion that neither settles nor runs off: under the holonomic law, with no
#: potential, the damped flow need not settle). The rule's decisive motions on the corpus
#: of benchmarks/agreement.py took at most a few hundred time steps each, and the whole
#: rule at most 18 000 factorizations on a wall.
JUDGE_TIME_STEPS = 2000
JUDGE_FACTORIZATIONS = 20_000


class StaticSolver(Corrector):
    """Incremental-iterative solver for one model (keeps the assembly and the state).

    ``bound``: an upper bound of the collapse multiplier (the associative limit-analysis
    multiplier of the model, a number or a function of the model) that a certified collapse
    may not exceed; None: the certificate says the bound was not checked.
    """

    def __init__(
        self, model: Model, settings: StaticSettings | None = None, bound: Bound = None
    ) -> None:
        super().__init__(model, settings)
        self.bound = bound
        self.load_factor = 0.0  # lambda of the last converged state
        # the law state (plastic part, cracked joints) the last converged state was found with
        self.search_state = (self.plastic.copy(), self.cracked.copy())
        #: the instability rule's verdict on the collapse, and the direction of its motion
        #: past the displacement limit (from the rest it started from)
        self.instability = NOT_CHECKED
        self.run_off: np.ndarray | None = None
        self._judge: QuasiStatic | None = None
        self._dead_rest: np.ndarray | None = None  # the dead-load state, once found
        #: the step from which the path measures its displacement limit: the dead-load
        #: state, then each rest the instability rule finds past the limit
        self.limit_origin = 0
        #: the law state (plastic part, cracked joints) the run starts from: None, the
        #: unloaded wall's; a later loading stage's, carried (:meth:`start_from`)
        self.start_state: tuple[np.ndarray, np.ndarray] | None = None

    def start_from(self, q: np.ndarray, plastic: np.ndarray, cracked: np.ndarray) -> None:
        """Start the run from the state (q, plastic part, cracked joints) another run ended
        in (the stage before, :mod:`.stages`): the held DOFs of q stay where they are."""
        self.q = np.asarray(q, dtype=float).reshape(-1).copy()
        self.plastic = np.asarray(plastic, dtype=float).copy()
        self.cracked = np.asarray(cracked, dtype=bool).copy()
        self.search_state = (self.plastic.copy(), self.cracked.copy())
        self.start_state = (self.plastic.copy(), self.cracked.copy())

    # ------------------------------------------------------------------ states of the path
    def accept(self, out: Outcome, step: int, control_value: float) -> StepResult:
        """Make a converged search the last converged state, as a StepResult."""
        rel = self.problem.asm.relative_displacements(out.q)
        resp = out.response
        # a rest of the damped motion keeps the law state it was found with: its slip and
        # cracks moved with the wall, so the steps before it cannot rebuild them
        found_with = out.found_with
        self.search_state = found_with or (self.plastic, self.cracked)
        self.plastic = self.law.plastic_part(rel, resp.actions)
        self.cracked = self.law.cracked_after(self.cracked, resp)
        self.q = out.q
        self.load_factor = float(out.load_factor)
        return StepResult(
            step=step,
            load_factor=float(out.load_factor),
            q=out.q.reshape(-1, 6).copy(),
            actions=resp.actions.copy(),
            state=resp.state.astype(np.int32),
            utilisation=np.minimum(self.law.utilisation(resp), 1.0),
            flags=resp.flags.astype(np.int32),
            control_displacement=float(control_value),
            iterations=out.iterations,
            found_plastic=None if found_with is None else found_with[0],
            found_cracked=None if found_with is None else found_with[1],
        )

    def snapshot(self) -> tuple[Any, ...]:
        """The last converged state, to go back to (:meth:`resume`)."""
        return (
            self.q.copy(),
            self.plastic.copy(),
            self.cracked.copy(),
            self.last_increment,
            self.load_factor,
            self.search_state,
        )

    def resume(self, kept: tuple[Any, ...]) -> None:
        (
            self.q,
            self.plastic,
            self.cracked,
            self.last_increment,
            self.load_factor,
            self.search_state,
        ) = kept

    def _control_value(self, q: np.ndarray, control_dof: int | None) -> float:
        if control_dof is None:
            return float(np.abs(q.reshape(-1, 6)[:, :3]).max(initial=0.0))
        return float(q[control_dof])

    # ------------------------------------------------------------------ the instability rule
    def judge(self) -> QuasiStatic:
        """The reference analysis's damped motion on this solver's discrete problem (its
        assembly, factorizer and count of factorizations), at the path's state."""
        if self._judge is None:
            # (the reference module imports this package's corrector: imported here)
            from masonry_dem.solvers.quasi_static import QuasiStatic, QuasiStaticSettings

            s = self.settings
            self._judge = QuasiStatic(
                self.model,
                QuasiStaticSettings(
                    newton_steps=True,
                    motion_tolerance=JUDGE_MOTION_TOLERANCE,
                    max_newton=JUDGE_NEWTON,
                    max_time_steps=JUDGE_TIME_STEPS,
                    tolerance=s.tolerance,
                    bracket_tolerance=s.bracket_tolerance,
                    displacement_limit=s.displacement_limit,
                    max_load_factor=s.max_load_factor,
                ),
                problem=self.problem,
            )
            # one budget for the rule's motions of the whole run
            self._judge.budget = self.factorizations + JUDGE_FACTORIZATIONS
        judge = self._judge
        judge.start_from(self.q, self.plastic, self.cracked, self._dead_rest)
        return judge

    def damped_motion(
        self,
        target: float,
        dead: float = 1.0,
        held: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Outcome:
        """The instability rule where Newton finds no equilibrium: the reference's damped
        motion (:meth:`QuasiStatic.move_to_rest`) from the last converged state at load
        (``dead`` F_D + ``target`` F_L). An equilibrium where it comes to rest; else why
        not, failing with ``Failure.DISPLACEMENT_LIMIT`` where it ran past the limit (the
        wall has no rest there) and ``Failure.NO_REST`` where it gave no verdict. With
        ``held`` = (c, start) the motion of a displacement-controlled test: c.q held at its
        value at ``start``, lambda (from ``target``) free, its rest's lambda the reaction."""
        judge = self.judge()
        if held is not None:
            # a held motion is a step of displacement control's path (max_steps bounds
            # them), not a verdict of the rule: each has the rule's whole budget, else a
            # long push spends the run's on its folds and then creeps in halved steps
            judge.budget = self.factorizations + JUDGE_FACTORIZATIONS
        before = judge.iterations
        motion = judge.move_to_rest(target, dead, held)
        if motion.load_factor is not None:
            target = motion.load_factor
        self.iterations += judge.iterations - before
        self.time_steps += motion.time_steps
        if motion.rest:
            assert judge.response is not None  # set at each rest
            self.last_increment = self.increment(judge.q)
            plastic, cracked = judge.found_with
            return Outcome(
                True,
                judge.q.copy(),
                target,
                judge.response,
                motion.time_steps,
                found_with=(plastic.copy(), cracked.copy()),
            )
        q = judge.q if motion.end is None else motion.end
        _, _, response = self.residual(q, target, dead)
        failure = Failure.DISPLACEMENT_LIMIT if motion.past_limit else Failure.NO_REST
        return Outcome(False, q.copy(), target, response, motion.time_steps, motion.reason, failure)

    # ------------------------------------------------------------------ analyses
    def run(
        self,
        control: DisplacementControl | None = None,
        callback: Callable[[StepResult], None] | None = None,
        monitor: Monitor | None = None,
        stream: bool | str | Path | None = None,
    ) -> History:
        """Dead load, then lambda raised (load control) or a DOF driven (displacement control).

        ``monitor`` = (block, dof name) picks the displacement stored on the pushover curve
        (default: the largest block translation). ``stream``: keep the History's steps on
        disk (:mod:`masonry_dem.streamed_history`): a folder, True (a temporary folder),
        False (in memory), None (on disk when the History would not fit in a quarter of
        the available memory).
        """
        if stream is None:
            stream = should_stream(self.model.blocks.count, self.model.interfaces.count)
        hist = History()
        if stream is not False:
            steps = StreamedSteps(None if stream is True else Path(stream))
            hist = History(steps=steps)
            log.info("%s: the History's steps go to %s", self.model.name, steps.folder)
        with kernel_threads_for(self.model.interfaces.count):
            try:
                return self._run(hist, control, callback, monitor)
            except SingularMatrix as exc:  # the steps recorded so far are kept
                hist.end(
                    Status.FAILED,
                    StopReason.SINGULAR_TANGENT,
                    f"the tangent stiffness cannot be factored, even with a stiffened floor "
                    f"({exc}): joint stiffnesses (kn, kt) many decades apart, or a wall "
                    f"with no stiffness along some mode",
                )
                return hist

    def _run(
        self,
        hist: History,
        control: DisplacementControl | None,
        callback: Callable[[StepResult], None] | None,
        monitor: Monitor | None,
    ) -> History:
        t0 = time.perf_counter()
        monitor_dof = None
        if monitor is not None:
            monitor_dof = self.model.dof_index(*monitor)
        if control is not None:
            monitor_dof = self.model.dof_index(control.block, control.dof)

        def record(out: Outcome) -> None:
            sr = self.accept(out, len(hist.steps), self._control_value(out.q, monitor_dof))
            hist.steps.append(sr)
            if callback is not None:
                callback(sr)

        dead = self.dead_load()
        if not dead.ok:
            reason = f"no equilibrium under the dead load: {dead.reason}"
            zero = self.residual(np.zeros_like(self.q), 0.0, 0.0)[2]
            record(Outcome(True, np.zeros_like(self.q), 0.0, zero, dead.iterations))
            hist.end(Status.FAILED, StopReason.DEAD_LOAD, reason)
            return self._finish(hist, t0)
        record(dead)
        if not np.any(self.problem.F_live):
            hist.end(
                Status.COMPLETED,
                StopReason.NO_LIVE_LOAD,
                "no live load: the dead-load state is the answer",
            )
            return self._finish(hist, t0)
        if control is None:
            paths.load_control(self, hist, record)
            if self.settings.certify and self.settings.refine:
                self._instability_rule(hist, record)
        else:
            assert monitor_dof is not None  # the control DOF, set above
            displacement_control(self, hist, record, control, monitor_dof)
        return self._finish(hist, t0)

    def rule_at(self, top: float) -> Outcome:
        """The instability rule at a stop of the path whose highest lambda is ``top``: the
        damped motion from the last converged state at ``top`` (1 + ``bracket_tolerance``)
        (at least the smallest load the residual tells from zero above it). Its verdict is
        kept for the certificate: no rest (the motion ran past the displacement limit, its
        direction the mechanism), no verdict, or rest (the returned equilibrium, from which
        the path goes on)."""
        s = self.settings
        resolvable = ZERO_LOAD * s.tolerance * self.problem.load_scale
        target = max(top * (1.0 + s.bracket_tolerance), top + resolvable)
        moved = self.damped_motion(target)
        self.run_off = None
        if moved.ok:
            self.instability = NOT_CHECKED
            log.debug("%s: at rest at lambda %.6g, above the stop", self.model.name, target)
        elif moved.past_limit:
            self.run_off = moved.q - self.q
            self.instability = f"no rest at lambda {target:.6g}: {moved.reason}"
        else:  # the certificate decides without it, and says so
            self.instability = f"no verdict at lambda {target:.6g}: {moved.reason}"
        return moved

    def _instability_rule(self, hist: History, record: Callable[[Outcome], None]) -> None:
        """The instability rule at a collapse the path reports (lambda_c) where it has not
        run yet (a refined load-control bracket): :meth:`rule_at` lambda_c. Coming to rest,
        it refutes the collapse: load control goes on from that rest (and work control, which
        applies the rule at each of its own stops)."""
        first: tuple[float, StopReason, str] | None = None
        while (
            hist.status is Status.COLLAPSE
            and self.instability == NOT_CHECKED
            and hist.stop is not StopReason.DISPLACEMENT_LIMIT
        ):
            lam_c = hist.collapse_multiplier
            assert lam_c is not None  # a collapse has its bracket
            moved = self.rule_at(lam_c)
            if not moved.ok:
                break
            first = first or (lam_c, hist.stop, hist.reason)
            record(moved)
            hist.collapse_bracket = None
            paths.load_control(self, hist, record, resume=True)
        if first is not None:
            lam_c, stop, refuted = first
            hist.reason += (
                f"; the path follower had stopped at lambda {lam_c:.6g} ({stop}: {refuted})"
            )

    def dead_load(self) -> Outcome:
        """The equilibrium under the dead load (the specimens stood: the damped fallback
        may be used). Elastic displacement is no mechanism: where the search passes the
        displacement limit, the limit is widened by the displacement of the bonded assembly
        under the dead load and the search repeated (a tall column shortens by more than
        half a block under its own weight)."""
        dead = self.equilibrate(0.0, 1.0, radius=self._dead_radius(), damped=True)
        if dead.past_limit:
            elastic = self.problem.elastic_displacement(self.problem.F_dead)
            if np.isfinite(elastic) and elastic > 0:
                self._limit_allowance = elastic
                log.debug("dead load: the limit widened by the elastic %.3g m", elastic)
                dead = self.equilibrate(0.0, 1.0, radius=self._dead_radius(), damped=True)
        if not dead.ok and not dead.past_limit:
            # where the damped Newton search stalls (a wall with openings, blocks settling
            # on their neighbours), the instability rule decides: the damped motion from the
            # unloaded wall, to rest or past the displacement limit
            settled = self.damped_motion(0.0)
            log.debug(
                "dead load: Newton %s; damped motion: %s",
                dead.reason,
                "at rest" if settled.ok else settled.reason,
            )
            dead = (
                settled
                if settled.ok
                else replace(dead, reason=f"{dead.reason}; damped motion: {settled.reason}")
            )
        self._limit_allowance = 0.0  # from here displacements are measured from this state
        if dead.ok:
            self._dead_rest = dead.q.copy()
        return dead

    def _dead_radius(self) -> float:
        """The trust radius of the dead-load search: 1000 elastic units of the wall (its
        first Newton step is about one), within the small-displacement range."""
        return min(self.limit, 1e3 * self.problem.displacement_scale)

    def _rests_at(self, lam: float) -> bool:
        """Does the damped motion from the last converged state come to rest at ``lam``?"""
        return self.damped_motion(lam).ok

    def _range_note(self, hist: History) -> str:
        """A note when the collapse state lies past the small-displacement range from the
        dead-load state: the path went on from the instability rule's rests there."""
        moved = moved_from_dead_load(self.problem, hist, hist.steps[-1].q)
        if moved <= self.limit:
            return ""
        return (
            f"; the collapse state is {moved:.3g} m from the dead-load state, past the "
            f"small-displacement range ({self.limit:.3g} m): joints this soft deflect beyond "
            f"it before the wall collapses (the multiplier does not depend on the scale of "
            f"kn and kt; the deflection does)"
        )

    def _finish(self, hist: History, t0: float) -> History:
        if hist.status is Status.COLLAPSE and self.settings.certify:
            cert = certify(
                self.problem,
                hist,
                self.settings,
                self.bound,
                self._rests_at,
                run_off=self.run_off,
                instability=self.instability,
                start=self.start_state,
            )
            hist.certificate = cert
            if cert.holds:
                hist.reason += self._range_note(hist)
            if not cert.holds:
                hist.status = Status.FAILED
                hist.collapse_bracket = None  # a failed run has no collapse multiplier
                hist.reason = f"{hist.reason}; not a certified collapse: {cert.reason}"
                log.warning(
                    "%s: the stop is not a certified collapse: %s", self.model.name, cert.reason
                )
        hist.seconds = time.perf_counter() - t0
        hist.iterations = self.iterations
        hist.factorizations = self.factorizations
        log.info(
            "%s: %s after %d steps, %d Newton iterations, %d factorizations, %d time steps of "
            "damped motion (%s)",
            self.model.name,
            hist.status,
            len(hist.steps),
            self.iterations,
            self.factorizations,
            self.time_steps,
            hist.reason,
        )
        return hist


def pushover(
    model: Model,
    settings: StaticSettings | None = None,
    control: DisplacementControl | None = None,
    monitor: Monitor | None = None,
    callback: Callable[[StepResult], None] | None = None,
    bound: Bound = None,
    stream: bool | str | Path | None = None,
    observer: Observer | None = None,
) -> History:
    """Run the static incremental analysis. ``callback(step)`` is called after each
    converged step (e.g. a progress bar); ``observer`` follows the run
    (:class:`~masonry_dem.results.Observer`: a results writer); ``bound`` see
    :class:`StaticSolver`; ``stream`` (the History's steps on disk) see
    :meth:`StaticSolver.run`. ``masonry_dem.pushover`` is this with ``out``, a results
    folder."""
    from masonry_dem.model import check_bound, require_model
    from masonry_dem.solvers.warmup import prepare

    require_model("pushover", model)
    check_bound(bound)
    prepare(model.interfaces.count)  # announced compilation of the kernels, on a cold cache
    solver = StaticSolver(model, settings, bound=bound)
    return observed(
        lambda on_step: solver.run(
            control=control, callback=on_step, monitor=monitor, stream=stream
        ),
        observer,
        callback,
    )
