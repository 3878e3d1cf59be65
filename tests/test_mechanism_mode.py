"""masonry_dem.mechanism.collapse_mode: the mechanism the live load drives through the damaged
stiffness of a step (Eqs. 13-14), checked on a single block whose base joint rocks."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem import mechanism as mech
from masonry_dem.geometry.builders import add_base, single_block
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import StaticSettings, pushover


def test_a_rocking_block_turns_about_its_base_joint():
    """A dry block (height a, thickness s) tilted to s/a: its base joint rocks, so the mode
    is the block turning forward about a horizontal axis along e1 at or below its base
    joint: u3 = w1 (a/2 + d) at the block centre with d >= 0 (the joint's shear stiffness is
    kept unless it is flagged as sliding too, which adds a slip d w1), and no vertical or
    in-plane motion."""
    a, s = 0.2, 0.1
    blocks, base = add_base(single_block(a, 0.25, s, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.7),
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )
    h = pushover(model, StaticSettings())
    assert h.collapse_multiplier == pytest.approx(s / a, rel=5e-3)
    mode = mech.collapse_mode(model, h.steps[-1])
    block = 1 - base
    u1, u2, u3, w1, w2, w3 = mode[block]
    assert u3 == pytest.approx(1.0)  # forward, with the load
    assert u3 / w1 >= a / 2 * (1 - 1e-6)
    assert u3 / w1 <= a  # a turn, not a slide
    np.testing.assert_allclose([u1, u2, w2, w3], 0.0, atol=1e-6)
    np.testing.assert_allclose(mode[base], 0.0)


def test_a_standing_wall_has_no_collapse_mode_without_live_load():
    blocks, base = add_base(single_block(0.2, 0.25, 0.1, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.7),
        supports=[Support([base])],
        loads=[SelfWeight()],
    )
    h = pushover(model, StaticSettings())
    with pytest.raises(ValueError, match="no collapse mode"):
        mech.collapse_mode(model, h.steps[-1])
