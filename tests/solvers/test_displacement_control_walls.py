"""Displacement control of the shear-wall test in stages (issue 41, item 5): a precompression
on the top beam, then the beam held at its height and rotation and pushed sideways by its
displacement. Past a fold of the controlled path the wall moves, damped, with the pushed
displacement held (the load the reaction), as under a testing machine: the push reaches its
target on cohesive, brittle joints and on dry ones."""

from __future__ import annotations

import numpy as np
import pytest

import masonry_dem as md

MU = 0.75
SIGMA = 0.1e6  # the precompression [Pa] on the wall's length x thickness
THICKNESS = 0.1
BEAM_WEIGHT = 20e3  # [N/m^3]


def _push(courses: int, material: md.InterfaceMaterial, target: float, steps: int, sigma: float):
    """The wall 0.63 m long (running bond, blocks 0.21 x 0.052 m with 0.01 m joints) between
    a fixed bottom beam and a top beam: (the push stage's steps, the top beam's index, the
    precompression, the beam's weight)."""
    blocks = md.shear_wall(
        0.63, courses, 0.052, 0.21, THICKNESS, 18e3, joint=0.01, beam_unit_weight=BEAM_WEIGHT
    )
    bottom, top = md.select.edge(blocks, "bottom"), md.select.edge(blocks, "top")
    beam = int(top[0])
    model = md.Model.build(
        blocks,
        material,
        [md.Support(bottom), md.Support(top, ["u3", "w1", "w2"])],
        [md.SelfWeight()],
    )
    precompression = sigma * 0.63 * THICKNESS
    stages = [
        md.Stage(loads=[md.PointLoad(top, (0.0, -precompression, 0.0))], name="precompression"),
        md.Stage(
            supports=[md.Support(top, ["u2", "w3"])],
            loads=[md.PointLoad(top, (1000.0, 0.0, 0.0), live=True)],
            control=md.DisplacementControl(block=beam, dof="u1", target=target, steps=steps),
            name="push",
        ),
    ]
    history = md.pushover(model, stages=stages)
    assert history.status == "completed", history.reason
    pushed = [s for s in history.steps if s.stage == 1]
    assert pushed[-1].q[beam, 0] == pytest.approx(target, rel=1e-9)
    weight = BEAM_WEIGHT * float(np.prod(blocks.sizes[beam]))
    return pushed, precompression, weight


def test_cohesive_brittle_wall_reaches_its_target_with_its_peak_step_converged():
    joint = md.InterfaceMaterial(
        kn=82e9,
        kt=36e9,
        friction=MU,
        tensile_strength=0.16e6,
        cohesion=0.224e6,
        tension="brittle",
    )
    peaks = []
    for steps in (20, 40):
        pushed, _, _ = _push(6, joint, 0.001, steps, SIGMA)
        lams = np.array([s.load_factor for s in pushed])
        assert np.count_nonzero(pushed[-1].state) > 0  # joints slide, rock or open
        peaks.append(float(lams.max()))
    assert peaks[1] == pytest.approx(peaks[0], rel=0.01)


def test_dry_wall_slides_under_the_beam_at_mu_p_plus_the_beam_weight():
    # one course: the joint under the beam carries the precompression and the beam's weight
    # only, less than the joint under the course, so the wall slides there
    dry = md.InterfaceMaterial(kn=82e9, kt=36e9, friction=MU)
    pushed, precompression, weight = _push(1, dry, 0.002, 20, 0.3e6)
    lams = np.array([s.load_factor for s in pushed])
    plateau = MU * (precompression + weight) / 1000.0  # the live load is 1000 N
    assert lams[-1] == pytest.approx(plateau, rel=0.01)
    assert lams.max() == pytest.approx(plateau, rel=0.01)
