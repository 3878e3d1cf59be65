"""Exact checks on walls that meet (geometry.plans): an L or U wall under its weight alone stays
elastic and settles as the closed form says; a square box whose four walls are tilted outwards
alike answers alike on each wall; a U wall of two courses collapses at the hand-computed
lambda of its mechanism."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.builders import add_base
from masonry_dem.geometry.plans import box_wall, l_wall, u_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import pushover

KN, KT, GAMMA = 2.4e9, 1.0e9, 20e3


def _dry(mu: float = 0.7) -> InterfaceMaterial:
    return InterfaceMaterial(kn=KN, kt=KT, friction=mu)


@pytest.mark.parametrize("plan", ["l", "u"])
def test_walls_that_meet_stay_elastic_under_their_weight(plan):
    """Under its weight alone every point of the plan carries the same height of masonry, so
    each bed joint j (0: on the base) is uniformly compressed by gamma a (nc - j) and, the
    blocks being rigid, every block of course k sinks by the same
    delta_k = (gamma a / kn) sum_{j <= k} (nc - j), without turning or moving sideways; the
    head joints (the interlocked corners included) carry nothing and no joint yields."""
    a, b, s, nc = 0.081, 0.21, 0.07, 6
    build = l_wall if plan == "l" else u_wall
    wall = build(5, nc, a, b, s, GAMMA, return_blocks=3)
    blocks, base = add_base(wall)
    model = Model.build(blocks, _dry(), [Support([base])], [SelfWeight()])
    h = pushover(model)
    assert h.status == "completed", h.reason
    q = h.last.q[: wall.count]
    k = np.rint(wall.centres[:, 1] / a - 0.5).astype(int)
    delta = GAMMA * a / KN * np.cumsum(nc - np.arange(nc))
    np.testing.assert_allclose(q[:, 1], -delta[k], rtol=1e-6)
    assert np.abs(q[:, [0, 2]]).max() <= 1e-6 * delta[0]
    assert np.abs(q[:, 3:]).max() * b <= 1e-6 * delta[0]
    head = model.interfaces.axis != 1
    assert np.abs(h.last.actions[head]).max() <= 1e-6 * GAMMA * a * s * b
    bed = ~head
    assert np.all(h.last.state[bed] == 0)  # every bed joint elastic ...
    assert h.last.utilisation[bed].max() < 1e-6  # ... without shear or torsion
    # (a dry head joint at zero compression is flagged at its zero capacity: its actions,
    # checked above, say that it carries nothing)


def _box_model(n: int, courses: int):
    a, b, s = 0.081, 0.21, 0.07
    wall = box_wall(n, courses, a, b, s, GAMMA)
    blocks, base = add_base(wall)
    outward = {"facade": (0, 0, 1), "return:right": (1, 0, 0), "back": (0, 0, -1)}
    outward["return:left"] = (-1, 0, 0)
    loads = [SelfWeight()] + [
        WeightProportional(d, blocks=sel.part(wall, p)) for p, d in outward.items()
    ]
    model = Model.build(blocks, _dry(), [Support([base])], loads)
    return wall, model


def _quarter_turn(wall):
    """Permutation p with block p[i] the image of block i under the quarter turn about the
    box's vertical axis that takes the front to the right side, (x, z) -> (z, -x), and its
    3 x 3 rotation matrix."""
    lo, hi = wall.lower.min(axis=0), wall.upper.max(axis=0)
    cx, cz = (lo[0] + hi[0]) / 2, (lo[2] + hi[2]) / 2
    turned = wall.centres.copy()
    turned[:, 0] = cx + (wall.centres[:, 2] - cz)
    turned[:, 2] = cz - (wall.centres[:, 0] - cx)
    d = np.linalg.norm(turned[:, None, :] - wall.centres[None, :, :], axis=2)
    image = np.argmin(d, axis=1)
    assert d[np.arange(wall.count), image].max() < 1e-9
    R = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    return image, R


def test_square_box_tilted_outwards_answers_alike_on_each_wall():
    """The box is the same after a quarter turn, and so is its load, so every converged state
    is too: block i's displacement turned equals that of its image block (to the solver's
    tolerance), and the four walls move out alike up to collapse."""
    wall, model = _box_model(5, 6)
    h = pushover(model)
    assert h.status == "collapse", h.reason
    image, R = _quarter_turn(wall)
    scale = np.abs(h.steps[-1].q[: wall.count, :3]).max()
    for step in h.steps[1:]:
        q = step.q[: wall.count]
        lam_scale = np.abs(q[:, :3]).max()
        for part in (0, 3):
            turned = q[:, part : part + 3] @ R.T
            np.testing.assert_allclose(
                q[image, part : part + 3], turned, atol=1e-5 * max(lam_scale, 1e-3 * scale)
            )
    out = {
        "facade": h.steps[-1].q[sel.part(wall, "facade"), 2],
        "back": -h.steps[-1].q[sel.part(wall, "back"), 2],
        "return:right": h.steps[-1].q[sel.part(wall, "return:right"), 0],
        "return:left": -h.steps[-1].q[sel.part(wall, "return:left"), 0],
    }
    peaks = np.array([v.max() for v in out.values()])
    np.testing.assert_allclose(peaks, peaks[0], rtol=1e-4)


@pytest.mark.parametrize(("n", "mu"), [(2, 2.0), (4, 0.7)])
def test_u_wall_of_two_courses_overturns_with_the_corner_blocks_it_holds(n, mu):
    """Hand calculation. A U wall of two courses (block a high, b long, s thick, facade n b)
    tilted towards +e3, away from its returns. Course 0 of the facade runs through both
    corners; in course 1 each return runs through its corner with a block s wide and b deep
    (centre b / 2 behind the facade's outer face z = s) and the facade between them is
    n b - 2 s long. The mechanism: the whole facade (both courses) and the two corner blocks
    of course 1 turn as one body about the front edge of the base; the corner blocks lift off
    course 0 of their return and leave its course-1 blocks behind them (a head joint that
    opens), the rest of the returns stays. Virtual work of a rotation about that edge, with
    V the volumes, z_c the centre's depth and y_c its height:

        lambda = sum V (s - z_c) / sum V y_c
               = [n b s . s/2 + (n b - 2 s) s . s/2 + 2 s b . b/2]
                 / [n b s . a/2 + (n b - 2 s) s . 3a/2 + 2 s b . 3a/2]
               = [s (n b - s) + b^2] / [a (2 n b - 3 s + 3 b)],

    7/11 = 0.636 for n = 2 and 11/19 = 0.579 for n = 4 with a = s = 0.1, b = 0.2: below the
    rocking of the top course's middle alone (s / a = 1) and below sliding (mu). The
    elastic joints (kn a / (gamma a) ~ 1e6) move it by less than 0.1 %."""
    a, b, s = 0.1, 0.2, 0.1
    wall = u_wall(n, 2, a, b, s, GAMMA, return_blocks=3)
    blocks, base = add_base(wall)
    model = Model.build(
        blocks, _dry(mu), [Support([base])], [SelfWeight(), WeightProportional((0, 0, 1))]
    )
    h = pushover(model)
    assert h.status == "collapse", h.reason
    hand = (s * (n * b - s) + b**2) / (a * (2 * n * b - 3 * s + 3 * b))
    assert h.collapse_multiplier == pytest.approx(hand, rel=1e-3)
    assert hand < min(mu, s / a)
    dq = h.steps[-1].q[: wall.count] - h.steps[-2].q[: wall.count]
    moving = np.flatnonzero(np.abs(dq[:, :3]).max(axis=1) > 0.05 * np.abs(dq[:, :3]).max())
    corners = np.concatenate([sel.part(wall, "corner:left"), sel.part(wall, "corner:right")])
    course1_corner = corners[np.isclose(wall.centres[corners, 1], 1.5 * a)]
    expected = np.union1d(sel.part(wall, "facade"), course1_corner)
    np.testing.assert_array_equal(moving, expected)
