"""Settings and statistics of dynamic relaxation: every knob that steers a run
(:class:`DRSettings`, with the choices as ``Literal`` types) and what a run cost
(:class:`DRStats`). Why each default has its value: docs/solvers.md."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, get_args

from masonry_dem._validation import (
    check_count_fields,
    check_load_path_fields,
    check_positive_fields,
)
from masonry_dem.constitutive.law import Memory, Tension
from masonry_dem.model import check_choice, deprecated_law_option

MassRule = Literal["stiffness", "density"]
TimeStepRule = Literal["gershgorin", "power"]
Damping = Literal["kinetic", "viscous"]
Loading = Literal["steps", "ramp"]
OnBlowup = Literal["cut", "refuse"]
Stability = Literal["elastic", "current"]

_CHOICES: dict[str, tuple[str, ...]] = {
    "mass": get_args(MassRule),
    "dt_rule": get_args(TimeStepRule),
    "damping": get_args(Damping),
    "loading": get_args(Loading),
    "on_blowup": get_args(OnBlowup),
    "stability": get_args(Stability),
}


@dataclass(frozen=True)
class DRSettings:
    """Knobs of dynamic relaxation (defaults: see docs/solvers.md for why).

    Load steps are in units of the load scale |F_D| / |F_L| (1 for a tilt table), as in
    :class:`~masonry_dem.solvers.incremental.StaticSettings`; ``ramp_rate`` is lambda (in load
    scales) per unit of pseudo time (the stiffness-scaled stable step is 2).
    """

    mass: MassRule = "stiffness"
    dt_rule: TimeStepRule = "gershgorin"
    dt_fraction: float = 0.9
    dt: float | None = None
    stability: Stability = "elastic"
    damping: Damping = "kinetic"
    viscous_ratio: float = 1.0
    loading: Loading = "steps"
    ramp_rate: float = 2e-4
    check_every: int = 25
    ramp_tolerance: float = 1e-2
    tolerance: float = 1e-4
    energy_tolerance: float = 1e-6
    # a relaxation that keeps halving its residual may run this long (near a peak one load
    # step can need 1e5 time steps); one that stops converging ends earlier, by the stall test
    max_cycles: int = 400_000
    stall_factor: float = 5.0
    min_stall_window: int = 200
    initial_step: float = 0.02
    max_step: float = 0.2
    growth: float = 1.5
    bracket_tolerance: float = 0.005
    refine: bool = True
    max_steps: int = 1000
    max_load_factor: float = math.inf
    displacement_limit: float | None = None
    tension: Tension | None = None  # deprecated: InterfaceMaterial(tension=...)
    memory: Memory | None = None  # deprecated: InterfaceMaterial(memory=...)
    max_time_steps: int = 2_000_000
    on_blowup: OnBlowup = "cut"
    max_cuts: int = 6
    blowup_patience: int = 5
    power_iterations: int = 30

    def __post_init__(self) -> None:
        deprecated_law_option("DRSettings", "tension", self.tension)
        deprecated_law_option("DRSettings", "memory", self.memory)
        for name, allowed in _CHOICES.items():
            check_choice(name, getattr(self, name), allowed)
        check_load_path_fields(self)
        check_positive_fields(
            self,
            (
                "dt_fraction",
                "viscous_ratio",
                "ramp_rate",
                "tolerance",
                "energy_tolerance",
                "ramp_tolerance",
                "stall_factor",
            ),
        )
        if self.dt is not None:
            check_positive_fields(self, ("dt",))
        check_count_fields(
            self,
            {
                "max_cycles": 1,
                "check_every": 1,
                "blowup_patience": 1,
                "min_stall_window": 1,
                "max_cuts": 0,
                "power_iterations": 1,
            },
        )


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
