"""The model stage of the data flow: what an analysis is given, checked and frozen.

- :mod:`.materials`: the joints' stiffness and strength and the interface law's options;
- :mod:`.supports`: the blocks' DOFs and the supports that hold them;
- :mod:`.loads`: the dead and live loads;
- :mod:`.model`: the frozen :class:`Model`, built from them and checked to be supported.

Block DOFs q = (u1, u2, u3, w1, w2, w3) at the block centre. Loads are generalised forces at
block centres: ``dead`` (applied first, held constant) and ``live`` (scaled by lambda).
"""

from masonry_dem.model.loads import (
    LOAD_TYPES,
    Load,
    PointLoad,
    Pressure,
    SelfWeight,
    WeightProportional,
    _warn_idle_load,
)
from masonry_dem.model.materials import (
    CAP_TOLERANCE,
    LAW_OPTIONS,
    PROJECTIONS,
    InterfaceMaterial,
    Memory,
    Tension,
    check_tension_cap,
)
from masonry_dem.model.model import Model, check_bound, require_model
from masonry_dem.model.supports import DOF_NAMES, DofGroup, DofName, Monitor, Support, dof_mask

__all__ = [
    "CAP_TOLERANCE",
    "DOF_NAMES",
    "LAW_OPTIONS",
    "LOAD_TYPES",
    "PROJECTIONS",
    "DofGroup",
    "DofName",
    "InterfaceMaterial",
    "Load",
    "Memory",
    "Model",
    "Monitor",
    "PointLoad",
    "Pressure",
    "SelfWeight",
    "Support",
    "Tension",
    "WeightProportional",
    "_warn_idle_load",
    "check_bound",
    "check_tension_cap",
    "dof_mask",
    "require_model",
]
