"""masonry_dem: nonlinear 3D discrete element analysis of masonry walls (Baraldi & Cecchi).

The data flow is the folder layout (docs/architecture.md): ``geometry`` (blocks, builders,
contacts) -> ``model`` (materials, supports, loads) -> ``assembly`` (H, Kbar, K) ->
``solvers`` (linear, static incremental, dynamic relaxation, limit analysis) with the
interface law of ``constitutive`` -> ``results`` -> ``export`` (VTU/PVD, renders, ParaView
states). This namespace is the public API; each name is imported on first use, so importing
the package costs milliseconds, not the 1.4 s of numpy, scipy and numba, and the command line
handles Ctrl-C before any heavy import starts.

Importing the package changes no environment variable: a script that runs long analyses
calls :func:`set_thread_wait_policy` first (the command line does).
"""

from __future__ import annotations

from importlib import import_module
from types import ModuleType
from typing import TYPE_CHECKING, Any

from masonry_dem._lazy import lazy_names

if TYPE_CHECKING:
    from masonry_dem._threads import set_thread_wait_policy
    from masonry_dem.analysis import analyze
    from masonry_dem.cases.casefile import Case, load_case
    from masonry_dem.export.analyses import pushover, relax
    from masonry_dem.geometry import selectors as select
    from masonry_dem.geometry.blocks import Blocks
    from masonry_dem.geometry.builders import (
        add_base,
        add_top_beam,
        boxes,
        cut_openings,
        running_bond_wall,
        running_bond_wall_of_size,
        single_block,
        stack_bond_column,
    )
    from masonry_dem.geometry.interfaces import detect_interfaces, subdivide_interfaces
    from masonry_dem.geometry.plans import box_wall, l_wall, t_wall, u_wall
    from masonry_dem.geometry.specimens import shear_wall, split_units
    from masonry_dem.mechanism import collapse_mode
    from masonry_dem.model import (
        InterfaceMaterial,
        Model,
        PointLoad,
        Pressure,
        SelfWeight,
        Support,
        WeightProportional,
    )
    from masonry_dem.results import (
        AnalysisResult,
        History,
        Observer,
        Status,
        StepResult,
        StopReason,
    )
    from masonry_dem.solvers.dynamic_relaxation import DRSettings
    from masonry_dem.solvers.incremental import DisplacementControl, StaticSettings
    from masonry_dem.solvers.limit_analysis import (
        LimitAnalysisResult,
        LimitSettings,
        limit_analysis,
    )
    from masonry_dem.solvers.linear import solve_linear
    from masonry_dem.solvers.quasi_static import QuasiStaticSettings, quasi_static
    from masonry_dem.solvers.static.stages import Stage
    from masonry_dem.studies.sweep import sweep

from masonry_dem._version import __version__ as __version__

#: public names imported on first use: name -> module
_LAZY = {
    "set_thread_wait_policy": "masonry_dem._threads",
    "Blocks": "masonry_dem.geometry.blocks",
    **dict.fromkeys(
        (
            "add_base",
            "add_top_beam",
            "boxes",
            "cut_openings",
            "running_bond_wall",
            "running_bond_wall_of_size",
            "single_block",
            "stack_bond_column",
        ),
        "masonry_dem.geometry.builders",
    ),
    "detect_interfaces": "masonry_dem.geometry.interfaces",
    "subdivide_interfaces": "masonry_dem.geometry.interfaces",
    **dict.fromkeys(("box_wall", "l_wall", "t_wall", "u_wall"), "masonry_dem.geometry.plans"),
    **dict.fromkeys(("shear_wall", "split_units"), "masonry_dem.geometry.specimens"),
    **dict.fromkeys(
        (
            "InterfaceMaterial",
            "Model",
            "PointLoad",
            "Pressure",
            "SelfWeight",
            "Support",
            "WeightProportional",
        ),
        "masonry_dem.model",
    ),
    "History": "masonry_dem.results",
    "Observer": "masonry_dem.results",
    "StepResult": "masonry_dem.results",
    "DisplacementControl": "masonry_dem.solvers.incremental",
    "StaticSettings": "masonry_dem.solvers.incremental",
    "pushover": "masonry_dem.export.analyses",
    "solve_linear": "masonry_dem.solvers.linear",
    "Status": "masonry_dem.results",
    "StopReason": "masonry_dem.results",
    "Case": "masonry_dem.cases.casefile",
    "load_case": "masonry_dem.cases.casefile",
    "collapse_mode": "masonry_dem.mechanism",
    "DRSettings": "masonry_dem.solvers.dynamic_relaxation",
    "relax": "masonry_dem.export.analyses",
    "LimitAnalysisResult": "masonry_dem.solvers.limit_analysis",
    "LimitSettings": "masonry_dem.solvers.limit_analysis",
    "analyze": "masonry_dem.analysis",
    "AnalysisResult": "masonry_dem.results",
    "limit_analysis": "masonry_dem.solvers.limit_analysis",
    "QuasiStaticSettings": "masonry_dem.solvers.quasi_static",
    "quasi_static": "masonry_dem.solvers.quasi_static",
    "sweep": "masonry_dem.studies.sweep",
    "Stage": "masonry_dem.solvers.static.stages",
}
_names = lazy_names(__name__, _LAZY)


def __getattr__(name: str) -> Any:
    if name == "select":  # a module, not a name defined in one
        module: ModuleType = import_module("masonry_dem.geometry.selectors")
        globals()["select"] = module
        return module
    return _names(name)


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


__all__ = [
    "AnalysisResult",
    "Blocks",
    "Case",
    "DRSettings",
    "DisplacementControl",
    "History",
    "InterfaceMaterial",
    "LimitAnalysisResult",
    "LimitSettings",
    "Model",
    "Observer",
    "PointLoad",
    "Pressure",
    "QuasiStaticSettings",
    "SelfWeight",
    "Stage",
    "StaticSettings",
    "Status",
    "StepResult",
    "StopReason",
    "Support",
    "WeightProportional",
    "add_base",
    "add_top_beam",
    "analyze",
    "box_wall",
    "boxes",
    "collapse_mode",
    "cut_openings",
    "detect_interfaces",
    "l_wall",
    "limit_analysis",
    "load_case",
    "pushover",
    "quasi_static",
    "relax",
    "running_bond_wall",
    "running_bond_wall_of_size",
    "select",
    "set_thread_wait_policy",
    "shear_wall",
    "single_block",
    "solve_linear",
    "split_units",
    "stack_bond_column",
    "subdivide_interfaces",
    "sweep",
    "t_wall",
    "u_wall",
]
