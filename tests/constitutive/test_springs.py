"""Spring (fibre) model of one interface (Section 2.1, Appendix) against the closed form."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.constitutive import (
    REFERENCE_INTERFACE,
    SpringInterface,
    fit_alpha,
    shear_strength,
    shear_strength_numeric,
    torsion_shear_domain,
    torsion_strength,
    torsion_strength_numeric,
)

# Table A1 entries where the exponent fitted to our spring-model domains differs from the
# published one by more than 0.1 (measured: 0.119, 0.119, 0.115, 0.115). The published values
# could not be reproduced with any fitting norm we tried (radial, area, minimax): the
# spring-model domain is exact rigid-plastic, so these are reported, not tuned away.
KNOWN_TABLE_A1_MISSES = {(5.0, "f1"), (0.2, "f2"), (0.5, "f1=f2"), (2.0, "f1=f2")}


@pytest.fixture(scope="module")
def ref(ref_interface):
    r = ref_interface
    return {
        "l1": r["block_width_b"],
        "l2": r["block_thickness_s"],
        "fn": r["normal_force"],
        "mu": r["friction"],
        "kn": r["kn"],
        "ks": r["ks"],
        "n": r["springs_per_side"],
    }


@pytest.fixture(scope="module")
def iface(ref):
    return SpringInterface(ref["l1"], ref["l2"], ref["n"], ref["kn"], ref["ks"], ref["mu"])


def test_embedded_reference_interface_matches_toml(ref, ref_interface):
    r = REFERENCE_INTERFACE
    assert (r.l1, r.l2, r.normal_force) == (ref["l1"], ref["l2"], ref["fn"])
    assert (r.kn, r.ks, r.friction, r.n) == (ref["kn"], ref["ks"], ref["mu"], ref["n"])
    # the normal force is the self-weight of the block above
    ri = ref_interface
    weight = (
        ri["unit_weight"] * ri["block_width_b"] * ri["block_height_a"] * ri["block_thickness_s"]
    )
    assert -weight == pytest.approx(ref["fn"])


# ------------------------------------------------------------------------------------------
# Section 2.1 reference figures


def test_shear_strength_168_N_in_every_direction(ref, ref_interface):
    angles = np.linspace(0.0, 2.0 * np.pi, 72, endpoint=False)
    fs = shear_strength_numeric(ref["l1"], ref["l2"], ref["fn"], ref["mu"], angles=angles, n=32)
    np.testing.assert_allclose(fs, ref_interface["shear_strength"], rtol=5e-3)
    np.testing.assert_allclose(fs, shear_strength(ref["fn"], ref["mu"]), rtol=1e-12)


def test_pure_torsion_16_2_N_m(ref, ref_interface):
    m3 = torsion_strength_numeric(ref["l1"], ref["l2"], ref["fn"], ref["mu"], n=32)
    assert m3 == pytest.approx(ref_interface["torsion_strength"], rel=1e-2)
    assert m3 == pytest.approx(
        torsion_strength(ref["fn"], ref["l1"], ref["l2"], ref["mu"]), rel=1e-3
    )


def test_torsion_strength_converges_to_closed_form(ref):
    closed = float(torsion_strength(ref["fn"], ref["l1"], ref["l2"], ref["mu"]))
    ns = [4, 8, 16, 32, 64]
    err = np.array(
        [
            abs(
                torsion_strength_numeric(ref["l1"], ref["l2"], ref["fn"], ref["mu"], n=n) / closed
                - 1
            )
            for n in ns
        ]
    )
    assert (np.diff(err) < 0).all(), err
    # midpoint quadrature of |r|: second order
    np.testing.assert_allclose(err[:-1] / err[1:], 4.0, rtol=0.1)
    assert err[-1] < 2e-4


def test_figure_a1_torsion_against_tensile_strength(ref):
    area = ref["l1"] * ref["l2"]
    for sigma_t in [0.0, 2e3, 1e4, 5e4, 2e5]:
        num = torsion_strength_numeric(ref["l1"], ref["l2"], ref["fn"], ref["mu"], sigma_t, n=32)
        closed = torsion_strength(ref["fn"], ref["l1"], ref["l2"], ref["mu"], sigma_t * area)
        assert num == pytest.approx(closed, rel=2e-2)


def test_figure_10_torsion_against_bending(ref):
    cap = -ref["fn"]
    m1_lim, m2_lim = cap * ref["l2"] / 2, cap * ref["l1"] / 2
    for u1, u2 in [(0.3, 0.0), (0.8, 0.0), (0.0, 0.5), (0.0, 0.9), (0.5, 0.5), (0.9, 0.7)]:
        m1, m2 = u1 * m1_lim, -u2 * m2_lim
        num = torsion_strength_numeric(ref["l1"], ref["l2"], ref["fn"], ref["mu"], m1=m1, m2=m2)
        closed = torsion_strength(ref["fn"], ref["l1"], ref["l2"], ref["mu"], 0.0, m1, m2)
        assert num == pytest.approx(closed, rel=2e-2)
    with pytest.raises(ValueError, match="rocking limit"):
        torsion_strength_numeric(ref["l1"], ref["l2"], ref["fn"], ref["mu"], m1=m1_lim)


def test_table_a1_alpha_within_0_1(table_a1, alpha_columns):
    for direction, column in alpha_columns.items():
        for aspect, paper in zip(table_a1["aspect_l1_over_l2"], column, strict=True):
            fitted = fit_alpha(aspect, direction, n=32)
            tol = 0.125 if (aspect, direction) in KNOWN_TABLE_A1_MISSES else 0.1
            assert fitted == pytest.approx(paper, abs=tol), (aspect, direction, fitted)


@pytest.mark.xfail(strict=True, reason="published alpha not reproduced within 0.1 (see report)")
@pytest.mark.parametrize(("aspect", "direction"), sorted(KNOWN_TABLE_A1_MISSES))
def test_table_a1_known_misses(table_a1, alpha_columns, aspect, direction):
    i = table_a1["aspect_l1_over_l2"].index(aspect)
    paper = alpha_columns[direction][i]
    assert fit_alpha(aspect, direction, n=32) == pytest.approx(paper, abs=0.1)


def test_torsion_shear_domain_shape():
    x, y = torsion_shear_domain(1.0, "f1", n=16, points=24)
    assert (x[0], y[0]) == (1.0, pytest.approx(0.0, abs=1e-9))
    assert (x[-1], y[-1]) == (pytest.approx(0.0, abs=1e-9), 1.0)
    assert (np.diff(x) <= 1e-12).all() and (np.diff(y) >= -1e-12).all()
    # square interface: the domain lies between the linear and the circular one
    assert (x + y**2 >= 1 - 1e-9).all() and (x**2 + y**2 <= 1 + 1e-9).all()
    # symmetry l1/l2 <-> shear direction
    xa, ya = torsion_shear_domain(2.0, "f1", n=16, points=12)
    xb, yb = torsion_shear_domain(0.5, "f2", n=16, points=12)
    np.testing.assert_allclose(xa, xb, atol=1e-9)
    np.testing.assert_allclose(ya, yb, atol=1e-9)


# ------------------------------------------------------------------------------------------
# mechanics of the model


def test_elastic_stiffness_and_sign_conventions(iface):
    n, a = iface.n, iface.cell_area
    y1, y2 = iface.centres.T
    i1, i2 = np.sum(y2**2) * a, np.sum(y1**2) * a  # discrete second moments
    assert i1 == pytest.approx(iface.l1 * iface.l2**3 / 12 * (1 - 1 / n**2))
    big = SpringInterface(iface.l1, iface.l2, n, iface.kn, iface.ks, 0.7, tensile_strength=1e9)
    d = np.array([[1e-7, -2e-7, 3e-7, 4e-7, -5e-7, 6e-7]])
    f = big.run(d).actions[0]
    kn, ks, area = iface.kn, iface.ks, iface.area
    expected = [ks * area * 1e-7, -ks * area * 2e-7, kn * area * 3e-7, kn * i1 * 4e-7,
                -kn * i2 * 5e-7, ks * (i1 + i2) * 6e-7]  # fmt: skip
    np.testing.assert_allclose(f, expected, rtol=1e-12)
    # work conjugacy: the resultants do the work of the spring stresses
    r = big.run(d)
    slip = np.column_stack([d[0, 0] - d[0, 5] * y2, d[0, 1] + d[0, 5] * y1])
    un = d[0, 2] + d[0, 3] * y2 - d[0, 4] * y1
    work = a * (np.sum(r.spring_shear[0] * slip) + r.spring_normal[0] @ un)
    assert work == pytest.approx(f @ d[0], rel=1e-12)


def test_no_tension_and_tension_cut_off(iface):
    opening = np.array([[0, 0, 1e-3, 0, 0, 0]])
    assert np.all(iface.run(opening).actions == 0.0)
    glued = SpringInterface(iface.l1, iface.l2, 8, iface.kn, iface.ks, 0.7, tensile_strength=5e4)
    r = glued.run(opening)
    assert r.actions[0, 2] == pytest.approx(5e4 * glued.area)
    np.testing.assert_allclose(r.spring_normal, 5e4)


def test_prescribed_normal_force_with_bending(iface):
    steps = 60
    path = np.zeros((steps, 6))
    path[:, 3] = np.linspace(0, 2e-2, steps)  # rocking about y1
    path[:, 4] = np.linspace(0, -5e-3, steps)
    r = iface.run(path, normal_force=-240.0)
    np.testing.assert_allclose(r.actions[:, 2], -240.0, rtol=1e-10)
    assert (r.spring_normal <= 0).all()
    # eccentricity bounded by the outer row of springs, and reached at large rotation
    h2 = iface.l2 / iface.n
    m1_max = 240.0 * (iface.l2 / 2 - h2 / 2)
    assert (r.actions[:, 3] <= m1_max + 1e-9).all()
    assert r.actions[-1, 3] > 0.9 * m1_max
    assert (r.actions[1:, 4] < 0).all()  # delta2 < 0 presses the y1 < 0 side: m2 < 0
    # dn solved exactly: brute-force bisection on the last step
    e = path[-1, 3] * iface.centres[:, 1] - path[-1, 4] * iface.centres[:, 0]

    def fn(dn):
        return np.minimum(iface.kn * (dn + e), 0).sum() * iface.cell_area

    lo, hi = -1.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fn(mid) < -240.0 else (lo, mid)
    assert r.displacements[-1, 2] == pytest.approx(0.5 * (lo + hi), abs=1e-15)


def test_prescribed_normal_force_with_tensile_strength():
    glued = SpringInterface(0.3, 0.2, 16, 2.4e9, 1e9, 0.7, tensile_strength=1e4)
    ft = glued.tensile_force
    path = np.zeros((5, 6))
    path[:, 3] = np.linspace(0, 0.05, 5)
    targets = np.array([-240.0, 0.0, 100.0, 0.5 * ft, ft])
    r = glued.run(path, normal_force=targets)
    np.testing.assert_allclose(r.actions[:, 2], targets, rtol=1e-10, atol=1e-9)
    with pytest.raises(ValueError, match="normal_force"):
        glued.run(path, normal_force=1.01 * ft)


def test_plastic_slip_memory_cyclic_shear(iface):
    fsu = 168.0
    k = iface.ks * iface.area
    uy = fsu / k
    u = np.array([0.5, 3.0, 2.0, 0.0, -1.0, -3.0, -2.5]) * uy
    path = np.zeros((u.size, 6))
    path[:, 0] = u
    f = iface.run(path, normal_force=-240.0).actions[:, 0]
    # elastic, yield, unload elastically from +fsu, reload to -fsu, unload
    expected = [0.5 * fsu, fsu, 0.0, -fsu, -fsu, -fsu, -0.5 * fsu]
    np.testing.assert_allclose(f, expected, rtol=1e-9, atol=1e-9)


def test_pure_torsion_stress_lines_are_circles(iface):
    path = iface.rotation_paths(0.0, np.zeros(1), -240.0, steps=3)[0]
    r = iface.run(path, normal_force=-240.0)
    tau = r.spring_shear[-1]
    radial = np.sum(tau * r.centres, axis=1)
    np.testing.assert_allclose(radial, 0.0, atol=1e-9)
    np.testing.assert_allclose(np.hypot(*tau.T), 0.7 * 240.0 / iface.area, rtol=1e-12)
    np.testing.assert_allclose(r.actions[-1, :2], 0.0, atol=1e-9)


def test_batched_paths_equal_single_runs(iface):
    rng = np.random.default_rng(3)
    paths = np.cumsum(rng.normal(size=(3, 25, 6)) * [2e-5, 2e-5, 0, 2e-4, 2e-4, 2e-4], axis=1)
    batch = iface.run(paths, normal_force=[[-240.0], [-100.0], [-500.0]])
    for i, fn in enumerate([-240.0, -100.0, -500.0]):
        one = iface.run(paths[i], normal_force=fn)
        np.testing.assert_allclose(batch.actions[i], one.actions, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(batch.spring_shear[i], one.spring_shear, rtol=1e-12, atol=1e-9)
    assert batch.ultimate.shape == (3, 6)


# ------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"l1": 0.0}, "l1"),
        ({"l2": -1.0}, "l2"),
        ({"n": 0}, "n"),
        ({"n": 2.5}, "n"),
        ({"kn": np.nan}, "kn"),
        ({"ks": 0.0}, "ks"),
        ({"friction": -0.7}, "friction"),
        ({"tensile_strength": -1.0}, "tensile_strength"),
    ],
)
def test_spring_interface_bad_input(kwargs, field):
    args = {"l1": 0.3, "l2": 0.2, "n": 4, "kn": 1e9, "ks": 1e9, "friction": 0.7}
    args.update(kwargs)
    with pytest.raises(ValueError, match=field):
        SpringInterface(**args)


def test_run_bad_input(iface):
    with pytest.raises(ValueError, match="path"):
        iface.run(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="path"):
        iface.run([[0, 0, 0, 0, np.nan, 0]])
    with pytest.raises(ValueError, match="normal_force"):
        iface.run(np.zeros((3, 6)), normal_force=[1.0, 2.0])
    with pytest.raises(ValueError, match="normal_force"):
        iface.run(np.zeros((3, 6)), normal_force=10.0)  # no tensile strength
    with pytest.raises(ValueError, match="direction"):
        fit_alpha(1.0, "diagonal")
    with pytest.raises(ValueError, match="aspect"):
        fit_alpha(0.0, "f1")
