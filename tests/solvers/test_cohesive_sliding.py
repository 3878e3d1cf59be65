"""A block on a cohesive base, under a dead vertical load N, pushed horizontally by a live
point load, slides at H = c A + mu N (Mohr-Coulomb with a cohesion of its own)."""

from __future__ import annotations

import pytest

from helpers.walls import JOINT_LENGTH, JOINT_LOAD, JOINT_WIDTH, pushed_joint
from masonry_dem.export.analyses import pushover
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation

B, S, N = JOINT_LENGTH, JOINT_WIDTH, JOINT_LOAD  # a joint of 0.4 x 0.2 m under 20 kN
MU, FT, C = 0.75, 0.16e6, 0.224e6  # Lourenco's joint


def _model(cohesion: float | None) -> Model:
    return pushed_joint(MU, FT, cohesion)


def _slide(cohesion: float | None) -> float:
    history = pushover(_model(cohesion))
    assert history.status == "collapse"
    return float(history.collapse_multiplier)


def test_a_cohesive_block_slides_at_c_a_plus_mu_n():
    # measured: 32920.0 N against c A + mu N = 17920 + 15000 = 32920 N
    assert _slide(C) == pytest.approx(C * B * S + MU * N, rel=1e-2)


def test_without_cohesion_it_slides_at_the_papers_mu_ft_a_plus_mu_n():
    # measured: 24600.0 N against mu ft A + mu N = 9600 + 15000 = 24600 N
    assert _slide(None) == pytest.approx(MU * FT * B * S + MU * N, rel=1e-2)


def test_the_relaxation_slides_it_there_too():
    history = DynamicRelaxation(_model(C), DRSettings(bracket_tolerance=0.01)).run()
    assert history.status == "collapse", history.reason
    assert history.collapse_multiplier == pytest.approx(C * B * S + MU * N, rel=1e-2)


def test_the_papers_cohesion_given_is_the_default_bit_for_bit():
    """c = mu ft given explicitly is the paper's reading: the same pushover, bit for bit."""
    blocks, base = add_base(running_bond_wall(3, 3, 0.1, 0.2, 0.1, 18e3))

    def run(cohesion: float | None):
        material = InterfaceMaterial(
            kn=1e9, kt=4e8, friction=0.7, tensile_strength=2e3, cohesion=cohesion
        )
        model = Model.build(
            blocks,
            material,
            supports=[Support([base])],
            loads=[SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
        )
        return pushover(model)

    paper, given = run(None), run(0.7 * 2e3)
    assert given.collapse_multiplier == paper.collapse_multiplier
    assert given.last.actions.tobytes() == paper.last.actions.tobytes()
