"""The judge of the agreement benchmark (``benchmarks/agreement.py``): the reference
quasi-static analysis (:func:`~masonry_dem.solvers.quasi_static.quasi_static`), run again with
stiffer joints where its last rest lies past the small-displacement range.

Each motion of the reference is judged against the displacement limit from the rest before
it. On a wall whose joints are so soft that it deflects more than half a block before it
collapses, the elastic deflection of one increment on a flattening curve can pass that limit,
and the verdict is the deflection's, not the mechanism's. The collapse multiplier of the
geometrically linear model does not depend on the scale of the joints' stiffness (kn and kt
together), only its deflection does: such a wall is judged with joints ten times stiffer, in
the same kt/kn, until its last rest lies within the range.
"""

from __future__ import annotations

from dataclasses import replace

from masonry_dem.model import Model
from masonry_dem.results import History
from masonry_dem.solvers.quasi_static import QuasiStatic, QuasiStaticSettings

#: the largest stiffening of the joints tried to bring the last rest within the range
STIFFER_AT_MOST = 1000.0


def reference_within_range(
    model: Model, settings: QuasiStaticSettings | None = None
) -> tuple[History, float]:
    """The reference analysis of ``model``, again with joints ten times stiffer (kn and kt
    together) while its last rest lies past the small-displacement range from its dead-load
    rest: (its History, the stiffening)."""
    stiffer = 1.0
    reference = QuasiStatic(model, settings)
    history = reference.run()
    while reference.past_range() and stiffer < STIFFER_AT_MOST:
        stiffer *= 10.0
        reference = QuasiStatic(
            replace(model, kn=model.kn * stiffer, kt=model.kt * stiffer), settings
        )
        history = reference.run()
    return history, stiffer
