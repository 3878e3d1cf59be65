"""The shear walls of Raijmakers & Vermeltfoort (TU Eindhoven, 1992) as loading stages: the
wall between its beams (:func:`~masonry_dem.shear_wall`), the precompression on the top beam
(stage 1), then the top beam held at its height and rotation and pushed sideways by
displacement (stage 2). Every number comes from ``data/raijmakers_vermeltfoort_1992.toml``,
with its source there; what no source in reach gives is absent and named.

Axes: e1 along the wall (the push), e2 up, e3 out of the wall's plane (held: the test is in
plane). lambda multiplies a horizontal force of :data:`FORCE_UNIT` on the top beam: the
reaction of the push in kN.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from masonry_dem._toml import tomllib
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.specimens import shear_wall, split_units
from masonry_dem.model import InterfaceMaterial, Model, PointLoad, SelfWeight, Support
from masonry_dem.solvers.static.settings import DisplacementControl
from masonry_dem.solvers.static.stages import Stage

DATA_FILE = "raijmakers_vermeltfoort_1992.toml"
#: the live load's horizontal force on the top beam [N]: lambda is the push's reaction in kN
FORCE_UNIT = 1000.0
#: how far the top beam is pushed [m] and in how many steps, unless a caller says otherwise
PUSH = 0.004
PUSH_STEPS = 80
#: unit weight of the brickwork [N/m^3]: no source in reach gives it; the weight of the wall
#: (about 1.8 kN) is under 1 % of the smallest precompression's 29.7 kN
UNIT_WEIGHT = 18e3


@lru_cache(maxsize=1)
def shear_wall_data() -> dict[str, Any]:
    """The specimens' data with their sources (the package's TOML)."""
    text = resources.files("masonry_dem.cases").joinpath("data", DATA_FILE).read_text()
    return tomllib.loads(text)


def wall_names() -> list[str]:
    """The walls, by the names of the data file (``rv-0.30``, ...)."""
    return [w["name"] for w in shear_wall_data()["wall"]]


@dataclass(frozen=True)
class ShearWallCase:
    """One shear wall ready to run: ``analyze(model, "pushover", stages=stages)``.

    Attributes:
        name: the wall's name in the data file.
        model: the wall, its beams and joints; the bottom beam held, the top beam held out
            of plane (its own weight only as a load).
        stages: the precompression, then the push.
        beam: the top beam's index (its u1 is the curve's displacement).
        precompression: [Pa] on the wall's cross-section.
        reference: the test's peak horizontal force [N], or None where no source in reach
            gives it (``reference_source`` says which).
        reference_source: where ``reference`` comes from, or why there is none.
        cracks: the (left, right) blocks of each split unit (None: units whole).
    """

    name: str
    model: Model
    stages: tuple[Stage, ...]
    beam: int
    precompression: float
    reference: float | None
    reference_source: str
    cracks: NDArray[np.intp] | None = None


def shear_wall_case(
    name: str,
    unit_crack: InterfaceMaterial | None = None,
    push: float = PUSH,
    steps: int = PUSH_STEPS,
) -> ShearWallCase:
    """The shear wall ``name`` of the data file as loading stages.

    ``unit_crack``: the material of a potential crack at mid-length of each unit
    (:func:`~masonry_dem.split_units`; None: rigid bricks). The data file has no unit
    strength (no source in reach gives one), so the caller gives it. ``push`` [m] in
    ``steps``: the top beam's horizontal displacement in stage 2.
    """
    data = shear_wall_data()
    walls = {w["name"]: w for w in data["wall"]}
    if name not in walls:
        raise ValueError(f"shear wall {name!r}: the walls are {', '.join(walls)}")
    wall, spec, joint = walls[name], data["specimen"], data["joint"]
    blocks = shear_wall(
        spec["length"],
        spec["active_courses"],
        spec["brick_height"],
        spec["brick_length"],
        spec["brick_thickness"],
        UNIT_WEIGHT,
        joint=spec["joint"],
    )
    cracks = None
    overrides: list[tuple[NDArray[np.intp], InterfaceMaterial]] = []
    if unit_crack is not None:
        # every unit of the wall (the two beams, last, stay whole), as [unit_cracks] does
        blocks, cracks = split_units(blocks, np.arange(blocks.count - 2))
        overrides.append((cracks, unit_crack))
    bottom, top = sel.edge(blocks, "bottom"), sel.edge(blocks, "top")
    material = InterfaceMaterial(
        kn=joint["kn"],
        kt=joint["kt"],
        friction=joint["friction"],
        tensile_strength=joint["tensile_strength"],
        cohesion=joint["cohesion"],
    )
    model = Model.build(
        blocks,
        material,
        supports=[Support(bottom), Support(top, ["u3", "w1", "w2"])],
        loads=[SelfWeight()],
        name=f"shear wall {name}",
        interface_overrides=overrides,
    )
    beam = int(top[0])
    force = wall["precompression"] * spec["length"] * spec["brick_thickness"]
    stages = (
        Stage(loads=[PointLoad(top, (0.0, -force, 0.0))], name="precompression"),
        Stage(
            supports=[Support(top, ["u2", "w3"])],
            loads=[PointLoad(top, (FORCE_UNIT, 0.0, 0.0), live=True)],
            control=DisplacementControl(block=beam, dof="u1", target=push, steps=steps),
            name="push",
        ),
    )
    reference = wall.get("peak_test")
    source = (
        wall.get("peak_test_source", "")
        if reference is not None
        else "no source in reach gives the test's peak"
    )
    return ShearWallCase(
        name,
        model,
        stages,
        beam,
        wall["precompression"],
        None if reference is None else float(reference),
        source,
        cracks,
    )
