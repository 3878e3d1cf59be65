"""Settings of the static solver: every number that steers it, with why it has its value
(the measurements behind each are in docs/solvers.md, "Settings and their evidence")."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal, get_args

from masonry_dem._validation import (
    check_count_fields,
    check_load_path_fields,
    check_positive_fields,
)
from masonry_dem.constitutive.law import TANGENT_METHODS, Memory, TangentMethod, Tension
from masonry_dem.model import DofName, check_choice, deprecated_law_option

#: what follows the first failure of load control (see ``StaticSettings.continuation``)
Continuation = Literal["work", "bracket"]
CONTINUATION: tuple[str, ...] = get_args(Continuation)


@dataclass(frozen=True)
class StaticSettings:
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
        law at one lambda (a wall with openings: 0.085 -> 0.111; docs/solvers.md, "Steps
        of the path").
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
    limit_elastic_multiple: along the path the limit is at least this multiple of the
        largest displacement under the dead load (0: off, the default). Off, because a limit
        that grows with 1 / kn lets a soft wall go past half a block, which is neither the
        model's small-displacement range nor invariant with kn (docs/solvers.md,
        "Invariance"); a path that leaves that range on a rising curve fails with that reason.
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
    transient_start, transient_shrink, transient_window: first pseudo time step 1 /
        ``transient_start`` (the tangent's floor, in units of the elastic stiffness), divided
        by ``transient_shrink`` beyond the residual ratio after a step that lowers the
        residual; it gives up when the residual has not halved in ``transient_window`` steps.

    Other strategies (off by default, or checks)
    --------------------------------------------
    robust_iterations: budget of initial-stiffness iterations with Anderson acceleration
        that re-try a failed load step; 0 disables it.
    anderson, divergence_window: the robust iterations mix the last ``anderson``
        corrections and stop when the residual has not fallen x10 in ``divergence_window``
        iterations with corrections that do not shrink.
    zero_load_robust_iterations: the robust re-try's budget where load control has halved
        its step down to what the residual cannot tell from zero load (100 x ``tolerance``
        load scales) and ``robust_iterations`` is 0: Newton stalls from the dead-load state
        of in-plane walls held on one edge (a held 9 x 3 wall: 1e-8 -> 0.93).
    rescue_time_steps: budget of a dynamic relaxation of a failed load step; 0 disables it.
    stop_check_time_steps: budget of the dynamic relaxation that checks a stop of work
        control (to lambda x (1 + transient_rise)) before the path is given up; 0 disables it.
        The relaxation ends sooner when the wall runs past the displacement limit or its
        residual has not halved in a quarter of the budget.
    stop_check_singular: run that check also where the tangent of the stuck state is
        singular along the load. A fold of the path has such a tangent as well as a peak,
        and only the check tells them apart; with a budget that covers a fold's settling
        the path passes folds the default certifies as collapses, at the price of a
        relaxation of the whole wall at every such stop (measured in docs/solvers.md, "The
        stop check: folds and peaks"). Off by default for that price.
    max_control_cuts: displacement control gives up after this many halvings in a row.

    Certificate of a collapse (see :mod:`masonry_dem.solvers.static.certificate`)
    ----------------------------------------------------------------------------
    certify: check a collapse before reporting it (False: the stop of the path is reported
        as a collapse, unchecked, as before the certificate existed).
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
    """

    initial_step: float = 0.02
    max_step: float = 1.0
    growth: float = 1.5
    easy_iterations: int = 6
    bracket_tolerance: float = 0.005
    refine: bool = True
    max_steps: int = 1000
    max_load_factor: float = math.inf
    continuation: Continuation = "work"
    secant_predictor: bool = True
    elastic_first_step: bool = True
    tolerance: float = 1e-8
    control_tolerance: float = 1e-6
    max_iterations: int = 40
    displacement_limit: float | None = None
    limit_elastic_multiple: float = 0.0
    residual_stiffness: float = 1e-9
    tangent: TangentMethod = "analytic"
    tension: Tension | None = None
    memory: Memory | None = None
    stall_window: int = 8
    stall_decrease: float = 0.5
    max_floor: float = 1e-3
    chord_ratio: float = 0.25
    creep: float = 1e-3
    search_cuts: int = 7
    trust_seed: float = 0.05
    radius_floor: float = 1e-9
    max_cuts: int = 10
    limit_cuts: int = 2
    flat_slope: float = 1e-3
    resume_step: float = 0.5
    fold_match: float = 1e-3
    transient_steps: int = 100
    transient_after: int = 2
    transient_rise: float = 0.005
    transient_start: float = 1e-3
    transient_shrink: float = 0.25
    transient_window: int = 30
    robust_iterations: int = 0
    zero_load_robust_iterations: int = 2000
    anderson: int = 5
    divergence_window: int = 30
    rescue_time_steps: int = 0
    stop_check_time_steps: int = 4000
    stop_check_singular: bool = False
    max_control_cuts: int = 12
    certify: bool = True
    admissible_tolerance: float = 1e-6
    mode_stiffness: float = 0.05
    mode_displacement: float = 0.5
    bound_tolerance: float = 0.01

    def __post_init__(self) -> None:
        check_load_path_fields(self)
        positive = (
            "tolerance",
            "control_tolerance",
            "residual_stiffness",
            "max_floor",
            "chord_ratio",
            "transient_rise",
            "transient_start",
            "transient_shrink",
            "resume_step",
            "stall_decrease",
            "trust_seed",
            "radius_floor",
            "admissible_tolerance",
            "mode_stiffness",
            "mode_displacement",
            "bound_tolerance",
        )
        check_positive_fields(self, positive)
        counts = {
            "max_iterations": 1,
            "easy_iterations": 0,
            "stall_window": 1,
            "search_cuts": 1,
            "max_cuts": 0,
            "limit_cuts": 0,
            "transient_steps": 0,
            "transient_after": 0,
            "transient_window": 1,
            "robust_iterations": 0,
            "zero_load_robust_iterations": 0,
            "anderson": 1,
            "divergence_window": 1,
            "rescue_time_steps": 0,
            "stop_check_time_steps": 0,
            "max_control_cuts": 0,
        }
        check_count_fields(self, counts)
        for name in ("creep", "flat_slope", "fold_match"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise ValueError(f"{name} must be a finite number, got {value!r}")
        if not (
            isinstance(self.limit_elastic_multiple, (int, float))
            and math.isfinite(self.limit_elastic_multiple)
            and self.limit_elastic_multiple >= 0
        ):
            raise ValueError(
                "limit_elastic_multiple must be a number >= 0 (0: off), got "
                f"{self.limit_elastic_multiple!r}"
            )
        deprecated_law_option("StaticSettings", "tension", self.tension)
        deprecated_law_option("StaticSettings", "memory", self.memory)
        check_choice("tangent", self.tangent, TANGENT_METHODS)
        check_choice("continuation", self.continuation, CONTINUATION)


SETTING_NAMES = tuple(f.name for f in fields(StaticSettings))


@dataclass(frozen=True)
class DisplacementControl:
    """Drive DOF ``dof`` (name, e.g. ``u3``) of ``block`` to ``target`` in ``steps`` steps."""

    block: int
    dof: DofName
    target: float
    steps: int = 50
