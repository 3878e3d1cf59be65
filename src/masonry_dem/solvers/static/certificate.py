"""The certificate of a collapse: what makes a stop of the static path a collapse.

A path follower stops for many reasons (a flat curve, a displacement limit, no equilibrium
for any step); only some of them are a collapse. :func:`certify` checks three conditions on
the state where the path stopped, each independently of how the path got there:

(a) **equilibrium** - the state is a converged equilibrium of the discrete problem at its
    lambda (the residual re-evaluated to the static tolerance) and statically admissible
    (every interface action inside its strength domain, to ``ADMISSIBLE_TOLERANCE``);
(b) **a collapse mode** - either the tangent of that state is singular along the motion
    the live load drives, v = K_t^-1 F_L, to a stated tolerance: the Rayleigh quotient of
    the tangent along v in the metric of the tangent K_0 of the dead-load state (the wall
    as it stands before the live load), rho = v.K_t v / v.K_0 v = F_L.v / v.K_0 v, is at
    most ``mode_stiffness`` (rho is 1 at the dead-load state, between 0 and 1 as joints
    open and slide, 0 along a mechanism, negative where the tangent softens along the load
    past a limit point; it is the smallest generalised eigenvalue of (K_t, K_0) when the
    load drives that mode, as inverse iteration from F_L finds it). K_0 and not the
    bonded elastic stiffness: a dry wall's head joints carry nothing under its weight, and
    against a bonded wall its own elastic state measured 0.03 in plane. Or the pushover
    curve is flat
    or falling past its peak over at least ``MODE_DISPLACEMENT`` x the work-conjugate
    displacement at the peak. Where the law has a kink (a joint that starts to slide, rock
    or lift: elastic up to its strength, then nothing along that motion) the singularity
    lies just past the last converged state, so the tangent is also taken at the linear
    extension of the state, q + (lambda_end - lambda) K_t^-1 F_L, across the bracket's
    tolerance, lambda_end = lambda x (1 + ``bracket_tolerance``). Either way the live
    load does positive work along the mode (F_L.v > 0). A path stopped by the displacement
    limit (where equilibria were still being found) must have stopped rising: rho at most
    ``flat_slope``, as work control measures a flat curve. The current stiffness parameter
    of Bergan, S = (d lambda / d w along the
    tangent) / (elastic d lambda / d w of the path), is reported beside it;
(c) **the bound** - lambda does not exceed the associative limit-analysis multiplier of the
    same model (Radenkovic: an upper bound of the non-associative one), within
    ``bound_tolerance``. The bound is injected (a number or a function of the model); with
    none, the field says ``"not checked"``, never a pass.

A multiplier the residual cannot tell from zero load (at most ZERO_LOAD x ``tolerance`` load
scales) needs more for (b): a mechanism of the dead-load state itself (its tangent, or the
tangent at its extension to the smallest resolvable lambda, singular along the load to
ZERO_MODE x the tangent's floor against the bonded elastic stiffness), which the damped
motion of the instability rule confirms by finding no rest at that lambda (a contact may
close after a small motion: an in-plane held wall whose tangent is singular there carries
0.08).

A stop that fails (a) or (b), or exceeds the bound, is reported ``failed`` with the reason
and every step kept.

Reported beside them, not a condition: ``curve_slope``, the d lambda / d w of the step into
the state over the elastic slope, and ``corner``, a stuck path that still rose there (at
least ``flat_slope``): its branch ended at a kink, where a fold of the path has a singular
tangent as well as a peak. Such a stop is a peak only if no rest is found above it, which
the instability rule checks (``instability``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from masonry_dem.constitutive.law import DETACHED_FLAG

if TYPE_CHECKING:
    from masonry_dem.model import Model
    from masonry_dem.results import History
    from masonry_dem.solvers.static.problem import DiscreteProblem
    from masonry_dem.solvers.static.settings import StaticSettings

#: an upper bound of the collapse multiplier: a number, or a function of the model
Bound = float | Callable[["Model"], "float | None"] | None
#: a law state: the joints' (m, 6) plastic part and (m,) cracked flags
LawState = tuple[np.ndarray, np.ndarray]

NOT_CHECKED = "not checked"
#: a multiplier at most ZERO_LOAD x tolerance (in load scales) cannot be told from zero load
#: by the residual; a collapse there needs a mechanism of the dead-load state itself: its
#: tangent singular along the load to ZERO_MODE x the tangent's floor (residual_stiffness)
ZERO_LOAD = 100.0
ZERO_MODE = 1e3
#: the last state's actions may exceed the strength domain by this fraction of the capacity
#: (the round-off of the return mapping)
ADMISSIBLE_TOLERANCE = 1e-6
#: a pushover curve flat or falling past its peak over at least this fraction of the
#: work-conjugate displacement at the peak (both from the dead-load state) is a collapse mode
MODE_DISPLACEMENT = 0.5


@dataclass
class Certificate:
    """Whether a stop of the path is a collapse, and the evidence. ``holds`` is the
    conjunction of ``equilibrium``, ``admissible``, ``mode_found`` and (when a bound was
    given) ``within_bound``."""

    holds: bool
    load_factor: float  # the certified multiplier (the peak of the path)
    state_load_factor: float  # lambda of the state checked (the last converged one)
    step: int  # the index in History.steps of the state checked (the last)
    # (a)
    residual: float
    tolerance: float
    equilibrium: bool
    utilisation: float  # largest demand/capacity of the actions of the state
    admissible: bool
    # (b)
    # "singular tangent" (at the state), "singular tangent at the end of the bracket",
    # "flat curve", or "none"
    mode: str
    mode_rayleigh: float  # rho = v.K_t v / v.K_0 v along v = K_t^-1 F_L
    mode_stiffness: float  # the tolerance applied (flat_slope after a displacement limit)
    stiffness_parameter: float  # Bergan's S along the load (reported, not a condition)
    curve_displacement: float  # w past the peak / w at the peak
    mode_displacement: float
    live_work: float  # F_L . mode (mode scaled to a largest translation of 1 m)
    mode_found: bool
    near_zero: bool  # lambda <= ZERO_LOAD x tolerance load scales: the stricter check applied
    zero_load_check: str  # the damped motion at the resolvable lambda: "no rest", ...
    # (c)
    bound: float | None
    bound_status: str  # "within", "exceeded", or "not checked"
    within_bound: bool | None
    reason: str
    # d lambda / d w of the step into the state checked, over the elastic slope; a stuck
    # path that still rose there (at least flat_slope) stopped at a corner, where a fold of
    # the path and a peak share a singular tangent (docs/history/solvers_record.md, "A corner is
    # checked")
    curve_slope: float = math.nan
    corner: bool = False
    # the instability rule: the damped motion from the last rest at (1 + bracket) lambda
    instability: str = NOT_CHECKED
    mode_vector: np.ndarray | None = field(default=None, repr=False)

    def as_dict(self) -> dict:
        """JSON-ready fields (no arrays)."""
        out = asdict(self)
        out.pop("mode_vector")
        for key, value in out.items():
            if isinstance(value, float) and not math.isfinite(value):
                out[key] = None if math.isnan(value) else str(value)
        return out


def _bound_value(bound: Bound, model: Model) -> float | None:
    if bound is None:
        return None
    value = bound(model) if callable(bound) else bound
    return None if value is None or not math.isfinite(float(value)) else float(value)


def certify(
    problem: DiscreteProblem,
    hist: History,
    settings: StaticSettings,
    bound: Bound = None,
    rests_at: Callable[[float], bool] | None = None,
    run_off: np.ndarray | None = None,
    instability: str = NOT_CHECKED,
    start: LawState | None = None,
) -> Certificate:
    """Check the stop of ``hist`` at its last recorded state (see the module). Only the
    model's discrete problem and the History are used: the law state of the last step (the
    joints cracked before it, the plastic part of the step before it) is rebuilt from the
    steps, so the check does not rest on how the path got there. ``rests_at(lambda)``: does
    the instability rule (the damped motion) find rest at that lambda from the last state;
    asked only of a multiplier the residual cannot tell from zero load. ``run_off``: the
    direction in which the instability rule's motion ran past the displacement limit (full
    DOFs), and ``instability`` its verdict, reported (:meth:`StaticSolver._instability_rule`
    reports a collapse only where that motion found no rest or no verdict)."""
    s = settings
    free = problem.free
    law = problem.law
    last = len(hist.steps) - 1
    state = hist.steps[last]
    lam_state = float(state.load_factor)
    peak = hist.collapse_multiplier
    lam = float(peak if peak is not None else hist.load_factors.max())
    q = state.q.reshape(-1)
    plastic, cracked = law_state_before(problem, hist, last, start)
    # (a) the residual re-evaluated at the state, with the law state it was found with
    _, rnorm, response = problem.residual(q, lam_state, plastic, cracked)
    equilibrium = bool(rnorm <= s.tolerance)
    util = float(np.max(law.admissibility(response), initial=0.0))
    admissible = bool(util <= 1.0 + ADMISSIBLE_TOLERANCE)
    # (b1) the tangent of the state along the load
    F = problem.F_live
    live_norm = float(np.linalg.norm(F))
    v = problem.factor(response).solve(F)
    compliance = float(F @ v)
    c = F / live_norm if live_norm > 0 else F
    q0 = hist.steps[0].q.reshape(-1)[free]
    path_w = np.array([float(c @ (st.q.reshape(-1)[free] - q0)) for st in hist.steps])
    path_lam = hist.load_factors
    elastic_slope = _elastic_slope(problem, path_w, path_lam)
    if compliance != 0.0 and math.isfinite(compliance) and elastic_slope > 0:
        stiffness = live_norm / compliance / elastic_slope
    else:
        stiffness = math.inf
    T0 = _dead_load_tangent(problem, hist, s, start)
    rho = _rayleigh(problem, v, compliance, T0)
    # a path stopped by the displacement limit still found equilibria: its curve must have
    # stopped rising there, as work control measures flatness (flat_slope); a path that
    # found none beyond its state needs only a near-singular tangent (mode_stiffness)
    from masonry_dem.solvers.static.outcome import StopReason

    tolerance = (
        min(s.flat_slope, s.mode_stiffness)
        if hist.stop is StopReason.DISPLACEMENT_LIMIT
        else s.mode_stiffness
    )
    singular = bool(compliance != 0 and rho <= tolerance)
    where = "singular tangent"
    if not singular and np.all(np.isfinite(v)):
        # a kink of the law (a joint that starts to slide, rock or lift) puts the
        # singularity just past the last converged state: the tangent at the linear
        # extension of the state across the collapse bracket's tolerance
        # (only that far: an unrefined bracket proves nothing about the state)
        probe_lam = lam_state * (1.0 + s.bracket_tolerance)
        probe = q.copy()
        probe[free] += (probe_lam - lam_state) * v
        _, _, beyond = problem.residual(probe, probe_lam, plastic, cracked)
        v_beyond = problem.factor(beyond).solve(F)
        compliance_beyond = float(F @ v_beyond)
        rho_beyond = _rayleigh(problem, v_beyond, compliance_beyond, T0)
        if compliance_beyond != 0 and rho_beyond <= tolerance:
            singular, where = True, "singular tangent at the end of the bracket"
            v, compliance, rho = v_beyond, compliance_beyond, rho_beyond
    # (b2) the curve past its peak, up to the state checked
    at_peak = int(np.argmax(path_lam))
    w_peak = path_w[at_peak]
    w_last = path_w[last]
    past = (w_last - w_peak) / w_peak if w_peak > 0 else 0.0
    flat = bool(last > at_peak and past >= MODE_DISPLACEMENT)
    # the mode and the work of the live load along it
    mode_vector: np.ndarray | None = None
    live_work = 0.0
    mode = "none"
    if singular and np.all(np.isfinite(v)):
        x = v if compliance > 0 else -v  # oriented so that the live load does work
        size = float(np.abs(x[problem.translation]).max(initial=0.0))
        if size > 0:
            x = x / size
            live_work = float(F @ x)
            mode, mode_vector = where, x
    if mode == "none" and flat:
        dq = (q - hist.steps[at_peak].q.reshape(-1))[free]
        size = float(np.abs(dq[problem.translation]).max(initial=0.0))
        if size > 0:
            live_work = float(F @ dq) / size
            mode, mode_vector = "flat curve", dq / size
    mode_found = bool(mode != "none" and live_work > 0)
    # the curve into the state: did the path stop at a corner, still rising?
    slope = curve_slope(path_w, path_lam, elastic_slope)
    corner = bool(
        hist.stop is StopReason.PATH_STUCK and still_rising(slope, s.flat_slope) and mode != "none"
    )
    # a multiplier the residual cannot tell from zero load: the states found there are
    # equilibria only to the tolerance, so the mode must be one of the dead-load state
    # itself, singular to the floor of the tangent against the bonded elastic stiffness
    near_zero = bool(lam <= ZERO_LOAD * s.tolerance * problem.load_scale)
    zero_rho = math.nan
    zero_check = NOT_CHECKED
    lam_end = ZERO_LOAD * s.tolerance * problem.load_scale
    if near_zero:
        zero_rho, zero_mode = _dead_load_mode(problem, hist, s, start)
        singular_at_zero = zero_rho <= ZERO_MODE * s.residual_stiffness
        # a contact may close after a small motion: the mechanism must also run away
        # where an independent method looks for rest (no rest at the resolvable lambda)
        zero_check = (
            NOT_CHECKED
            if rests_at is None or not singular_at_zero
            else ("rest found" if rests_at(lam_end) else "no rest")
        )
        if singular_at_zero and zero_check == "no rest" and zero_mode is not None:
            mode, mode_vector = "mechanism of the dead-load state", zero_mode
            live_work = float(F @ zero_mode)
            mode_found = live_work > 0
        else:
            mode_found, mode, mode_vector, live_work = False, "none", None, 0.0
    # where the tangent and the curve show no mode, the direction of the instability rule's
    # motion past the displacement limit is the mode; not at a stop of the path by that
    # limit, where a curve still rising has left the small-displacement range (soft joints,
    # or a limit the elastic wall passes): there the motion measures the deflection
    if not mode_found and run_off is not None and hist.stop is not StopReason.DISPLACEMENT_LIMIT:
        direction = run_off[free]
        size = float(np.abs(direction[problem.translation]).max(initial=0.0))
        if size > 0:
            mode, mode_vector = "motion past the displacement limit", direction / size
            live_work = float(F @ mode_vector)
            mode_found = live_work > 0
    # (c) the bound
    value = _bound_value(bound, problem.model)
    if value is None:
        bound_status, within = NOT_CHECKED, None
    else:
        within = bool(lam <= value * (1.0 + s.bound_tolerance) + 1e-12 * abs(value))
        bound_status = "within" if within else "exceeded"
    holds = equilibrium and admissible and mode_found and within is not False
    why = []
    if not equilibrium:
        why.append(f"the last state is not an equilibrium (residual {rnorm:.2e} > {s.tolerance:g})")
    if not admissible:
        why.append(f"the last state is not admissible (utilisation {util:.6g})")
    if not mode_found and near_zero:
        why.append(
            f"lambda {lam:.3g} is below what the residual tolerance resolves "
            f"({ZERO_LOAD:g} x {s.tolerance:g} load scales) and the dead-load state shows no "
            f"mechanism along the load (its tangent keeps {zero_rho:.3g} of the bonded "
            f"elastic stiffness, limit {ZERO_MODE:g} x the floor {s.residual_stiffness:g}; "
            f"the damped motion at lambda {lam_end:.3g}: {zero_check})"
        )
    elif not mode_found and mode == "motion past the displacement limit":
        why.append("the motion past the displacement limit does no work of the live load")
    elif not mode_found and hist.stop is StopReason.DISPLACEMENT_LIMIT:
        # equilibria were still being found: the wall left the small-displacement range of
        # the geometrically linear model before its curve stopped rising (joints so soft
        # that the displacement at the peak would be a sizeable part of a block)
        moved = moved_from_dead_load(problem, hist, q)
        limit_is = (
            "half the smallest moving block"
            if s.displacement_limit is None
            else "the displacement_limit given"
        )
        if moved > problem.limit:
            why.append(
                f"the wall left the small-displacement range before its curve stopped "
                f"rising: {moved:.3g} m from the dead-load state (limit {problem.limit:.3g} "
                f"m, {limit_is}) at lambda {lam_state:.6g}, where the "
                f"tangent still keeps {rho:.3g} of its stiffness along the load "
                f"(> {tolerance:g}); its joints are too soft for a small-displacement "
                f"analysis to reach the peak (the dead load alone moves it "
                f"{problem.displacement_scale:.3g} m bonded): stiffer joints in the same "
                f"kt/kn ratio give the multiplier"
                + ("" if s.displacement_limit is None else ", or a larger displacement_limit")
            )
        else:
            # no state passed the limit: the searches from the last one ran off
            why.append(
                f"no state left the small-displacement range: the last, at lambda "
                f"{lam_state:.6g}, is {moved:.3g} m from the dead-load state (limit "
                f"{problem.limit:.3g} m, {limit_is}), and only the "
                f"searches from it ran past the limit, while the curve still rose into it at "
                f"{slope:.2g} of its elastic slope and its tangent keeps {rho:.3g} of its "
                f"stiffness along the load (> {tolerance:g}): no mechanism formed there"
            )
    elif not mode_found:
        why.append(
            f"no collapse mode: the tangent keeps {rho:.3g} of the elastic stiffness along "
            f"the motion the load drives (> {tolerance:g}) and the curve goes "
            f"{past:.3g} of its peak displacement past the peak (< {MODE_DISPLACEMENT:g})"
        )
    if not mode_found and instability != NOT_CHECKED:
        why.append(f"the instability rule: {instability}")
    if within is False:
        why.append(f"lambda {lam:.6g} exceeds the limit-analysis bound {value:.6g}")
    reason = (
        f"certified: {mode} (rho {rho:.2e}, live-load work {live_work:.3g} per m), "
        f"bound {bound_status}"
        if holds
        else "; ".join(why)
    )
    if holds and instability != NOT_CHECKED:
        reason += f"; instability rule: {instability}"
    if holds and corner:
        reason += (
            f"; the path stopped at a corner (its curve still rose at {slope:.2g} of "
            f"its elastic slope), where a fold of the path has a singular tangent too"
        )
    return Certificate(
        holds=bool(holds),
        load_factor=lam,
        state_load_factor=lam_state,
        step=int(last),
        residual=float(rnorm),
        tolerance=s.tolerance,
        equilibrium=equilibrium,
        utilisation=util,
        admissible=admissible,
        mode=mode,
        mode_rayleigh=float(rho),
        mode_stiffness=tolerance,
        stiffness_parameter=float(stiffness),
        curve_displacement=float(past),
        mode_displacement=MODE_DISPLACEMENT,
        live_work=float(live_work),
        mode_found=mode_found,
        near_zero=near_zero,
        zero_load_check=zero_check,
        bound=value,
        bound_status=bound_status,
        within_bound=within,
        reason=reason,
        curve_slope=slope,
        corner=corner,
        instability=instability,
        mode_vector=None if mode_vector is None else _full(problem, mode_vector),
    )


def curve_slope(
    path_w: Sequence[float] | np.ndarray,
    path_lam: Sequence[float] | np.ndarray,
    elastic_slope: float,
) -> float:
    """The slope of the last step of a pushover curve, d lambda / d w over ``elastic_slope``
    (w the work-conjugate displacement of the live load, from the dead-load state): the one
    measure of "still rising" that the stop check of work control and the certificate
    share. A step that turned back in w (dw <= 0) while gaining load is a snap-back of the
    curve, still rising: +inf; one that went back in w losing load, or made no move: -inf
    (its d lambda / d w is positive or undefined, but the curve did not rise). nan with
    fewer than two states or no elastic slope."""
    if len(path_w) < 2 or not elastic_slope > 0:
        return math.nan
    dlam = float(path_lam[-1] - path_lam[-2])
    dw = float(path_w[-1] - path_w[-2])
    if dw <= 0:
        return math.inf if dlam > 0 else -math.inf
    return dlam / dw / elastic_slope


def moved_from_dead_load(problem: DiscreteProblem, hist: History, q: np.ndarray) -> float:
    """The largest translation of the state ``q`` (all DOFs) from the dead-load state (the
    first of ``hist``): the one measure of the displacement limit in the path's stop reason
    and in the certificate (elastic displacement under the dead load never counts)."""
    return moved_from(problem, hist.steps[0].q, q)


def moved_from(problem: DiscreteProblem, origin: np.ndarray, q: np.ndarray) -> float:
    """The largest translation of the state ``q`` from the state ``origin`` (all DOFs)."""
    dq = (np.asarray(q).reshape(-1) - np.asarray(origin).reshape(-1))[problem.free]
    return float(np.abs(dq[problem.translation]).max(initial=0.0))


def still_rising(slope: float, flat_slope: float) -> bool:
    """Did a step of ``curve_slope`` ``slope`` still rise, at ``flat_slope`` of the elastic
    slope or more (work control's measure of a formed mechanism)? A stuck path that still
    rose stopped at a corner: the end of its branch, a fold or a peak."""
    return bool(slope >= flat_slope)


def _full(problem: DiscreteProblem, x: np.ndarray) -> np.ndarray:
    q = np.zeros(problem.model.n_dofs)
    q[problem.free] = x
    return q.reshape(-1, 6)


def law_state_before(
    problem: DiscreteProblem, hist: History, index: int, start: LawState | None = None
):
    """(plastic part, cracked joints) that step ``index`` of the path was found with (or a
    step after the last would be): the joints detached at the steps before it (brittle
    tension), the plastic part stored at the step before it (memory of slip); or, for a rest
    of the damped motion, the law state kept with the step. ``start``: the law state the
    path started from (a later loading stage's, carried from the stage before; None: the
    unloaded wall's, no slip and no crack)."""
    law = problem.law
    if index < len(hist.steps):
        found = hist.steps[index]
        if found.found_plastic is not None and found.found_cracked is not None:
            return found.found_plastic, found.found_cracked
    m = problem.model.interfaces.count
    cracked = np.zeros(m, dtype=bool) if start is None else start[1].copy()
    if law.tension == "brittle" and index > 0:
        flags = np.array([st.flags for st in hist.steps[:index]])
        cracked |= np.any((flags & DETACHED_FLAG) > 0, axis=0)
    plastic = np.zeros((m, 6)) if start is None else start[0].copy()
    if index > 0:
        before = hist.steps[index - 1]
        relative = problem.asm.relative_displacements(before.q.reshape(-1))
        plastic = law.plastic_part(relative, before.actions)
    return plastic, cracked


def _dead_load_tangent(
    problem: DiscreteProblem,
    hist: History,
    settings: StaticSettings,
    start: LawState | None = None,
) -> np.ndarray:
    """(m, 6, 6) tangents of the joints at the dead-load state (the first step), as Newton
    assembles them (:meth:`DiscreteProblem.joint_tangents`): the head joints of a dry wall
    carry nothing under its weight, so round-off alone set their trial actions and, through
    the law's flags, whether the raw tangent gave them their elastic shear and bending
    stiffness or none; with that, rho moved across the threshold between kn and 10 kn on a
    wall whose path was the same to 1e-15. Reduced to their normal stiffness, as the
    corrector takes them, they give a metric that scales with kn exactly."""
    m = problem.model.interfaces.count
    first = hist.steps[0].q.reshape(-1)
    plastic, cracked = (np.zeros((m, 6)), np.zeros(m, dtype=bool)) if start is None else start
    _, _, response = problem.residual(first, 0.0, plastic, cracked)
    return problem.joint_tangents(response, settings.residual_stiffness)


def _dead_load_mode(
    problem: DiscreteProblem,
    hist: History,
    settings: StaticSettings,
    start: LawState | None = None,
) -> tuple[float, np.ndarray | None]:
    """The smaller rho of the dead-load state's tangent along K_0^-1 F_L, and of the tangent
    at that state's linear extension to the smallest resolvable multiplier (ZERO_LOAD x
    tolerance load scales: a joint with no strength along the load, e.g. no friction, is
    elastic at zero demand and yields just past it), against the bonded elastic stiffness
    (every joint at kbar); with that mode (free DOFs), scaled to a largest translation of 1
    and oriented so that the live load does work on it."""
    m = problem.model.interfaces.count
    none = (np.zeros((m, 6)), np.zeros(m, dtype=bool)) if start is None else start
    first = hist.steps[0].q.reshape(-1)
    F = problem.F_live
    _, _, response = problem.residual(first, 0.0, *none)
    best: tuple[float, np.ndarray | None] = (math.inf, None)
    v0 = None
    for _ in range(2):
        v = problem.factor(response).solve(F)
        compliance = float(F @ v)
        if not (np.all(np.isfinite(v)) and math.isfinite(compliance)) or compliance == 0:
            break
        relative = problem.asm.relative_displacements(_full(problem, v).reshape(-1))
        energy = float(np.sum(problem.law.kbar * relative**2))
        x = v if compliance > 0 else -v
        size = float(np.abs(x[problem.translation]).max(initial=0.0))
        if energy > 0 and size > 0 and compliance / energy < best[0]:
            best = (compliance / energy, x / size)
        if v0 is not None:
            break
        v0 = v
        lam_end = ZERO_LOAD * settings.tolerance * problem.load_scale
        probe = first.copy()
        probe[problem.free] += lam_end * v0
        _, _, response = problem.residual(probe, lam_end, *none)
    return best


def _rayleigh(problem: DiscreteProblem, v: np.ndarray, compliance: float, T0: np.ndarray) -> float:
    """F_L.v / v.K_0 v (K_0 = H^T T0 H, the tangent of the dead-load state)."""
    if not (np.all(np.isfinite(v)) and math.isfinite(compliance)):
        return math.inf
    relative = problem.asm.relative_displacements(_full(problem, v).reshape(-1))
    metric = _metric(relative, T0)
    return compliance / metric if math.isfinite(metric) else math.inf


def _metric(relative: np.ndarray, T0: np.ndarray) -> float:
    """v.K_0 v as a sum over the joints of their energy in the dead-load state's tangent,
    each counted where it is positive (a joint that slides under the dead load has a
    non-symmetric tangent whose energy may be negative along some motions; the metric must
    not be: with joints at zero gap and zero force, which side of the contact round-off puts
    them on changed its sign, and with it the certificate, between kn and 1000 kn); inf
    when nothing is left."""
    energy = np.einsum("mi,mij,mj->m", relative, T0, relative)
    total = float(np.sum(np.maximum(energy, 0.0)))
    return total if total > 0 else math.inf


def _elastic_slope(problem: DiscreteProblem, path_w: np.ndarray, path_lam: np.ndarray) -> float:
    """d lambda / d w of the first live-load step (elastic for a wall that stands), else of
    the bonded assembly."""
    if path_w.size > 1 and path_w[1] - path_w[0] > 0:
        return float((path_lam[1] - path_lam[0]) / (path_w[1] - path_w[0]))
    F = problem.F_live
    live_norm = float(np.linalg.norm(F))
    compliance = float(F @ problem.elastic_factor().solve(F))
    return live_norm / compliance if compliance > 0 else 0.0
