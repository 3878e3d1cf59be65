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
from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem._threads import kernel_threads_for
from masonry_dem.model import Model, Monitor
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.factorization import SingularMatrix
from masonry_dem.solvers.static import paths
from masonry_dem.solvers.static.certificate import NOT_CHECKED, ZERO_LOAD, Bound, certify
from masonry_dem.solvers.static.displacement_control import displacement_control
from masonry_dem.solvers.static.outcome import Outcome, Status, StopReason
from masonry_dem.solvers.static.relaxations import Relaxations
from masonry_dem.solvers.static.settings import DisplacementControl, StaticSettings
from masonry_dem.streamed_history import StreamedSteps, should_stream

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


class StaticSolver(Relaxations):
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

    # ------------------------------------------------------------------ states of the path
    def accept(self, out: Outcome, step: int, control_value: float) -> StepResult:
        """Make a converged search the last converged state, as a StepResult."""
        rel = self.problem.asm.relative_displacements(out.q)
        resp = out.response
        self.search_state = (self.plastic, self.cracked)
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
            if hist.status is Status.COLLAPSE and self.settings.certify and self.settings.refine:
                self._instability_rule(hist, record)
        else:
            assert monitor_dof is not None  # the control DOF, set above
            displacement_control(self, hist, record, control, monitor_dof)
        return self._finish(hist, t0)

    def _instability_rule(self, hist: History, record: Callable[[Outcome], None]) -> None:
        """The instability rule at the collapse the path reports (lambda_c): the damped
        motion of the reference analysis (:mod:`masonry_dem.solvers.quasi_static`) from the
        last converged state at lambda_c (1 + ``bracket_tolerance``). Running past the
        displacement limit, it confirms the collapse, and its direction is the mechanism.
        Coming to rest, it refutes it: the wall carries more than the path follower found,
        and the reference's load steps (Newton from each rest, the damped motion where
        Newton fails) go on from that rest to the first load with no rest."""
        from masonry_dem.solvers.quasi_static import QuasiStatic, QuasiStaticSettings

        s = self.settings
        lam_c = hist.collapse_multiplier
        assert lam_c is not None  # a collapse has its bracket
        judge = QuasiStatic(
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
        judge.budget = self.factorizations + JUDGE_FACTORIZATIONS
        judge.start_from(self.q, self.plastic, self.cracked, hist.steps[0].q)
        # (at least the smallest load the residual tells from zero: at a lower one, the
        # state the path stopped at is a rest to the tolerance)
        resolvable = ZERO_LOAD * s.tolerance * self.problem.load_scale
        target = max(lam_c * (1.0 + s.bracket_tolerance), lam_c + resolvable)
        motion = judge.move_to_rest(target)
        if motion.past_limit and motion.end is not None:
            self.run_off = motion.end - self.q
            self.instability = f"no rest at lambda {target:.6g}: {motion.reason}"
        elif motion.undecided:  # the certificate decides without it, and says so
            self.instability = f"no verdict at lambda {target:.6g}: {motion.reason}"
        else:
            log.info(
                "%s: the wall rests at lambda %.6g, above the collapse %.6g the path reported "
                ": the reference's load steps go on",
                self.model.name,
                target,
                lam_c,
            )
            refuted = (
                f"the path follower stopped at lambda {lam_c:.6g} ({hist.stop}), but the "
                f"wall rests at {target:.6g}, where the reference's load steps went on"
            )

            def rest(lam: float) -> None:
                assert judge.response is not None  # set at each rest
                record(Outcome(True, judge.q.copy(), lam, judge.response, 0))

            def finish(status: Status, stop: StopReason, reason: str) -> History:
                hist.end(status, stop, f"{reason}; {refuted}")
                if judge.no_rest is not None:  # the collapse the load steps found
                    lam_off, motion_off = judge.no_rest
                    if motion_off.end is not None:
                        self.run_off = motion_off.end - judge.q
                    self.instability = f"no rest at lambda {lam_off:.6g}: {motion_off.reason}"
                return hist

            rest(target)
            judge.raise_load(target, s.bracket_tolerance * target, hist, rest, finish)
        self.iterations += judge.iterations  # its factorizations are the problem's own

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
        if not dead.ok and self.settings.transient_steps > 0 and not dead.past_limit:
            # where the damped Newton search stalls (a wall with openings, blocks settling
            # on their neighbours), an overdamped relaxation may still come to rest: from
            # where Newton stopped (often a few pseudo time steps away), else from the start
            settled = None
            if np.all(np.isfinite(dead.q)):
                settled = self.pseudo_transient(0.0, start=dead.q)
            if settled is None or not settled.ok:
                settled = self.pseudo_transient(0.0)
            log.debug(
                "dead load: Newton %s; pseudo-transient: %s",
                dead.reason,
                "ok" if settled.ok else settled.reason,
            )
            dead = (
                settled
                if settled.ok
                else replace(dead, reason=f"{dead.reason}; pseudo-transient: {settled.reason}")
            )
        self._limit_allowance = 0.0  # from here displacements are measured from this state
        return dead

    def _dead_radius(self) -> float:
        """The trust radius of the dead-load search: 1000 elastic units of the wall (its
        first Newton step is about one), within the small-displacement range."""
        return min(self.limit, 1e3 * self.problem.displacement_scale)

    def _rests_at(self, lam: float) -> bool:
        """Does dynamic relaxation from the last converged state come to rest at ``lam``
        (within ``stop_check_time_steps``, at least 4000 time steps)?"""
        budget = max(self.settings.stop_check_time_steps, 4000)
        out = self.dynamic_rescue(lam, self.load_factor, budget, polish=False)
        return bool(out is not None and out.ok)

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
            )
            hist.certificate = cert
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
            "dynamic relaxation, %d implicit steps of corner checks (%s)",
            self.model.name,
            hist.status,
            len(hist.steps),
            self.iterations,
            self.factorizations,
            self.time_steps,
            self.implicit_steps,
            hist.reason,
        )
        return hist


def pushover(
    model: Model,
    settings: StaticSettings | None = None,
    control: DisplacementControl | None = None,
    out: str | Path | None = None,
    monitor: Monitor | None = None,
    write_every: int = 1,
    callback: Callable[[StepResult], None] | None = None,
    bound: Bound = None,
    stream: bool | str | Path | None = None,
) -> History:
    """Run the static incremental analysis; with ``out`` write VTU/PVD, pushover.csv and
    summary.json to that folder as the steps converge. ``callback(step)`` is called after
    each converged step (e.g. a progress bar); ``bound`` see :class:`StaticSolver`;
    ``stream`` (the History's steps on disk) see :meth:`StaticSolver.run`."""
    from masonry_dem.model import check_bound, require_model
    from masonry_dem.solvers.warmup import prepare

    require_model("pushover", model)
    check_bound(bound)
    prepare(model.interfaces.count)  # announced compilation of the kernels, on a cold cache
    writer = None
    if out is not None:
        from masonry_dem.export.writer import ResultsWriter

        writer = ResultsWriter(out, model, every=write_every, background=True)

    def on_step(step: StepResult) -> None:
        if writer is not None:
            writer(step)
        if callback is not None:
            callback(step)

    solver = StaticSolver(model, settings, bound=bound)
    with writer or nullcontext():  # the steps handed to the writer reach the disk
        history = solver.run(control=control, callback=on_step, monitor=monitor, stream=stream)
    if writer is not None:
        writer.finish(history)
    return history
