"""Settings and statistics of dynamic relaxation: every knob that steers a run
(:class:`DRSettings`, with the choices as ``Literal`` types) and what a run cost
(:class:`DRStats`). Why each default has its value: docs/solvers.md."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, get_args

from masonry_dem._validation import choice, count, positive, positive_or_none
from masonry_dem.solvers.load_path import LoadPathSettings

MassRule = Literal["stiffness", "density"]
TimeStepRule = Literal["gershgorin", "power"]
Damping = Literal["kinetic", "viscous"]
Loading = Literal["steps", "ramp"]
OnBlowup = Literal["cut", "refuse"]
Stability = Literal["elastic", "current"]


@dataclass(frozen=True)
class DRSettings(LoadPathSettings):
    """Knobs of dynamic relaxation (defaults: see docs/solvers.md for why).

    The load path's fields (steps, bracket, caps) are those of
    :class:`~masonry_dem.solvers.load_path.LoadPathSettings`, as in
    :class:`~masonry_dem.solvers.incremental.StaticSettings`, with a shorter ``max_step``;
    ``ramp_rate`` is lambda (in load scales) per unit of pseudo time (the stiffness-scaled
    stable step is 2).
    """

    max_step: float = positive(0.2)  # redeclared with its own default (the base's is 1.0)
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
    max_time_steps: int = 2_000_000
    on_blowup: OnBlowup = choice("cut", get_args(OnBlowup))
    max_cuts: int = count(6, least=0)
    blowup_patience: int = count(5, least=1)
    power_iterations: int = count(30, least=1)


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
