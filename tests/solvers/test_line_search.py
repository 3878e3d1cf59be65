"""The corrector's line search (``StaticSettings.line_search``): what a trial step of a Newton
search must lower to be taken.

Proves: whatever the merit, a converged state is an exact equilibrium of the law, so each
reaches the closed forms (a block tilting at s / a, a squat block sliding at mu, a free wall
tilting at t / H, all within 1e-6: the plateau of work control is the rigid-block limit,
which the elastic joints do not move); the natural merit of a trial is the size of the
simplified Newton correction, so at the start of a step (t = 0) it is the Newton
correction's own size, and a bad choice is named.
"""

from __future__ import annotations

import pytest

from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import add_base, running_bond_wall, single_block
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import StaticSettings, pushover

DRY = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)
MERITS = ("residual", "natural", "directional")


def _tilt(blocks: Blocks, base: int, material=DRY) -> Model:
    return Model.build(
        blocks,
        material,
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )


def _collapse(model: Model, merit: str) -> float:
    h = pushover(model, StaticSettings(line_search=merit))
    assert h.status == "collapse", h.reason
    return h.collapse_multiplier


@pytest.mark.parametrize("merit", MERITS)
def test_a_block_tilts_at_s_over_a_with_every_merit(merit):
    a, s = 0.2, 0.1
    blocks, base = add_base(single_block(a, 0.25, s, 20e3))
    assert _collapse(_tilt(blocks, base), merit) == pytest.approx(s / a, rel=1e-6)


@pytest.mark.parametrize("merit", MERITS)
def test_a_squat_block_slides_at_mu_with_every_merit(merit):
    blocks, base = add_base(single_block(0.05, 0.25, 0.2, 20e3))  # s / a = 4 > mu
    material = InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.45)
    assert _collapse(_tilt(blocks, base, material), merit) == pytest.approx(0.45, rel=1e-6)


@pytest.mark.parametrize("merit", MERITS)
def test_a_free_wall_tilts_at_t_over_h_with_every_merit(merit):
    a, s, courses = 0.081, 0.07, 9
    blocks, base = add_base(running_bond_wall(4, courses, a, 0.21, s, 20e3))
    lam = _collapse(_tilt(blocks, base), merit)
    assert lam == pytest.approx(s / (courses * a), rel=1e-6)


def test_an_unknown_line_search_is_named():
    with pytest.raises(ValueError, match="line_search"):
        StaticSettings(line_search="energy")  # type: ignore[arg-type]
