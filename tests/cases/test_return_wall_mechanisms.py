"""Which joints fail when the Restrepo Velez specimens stand with their return walls as blocks
(4 blocks long, the default), read in the last increment of the collapse run as in
test_mechanisms.py:

* one return wall (S13 as an L wall): the facade cracks along the diagonal from its lower free
  corner up to the corner, as with a held column, and tears away from its return along the
  corner in the upper half (the joints between facade and return blocks open there and stay
  shut below); the return wall itself stays put;
* two return walls (S5 as a U wall): the facade opens the vertical crack on its axis with the
  diagonals down to it, mirror symmetric, and drags a wedge of each return wall with it: the
  upper courses of the returns move out whole, the free ends of their lower courses stay,
  and the moving part reaches lower by the corner than at the free end (a crack that climbs
  through the return from the corner to its free end).
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers import mechanism_checks as chk
from helpers.paper_runs import run_case
from masonry_dem import mechanism as mech
from masonry_dem.geometry import selectors as sel

RETURN = {"restraint": "return-walls", "return_blocks": 4}


def _collapse(name: str):
    case, h = run_case(name, **RETURN)
    assert h.status == "collapse", h.reason
    return case, mech.last_increment(h)


@pytest.fixture(scope="module")
def l_wall():
    return _collapse("S13")


@pytest.fixture(scope="module")
def u_wall():
    return _collapse("S5")


def _motion(dq, idx):
    m = np.linalg.norm(dq[:, :3], axis=1)
    return m[idx] / m.max()


def _courses(case, idx):
    a = float(np.median(case.model.blocks.sizes[case.wall, 1]))
    return np.rint(case.model.blocks.centres[idx, 1] / a - 0.5).astype(int)


def test_l_wall_facade_cracks_along_the_diagonal(l_wall):
    case, dq = l_wall
    facade = case.extra["facade"]
    chk.assert_diagonal_from_free_corner(case.model, facade, dq)
    chk.assert_free_top_corner_moves_most(case.model, facade, dq)


def test_l_wall_tears_from_its_return_along_the_upper_corner(l_wall):
    case, dq = l_wall
    model = case.model
    wall = model.blocks.subset(case.wall)
    facade = np.zeros(model.blocks.count, bool)
    facade[case.extra["facade"]] = True
    ret = np.zeros(model.blocks.count, bool)
    ret[sel.part(wall, "return:left")] = True
    its = model.interfaces
    across = (facade[its.block_i] & ret[its.block_j]) | (ret[its.block_i] & facade[its.block_j])
    opening = mech.joint_motion(model, dq).opening
    opening = opening / opening[mech.between(model, case.wall)].max()
    course = _courses(case, its.block_i)
    n = course.max() + 1
    upper = across & (course >= n - n // 4)
    lower = across & (course < 0.4 * n)
    assert opening[upper].max() >= 0.5, opening[upper]
    assert opening[lower].max() <= 0.05, opening[lower]
    # the return wall stays: only its corner blocks at the top follow the facade a little
    assert _motion(dq, np.flatnonzero(ret)).max() <= 0.1


def test_u_wall_facade_opens_on_its_axis_symmetrically(u_wall):
    case, dq = u_wall
    facade = case.extra["facade"]
    chk.assert_vertical_crack_on_axis(case.model, facade, dq)
    chk.assert_diagonals_down_to_axis(case.model, facade, dq)
    chk.assert_symmetric(case.model, facade, dq)
    # the returns mirror each other: block by block the same motion (mirror about the axis)
    blocks = case.model.blocks
    wall = blocks.subset(case.wall)
    left, right = sel.part(wall, "return:left"), sel.part(wall, "return:right")
    axis = (wall.lower[:, 0].min() + wall.upper[:, 0].max()) / 2
    mirrored = blocks.centres[right].copy()
    mirrored[:, 0] = 2 * axis - mirrored[:, 0]
    pair = np.argmin(np.linalg.norm(mirrored[:, None] - blocks.centres[left][None], axis=2), 1)
    np.testing.assert_allclose(dq[right, 2], dq[left[pair], 2], atol=0.02 * np.abs(dq[:, 2]).max())


@pytest.mark.parametrize("side", ["return:left", "return:right"])
def test_u_wall_drags_a_wedge_of_each_return(u_wall, side):
    case, dq = u_wall
    blocks = case.model.blocks
    wall = blocks.subset(case.wall)
    ret = sel.part(wall, side)
    motion = _motion(dq, ret)
    course = _courses(case, ret)
    depth = wall.upper[:, 2].max() - wall.centres[ret, 2]  # from the facade's outer face
    b = float(np.max(wall.sizes[:, 0]))
    n = course.max() + 1
    assert motion[course == n - 1].min() >= 0.4  # the top course moves out whole
    free_end = depth >= 3 * b
    assert motion[free_end & (course < n // 4)].max() <= 0.05  # the free end's foot stays
    # the moving part (>= 10 % of the largest motion) reaches lower by the corner
    moving = motion >= 0.1
    lowest_by_corner = course[moving & (depth <= 1.5 * b)].min()
    lowest_at_end = course[moving & free_end].min()
    assert lowest_by_corner < lowest_at_end - 3
