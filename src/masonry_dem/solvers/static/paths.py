"""Path followers of the static solver, sharing one corrector (:mod:`.corrector`) and one
step rule (:class:`StepController`):

* :func:`load_control` - lambda raised step by step; at its first failure it hands over
  to work control, or refines the bracket [last converged, first failed];
* :func:`work_control` - the work-conjugate displacement w = c.q of the live load
  prescribed (c = F_L / |F_L|, lambda free), past limit points and plastic plateaus, with
  a pseudo-transient step where the path folds at a kink of the law;
* displacement control (one DOF driven to a target, lambda free) lives in
  :mod:`.displacement_control`.

The step rule, the secant start and the elastic first step live in :mod:`.steps`.

Each sets the provisional ``hist.status``, ``hist.stop`` (a :class:`StopReason`) and
``hist.reason``; the solver then certifies a collapse before it reports one.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from masonry_dem.results import History
from masonry_dem.solvers.static.certificate import (
    ZERO_LOAD,
    curve_slope,
    moved_from_dead_load,
    still_rising,
)
from masonry_dem.solvers.static.outcome import Outcome, Status, StopReason
from masonry_dem.solvers.static.steps import (
    SecantPredictor,
    StepController,
    elastic_range,
    straight,
    tail_cap,
    transient_target,
)

if TYPE_CHECKING:
    from masonry_dem.solvers.static.solver import StaticSolver

log = logging.getLogger(__name__)

Record = Callable[[Outcome], None]


def load_control(solver: StaticSolver, hist: History, record: Record) -> None:
    s = solver.settings
    lam = 0.0
    dlam = s.initial_step * solver.problem.load_scale
    max_dlam = s.max_step * solver.problem.load_scale
    start: np.ndarray | None = None  # the elastic predictor of the first step
    if s.elastic_first_step:
        # the first step is the longer of initial_step and the elastic range: inside the
        # range the elastic predictor is the equilibrium, so a shorter step only creeps; a
        # range shorter than initial_step (a few joints yield first) says nothing of how far
        # Newton goes from there (docs/history/solvers_record.md, "Steps of the path: the elastic
        # first step"). It ends a bracket tolerance short of the range: at its very end a joint
        # sits on the edge of its domain (a joint of no tension at zero force), whose state
        # round-off decides, the worst start for the next search
        cap = min(max_dlam, s.max_load_factor)
        elastic = elastic_range(solver, cap)
        short = (1.0 - s.bracket_tolerance) * (elastic.load_factor if elastic else 0.0)
        if elastic is not None and short >= dlam:
            dlam = min(short, cap)
            start = solver.q.copy()
            start[solver.problem.free] += dlam * elastic.rate
            log.debug("the first live step: the elastic range, lambda=%.6g", dlam)
    lam_fail = math.inf
    failed_step = dlam
    last_reason = ""
    verified = False  # the first failure was re-tried from the end of the bracket
    hand_over = True  # work control takes over at the first failure (continuation="work")
    work_reason: tuple[str, StopReason] | None = None
    # max_steps counts converged steps, as the other path followers do: the failed attempts
    # of a bracket are bounded by its halvings down to the bracket tolerance
    while len(hist.steps) < s.max_steps:
        target = min(lam + dlam, s.max_load_factor)
        out = solver.equilibrate(target, start=start)
        start = None
        robust_ok = False
        # the robust re-try: the last resort of a bracket refined down to what the residual
        # cannot tell from zero load (where Newton stalls from the dead-load state: in-plane
        # walls held on one edge)
        near_zero = target <= ZERO_LOAD * s.tolerance * solver.problem.load_scale
        budget = s.zero_load_robust_iterations if near_zero else 0
        if not out.ok and budget > 0 and not out.past_limit:
            second = solver.robust(target, budget=budget)  # logs its outcome
            if second.ok:
                out, robust_ok = second, True
            else:
                out = replace(out, reason=f"{out.reason}; {second.reason}")
        if out.ok:
            record(out)
            lam = target
            if lam >= s.max_load_factor:
                hist.end(
                    Status.COMPLETED,
                    StopReason.MAX_LOAD_FACTOR,
                    f"reached max_load_factor {lam:.6g}",
                )
                return
            if lam >= lam_fail:  # the earlier failure came from a long step only
                log.debug("lambda=%.6g passed after an earlier failure", lam)
                lam_fail, verified = math.inf, False
                # the bracket's halvings came from a long step only: resume with half
                # the step that failed instead of creeping on at the bracket width
                dlam = max(dlam, min(failed_step / 2, max_dlam))
            if math.isfinite(lam_fail) and not verified and out.iterations <= s.easy_iterations:
                # an easy step inside a bracket opened by a longer step: the failure is
                # re-tried at once from here (a step too long fails no more from nearer,
                # and a limit fails again, which verifies it); halving the gap instead
                # creeps up on a step-length failure in ever shorter steps
                dlam = lam_fail - lam
            elif math.isfinite(lam_fail):
                dlam = (lam_fail - lam) / 2
            elif out.iterations <= s.easy_iterations or robust_ok:
                # the robust strategy copes with long steps: grow them after it too
                dlam = min(dlam * s.growth, max_dlam)
        else:
            last_reason = out.reason
            log.debug("step to lambda=%.6g failed: %s", target, out.reason)
            if target < lam_fail:
                if not math.isfinite(lam_fail):  # the step that opened this bracket
                    failed_step = target - lam
                lam_fail, verified = target, False
            elif target == lam_fail:
                verified = True
            if not s.refine:
                break
            if hand_over and s.continuation == "work" and _hands_over(hist):
                # work control follows the curve from here past any limit point, so
                # refining this bracket would only cost failing steps; if it finds
                # nothing higher, the bracket is refined after all (below)
                hand_over = False
                kept = solver.snapshot()
                hist.collapse_bracket = (lam, lam_fail)
                work_reason = work_control(solver, hist, record, first_failure=out.reason)
                if work_reason is None:
                    return
                log.debug(
                    "work control found nothing above lambda=%.6g (%s): refining "
                    "the load-control bracket",
                    lam,
                    work_reason[0],
                )
                solver.resume(kept)
                hist.collapse_bracket = None
            dlam = (lam_fail - lam) / 2
        if math.isfinite(lam_fail) and lam_fail - lam <= s.bracket_tolerance * max(
            abs(lam), 1e-12 * solver.problem.load_scale
        ):
            if verified:
                break
            dlam = lam_fail - lam  # re-try the first failure from the bracket's end
    else:
        hist.end(
            Status.FAILED,
            StopReason.MAX_STEPS,
            f"max_steps={s.max_steps} reached at lambda={lam:.6g}",
        )
        return
    hist.collapse_bracket = (lam, lam_fail)
    hist.end(
        Status.COLLAPSE,
        StopReason.LOAD_BRACKET,
        f"no equilibrium beyond lambda={lam:.6g} (first failure at {lam_fail:.6g}: {last_reason})",
    )
    if not s.refine:  # a long step may fail where a shorter one would not
        hist.reason += "; refine=False: the failed step was not cut, so this is an upper "
        hist.reason += "bracket of the first failure only, not a refined collapse load"
    if hand_over and s.continuation == "work" and _hands_over(hist):
        work_reason = work_control(solver, hist, record, first_failure=last_reason)
    if work_reason is not None:
        hist.reason += f"; work control found no higher equilibrium ({work_reason[0]})"


def _hands_over(hist: History) -> bool:
    """Work control takes over at the first failure of load control once the path has two
    live-load steps (the first is its elastic scale). An earlier failure is halved first:
    there it is far more often a step too long than a limit (the measurements are in
    docs/history/solvers_record.md, "Settings and their evidence"). A wall whose very first
    step finds its limit (a block that slides or lifts at once) ends in the refined
    bracket, which the certificate checks across its tolerance."""
    return len(hist.steps) > 2


def control_radius(solver: StaticSolver, c: np.ndarray, dw: float) -> float:
    """Trust radius for a controlled step: room for the requested increment."""
    return max(
        4.0 * solver.last_increment,
        solver.search_seed,
        4.0 * abs(dw) / max(float(np.abs(c).max()), 1e-300),
    )


def work_control(
    solver: StaticSolver, hist: History, record: Record, first_failure: str
) -> tuple[str, StopReason] | None:
    """Continue past the first failure of load control with lambda free and the
    work-conjugate displacement w = c . q (c = F_L / |F_L|) prescribed, from the last
    converged state. Returns None when the run is decided (a peak above the last
    load-control state, or ``max_steps`` / ``max_load_factor``), else why nothing
    higher was found and the stop it met (load control then refines its bracket).

    Load control fails where the pushover curve turns flat (a plastic plateau or a
    limit point); under work control the same equilibria are found with bounded
    increments. The curve is followed until one of: lambda at w has risen less than
    ``bracket_tolerance`` x lambda since w / 2 (w measured from the dead-load state);
    three steps in a row gain less than ``flat_slope`` of the elastic d(lambda) / d(w) (a
    formed mechanism, or creeping steps when Newton stalls at a kink); the step has been
    halved ``max_cuts`` times or below what the control tolerance can resolve, and a
    pseudo-transient step to lambda x (1 + transient_rise) finds no rest either
    (one is tried as soon as the step has been halved ``transient_after`` times in a
    row: a fold of the path, which no shorter step passes); the displacements pass the
    limit. The collapse multiplier is the highest lambda on the path. With
    ``tail_resolution`` each step is bounded by the load it can gain where the path may stop
    (:func:`.steps.tail_cap`)."""
    s = solver.settings
    free = solver.problem.asm.free_index
    c = solver.problem.F_live / float(np.linalg.norm(solver.problem.F_live))
    q0 = hist.steps[0].q.reshape(-1)[free]
    path_w = [float(c @ (st.q.reshape(-1)[free] - q0)) for st in hist.steps]
    path_lam = [float(st.load_factor) for st in hist.steps]
    w = path_w[-1]
    line = SecantPredictor(s.secant_predictor, [])
    for st, stw in zip(hist.steps[-2:], path_w[-2:], strict=False):
        line.add(stw, st.q.reshape(-1), float(st.load_factor))
    if len(path_w) > 1:
        # the first live-load step is elastic for walls that stand: its secant is the scale
        elastic_slope = (path_lam[1] - path_lam[0]) / max(path_w[1] - path_w[0], 1e-300)
        first = w - path_w[-2]
        first_w = path_w[1] - path_w[0]
    else:
        # the very first live-load step failed (a block that slides or lifts at once): the
        # scale is the tangent of the dead-load state, the first step half the failed one
        elastic_slope = _tangent_slope(solver)
        failed = hist.collapse_bracket[1] - path_lam[-1] if hist.collapse_bracket else 0.0
        first = 0.5 * failed / elastic_slope if elastic_slope > 0 else 0.0
        first_w = first
    step = StepController(
        max(first, 1e-3 * abs(w), s.radius_floor * solver.problem.displacement_scale),
        s.growth,
        easy_iterations=s.easy_iterations,
    )
    lam = path_lam[-1]
    first_lambda = hist.collapse_bracket[1] if hist.collapse_bracket else lam
    peak = max(path_lam)
    flat_steps = 0
    first_dw = step.size  # the scale of the steps after a fold (resume_step)
    uncut = step.size  # the step before the present run of halvings
    transient_from = -1  # the step from which the last pseudo-transient step started
    transient_failed = False
    reason = ""
    stop = StopReason.NONE
    checked_from = -1  # the step from which the last dynamic-relaxation check started
    last_fold: float | None = None  # lambda where the last failed search stopped
    fold_failed = False  # a pseudo-transient step past a fold found no rest
    # the lowest lambda toward which a motion from this branch of the path ran past the
    # displacement limit: no rest there or higher while the path stays on it
    ran_off = math.inf

    def transient(why: str, stopped: float, above: float | None = None) -> bool:
        """A pseudo-transient step to a lambda a little higher (or up to where the failed
        search ``stopped``, on a straight path: ``transient_target``; and past ``above``),
        once from each state."""
        nonlocal transient_from, ran_off
        transient_from = len(hist.steps)
        on_line = straight(path_w, path_lam, elastic_slope)
        target = transient_target(lam, stopped, s.transient_rise, s.transient_reach, on_line)
        if above is not None:  # just past a fold known to within s.fold_match
            target = max(target, above + s.fold_match * abs(above))
        if answered(target, "pseudo-transient step"):
            return False
        moved = solver.pseudo_transient(target)
        if moved.past_limit:
            ran_off = min(ran_off, target)
        log.debug(
            "work control stuck at lambda=%.6g (%s); pseudo-transient step to %.6g: %s",
            lam,
            why,
            target,
            f"ok in {moved.iterations}" if moved.ok else moved.reason,
        )
        if moved.ok:
            accept_moved(moved)
        return moved.ok

    def at_corner() -> bool:
        """Did the path's curve still rise into its last state (the corner check is on)? A
        path stuck there, or whose searches ran off from there, never ran along the
        mechanism its tangent, taken past the kink, may show: a fold or a peak. The slope
        is the secant of the last three steps, the span over which work control calls a
        curve flat: the halved steps that close in on a fold are as short as the control
        can tell, and one of them may lose a trace of load on the way (a joint that
        unloads) without the curve having turned."""
        span = slice(-4, None, 3) if len(path_w) >= 4 else slice(None)
        return (
            s.stop_check_time_steps > 0
            and s.fold_check_time_steps > 0
            and still_rising(curve_slope(path_w[span], path_lam[span], elastic_slope), s.flat_slope)
        )

    def answered(target: float, what: str) -> bool:
        """Has a motion from this branch already run past the displacement limit toward
        ``target`` or a lower lambda? Then the relaxation to
        ``target`` would be asked what that motion answered: no rest."""
        if target < ran_off:
            return False
        log.debug(
            "work control at lambda=%.6g: no %s to %.6g, a motion from this branch ran "
            "past the displacement limit toward %.6g",
            lam,
            what,
            target,
            ran_off,
        )
        return True

    def rest_above(budget: int, corner: bool = False) -> bool:
        """A relaxation looks for rest a little above the last state (once from each
        state), and the path goes on from there if it finds it. At a corner
        :meth:`Relaxations.implicit_relaxation` first: its motion running past the
        displacement limit is a peak; rest is a fold (the path goes on from dynamic
        relaxation's rest, if it finds one); its budget spent, dynamic relaxation decides.
        Elsewhere dynamic relaxation of ``budget`` time steps."""
        nonlocal checked_from
        checked_from = len(hist.steps)
        target = lam + s.transient_rise * abs(lam)
        if answered(target, "check"):
            return False
        rescued: Outcome | None
        if corner:
            moved = solver.implicit_relaxation(target)
            how = "implicit relaxation"
            verdict = f"ok in {moved.iterations} steps" if moved.ok else moved.reason
            settled: Outcome | None = None
            # dynamic relaxation runs at a fold (the path goes on from its rest: the implicit
            # motion may settle in another basin at the same lambda; for at most the check's
            # own effort) and where the implicit check gave no verdict (neither rest nor a
            # run-off within corner_check_steps: a slow fold, or a peak that creeps)
            if not moved.past_limit:
                settled = solver.dynamic_rescue(target, lam, rest_budget(budget, moved))
                verdict += "; dynamic relaxation: " + ("no rest" if settled is None else "ok")
            if settled is None and moved.ok:  # the path goes on from the implicit rest
                solver.last_increment = solver.increment(moved.q)
            rescued = settled if settled is not None else (moved if moved.ok else None)
        else:
            rescued = solver.dynamic_rescue(target, lam, budget)
            how, verdict = "dynamic relaxation", "ok" if rescued else "no rest"
        log.debug("work control stuck at lambda=%.6g; %s to %.6g: %s", lam, how, target, verdict)
        if rescued is not None:
            accept_moved(rescued)
        return rescued is not None

    def rest_budget(budget: int, moved: Outcome) -> int:
        """The time steps dynamic relaxation may take to find its own rest where the
        implicit check already came to rest: the check's own effort at the rate the two
        budgets are set by (``budget`` time steps for ``corner_check_steps`` implicit steps);
        all of ``budget`` where it gave no verdict."""
        if not moved.ok:
            return budget
        return max(1, min(budget, budget * moved.iterations // s.corner_check_steps))

    def accept_moved(moved: Outcome) -> None:
        """Go on from a state found at a higher lambda (not by a work step)."""
        nonlocal lam, w, peak, flat_steps, ran_off
        record(moved)
        ran_off = math.inf  # another branch: what ran off from the last one says nothing here
        lam = float(moved.load_factor)
        w = float(c @ (moved.q[free] - q0))
        path_w.append(w)
        path_lam.append(lam)
        line.restart(w, moved.q, lam)
        peak = max(peak, lam)
        # a fraction of the step before the fold's halvings, or of the first step when longer
        # (so that folds in a row, without growth in between, do not shrink the steps)
        resume = max(uncut, first_dw) * s.resume_step
        step.size, step.cuts, flat_steps = max(step.size, resume), 0, 0

    while len(hist.steps) < s.max_steps:
        if s.tail_resolution > 0:
            step.cap = tail_cap(
                lam,
                elastic_slope,
                s.flat_slope,
                s.tail_resolution,
                curve_slope(path_w, path_lam, elastic_slope),
                _to_limit(solver, hist, path_w),
            )
            step.size = min(step.size, step.cap)
        goal = w + step.size
        q_start, lam_start = line.start(goal)
        out = solver.equilibrate(
            lam if lam_start is None else lam_start,
            control=(c, goal + float(c @ q0), step.size),
            radius=control_radius(solver, c, step.size),
            start=q_start,
        )
        if not out.ok and not out.past_limit:
            # on a plateau the search may meet equilibria short of the goal (lambda is
            # free, so any converged state on the way is a point of the curve)
            reached = float(c @ (out.q[free] - q0))
            _, rnorm, response = solver.residual(out.q, out.load_factor)
            if rnorm <= s.tolerance and reached > w + 0.1 * step.size:
                out = replace(out, ok=True, response=response)
                goal = reached
        if not out.ok:
            log.debug("work step to w=%.6g failed: %s", goal, out.reason)
            if out.past_limit and step.cuts >= s.limit_cuts:
                # a corner too: the searches run off while the curve still rose into the
                # state (no state left the small-displacement range), so the wall may snap
                # through to rest higher up, as at a stuck corner
                if (
                    checked_from != len(hist.steps)
                    and at_corner()
                    and rest_above(s.fold_check_time_steps, corner=True)
                ):
                    transient_failed = False
                    continue
                # measured from the dead-load state, as the certificate measures it
                ran = moved_from_dead_load(solver.problem, hist, out.q)
                reason = (
                    f"a search from the state at lambda={lam:.6g} "
                    f"({moved_from_dead_load(solver.problem, hist, solver.q):.3g} m from the "
                    f"dead-load state) ran past the displacement limit {solver.limit:.3g} m "
                    f"(to {ran:.3g} m from the dead-load state; peak {peak:.6g})"
                )
                stop = StopReason.DISPLACEMENT_LIMIT
                break
            if step.cuts == 0:
                uncut = step.size
            step.cut()
            # a step below this cannot be told from no step (the control tolerance)
            tiny = 1e-4 * max(abs(w), first_w, 1e-4 * solver.problem.displacement_scale)
            stuck = step.cuts > s.max_cuts or step.size < tiny
            # the search stops where the one before it stopped: a fold of the path that
            # halved steps only close in on (each half converges, the next full step
            # fails there again), so the pseudo-transient step goes past it at once
            fold = float(out.load_factor)
            refold = (
                last_fold is not None
                and abs(fold - last_fold) <= s.fold_match * abs(lam)
                and not fold_failed
            )
            last_fold = fold
            if (
                (stuck or refold or (step.cuts == s.transient_after and not transient_failed))
                and s.transient_steps > 0
                and transient_from != len(hist.steps)
            ):
                # Newton stops at a fold of the path
                if transient(out.reason, fold, above=fold if refold else None):
                    continue
                if refold:
                    fold_failed = True
                else:
                    transient_failed = True
            # neither Newton nor the pseudo-transient step passes: before calling this a
            # collapse, let dynamic relaxation look for rest a little higher (where the
            # tangent is singular along the load only at a corner: a fold of the path has
            # that too, but so has a flat peak, and the check is dear)
            corner = stuck and at_corner()
            budget = max(s.stop_check_time_steps, s.fold_check_time_steps if corner else 0)
            if (
                stuck
                and s.stop_check_time_steps > 0
                and checked_from != len(hist.steps)
                and (corner or not _singular_along_load(solver, hist))
                and rest_above(budget, corner)
            ):
                transient_failed = False
                continue
            if stuck:
                reason = f"no equilibrium beyond lambda={lam:.6g} under work control ({out.reason})"
                if math.isfinite(ran_off):
                    reason += (
                        f"; no rest above it: a pseudo-transient motion from this branch ran "
                        f"past the displacement limit toward lambda={ran_off:.6g}"
                    )
                stop = StopReason.PATH_STUCK
                break
            continue
        if float(out.load_factor) > s.max_load_factor:
            # lambda is free under work control: the step passed the cap, so the last
            # state is found again by load control at the cap itself
            capped = solver.equilibrate(s.max_load_factor)
            if capped.ok:
                out = capped
        record(out)
        w, lam = goal, float(out.load_factor)
        if lam >= ran_off:  # the path found rest where the motion ran off: no verdict
            ran_off = math.inf
        line.add(w, out.q, lam)
        path_w.append(w)
        path_lam.append(lam)
        peak = max(peak, lam)
        if lam >= s.max_load_factor:
            hist.end(
                Status.COMPLETED, StopReason.MAX_LOAD_FACTOR, f"reached max_load_factor {lam:.6g}"
            )
            return None
        total = moved_from_dead_load(solver.problem, hist, out.q)
        if total > solver.limit:
            reason = (
                f"a mechanism: displacements {total:.3g} m exceed the limit "
                f"{solver.limit:.3g} m at lambda={lam:.6g}"
            )
            stop = StopReason.DISPLACEMENT_LIMIT
            break
        half = float(np.interp(w / 2, path_w, path_lam))
        if w > 0 and lam - half <= s.bracket_tolerance * abs(peak) and lam < peak + 1e-12:
            reason = (
                f"the pushover curve is flat: lambda rose {lam - half:.3g} while the "
                f"work-conjugate displacement doubled to {w:.3g} m (peak {peak:.6g})"
            )
            stop = StopReason.CURVE_FLAT
            break
        # a formed mechanism: the last steps gained (almost) nothing for their
        # displacement, compared with the elastic stiffness of the live load
        slope = (path_lam[-1] - path_lam[-2]) / max(path_w[-1] - path_w[-2], 1e-300)
        flat_steps = flat_steps + 1 if slope < s.flat_slope * elastic_slope else 0
        if flat_steps >= 3:
            tiny = path_w[-1] - path_w[-4] < 1e-3 * w
            reason = (
                f"no equilibrium beyond lambda={peak:.6g}: work control creeps "
                f"(w {path_w[-4]:.6g} -> {w:.6g} m in 3 steps)"
                if tiny
                else f"a mechanism: lambda gains {slope / elastic_slope:.1e} of the "
                f"elastic stiffness per unit displacement over 3 steps (peak {peak:.6g})"
            )
            stop = StopReason.CREEPING if tiny else StopReason.STIFFNESS_LOST
            break
        if step.cuts == 0:
            step.grow(out.iterations)
        step.cuts = 0
    else:
        hist.end(
            Status.FAILED,
            StopReason.MAX_STEPS,
            f"max_steps={s.max_steps} reached at lambda={lam:.6g}",
        )
        return None
    assert hist.collapse_bracket is not None  # set by the caller
    if peak <= hist.collapse_bracket[0]:
        return reason, stop
    hist.collapse_bracket = (peak, peak)
    hist.end(
        Status.COLLAPSE,
        stop,
        f"{reason}; load control first failed at {first_lambda:.6g} ({first_failure})",
    )
    return None


def _to_limit(solver: StaticSolver, hist: History, path_w: list[float]) -> float:
    """How far in w the displacement limit lies ahead, by the secant of the largest
    translation over the last two states (inf where it did not grow)."""
    if len(hist.steps) < 2 or path_w[-1] <= path_w[-2]:
        return math.inf
    last = moved_from_dead_load(solver.problem, hist, hist.steps[-1].q)
    rate = (last - moved_from_dead_load(solver.problem, hist, hist.steps[-2].q)) / (
        path_w[-1] - path_w[-2]
    )
    return (solver.limit - last) / rate if rate > 0 else math.inf


def _singular_along_load(solver: StaticSolver, hist: History) -> bool:
    """Is the tangent of the last converged state singular along the motion the live load
    drives (the certificate's rho at most ``mode_stiffness``)? A peak or a fold of the path:
    the dynamic-relaxation check is skipped there."""
    from masonry_dem.solvers.static.certificate import _dead_load_tangent, _rayleigh

    F = solver.problem.F_live
    _, _, response = solver.residual(solver.q, solver.load_factor)
    v = solver.problem.factor(response).solve(F)
    rho = _rayleigh(
        solver.problem, v, float(F @ v), _dead_load_tangent(solver.problem, hist, solver.settings)
    )
    return bool(rho <= solver.settings.mode_stiffness)


def _tangent_slope(solver: StaticSolver) -> float:
    """d lambda / d w along the tangent of the last converged state: |F_L| / F_L.K_t^-1 F_L."""
    F = solver.problem.F_live
    _, _, response = solver.residual(solver.q, solver.load_factor)
    compliance = float(F @ solver.problem.factor(response).solve(F))
    return float(np.linalg.norm(F)) / compliance if compliance > 0 else 0.0
