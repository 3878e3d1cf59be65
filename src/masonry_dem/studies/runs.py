"""The methods a study compares, run and timed one way: :class:`Method`, :func:`run_method`
(one timed run and what it cost), the study cases (:func:`load_study_case`) and
:func:`warm_up`, which loads the compiled law before anything is timed.

Settings of each method: :class:`~masonry_dem.solvers.incremental.StaticSettings`,
:class:`~masonry_dem.solvers.dynamic_relaxation.DRSettings`, and for limit analysis the
keyword arguments of :func:`masonry_dem.solvers.limit_analysis.limit_analysis` (a dict).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from enum import Enum
from typing import Any

import numpy as np

from masonry_dem.analysis import collapse_lambda as collapse_lambda
from masonry_dem.model import Model
from masonry_dem.results import History

#: initial and largest load step of the Table 3 cases, in load scales
PRESSURE_STEPS = (1.0, 4.0)
#: step-size knobs copied from a case's static settings into DR (the same load stepping)
SHARED_STEPPING = (
    "initial_step",
    "max_step",
    "growth",
    "max_load_factor",
    "displacement_limit",
    "tension",
)


class Method(str, Enum):
    """A method of finding the collapse multiplier (``str``: compares and dumps as its value)."""

    STATIC = "static"
    DYNAMIC_RELAXATION = "dynamic_relaxation"
    LIMIT_ANALYSIS = "limit_analysis"

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)

    @property
    def short(self) -> str:
        """The name in a table column."""
        return {"static": "static", "dynamic_relaxation": "DR", "limit_analysis": "LA"}[self.value]

    @classmethod
    def parse(cls, text: str) -> Method:
        """The method named ``text``; a ValueError naming the allowed values otherwise."""
        try:
            return cls(text)
        except ValueError:
            allowed = ", ".join(m.value for m in cls)
            raise ValueError(f"method must be one of {allowed}, got {text!r}") from None


@dataclass(frozen=True)
class Timed:
    """One timed run: ``load_factor`` is the collapse multiplier (None unless ``status`` is
    ``collapse``), ``cost`` the work (Newton iterations and factorizations, time steps, or
    the convex solves of limit analysis), ``history`` the path (static and DR only)."""

    method: Method
    status: str
    reason: str
    load_factor: float | None
    seconds: float
    cost: dict[str, int] = field(default_factory=dict)
    history: History | None = None
    bound: str | None = None  # limit analysis: "upper" or "estimate"


@dataclass(frozen=True)
class StudyCase:
    name: str
    model: Model
    reference: float | None  # the test value (Table 1: the FEM's)
    static: Any  # StaticSettings of the case
    unit: str = "lambda"


def load_study_case(name: str) -> StudyCase:
    """A validation case of :mod:`masonry_dem.cases.paper`; ``default`` is the bundled wall."""
    if name == "default":
        from masonry_dem.cases.casefile import load_case

        case = load_case()
        return StudyCase("default", case.model, None, case.settings)
    from masonry_dem.cases.paper import build_case
    from masonry_dem.solvers.incremental import StaticSettings

    pc = build_case(name)
    settings = pc.settings
    default = StaticSettings()
    if pc.unit == "Pa" and (settings.initial_step, settings.max_step) == (
        default.initial_step,
        default.max_step,
    ):
        # pressure cases collapse at ~30 load scales (|F_D| / |F_L| = weight per unit of
        # pressure): default steps would take ~150 of them; the refined bracket does not
        # depend on the steps, so both methods start with larger ones here
        settings = replace(settings, initial_step=PRESSURE_STEPS[0], max_step=PRESSURE_STEPS[1])
    return StudyCase(pc.name, pc.model, float(pc.reference), settings, pc.unit)


def with_changes(base: Any, changes: dict[str, Any]) -> Any:
    """``base`` settings with ``changes``: a dataclass (an unknown knob is a TypeError naming
    it) or the keyword dict of limit analysis."""
    if isinstance(base, dict):
        return {**base, **changes}
    return replace(base, **changes)


def dr_settings_like(static: Any) -> Any:
    """Dynamic-relaxation settings with the load stepping of the static ``static``."""
    from masonry_dem.solvers.dynamic_relaxation import DRSettings

    shared = {k: getattr(static, k) for k in SHARED_STEPPING if hasattr(static, k)}
    return replace(DRSettings(), **shared)


def settings_for(method: Method, static: Any) -> Any:
    """The base settings of ``method`` on a case whose static settings are ``static``."""
    if method is Method.STATIC:
        return static
    if method is Method.DYNAMIC_RELAXATION:
        return dr_settings_like(static)
    if method is Method.LIMIT_ANALYSIS:
        return {}
    raise ValueError(f"unknown method {method!r}")


def relative_error(value: float | None, ref: float | None) -> float | None:
    if value is None or ref is None or ref == 0:
        return None
    return abs(value - ref) / abs(ref)


def run_method(method: Method, model: Model, settings: Any) -> Timed:
    """One run of ``method`` on ``model`` through :func:`masonry_dem.analyze`, timed (wall
    clock) around it (the collapse mechanism, computed on first use, left out)."""
    from masonry_dem.analysis import analyze

    method = Method(method)
    t0 = time.perf_counter()
    result = analyze(model, method.value, settings)
    seconds = time.perf_counter() - t0
    return Timed(
        method,
        result.status,
        result.reason,
        result.load_factor,
        seconds,
        result.cost,
        result.history,
        bound=result.bound,
    )


def warm_up(limit: bool = False) -> None:
    """Load the compiled interface law (numba's on-disk cache: about 0.4 s once per process)
    with both incremental solvers on one block, so that the first timed run does not pay
    for it; ``limit``: also both backends of limit analysis (their imports)."""
    from masonry_dem.analysis import analyze
    from masonry_dem.geometry import builders
    from masonry_dem.model import InterfaceMaterial, SelfWeight, Support, WeightProportional
    from masonry_dem.solvers.dynamic_relaxation import DRSettings

    blocks, base = builders.add_base(builders.single_block(0.2, 0.3, 0.1, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(1e9, 4e8, 0.7),
        [Support(np.array([base]))],
        [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )
    analyze(model, "pushover")
    analyze(model, "relaxation", DRSettings(bracket_tolerance=0.05))
    if limit:
        for backend in ("highs", "clarabel"):
            analyze(model, "limit", {"backend": backend})
