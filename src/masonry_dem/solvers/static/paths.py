"""Path followers of the static solver, sharing one corrector (:mod:`.corrector`) and one
step rule (:class:`StepController`):

* :func:`load_control` - lambda raised step by step; at its first failure it hands over
  to work control, or refines the bracket [last converged, first failed];
* :func:`work_control` - the work-conjugate displacement w = c.q of the live load
  prescribed (c = F_L / |F_L|, lambda free) along plastic plateaus, up to the first limit
  point, with the instability rule (the damped motion of :mod:`..quasi_static`) where
  Newton finds no equilibrium;
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
    moved_from,
    moved_from_dead_load,
)
from masonry_dem.solvers.static.corrector import RADIUS_FLOOR
from masonry_dem.solvers.static.outcome import Outcome, Status, StopReason
from masonry_dem.solvers.static.steps import (
    SecantPredictor,
    StepController,
    elastic_range,
    tail_cap,
)

if TYPE_CHECKING:
    from masonry_dem.solvers.static.path_solver import PathSolver

log = logging.getLogger(__name__)

#: work control is stuck after this many halvings of its step in a row (a step 1e-3 of the
#: one that failed first: shorter steps only close in on a fold)
MAX_CUTS = 10
#: a work step whose searches pass the displacement limit is a mechanism only when they
#: do so again after this many halvings in a row (a long first step may run off along a mode
#: the load does not drive yet)
LIMIT_CUTS = 2

Record = Callable[[Outcome], None]


#: what work control returns when the instability rule found the wall at rest above a stop
#: where the curve had turned flat or fallen: load control goes on from that rest
RESUMED = ("resumed", StopReason.NONE)


def _out_of_steps(hist: History, max_steps: int, lam: float) -> None:
    """End the path as failed: ``max_steps`` converged steps and no stop, at lambda ``lam``."""
    hist.end(
        Status.FAILED, StopReason.MAX_STEPS, f"max_steps={max_steps} reached at lambda={lam:.6g}"
    )


def load_control(solver: PathSolver, hist: History, record: Record, resume: bool = False) -> None:
    """Load control from the dead-load state (or, ``resume``, from the last converged state, a
    rest the instability rule found), handing over to work control at its first failure,
    and again from each rest the rule finds above a stop of work control."""
    while _load_control(solver, hist, record, resume) is RESUMED:
        resume = True


def _load_control(
    solver: PathSolver, hist: History, record: Record, resume: bool
) -> tuple[str, StopReason] | None:
    s = solver.settings
    lam = solver.load_factor if resume else 0.0
    # the smallest load the residual tells from zero
    resolvable = ZERO_LOAD * s.tolerance * solver.problem.load_scale
    dlam = s.initial_step * solver.problem.load_scale
    if resume:  # the rule's rest is a bracket above the stop: twice that to begin with
        dlam = max(2.0 * s.bracket_tolerance * abs(lam), resolvable)
    max_dlam = s.max_step * solver.problem.load_scale
    start: np.ndarray | None = None  # the elastic predictor of the first step
    if s.elastic_first_step and not resume:
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
        if not out.ok and not out.past_limit and target <= resolvable:
            # Newton stalls from the dead-load state of in-plane walls held on one edge,
            # at loads the residual cannot tell from zero: the instability rule decides
            second = solver.damped_motion(target)
            out = second if second.ok else replace(out, reason=f"{out.reason}; {second.reason}")
        if out.ok:
            record(out)
            lam = target
            if unstable(solver, out):
                # the wall leaves an unstable equilibrium: the instability rule decides
                moved = solver.rule_at(lam)
                if not moved.ok:
                    hist.collapse_bracket = (lam, float(moved.load_factor))
                    hist.end(
                        Status.COLLAPSE,
                        StopReason.UNSTABLE,
                        f"an unstable equilibrium at lambda={lam:.6g} (det K_t < 0) under "
                        f"load control, and {solver.instability}",
                    )
                    return None
                record(moved)
                lam = float(moved.load_factor)
            if lam >= s.max_load_factor:
                hist.end(
                    Status.COMPLETED,
                    StopReason.MAX_LOAD_FACTOR,
                    f"reached max_load_factor {lam:.6g}",
                )
                return None
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
            elif out.iterations <= s.easy_iterations:
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
                if work_reason is None or work_reason is RESUMED:
                    return work_reason
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
        _out_of_steps(hist, s.max_steps, lam)
        return None
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
        if work_reason is RESUMED:
            return RESUMED
    if work_reason is not None:
        hist.reason += f"; work control found no higher equilibrium ({work_reason[0]})"
    return None


def unstable(solver: PathSolver, out: Outcome) -> bool:
    """Is the converged state ``out`` of the path an unstable equilibrium: det K_t < 0
    (:meth:`.problem.DiscreteProblem.determinant_sign`)? The path follower's equilibria
    are those of any branch, stable or not; the damped, slowly loaded wall of the reference
    leaves an unstable one, so the instability rule runs there. Tested where the rule can
    run (``certify`` and ``refine``)."""
    s = solver.settings
    if not (s.certify and s.refine):
        return False
    return solver.problem.determinant_sign(out.response) < 0


def _hands_over(hist: History) -> bool:
    """Work control takes over at the first failure of load control once the path has two
    live-load steps (the first is its elastic scale). An earlier failure is halved first:
    there it is far more often a step too long than a limit (the measurements are in
    docs/history/solvers_record.md, "Settings and their evidence"). A wall whose very first
    step finds its limit (a block that slides or lifts at once) ends in the refined
    bracket, which the certificate checks across its tolerance."""
    return len(hist.steps) > 2


def control_radius(solver: PathSolver, c: np.ndarray, dw: float) -> float:
    """Trust radius for a controlled step: room for the requested increment."""
    return max(
        4.0 * solver.last_increment,
        solver.search_seed,
        4.0 * abs(dw) / max(float(np.abs(c).max()), 1e-300),
    )


def work_control(
    solver: PathSolver, hist: History, record: Record, first_failure: str
) -> tuple[str, StopReason] | None:
    """Continue past the first failure of load control with lambda free and the
    work-conjugate displacement w = c . q (c = F_L / |F_L|) prescribed, from the last
    converged state. Returns None when the run is decided (a peak above the last
    load-control state, or ``max_steps`` / ``max_load_factor``), ``RESUMED`` when the
    instability rule found the wall at rest above a flat or falling curve (load control goes
    on from there), else why nothing higher was found and the stop it met (load control then
    refines its bracket).

    Load control fails where the pushover curve turns flat (a plastic plateau or a
    limit point); under work control (displacement control on the live load's
    work-conjugate displacement: Batoz & Dhatt 1979, Int. J. Numer. Meth. Eng. 14) the
    same equilibria are found with bounded increments. The curve is followed until one of:
    lambda falls by more than ``bracket_tolerance`` below its peak (a limit point: under a
    load that does not fall the wall leaves the path there); lambda at w has risen less than
    ``bracket_tolerance`` x lambda since w / 2 (w measured from the dead-load state); three
    steps in a row gain less than ``flat_slope`` of the elastic d(lambda) / d(w) (a formed
    mechanism); the step has been halved ``max_cuts`` times or below what the control
    tolerance can resolve, and the instability rule finds no rest at lambda (1 +
    ``bracket_tolerance``); the displacements pass the limit and the rule finds no rest above
    (where it finds one, displacements are measured from that rest on). The collapse
    multiplier is the highest lambda on the path. With ``flat_slope`` > 0 each step is
    bounded by the load it can gain where the path may stop (:func:`.steps.tail_cap`)."""
    s = solver.settings
    free = solver.problem.asm.free_index
    c = solver.problem.F_live / float(np.linalg.norm(solver.problem.F_live))
    q0 = hist.steps[0].q.reshape(-1)[free]
    path_w = [float(c @ (st.q.reshape(-1)[free] - q0)) for st in hist.steps]
    path_lam = [float(st.load_factor) for st in hist.steps]
    w = path_w[-1]
    line = SecantPredictor()
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
        max(first, 1e-3 * abs(w), RADIUS_FLOOR * solver.problem.displacement_scale),
        s.growth,
        easy_iterations=s.easy_iterations,
    )
    lam = path_lam[-1]
    # where the displacement limit is measured from (read once: the steps may be on disk)
    origin = hist.steps[solver.limit_origin].q
    first_lambda = hist.collapse_bracket[1] if hist.collapse_bracket else lam
    peak = max(path_lam)
    flat_steps = 0
    reason = ""
    stop = StopReason.NONE
    turned: tuple[str, StopReason] | None = None  # a stop where the curve fell or went flat

    def rest_above(why: str) -> bool:
        """The instability rule where work control stops (:meth:`StaticSolver.rule_at` the
        peak of the path): where the damped motion comes to rest (the wall snaps through a
        fold of the path, or carries more past a plateau), the path goes on from there;
        else the path stops, and the rule's verdict is the certificate's."""
        nonlocal lam, w, peak, flat_steps
        if not s.certify or not s.refine:
            return False
        moved = solver.rule_at(peak)
        log.debug(
            "work control stopped at lambda=%.6g (%s); damped motion to %.6g: %s",
            lam,
            why,
            moved.load_factor,
            "at rest" if moved.ok else moved.reason,
        )
        if not moved.ok:
            return False
        record(moved)
        lam = float(moved.load_factor)
        w = float(c @ (moved.q[free] - q0))
        path_w.append(w)
        path_lam.append(lam)
        line.restart(w, moved.q, lam)
        peak = max(peak, lam)
        step.size, step.cuts, flat_steps = max(step.size, first_dw), 0, 0
        return True

    first_dw = step.size  # the scale of the steps after a rest past a fold
    while len(hist.steps) < s.max_steps:
        if s.flat_slope > 0:
            step.cap = tail_cap(
                lam,
                elastic_slope,
                s.flat_slope,
                s.flat_slope,
                curve_slope(path_w, path_lam, elastic_slope),
                _to_limit(solver, hist, path_w, origin),
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
            if out.past_limit and step.cuts >= LIMIT_CUTS:
                # measured from the dead-load state, as the certificate measures it
                ran = moved_from_dead_load(solver.problem, hist, out.q)
                reason = (
                    f"a search from the state at lambda={lam:.6g} "
                    f"({moved_from_dead_load(solver.problem, hist, solver.q):.3g} m from the "
                    f"dead-load state) ran past the displacement limit {solver.limit:.3g} m "
                    f"(to {ran:.3g} m from the dead-load state; peak {peak:.6g})"
                )
                if rest_above(reason):
                    continue
                stop = StopReason.DISPLACEMENT_LIMIT
                break
            step.cut()
            # a step below this cannot be told from no step (the control tolerance)
            tiny = 1e-4 * max(abs(w), first_w, 1e-4 * solver.problem.displacement_scale)
            if step.cuts > MAX_CUTS or step.size < tiny:
                if rest_above(out.reason):
                    continue
                reason = f"no equilibrium beyond lambda={lam:.6g} under work control ({out.reason})"
                stop = StopReason.PATH_STUCK
                break
            continue
        if float(out.load_factor) > s.max_load_factor:
            # lambda is free under work control: the step passed the cap, so the last
            # state is found again by load control at the cap itself
            capped = solver.equilibrate(s.max_load_factor)
            if capped.ok:
                out = capped
        if float(out.load_factor) < peak * (1.0 - s.bracket_tolerance):
            # past a limit point: the equilibria ahead carry less load, and a wall under a
            # load that does not fall moves away from them (the instability rule decides
            # at the collapse whether it comes to rest higher up)
            turned = (
                f"a limit point: the pushover curve falls from lambda={peak:.6g} "
                f"to {float(out.load_factor):.6g}",
                StopReason.LIMIT_POINT,
            )
            break
        record(out)
        w, lam = goal, float(out.load_factor)
        line.add(w, out.q, lam)
        path_w.append(w)
        path_lam.append(lam)
        rising = lam >= peak
        peak = max(peak, lam)
        if rising and unstable(solver, out):
            # (past a limit point det K_t < 0 too, but there the curve falls: stopped above)
            turned = (
                f"an unstable equilibrium at lambda={lam:.6g} (det K_t < 0: the path passed "
                f"a bifurcation or limit point)",
                StopReason.UNSTABLE,
            )
            break
        if lam >= s.max_load_factor:
            hist.end(
                Status.COMPLETED, StopReason.MAX_LOAD_FACTOR, f"reached max_load_factor {lam:.6g}"
            )
            return None
        total = moved_from(solver.problem, origin, out.q)
        if total > solver.limit:
            # the displacement limit is a mechanism of the small-displacement model only where
            # the instability rule finds no rest above: a curve still rising there (soft
            # joints, or a wall that settles joint by joint) goes on from the rule's rest,
            # its displacements measured from there, as the reference measures each motion
            # from its last rest
            turned = (
                f"a mechanism: displacements {total:.3g} m exceed the limit "
                f"{solver.limit:.3g} m at lambda={lam:.6g}",
                StopReason.DISPLACEMENT_LIMIT,
            )
            break
        half = float(np.interp(w / 2, path_w, path_lam))
        if w > 0 and lam - half <= s.bracket_tolerance * abs(peak) and lam < peak + 1e-12:
            turned = (
                f"the pushover curve is flat: lambda rose {lam - half:.3g} while the "
                f"work-conjugate displacement doubled to {w:.3g} m (peak {peak:.6g})",
                StopReason.CURVE_FLAT,
            )
            break
        # a formed mechanism: the last steps gained (almost) nothing for their
        # displacement, compared with the elastic stiffness of the live load
        slope = (path_lam[-1] - path_lam[-2]) / max(path_w[-1] - path_w[-2], 1e-300)
        flat_steps = flat_steps + 1 if slope < s.flat_slope * elastic_slope else 0
        if flat_steps >= 3:
            tiny = path_w[-1] - path_w[-4] < 1e-3 * w
            turned = (
                f"no equilibrium beyond lambda={peak:.6g}: work control creeps "
                f"(w {path_w[-4]:.6g} -> {w:.6g} m in 3 steps)"
                if tiny
                else f"a mechanism: lambda gains {slope / elastic_slope:.1e} of the "
                f"elastic stiffness per unit displacement over 3 steps (peak {peak:.6g})",
                StopReason.CREEPING if tiny else StopReason.STIFFNESS_LOST,
            )
            break
        if step.cuts == 0:
            step.grow(out.iterations)
        step.cuts = 0
    else:
        _out_of_steps(hist, s.max_steps, lam)
        return None
    if turned is not None:  # the curve fell, went flat or ran far: the rule looks above the peak
        reason, stop = turned
        if rest_above(reason):
            if stop is StopReason.DISPLACEMENT_LIMIT:
                solver.limit_origin = len(hist.steps) - 1
            return RESUMED  # the curve had not turned after all: load control goes on
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


def _to_limit(solver: PathSolver, hist: History, path_w: list[float], origin: np.ndarray) -> float:
    """How far in w the displacement limit (measured from the state ``origin``) lies ahead,
    by the secant of the largest translation over the last two states (inf where it did
    not grow)."""
    if len(hist.steps) < 2 or path_w[-1] <= path_w[-2]:
        return math.inf
    last = moved_from(solver.problem, origin, hist.steps[-1].q)
    rate = (last - moved_from(solver.problem, origin, hist.steps[-2].q)) / (path_w[-1] - path_w[-2])
    return (solver.limit - last) / rate if rate > 0 else math.inf


def _tangent_slope(solver: PathSolver) -> float:
    """d lambda / d w along the tangent of the last converged state: |F_L| / F_L.K_t^-1 F_L."""
    F = solver.problem.F_live
    _, _, response = solver.residual(solver.q, solver.load_factor)
    compliance = float(F @ solver.problem.factor(response).solve(F))
    return float(np.linalg.norm(F)) / compliance if compliance > 0 else 0.0
