"""Small models on a rigid base for the solver tests: one block of a x b x s (``A, B, S``),
whose tilting load factor out of plane is S / A, and walls held on their left column."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from masonry_dem.geometry import builders
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional

A, B, S = 0.2, 0.3, 0.1  # block height, width, thickness [m]


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
