"""masonry_dem: nonlinear 3D discrete element analysis of masonry walls (Baraldi & Cecchi).

The data flow is the folder layout: ``geometry`` (blocks, builders, contacts) -> ``model``
(materials, supports, loads) -> ``assembly`` (H, Kbar, K) -> ``solvers`` (linear, static
incremental) with the interface law of ``constitutive`` -> ``results`` -> ``export`` (VTU/PVD,
renders, ParaView states).
"""

import os

# The compiled kernels share their loops among the cores with OpenMP (numba). Threads that
# spin while they wait (OpenMP's default) took a core from the serial parts between the
# parallel loops: the 20 x 40 mortar wall ran 35 s against 19 s waiting passively (and 20 s
# before the kernels were parallel), and a background results writer or a second process
# slowed a run 3-4x. Waiting passively costs about a tenth on the small validation walls.
# Set before the first parallel loop starts OpenMP; a value set by the user is kept.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from masonry_dem.geometry import selectors as select  # noqa: E402
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
from masonry_dem.geometry.interfaces import detect_interfaces, subdivide_interfaces
from masonry_dem.geometry.plans import box_wall, l_wall, t_wall, u_wall
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
from masonry_dem.studies.sweep import sweep  # dask is imported only when a sweep runs

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
    "box_wall",
    "boxes",
    "cut_openings",
    "detect_interfaces",
    "l_wall",
    "pushover",
    "running_bond_wall",
    "running_bond_wall_of_size",
    "select",
    "single_block",
    "solve_linear",
    "stack_bond_column",
    "subdivide_interfaces",
    "sweep",
    "t_wall",
    "u_wall",
]
