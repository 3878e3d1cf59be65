"""Areas and second moments of the running-bond interfaces equal Eq. (5) of the paper.

Paper labels -> ours. The paper writes A_h, A_v in global component order (1, 2, 3 = e1, e2,
e3). Our interfaces use local axes y1 = e[(n+1)%3], y2 = e[(n+2)%3], normal y3 = e[n]:

- bed (horizontal) joint, normal e2 (n = 1): y1 = e3, y2 = e1, l1 = s, l2 = b/2.
  S_h = b s/2 = area; I_h1 (about e1) = b s^3/24 = inertia2 (about y2 = e1);
  I_h3 (about e3) = b^3 s/96 = inertia1 (about y1 = e3); polar I_h1 + I_h3 = polar.
- head (vertical) joint, normal e1 (n = 0): y1 = e2, y2 = e3, l1 = a, l2 = s.
  S_v = a s = area; I_v2 (about e2) = a s^3/12 = inertia1 (about y1 = e2);
  I_v3 (about e3) = a^3 s/12 = inertia2 (about y2 = e3); polar I_v2 + I_v3 = polar.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from masonry_dem.geometry.builders import running_bond_wall
from masonry_dem.geometry.interfaces import detect_interfaces

RTOL = 1e-12


def eq5(a, b, s):
    return {
        "S_h": b * s / 2,
        "I_h1": b * s**3 / 24,
        "I_h3": b**3 * s / 96,
        "S_v": a * s,
        "I_v2": a * s**3 / 12,
        "I_v3": a**3 * s / 12,
    }


def _check(a, b, s, n=5, nc=4):
    w = running_bond_wall(n, nc, a, b, s, 1.0)
    its = detect_interfaces(w)
    p = eq5(a, b, s)
    h, v = its.axis == 1, its.axis == 0
    assert h.sum() == (nc - 1) * 2 * n and v.sum() > 0
    np.testing.assert_allclose(its.area[h], p["S_h"], rtol=RTOL)
    np.testing.assert_allclose(its.inertia2[h], p["I_h1"], rtol=RTOL)
    np.testing.assert_allclose(its.inertia1[h], p["I_h3"], rtol=RTOL)
    np.testing.assert_allclose(its.polar[h], p["I_h1"] + p["I_h3"], rtol=RTOL)
    np.testing.assert_allclose(its.area[v], p["S_v"], rtol=RTOL)
    np.testing.assert_allclose(its.inertia1[v], p["I_v2"], rtol=RTOL)
    np.testing.assert_allclose(its.inertia2[v], p["I_v3"], rtol=RTOL)
    np.testing.assert_allclose(its.polar[v], p["I_v2"] + p["I_v3"], rtol=RTOL)


@pytest.mark.parametrize(
    ("a", "b", "s"),
    [
        (0.2, 0.3, 0.2),  # the paper's Orduna block (Section 2.1)
        (0.055, 0.25, 0.12),  # a standard brick
        (0.1, 0.25, 0.12),
        (1.0, 1.0, 1.0),
    ],
)
def test_running_bond_interfaces_equal_eq5(a, b, s):
    _check(a, b, s)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    a=st.floats(0.01, 2.0),
    b=st.floats(0.01, 2.0),
    s=st.floats(0.01, 2.0),
    n=st.integers(1, 6),
    nc=st.integers(2, 6),
)
def test_running_bond_interfaces_equal_eq5_any_size(a, b, s, n, nc):
    _check(a, b, s, n, nc)


def test_eq5_with_a_mortar_joint_uses_the_pitch():
    # the joint thickness e is included in the blocks: Eq. (5) holds with a+e, b+e
    a, b, s, e = 0.055, 0.25, 0.12, 0.01
    w = running_bond_wall(4, 3, a, b, s, 1.0, joint=e)
    its = detect_interfaces(w)
    p = eq5(a + e, b + e, s)
    h, v = its.axis == 1, its.axis == 0
    np.testing.assert_allclose(its.area[h], p["S_h"], rtol=RTOL)
    np.testing.assert_allclose(its.inertia1[h], p["I_h3"], rtol=RTOL)
    np.testing.assert_allclose(its.inertia2[v], p["I_v3"], rtol=RTOL)
