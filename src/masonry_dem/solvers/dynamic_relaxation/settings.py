"""Settings and statistics of dynamic relaxation: every knob that steers a run
(:class:`DRSettings`, with the choices as ``Literal`` types) and what a run cost
(:class:`DRStats`). Why each default has its value: docs/history/solvers_record.md, "Dynamic
relaxation: what it does and its defaults"."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, get_args

from masonry_dem._docstrings import fill
from masonry_dem._validation import choice, count, positive, positive_or_none
from masonry_dem.solvers.load_path import DOCS, LoadPathSettings

MassRule = Literal["stiffness", "density"]
TimeStepRule = Literal["gershgorin", "power"]
Damping = Literal["kinetic", "viscous"]
Loading = Literal["steps", "ramp"]
OnBlowup = Literal["cut", "refuse"]
Stability = Literal["elastic", "current"]


@fill(DOCS)
@dataclass(frozen=True)
class DRSettings(LoadPathSettings):
    """Knobs of dynamic relaxation.

    Why each default has its value: docs/history/solvers_record.md, "Dynamic relaxation: what
    it does and its defaults". The load path's fields (steps, bracket, caps: ``initial_step``
    to ``displacement_limit``) are those of
    :class:`~masonry_dem.solvers.load_path.LoadPathSettings`, as in
    :class:`~masonry_dem.solvers.static.settings.StaticSettings`; only ``max_step`` has its
    own default here. A value out of range is refused at construction, by the field's name.

    Parameters
    ----------
    initial_step : float, default 0.02
        The first lambda increment, in load scales ``|F_D| / |F_L|``, > 0.
    max_step : float, default 0.2
        The largest lambda increment of a load step (shorter than the static solver's: each
        step is relaxed from the last converged state), > 0.
    %(load_path_fields)s
    mass : {"stiffness", "density"}, default "stiffness"
        ``"stiffness"`` (M_ii from the rows of the elastic K: the stable step is 2 on every
        wall) or ``"density"`` (the blocks' masses and inertias, one common factor).
    dt_rule : {"gershgorin", "power"}, default "gershgorin"
        How the stability limit 2 / sqrt(lambda_max(M^-1 K)) is estimated: ``"gershgorin"``
        (a bound, never under) or ``"power"`` (power iterations, 5 % margin).
    dt_fraction : float, default 0.9
        The time step as a fraction of that limit, > 0.
    dt : float, optional
        The time step by hand, finite and > 0 (None: from ``dt_rule`` and ``dt_fraction``).
    stability : {"elastic", "current"}, default "elastic"
        The stiffness the limit is taken from: ``"elastic"`` (bounds every state of the law)
        or ``"current"`` (the secant stiffness of the last converged state).
    damping : {"kinetic", "viscous"}, default "kinetic"
        ``"kinetic"`` (velocities zeroed at each peak of the kinetic energy) or ``"viscous"``
        (Underwood's adaptive C = 2 xi omega_min M).
    viscous_ratio : float, default 1.0
        xi of the viscous damping, as a fraction of critical, > 0.
    loading : {"steps", "ramp"}, default "steps"
        ``"steps"`` (load steps relaxed one by one, as in the static solver) or ``"ramp"``
        (lambda grows continuously, then the passed states are verified).
    ramp_rate : float, default 2e-4
        lambda, in load scales, per unit of pseudo time of the ramp (the stable step is 2),
        > 0.
    check_every : int, default 25
        The ramp offers a state for verification every ``check_every`` time steps when its
        relative residual is at most ``ramp_tolerance``; >= 1.
    ramp_tolerance : float, default 0.01
        See ``check_every``; > 0.
    tolerance : float, default 1e-4
        A relaxation is at rest when its relative residual is at most ``tolerance`` and its
        kinetic energy at most ``energy_tolerance`` times its peak; > 0.
    energy_tolerance : float, default 1e-6
        See ``tolerance``; > 0.
    max_cycles : int, default 400000
        The most time steps one relaxation may take while its residual keeps halving (near a
        peak one load step can need 1e5 time steps; one that stops converging ends earlier,
        by the stall test); >= 1.
    stall_factor : float, default 5.0
        A relaxation whose residual does not halve within ``stall_factor`` times the time
        steps of the slowest converged one (at least ``min_stall_window``) has stalled: a
        mechanism, or too close to one to settle; > 0.
    min_stall_window : int, default 200
        See ``stall_factor``; >= 1.
    max_time_steps : int, default 2000000
        Time steps of the whole run; spent, the run ends ``failed``. >= 1.
    on_blowup : {"cut", "refuse"}, default "cut"
        A time step found above the stability limit is ``"cut"`` (halved, and the relaxation
        repeated from its start) or ends the run (``"refuse"``).
    max_cuts : int, default 6
        The most halvings of the time step in one run, >= 0.
    blowup_patience : int, default 5
        Steps above the stability limit that end a relaxation, >= 1.
    power_iterations : int, default 30
        Iterations of ``dt_rule="power"``, >= 1.
    compiled_steps : bool, default True
        The time steps of kinetic damping at a fixed load run in one compiled function (the
        same bits as the Python loop, which False selects; docs/history/solvers_record.md,
        "One compiled time step").

    %(field_errors)s

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.DRSettings(damping="viscous").max_step
    0.2
    """

    max_step: float = positive(0.2)
    mass: MassRule = choice("stiffness", get_args(MassRule))
    dt_rule: TimeStepRule = choice("gershgorin", get_args(TimeStepRule))
    dt_fraction: float = positive(0.9)
    dt: float | None = positive_or_none(finite=True)
    stability: Stability = choice("elastic", get_args(Stability))
    damping: Damping = choice("kinetic", get_args(Damping))
    viscous_ratio: float = positive(1.0)
    loading: Loading = choice("steps", get_args(Loading))
    ramp_rate: float = positive(2e-4)
    check_every: int = count(25, least=1)
    ramp_tolerance: float = positive(1e-2)
    tolerance: float = positive(1e-4)
    energy_tolerance: float = positive(1e-6)
    # a relaxation that keeps halving its residual may run this long (near a peak one load
    # step can need 1e5 time steps); one that stops converging ends earlier, by the stall test
    max_cycles: int = count(400_000, least=1)
    stall_factor: float = positive(5.0)
    min_stall_window: int = count(200, least=1)
    max_time_steps: int = count(2_000_000, least=1)
    on_blowup: OnBlowup = choice("cut", get_args(OnBlowup))
    max_cuts: int = count(6, least=0)
    blowup_patience: int = count(5, least=1)
    power_iterations: int = count(30, least=1)
    compiled_steps: bool = True


@dataclass
class DRStats:
    """What a run cost: time steps, law evaluations, cuts of the step, estimates of the limit."""

    time_steps: int = 0
    law_evaluations: int = 0
    kinetic_resets: int = 0
    cuts: int = 0
    dt: float = 0.0
    dt_limit: float = 0.0
    lambda_max: float = 0.0
    courant: float = 0.0  # largest omega^2 dt^2 met (central differences are stable below 4)
    events: list[str] = field(default_factory=list)
