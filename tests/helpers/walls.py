"""Small models on a rigid base for the solver tests: one block of a x b x s (``A, B, S``),
whose tilting load factor out of plane is S / A, walls held on their left column, and a
block pushed along its bed joint under a dead load (:func:`pushed_joint`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pytest

from masonry_dem.geometry import builders
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    PointLoad,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.solvers.static import StaticSettings, StaticSolver

A, B, S = 0.2, 0.3, 0.1  # block height, width, thickness [m]
#: the pushed joint: a block 0.1 high on a bed joint of 0.4 x 0.2 m under a dead load [N]
JOINT_HEIGHT, JOINT_LENGTH, JOINT_WIDTH, JOINT_LOAD = 0.1, 0.4, 0.2, 20e3


def on_base(
    blocks: Blocks,
    friction: float = 0.7,
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0),
    kn: float = 1e9,
    left: Sequence[str] | None = None,
    name: str = "model",
) -> Model:
    """``blocks`` on a rigid base slab (kt = 0.4 kn), under self weight and a live load of
    lambda x the weight along ``direction``; ``left``: DOFs held on the left column."""
    wall = np.arange(blocks.count)
    blocks, base = builders.add_base(blocks)
    supports = [Support(np.array([base]))]
    if left is not None:
        supports.append(Support(sel.column(blocks, "left", among=wall), list(left)))
    return Model.build(
        blocks,
        InterfaceMaterial(kn, 0.4 * kn, friction),
        supports,
        [SelfWeight(), WeightProportional(direction)],
        name=name,
    )


#: dry joints of the tilt-table checks of the static solver's corner and endgame tests
DRY = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)


def tilted(blocks: Blocks, base: int, material: InterfaceMaterial = DRY) -> Model:
    """``blocks`` with joints of ``material`` (dry by default) on ``base`` (held), under self
    weight and lambda x the weight out of plane (a tilt table)."""
    return Model.build(
        blocks,
        material,
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )


def tilted_block() -> tuple[Model, float]:
    """A block a = 0.2 high, s = 0.1 thick on a base, and its tilting load factor s / a."""
    a, s = 0.2, 0.1
    return tilted(*builders.add_base(builders.single_block(a, 0.25, s, 20e3))), s / a


def tilted_wall() -> tuple[Model, float]:
    """A free-standing 4 x 9 running-bond wall on a base, and its tilting load factor t / H
    (the weight's moment about the toe, W t / 2, against the live load's, lambda W H / 2)."""
    a, s, courses = 0.081, 0.07, 9
    wall = builders.running_bond_wall(4, courses, a, 0.21, s, 20e3)
    return tilted(*builders.add_base(wall)), s / (courses * a)


def tilted_panel() -> Model:
    """A dry panel of 3 x 13 blocks on a base, its left column held in u1 and u3 and its
    right edge free, tilted out of plane: its path passes folds, and many of its work
    searches fail where no correction lowers the residual."""
    wall = builders.running_bond_wall(3, 13, 0.081, 0.21, 0.07, 20e3)
    blocks, base = builders.add_base(wall)
    return Model.build(
        blocks,
        DRY,
        supports=[Support([base]), Support(sel.column(wall, "left"), ["u1", "u3"])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )


def tilt_table_block(a: float, s: float, friction: float) -> Model:
    """A block a high and s thick (0.25 wide) on its base, kn 2.4e9: it tilts at s / a or,
    squat with s / a above ``friction``, slides at ``friction``."""
    return on_base(builders.single_block(a, 0.25, s, 20e3), friction=friction, kn=2.4e9)


#: closed-form collapses on the tilt table, by name: (the model's builder, lambda)
CLOSED_FORMS = {
    "block tilts at s/a": (lambda: tilt_table_block(0.2, 0.1, 0.7), 0.5),
    "block slides at mu": (lambda: tilt_table_block(0.05, 0.2, 0.45), 0.45),
    "wall tilts at t/H": (
        lambda: on_base(builders.running_bond_wall(4, 9, 0.081, 0.21, 0.07, 20e3), kn=2.4e9),
        0.07 / 0.729,
    ),
}


#: the two tilt-table scenes with a closed form that the solver's options are checked on
TILTED = pytest.mark.parametrize(
    "build", [tilted_block, tilted_wall], ids=["block s/a", "wall t/H"]
)


def assert_closed_form(build, settings: StaticSettings | None = None) -> None:
    """``build()`` (a model and its closed-form collapse multiplier) pushed over with
    ``settings``: a collapse at that multiplier within 1e-6."""
    model, closed_form = build()
    hist = StaticSolver(model, settings or StaticSettings()).run()
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(closed_form, rel=1e-6)


def pushed_joint(friction: float, tensile_strength: float, cohesion: float | None) -> Model:
    """One block on a rigid base under a dead load of ``JOINT_LOAD`` N and a live unit
    force along e1, both at its centre, and no self-weight: it slides at c A + mu N, N the
    dead load alone."""
    blocks, base = builders.add_base(
        builders.single_block(JOINT_HEIGHT, JOINT_LENGTH, JOINT_WIDTH, 18e3)
    )
    material = InterfaceMaterial(
        kn=1e10,
        kt=4e9,
        friction=friction,
        tensile_strength=tensile_strength,
        cohesion=cohesion,
    )
    return Model.build(
        blocks,
        material,
        supports=[Support([base])],
        loads=[
            PointLoad([0], (0.0, -JOINT_LOAD, 0.0)),
            PointLoad([0], (1.0, 0.0, 0.0), live=True),
        ],
    )
