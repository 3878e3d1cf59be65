"""Settings of the static solver: every number that steers it, with why it has its value
(the measurements behind each are in docs/history/solvers_record.md, "Settings and their
evidence")."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal, get_args

from masonry_dem._validation import (
    at_least,
    check_choice,
    choice,
    count,
    finite,
    is_count,
    is_number,
    positive,
)
from masonry_dem.constitutive.law import TANGENT_METHODS, TangentMethod
from masonry_dem.model import DofName
from masonry_dem.solvers.load_path import LoadPathSettings

#: what follows the first failure of load control (see ``StaticSettings.continuation``)
Continuation = Literal["work", "bracket"]
CONTINUATION: tuple[str, ...] = get_args(Continuation)


@dataclass(frozen=True)
class StaticSettings(LoadPathSettings):
    """Knobs of the static solver. Step sizes are in units of the load scale |F_D| / |F_L|
    (1 for a tilt table, where the live load is the weight turned horizontal).

    Path and steps
    --------------
    initial_step, max_step, growth: lambda increments in units of the load scale
        |F_D| / |F_L| (1 when both loads are weights; the weight per unit of a pressure),
        grown by ``growth`` after easy steps. ``max_step`` 1.0: a pressure wall collapses at
        7-26 load scales and took 60-140 steps at the former cap of 0.2.
    easy_iterations: a step that converges in at most this many Newton iterations is easy:
        the next one is ``growth`` times longer (Newton converges quadratically: a handful of
        iterations means the step was well inside the convergence basin).
    bracket_tolerance: collapse bracket width, relative to lambda.
    refine: halve a failed load step (False: stop at the first failure, an upper bracket only).
    max_steps: converged steps of a run (all path followers together).
    max_load_factor: the run ends ``completed`` when lambda reaches it.
    continuation: what follows the first failure of load control. ``"work"`` (default): the
        work-conjugate displacement of the live load prescribed, lambda free, which passes
        limit points and plastic plateaus, until the pushover curve is flat; ``"bracket"``:
        refine the load-control bracket and stop there.
    secant_predictor: each search of work control starts on the line through the last two
        converged states of the path, extended by the step (False: from the last state).
        Newton then starts a fraction of a step from the answer on smooth stretches. Not
        under load control, where the start picks among the equilibria of a non-associative
        law at one lambda (a wall with openings: 0.085 -> 0.111; docs/history/solvers_record.md,
        "Steps of the path").
    elastic_first_step: where the elastic range is longer than ``initial_step``, the first
        live step goes to ``bracket_tolerance`` short of its end (the load factor at which
        the first joint that carries load reaches its strength domain along the tangent
        response K_t^-1 F_L of the dead-load state), started from that response (no Newton
        iteration while no joint changes state); False: ``initial_step`` always.

    One equilibrium (the corrector)
    -------------------------------
    tolerance: force residual |R| / |F_D + lambda F_L| (moments measured as forces at the
        median block size) below which a state is in equilibrium.
    control_tolerance: a controlled displacement is reached when within this fraction of the
        step asked for (relative to the step, so stiff joints are followed as closely as soft).
    max_iterations: Newton iterations per attempt.
    displacement_limit: largest translation [m] (from the last converged state, or from the
        dead-load state along a path) still in the small-displacement range (None: half the
        smallest dimension of the blocks that can move). Under the dead load the elastic
        displacement of the bonded assembly is added to it: elastic shortening is no mechanism.
    residual_stiffness: fraction of the elastic stiffness kept on the diagonal of the tangent.
    tangent: ``"analytic"`` (closed-form derivative of the return) or ``"difference"``.
    tension, memory: deprecated (None: the material's). They are the interface law's, set on
        :class:`~masonry_dem.model.InterfaceMaterial`; given here they warn and override it.
    stall_window, stall_decrease: a Newton search that has not lowered its merit by
        ``stall_decrease`` in ``stall_window`` iterations (with no cut of the trust radius)
        is stalled: no equilibrium near the last converged state.
    max_floor: largest tangent floor (fraction of the elastic stiffness) of the
        Levenberg-Marquardt fallback used under the dead load.
    chord_ratio: a factorized tangent is reused while each full step divides the residual
        by at least 1 / ``chord_ratio`` (modified Newton: a solve instead of a factorization).
    creep: a step shorter than this fraction of the Newton correction, with no joint changing
        state, leaves the tangent as it was (its factorization is kept).
    search_cuts: a search gives up after this many cuts (by 8) of its trust radius.
    trust_seed: the trust radius of a search with no previous increment to go by (the dead
        load's first live step, a controlled step), in elastic units of the wall
        (``DiscreteProblem.displacement_scale``: the bonded assembly's largest translation
        under the dead load). In units of the wall, not metres, so that a wall with kn and kt
        x f takes the same iterates scaled by 1 / f (a seed of 1e-4 x the displacement limit
        in metres made a 13 x 19 panel with kn x 1e3 stop at 0.650 instead of 0.864).
    radius_floor: a search also gives up when its trust radius falls below this many elastic
        units (it was 1e-12 m x the limit in metres: reached after 5 cuts on stiff joints
        and after 7 on soft ones).

    Work control
    ------------
    max_cuts: work control gives up after this many halvings of its step in a row.
    limit_cuts: a work step whose iterations pass the displacement limit is a mechanism only
        when it does so again after this many halvings in a row (a long first step may run
        off along a mode the load does not drive yet).
    flat_slope: a step whose d(lambda)/dw is below this fraction of the elastic one gains
        nothing; three in a row end the path (a formed mechanism).
    resume_step: after a pseudo-transient (or dynamic-relaxation) step past a fold, work
        control goes on with this fraction of the longer of its step before the fold's
        halvings and its first step (or the present one if longer).
    fold_match: two failed work steps whose searches stop at lambdas this close (relative)
        stop at one fold.

    Pseudo-transient step (where Newton stops at a fold of the path)
    ----------------------------------------------------------------
    transient_steps: budget of pseudo time steps; 0 disables it.
    transient_after: tried once work control has halved its step this many times in a row.
    transient_rise: it relaxes to lambda x (1 + transient_rise): far enough to leave the
        fold, near enough not to jump past the peak.
    transient_reach: where the path is still straight (its last step rose at least half as
        steeply as the elastic slope), it relaxes instead to the lambda at which the failed
        work search before it stopped (the lambda of the path at that search's goal, on a
        straight path), at most lambda x (1 + transient_reach): a chain of folds is then
        passed in the steps work control asked for, not in rises of transient_rise.
        0: always transient_rise.
    transient_start, transient_shrink, transient_window: first pseudo time step 1 /
        ``transient_start`` (the tangent's floor, in units of the elastic stiffness), divided
        by ``transient_shrink`` beyond the residual ratio after a step that lowers the
        residual; it gives up when the residual has not halved in ``transient_window`` steps.

    Other strategies (off by default, or checks)
    --------------------------------------------
    anderson, divergence_window: the robust iterations mix the last ``anderson``
        corrections and stop when the residual has not fallen x10 in ``divergence_window``
        iterations with corrections that do not shrink.
    zero_load_robust_iterations: the robust re-try's budget where load control has halved
        its step down to what the residual cannot tell from zero load (100 x ``tolerance``
        load scales): Newton stalls from the dead-load state of in-plane walls held on one
        edge (a held 9 x 3 wall: 1e-8 -> 0.93).
    stop_check_time_steps: budget of the dynamic relaxation that checks a stop of work
        control (to lambda x (1 + transient_rise)) before the path is given up; 0 disables it.
        The relaxation ends sooner when the wall runs past the displacement limit or its
        residual has not halved in a quarter of the budget.
    fold_check_time_steps: budget of that check where the path got stuck while its curve
        still rose: the last step gained at least ``flat_slope`` of the elastic d lambda / d w
        (a corner of the curve, where the tangent of the state, taken past the kink, may be
        singular although the path never ran along a mechanism: a fold of the path, or a
        peak). The check runs there whatever the tangent, with the larger of this and
        ``stop_check_time_steps``; its budget covers the settling of every fold measured
        (docs/history/solvers_record.md, "The corner check on by default"). The implicit check
        (below) decides, and this relaxation runs only at a fold, for the state the path goes on
        from, or where that check gives no verdict. A path whose searches run past the
        displacement limit while its curve still rose is a corner too. 0: such stops are
        checked as any other, so a singular tangent skips the check
        (``stop_check_time_steps`` = 0 disables both).
    fold_probe_every: while a check (or a rescue) relaxes, Newton is tried at its target
        from the relaxation's state at the first peak of the kinetic energy at least this
        many time steps after the last try; a converged search ends the relaxation (Newton
        finds the equilibrium long before the motion dies out). 0: the relaxation runs to
        its own tolerance.
    fold_creep_cos: while such a check relaxes, the motion along its creep (the mean state
        at the kinetic-energy peaks, from one probe's time to the next) is not damped once
        two successive creeps point the same way, their mass-weighted cosine above this:
        kinetic damping kills a slow mode's velocity at every peak of the fast ones, and a
        wall snapping through to a fold's rest moves along such a mode. 0: every velocity
        is zeroed at each peak, as before. Needs ``fold_probe_every`` (its windows).
    max_control_cuts: displacement control gives up after this many halvings in a row.

    Certificate of a collapse (see :mod:`masonry_dem.solvers.static.certificate`)
    ----------------------------------------------------------------------------
    certify: check a collapse before reporting it: the instability rule (the reference's
        damped motion at (1 + ``bracket_tolerance``) lambda from the last state, which sends
        the load on where it finds rest; not with ``refine`` False) and the certificate
        (False: the stop of the path is reported as a collapse, unchecked).
    admissible_tolerance: the last state's actions may exceed the strength domain by this
        fraction of the capacity (round-off of the return).
    mode_stiffness: the tangent of the last state is singular along the live load's mode
        when its current stiffness parameter (Bergan) F_L.K_el^-1 F_L / F_L.K_t^-1 F_L is
        at most this.
    mode_displacement: the pushover curve is flat or falling over a stated displacement
        when the work-conjugate displacement past the peak is at least this fraction of
        the displacement at the peak (both from the dead-load state).
    bound_tolerance: lambda may exceed the associative limit-analysis bound (when one is
        given) by this fraction (the bound's own discretisation and solver tolerance).

    The corner check (docs/history/solvers_record.md, "The corner check, implicit")
    ---------------------------------------------------------------
    The check at a corner tells a fold from a peak:
    :meth:`~masonry_dem.solvers.static.relaxations.Relaxations.implicit_relaxation` first
    (linearly implicit Euler steps of the overdamped motion D dq/dt = R(q), D the joints'
    elastic stiffness, one factorization each, to the same target lambda x (1 +
    transient_rise) from the same state). Its motion running past the displacement limit is
    a peak, with no time step of dynamic relaxation (a peak's explicit relaxation stalls for
    its whole budget). Rest is a fold: the path goes on from the rest dynamic relaxation
    finds, or from the implicit one's where that finds none. That relaxation is given the
    check's own effort at the rate the two budgets are set by, ``fold_check_time_steps`` x
    (implicit steps taken / ``corner_check_steps``) (docs/history/solvers_record.md, "The cost of
    passing a fold"). No verdict within ``corner_check_steps`` (a slow fold): dynamic relaxation of
    ``fold_check_time_steps`` decides. A pseudo-transient step (the same overdamped motion)
    whose motion ran past the displacement limit toward lambda T answers every later check
    or pseudo-transient step of the same branch whose target is T or more: no rest
    (docs/history/solvers_record.md, "The endgame at the peak").
    corner_check_steps: budget of implicit steps (factorizations) of that check, the most a
        check without a verdict costs before dynamic relaxation decides. 500: about what the
        fallback's budget costs (``fold_check_time_steps`` of dynamic relaxation at the
        13-29 time steps a factorization costs), so a slow fold is given the same effort by
        the check that decides it best; a smaller budget hands slow folds to dynamic
        relaxation, which may find no rest and call them peaks. A check that creeps is given
        no verdict from its pace (docs/history/solvers_record.md, "A motion that creeps").
    corner_check_rise: an implicit step whose residual is more than (1 + this) times the
        last one's is too long (it crossed kinks of the law the tangent did not see): it is
        taken again with a time step a quarter as long, down to the elastic relaxation
        time (D = the elastic stiffness), which is always taken, the residual may rise on
        the way (a wall snapping through is out of balance until it arrives).
    corner_check_start: the first implicit step's D / dt in units of the joints' elastic
        stiffness (a pseudo time step of 1 / this elastic relaxation times); halved after
        each step taken, so the steps grow towards Newton's as the wall settles.

    The step near the peak (docs/history/solvers_record.md, "The step near the peak")
    ------------------------------------------------------------------
    On a curve whose slope fades (a mechanism that forms joint by joint) the path stops three
    steps after the slope fell below ``flat_slope`` and reports the highest lambda reached;
    the paths of all step lengths coincide, and the answer moves with the steps only
    because the steps that prove the stop also gain load.
    tail_resolution: the most a work step may gain, as a fraction of lambda, at the slope
        of the stop (``flat_slope`` of the elastic slope), and at the displacement limit at
        the last step's slope: each step is at most ``tail_resolution`` / ``flat_slope``
        times the elastic displacement at lambda (``steps.tail_cap``). The default 1e-3,
        equal to ``flat_slope``'s, makes the cap the elastic displacement at lambda itself,
        which the steps of a rising path do not reach: it binds only in the tail, and the
        answer no longer moves with ``growth``. 0: off (steps grow by ``growth`` without a
        bound).
    """

    easy_iterations: int = count(6, least=0)
    continuation: Continuation = choice("work", CONTINUATION)
    secant_predictor: bool = True
    elastic_first_step: bool = True
    tolerance: float = positive(1e-8)
    control_tolerance: float = positive(1e-6)
    max_iterations: int = count(40, least=1)
    residual_stiffness: float = positive(1e-9)
    tangent: TangentMethod = choice("analytic", TANGENT_METHODS)
    stall_window: int = count(8, least=1)
    stall_decrease: float = positive(0.5)
    max_floor: float = positive(1e-3)
    chord_ratio: float = positive(0.25)
    creep: float = finite(1e-3)
    search_cuts: int = count(7, least=1)
    trust_seed: float = positive(0.05)
    radius_floor: float = positive(1e-9)
    max_cuts: int = count(10, least=0)
    limit_cuts: int = count(2, least=0)
    flat_slope: float = finite(1e-3)
    resume_step: float = positive(0.5)
    fold_match: float = finite(1e-3)
    transient_steps: int = count(100, least=0)
    transient_after: int = count(2, least=0)
    transient_rise: float = positive(0.005)
    transient_reach: float = at_least(0.1, 0.0, " (0: off)")
    transient_start: float = positive(1e-3)
    transient_shrink: float = positive(0.25)
    transient_window: int = count(30, least=1)
    zero_load_robust_iterations: int = count(2000, least=0)
    anderson: int = count(5, least=1)
    divergence_window: int = count(30, least=1)
    stop_check_time_steps: int = count(4000, least=0)
    fold_check_time_steps: int = count(20_000, least=0)
    fold_probe_every: int = count(500, least=0)
    fold_creep_cos: float = at_least(0.95, 0.0, " (0: off)")
    max_control_cuts: int = count(12, least=0)
    certify: bool = True
    admissible_tolerance: float = positive(1e-6)
    mode_stiffness: float = positive(0.05)
    mode_displacement: float = positive(0.5)
    bound_tolerance: float = positive(0.01)
    corner_check_steps: int = count(500, least=1)
    corner_check_rise: float = positive(0.5)
    corner_check_start: float = positive(1e-2)
    # the step near the peak
    tail_resolution: float = at_least(1e-3, 0.0, " (0: off)")


SETTING_NAMES = tuple(f.name for f in fields(StaticSettings))


@dataclass(frozen=True)
class DisplacementControl:
    """Drive DOF ``dof`` (name, e.g. ``u3``) of ``block`` to ``target`` in ``steps`` steps."""

    block: int
    dof: DofName
    target: float
    steps: int = 50

    def __post_init__(self) -> None:
        if not is_count(self.block, 0):
            raise ValueError(f"block must be an integer >= 0, got {self.block!r}")
        check_choice("dof", self.dof, get_args(DofName))
        if not is_number(self.target) or not math.isfinite(self.target) or self.target == 0:
            raise ValueError(f"target must be a finite number other than 0, got {self.target!r}")
        if not is_count(self.steps, 1):
            raise ValueError(f"steps must be an integer >= 1, got {self.steps!r}")
