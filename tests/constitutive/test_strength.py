"""Closed-form interface strength domain (Section 2.1, Eqs. 9-14, A4-A5)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from masonry_dem.constitutive import (
    ALPHA_TABLE_A1,
    DEFAULT_ALPHA,
    FLAG_DETACHED,
    FLAG_ROCKING_1,
    FLAG_ROCKING_2,
    FLAG_SHEAR_TORSION,
    STATE_DETACHED,
    STATE_ELASTIC,
    STATE_ROCKING,
    STATE_SLIDING,
    STATE_SLIDING_ROCKING,
    alpha_from_table,
    check_strength,
    shear_strength,
    torsion_constant,
    torsion_strength,
)
from masonry_dem.constitutive.strength import SHEAR_TORSION_TOLERANCE


def _phi(actions, l1, l2, mu, ft, alpha=DEFAULT_ALPHA):
    """Value of Eq. (A5) on the reduced rectangle, computed independently of check_strength."""
    f1, f2, fn, m1, m2, m3 = np.asarray(actions, dtype=float).T
    fsu = shear_strength(fn, mu, ft)
    m3u = torsion_strength(fn, l1, l2, mu, ft, m1, m2)
    return (np.abs(m3) / m3u) ** alpha + (f1**2 + f2**2) / fsu**2


# ------------------------------------------------------------------------------------------
# reference numbers


def test_reference_shear_and_torsion_strength(ref_interface):
    r = ref_interface
    l1, l2 = r["block_width_b"], r["block_thickness_s"]
    fsu = shear_strength(r["normal_force"], r["friction"])
    assert fsu == pytest.approx(r["shear_strength"], rel=5e-3)
    c_t = torsion_constant(l1, l2)
    assert c_t == pytest.approx(0.09681, abs=5e-6)  # DESIGN.md
    m3u = torsion_strength(r["normal_force"], l1, l2, r["friction"])
    assert m3u == pytest.approx(c_t * fsu)
    assert m3u == pytest.approx(r["torsion_strength"], rel=1e-2)


def test_torsion_constant_is_mean_distance_from_centre():
    for l1, l2 in [(0.3, 0.2), (0.2, 0.3), (1.0, 1.0), (1.0, 0.1), (0.05, 2.0)]:
        n = 1200
        y1 = ((np.arange(n) + 0.5) / n - 0.5) * l1
        y2 = ((np.arange(n) + 0.5) / n - 0.5) * l2
        mean_r = np.hypot(y1[:, None], y2[None, :]).mean()
        assert torsion_constant(l1, l2) == pytest.approx(mean_r, rel=1e-5)
    # square: (sqrt(2) + asinh(1)) / 6; symmetry; degenerate limits used by the reduced rectangle
    assert torsion_constant(1.0, 1.0) == pytest.approx((np.sqrt(2) + np.arcsinh(1.0)) / 6)
    assert torsion_constant(0.3, 0.2) == pytest.approx(torsion_constant(0.2, 0.3))
    assert torsion_constant(0.3, 1e-12) == pytest.approx(0.3 / 4, rel=1e-9)
    assert torsion_constant([0.3, 0.6], 0.2).shape == (2,)


def test_embedded_table_a1_matches_reference(table_a1, alpha_columns):
    assert list(ALPHA_TABLE_A1["aspect"]) == table_a1["aspect_l1_over_l2"]
    for direction, column in alpha_columns.items():
        assert list(ALPHA_TABLE_A1[direction]) == column
    assert table_a1["alpha_masonry_default"] == DEFAULT_ALPHA


def test_alpha_from_table(table_a1, alpha_columns):
    aspects = np.array(table_a1["aspect_l1_over_l2"])
    for direction, column in alpha_columns.items():
        np.testing.assert_allclose(alpha_from_table(aspects, direction), column)
    lo, hi = table_a1["alpha_shear_f1"][2:4]
    mid = alpha_from_table(np.sqrt(0.5 * 1.0), "f1")  # geometric mean of 0.5 and 1.0
    assert mid == pytest.approx(0.5 * (lo + hi))
    assert alpha_from_table(100.0, "f1") == table_a1["alpha_shear_f1"][-1]
    assert alpha_from_table(1e-3, "f2") == table_a1["alpha_shear_f2"][0]
    with pytest.raises(ValueError, match="direction"):
        alpha_from_table(1.0, "f3")
    with pytest.raises(ValueError, match="aspect"):
        alpha_from_table(0.0, "f1")


# ------------------------------------------------------------------------------------------
# the criteria one by one


L1, L2, MU, FN = 0.3, 0.2, 0.7, -240.0


def test_shear_domain_is_a_circle():
    ang = np.linspace(0, 2 * np.pi, 37)
    inside = np.zeros((ang.size, 6))
    inside[:, 0], inside[:, 1], inside[:, 2] = 167.9 * np.cos(ang), 167.9 * np.sin(ang), FN
    r = check_strength(inside, L1, L2, MU, 0.0)
    assert (r.state == STATE_ELASTIC).all()
    np.testing.assert_allclose(r.utilisation, 167.9 / 168.0)
    outside = inside.copy()
    outside[:, :2] *= 2.0
    r = check_strength(outside, L1, L2, MU, 0.0)
    assert (r.state == STATE_SLIDING).all()
    assert (r.flags == FLAG_SHEAR_TORSION).all()
    np.testing.assert_allclose(np.hypot(*r.projected[:, :2].T), 168.0, rtol=1e-12)
    np.testing.assert_allclose(r.projected[:, :2], inside[:, :2] * 168.0 / 167.9, rtol=1e-12)
    np.testing.assert_allclose(r.utilisation, 2 * 167.9 / 168.0)
    np.testing.assert_array_equal(r.stiffness_factors[0], [0, 0, 1, 1, 1, 0])


def test_pure_torsion_limit():
    m3u = float(torsion_strength(FN, L1, L2, MU))
    r = check_strength([[0, 0, FN, 0, 0, 0.999 * m3u], [0, 0, FN, 0, 0, -1.5 * m3u]], L1, L2, MU, 0)
    np.testing.assert_array_equal(r.state, [STATE_ELASTIC, STATE_SLIDING])
    assert r.projected[1, 5] == pytest.approx(-m3u, rel=1e-12)
    np.testing.assert_allclose(r.utilisation, [0.999, 1.5])


def test_rocking_levers_are_half_sides():
    # the paper's horizontal running-bond joint: l1 = b/2, l2 = s -> lc1 = s/2, lc2 = b/4
    b, s, ft, fn = 0.21, 0.07, 50.0, -300.0
    l1, l2 = b / 2, s
    cap = ft - fn
    trial = np.array([[0, 0, fn, 1.2 * cap * s / 2, 0, 0], [0, 0, fn, 0, -1.2 * cap * b / 4, 0]])
    r = check_strength(trial, l1, l2, MU, ft)
    np.testing.assert_array_equal(r.state, [STATE_ROCKING, STATE_ROCKING])
    np.testing.assert_array_equal(r.flags, [FLAG_ROCKING_1, FLAG_ROCKING_2])
    assert r.projected[0, 3] == pytest.approx(cap * s / 2)
    assert r.projected[1, 4] == pytest.approx(-cap * b / 4)
    np.testing.assert_array_equal(r.stiffness_factors[0], [1, 1, 1, 0, 1, 1])
    np.testing.assert_array_equal(r.stiffness_factors[1], [1, 1, 1, 1, 0, 1])
    np.testing.assert_allclose(r.utilisation, 1.2)


def test_detachment():
    trial = np.array([[10.0, -3.0, 5.0, 1.0, 2.0, 3.0], [10.0, -3.0, 12.0, 1.0, 2.0, 3.0]])
    r = check_strength(trial, L1, L2, MU, [0.0, 6.0])
    np.testing.assert_array_equal(r.state, [STATE_DETACHED, STATE_DETACHED])
    np.testing.assert_array_equal(r.flags, [FLAG_DETACHED, FLAG_DETACHED])
    np.testing.assert_array_equal(r.projected, [[0, 0, 0, 0, 0, 0], [0, 0, 6, 0, 0, 0]])
    np.testing.assert_array_equal(r.stiffness_factors, 0.0)
    assert r.utilisation[0] == np.inf and r.utilisation[1] == pytest.approx(2.0)


def test_sliding_and_rocking_together():
    trial = [[300.0, 0, FN, 30.0, 0, 0]]
    r = check_strength(trial, L1, L2, MU, 0.0)
    assert r.state[0] == STATE_SLIDING_ROCKING
    assert r.flags[0] == FLAG_SHEAR_TORSION | FLAG_ROCKING_1
    np.testing.assert_array_equal(r.stiffness_factors[0], [0, 0, 1, 0, 1, 0])


def test_torsion_reduced_by_bending_figure_10():
    m1, m2 = 6.0, 9.0
    cap = -FN
    l1r, l2r = L1 - 2 * m2 / cap, L2 - 2 * m1 / cap
    m3u = torsion_constant(l1r, l2r) * MU * cap
    assert torsion_strength(FN, L1, L2, MU, 0.0, m1, -m2) == pytest.approx(m3u)
    trial = [[0, 0, FN, m1, -m2, 1.01 * m3u], [0, 0, FN, m1, -m2, 0.99 * m3u]]
    r = check_strength(trial, L1, L2, MU, 0.0)
    np.testing.assert_array_equal(r.state, [STATE_SLIDING, STATE_ELASTIC])
    assert r.projected[0, 5] == pytest.approx(m3u, rel=1e-12)
    r = check_strength(trial, L1, L2, MU, 0.0, torsion_bending_interaction=False)
    np.testing.assert_array_equal(r.state, [STATE_ELASTIC, STATE_ELASTIC])
    # rocking moments are clipped before the reduced rectangle is formed: zero side, cT = l1'/4
    r = check_strength([[0, 0, FN, 100.0, 0, 20.0]], L1, L2, MU, 0.0)
    assert r.projected[0, 5] == pytest.approx(L1 / 4 * MU * cap, rel=1e-12)
    # both moments at their limits: the joint bears on a corner, no torsion capacity. A point
    # contact still carries shear up to mu |fn|: the energy projection keeps it and drops the
    # torsion; the radial projection's limit drops the shear too
    trial = [[50.0, 0, FN, 100.0, 100.0, 10.0], [50.0, 0, FN, 100, 100, 0]]
    r = check_strength(trial, L1, L2, MU, 0)
    np.testing.assert_allclose(r.projected, [[50, 0, FN, 24.0, 36.0, 0], [50.0, 0, FN, 24, 36, 0]])
    np.testing.assert_allclose(r.utilisation, [np.inf, 100.0 / 24.0])  # trial rocking ratio
    r = check_strength([[500.0, 0, FN, 100.0, 100.0, 10.0]], L1, L2, MU, 0)
    np.testing.assert_allclose(r.projected, [[MU * cap, 0, FN, 24.0, 36.0, 0]])
    r = check_strength(trial, L1, L2, MU, 0, projection="radial")
    np.testing.assert_allclose(r.projected, [[0, 0, FN, 24.0, 36.0, 0], [50.0, 0, FN, 24, 36, 0]])


@pytest.mark.parametrize("alpha", [1.0, 1.43, 2.0, 2.56, 3.7])
def test_shear_torsion_projection_lands_on_eq_a5(alpha):
    rng = np.random.default_rng(1)
    trial = np.zeros((200, 6))
    trial[:, [0, 1, 5]] = rng.normal(size=(200, 3)) * [200.0, 200.0, 20.0]
    trial[:, 2] = FN
    r = check_strength(trial, L1, L2, MU, 0.0, alpha=alpha, projection="radial")
    sl = r.state == STATE_SLIDING
    assert sl.sum() > 50
    phi = _phi(r.projected[sl], L1, L2, MU, 0.0, alpha)
    np.testing.assert_allclose(phi, 1.0, atol=1e-12)
    # radial: the projected (f1, f2, m3) is a positive multiple of the trial one
    ratio = r.projected[sl][:, [0, 1, 5]] / trial[sl][:, [0, 1, 5]]
    np.testing.assert_allclose(ratio, ratio[:, :1] * np.ones((1, 3)), rtol=1e-12)
    assert ((ratio > 0) & (ratio < 1)).all()
    np.testing.assert_allclose(r.utilisation[sl], 1.0 / ratio[:, 0], rtol=1e-12)


def test_alpha_per_interface_and_broadcasting():
    m3u = float(torsion_strength(FN, L1, L2, MU))
    trial = np.tile([84.0, 0.0, FN, 0.0, 0.0, 0.8 * m3u], (2, 1))
    # 0.8^alpha + (84/168)^2: 1.05 for alpha = 1 (outside), 0.89 for alpha = 2 (inside)
    r = check_strength(trial, L1, L2, MU, 0.0, alpha=[1.0, 2.0])
    np.testing.assert_array_equal(r.state, [STATE_SLIDING, STATE_ELASTIC])
    single = check_strength(trial[0], L1, L2, MU, 0.0, alpha=1.0)
    assert single.projected.shape == (1, 6)
    np.testing.assert_array_equal(single.projected[0], r.projected[0])


def test_utilisation_zero_capacity_conventions():
    trial = np.array(
        [
            [0, 0, 0.0, 0, 0, 0],  # dry joint at fn = ft = 0: on the detachment limit
            [1.0, 0, 0.0, 0, 0, 0],  # shear demand at zero capacity
            [0, 0, -10.0, 0, 0, 0],  # compressed, no other demand
            [0, 0, 3.0, 0, 0, 0],  # tension within ft = 4
        ]
    )
    r = check_strength(trial, L1, L2, MU, [0.0, 0.0, 0.0, 4.0])
    np.testing.assert_array_equal(r.utilisation, [1.0, np.inf, 0.0, 0.75])
    np.testing.assert_array_equal(r.state, [STATE_ELASTIC, STATE_SLIDING, 0, 0])
    np.testing.assert_array_equal(r.projected[1], 0.0)


# ------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"friction": -0.1}, "friction"),
        ({"l1": 0.0}, "l1"),
        ({"l2": -0.2}, "l2"),
        ({"tensile_force": -1.0}, "tensile_force"),
        ({"alpha": 0.5}, "alpha"),
        ({"l1": np.nan}, "l1"),
        ({"friction": [0.7, 0.7, 0.7]}, "friction"),
        ({"actions": [[0, 0, -1, 0, 0, np.nan]]}, "actions"),
        ({"actions": [[0, 0, -1, 0, np.inf, 0]]}, "actions"),
        ({"actions": np.zeros((2, 5))}, "actions"),
    ],
)
def test_bad_input_names_the_field(kwargs, field):
    args = {
        "actions": np.zeros((2, 6)),
        "l1": L1,
        "l2": L2,
        "friction": MU,
        "tensile_force": 0.0,
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=field):
        check_strength(**args)


def test_helpers_bad_input():
    with pytest.raises(ValueError, match="friction"):
        shear_strength(-1.0, -0.7)
    with pytest.raises(ValueError, match="l2"):
        torsion_strength(-1.0, 0.3, 0.0, 0.7)
    with pytest.raises(ValueError, match="l1"):
        torsion_constant(-0.3, 0.2)


# ------------------------------------------------------------------------------------------
# properties

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
rows = st.lists(st.tuples(*[finite] * 6), min_size=1, max_size=40)
geometry = st.tuples(
    st.floats(0.01, 2.0),  # l1
    st.floats(0.01, 2.0),  # l2
    st.floats(0.0, 1.5),  # friction
    st.floats(0.0, 500.0),  # tensile force
    st.floats(1.0, 3.0),  # alpha
)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(rows, geometry, st.booleans())
def test_projection_lies_on_or_inside_the_domain(data, geom, interaction):
    l1, l2, mu, ft, alpha = geom
    trial = np.array(data)
    r = check_strength(trial, l1, l2, mu, ft, alpha, interaction)
    assert np.isfinite(r.projected).all()
    assert not np.isnan(r.utilisation).any()
    p = r.projected
    cap = ft - p[:, 2]
    assert (cap >= 0).all()
    # limits computed as 0.5 cap l: (cap l) / 2 rounds differently only for subnormal cap
    assert (np.abs(p[:, 3]) <= cap * l2 / 2 * (1 + 1e-12) + 1e-300).all()
    assert (np.abs(p[:, 4]) <= cap * l1 / 2 * (1 + 1e-12) + 1e-300).all()
    again = check_strength(p, l1, l2, mu, ft, alpha, interaction)
    assert (again.state == STATE_ELASTIC).all()
    assert (again.utilisation <= 1.0 + 1e-9).all()
    np.testing.assert_array_equal(again.projected, p)  # a projection is idempotent
    # states and flags agree
    assert ((r.state == STATE_DETACHED) == ((r.flags & FLAG_DETACHED) > 0)).all()
    rocking = (r.flags & (FLAG_ROCKING_1 | FLAG_ROCKING_2)) > 0
    sliding = (r.flags & FLAG_SHEAR_TORSION) > 0
    live = r.state != STATE_DETACHED
    np.testing.assert_array_equal(r.state[live], (sliding * 1 + rocking * 2)[live])


@settings(max_examples=150, deadline=None, derandomize=True)
@given(rows, geometry, st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_actions_inside_are_returned_unchanged(data, geom, shrink_st, shrink_m):
    l1, l2, mu, ft, alpha = geom
    on = check_strength(np.array(data), l1, l2, mu, ft, alpha).projected
    inside = on.copy()
    inside[:, [0, 1, 5]] *= shrink_st  # smaller shear and torsion
    inside[:, [3, 4]] *= shrink_m  # smaller bending only enlarges the torsion capacity
    r = check_strength(inside, l1, l2, mu, ft, alpha)
    assert (r.state == STATE_ELASTIC).all()
    assert r.projected.tobytes() == inside.tobytes()  # bitwise
    assert (r.stiffness_factors == 1.0).all()


@settings(max_examples=150, deadline=None, derandomize=True)
@given(rows, geometry, st.floats(0.01, 100.0))
def test_domain_scales_linearly_with_compression(data, geom, k):
    l1, l2, mu, ft, alpha = geom
    trial = np.array(data)
    # scaling is exact only while no entry underflows to zero (e.g. a subnormal torsion)
    assume(np.array_equal(k * trial == 0, trial == 0) and (k * ft == 0) == (ft == 0))
    base = check_strength(trial, l1, l2, mu, ft, alpha)
    scaled = check_strength(k * trial, l1, l2, mu, k * ft, alpha)
    # away from the boundary (where rounding may flip a state) the answers scale exactly
    clear = np.abs(base.utilisation - 1.0) > 1e-6
    assume(clear.any())
    np.testing.assert_array_equal(scaled.state[clear], base.state[clear])
    np.testing.assert_allclose(
        scaled.projected[clear], k * base.projected[clear], rtol=1e-9, atol=1e-9 * k
    )
    finite_u = clear & (base.utilisation < 1e12)
    np.testing.assert_allclose(scaled.utilisation[finite_u], base.utilisation[finite_u], rtol=1e-9)


def test_tolerance_is_tiny():
    assert 0 < SHEAR_TORSION_TOLERANCE <= 1e-8


@pytest.mark.parametrize("alpha", [1.0, 1.43, 2.0, 2.56, 3.7])
def test_energy_projection_is_the_closest_boundary_point(alpha):
    """The default return lands on Eq. (A5) at the point of least elastic energy of the
    correction, |df|^2 / (kt A) + dm3^2 / (kt J): checked against 200 001 points sampled on
    the boundary (shear direction kept, so the problem is two-dimensional)."""
    rng = np.random.default_rng(2)
    trial = np.zeros((100, 6))
    trial[:, [0, 1, 5]] = rng.normal(size=(100, 3)) * [200.0, 200.0, 20.0]
    trial[:, 2] = FN
    r = check_strength(trial, L1, L2, MU, 0.0, alpha=alpha)
    sl = r.state == STATE_SLIDING
    assert sl.sum() > 30
    p, t = r.projected[sl], trial[sl]
    np.testing.assert_allclose(_phi(p, L1, L2, MU, 0.0, alpha), 1.0, atol=1e-9)
    rho2 = (L1**2 + L2**2) / 12.0  # J / A
    fsu = MU * -FN
    m3u = torsion_constant(L1, L2) * fsu
    s = np.linspace(0.0, 1.0, 200_001)
    z, rr = m3u * s, fsu * np.sqrt(1.0 - s**alpha)
    r0, z0 = np.hypot(t[:, 0], t[:, 1]), np.abs(t[:, 5])
    best = ((rr[None] - r0[:, None]) ** 2 + (z[None] - z0[:, None]) ** 2 / rho2).min(axis=1)
    got = (np.hypot(p[:, 0], p[:, 1]) - r0) ** 2 + (np.abs(p[:, 5]) - z0) ** 2 / rho2
    assert np.all(got <= best * (1 + 1e-6) + 1e-12)
    # the shear keeps its direction, the torsion its sign
    cross = p[:, 0] * t[:, 1] - p[:, 1] * t[:, 0]
    np.testing.assert_allclose(cross, 0.0, atol=1e-9)
    assert np.all(p[:, 5] * t[:, 5] >= 0)


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.0, 2.7, 3.7])
def test_energy_projection_converges_at_both_ends_of_the_curve(alpha, caplog):
    """Trials near pure torsion (where sqrt(1 - t^alpha) is singular in the shear-end
    parameter) and near pure shear (alpha = 1 has a vertex there) converge, every row, to the
    closest boundary point; no row is left to the radial fallback."""
    from helpers.numpy_reference import _energy_closest_point

    ang = np.concatenate([np.geomspace(1e-9, 1e-2, 40), np.pi / 2 - np.geomspace(1e-9, 1e-2, 40)])
    ang = np.concatenate([ang, np.linspace(0.01, np.pi / 2 - 0.01, 40)])
    scale = np.repeat([1.02, 3.0, 50.0], ang.size)
    ang = np.tile(ang, 3)
    a, b = np.full(ang.size, 2.0), np.full(ang.size, 0.7)
    r0, z0 = a * scale * np.cos(ang), b * scale * np.sin(ang)
    with caplog.at_level("DEBUG", logger="masonry_dem.constitutive.strength"):
        r, z = _energy_closest_point(r0, z0, a, b, alpha)
    assert "did not converge" not in caplog.text
    np.testing.assert_allclose((z / b) ** alpha + (r / a) ** 2, 1.0, atol=1e-12)
    s = np.linspace(0.0, 1.0, 400_001)
    zz, rr = b[0] * s, a[0] * np.sqrt(1.0 - s**alpha)
    best = np.array([((rr - x) ** 2 + (zz - y) ** 2).min() for x, y in zip(r0, z0, strict=True)])
    got = (r - r0) ** 2 + (z - z0) ** 2
    assert np.all(got <= best * (1 + 1e-6) + 1e-14)
