"""masonry_dem: nonlinear 3D discrete element analysis of masonry walls (Baraldi & Cecchi).

The data flow is the folder layout: ``geometry`` (blocks, builders, contacts) -> ``model``
(materials, supports, loads) -> ``assembly`` (H, Kbar, K) -> ``solvers`` (linear, static
incremental) with the interface law of ``constitutive`` -> ``results`` -> ``export`` (VTU/PVD,
renders, ParaView states).
"""

from masonry_dem.geometry import selectors as select
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import (
    add_base,
    boxes,
    cut_openings,
    running_bond_wall,
    running_bond_wall_of_size,
    single_block,
    stack_bond_column,
)
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    PointLoad,
    Pressure,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.solvers.incremental import DisplacementControl, StaticSettings, pushover
from masonry_dem.solvers.linear import solve_linear

__version__ = "0.1.0"

__all__ = [
    "Blocks",
    "DisplacementControl",
    "InterfaceMaterial",
    "Model",
    "PointLoad",
    "Pressure",
    "SelfWeight",
    "StaticSettings",
    "Support",
    "WeightProportional",
    "add_base",
    "boxes",
    "cut_openings",
    "pushover",
    "running_bond_wall",
    "running_bond_wall_of_size",
    "select",
    "single_block",
    "solve_linear",
    "stack_bond_column",
]
