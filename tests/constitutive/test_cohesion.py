"""A cohesion of its own: the Mohr-Coulomb domain |tau| <= c - mu sigma with the tension cap
sigma <= ft <= c / mu (Lourenco's joint: ft 0.16 MPa, c 0.224 MPa, mu 0.75), against its closed
forms, the spring model and the interface law."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.constitutive import (
    FLAG_DETACHED,
    FLAG_SHEAR_TORSION,
    check_strength,
    shear_strength,
    shear_strength_numeric,
    torsion_constant,
    torsion_strength,
    torsion_strength_numeric,
)
from masonry_dem.constitutive.law import InterfaceLaw
from masonry_dem.geometry.builders import add_base, single_block
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support

L1, L2 = 0.3, 0.2
AREA = L1 * L2
MU, FT, C = 0.75, 0.16e6, 0.224e6  # Lourenco's joint [Pa]
FTA, CA = FT * AREA, C * AREA
C0 = CA - MU * FTA  # the shear strength left at the cap
FNS = np.array([-5.0e4, -1.0e3, 0.0, 0.5 * FTA, FTA])  # compression and tension


def test_shear_strength_is_c_a_minus_mu_fn_up_to_the_cap():
    fsu = shear_strength(FNS, MU, FTA, CA)
    np.testing.assert_allclose(fsu, CA - MU * FNS, rtol=1e-9)
    assert fsu[-1] == pytest.approx(C0, rel=1e-9)  # at the cap: the vertical side
    assert shear_strength(FTA * (1 + 1e-9), MU, FTA, CA) == 0.0  # beyond it: detached
    # without a cohesion of its own: the paper's mu (ft - fn), zero at the cap
    np.testing.assert_array_equal(shear_strength(FNS, MU, FTA), MU * np.maximum(FTA - FNS, 0))


def test_torsion_strength_generalises_eq_12():
    c_t = float(torsion_constant(L1, L2))
    m3u = torsion_strength(FNS, L1, L2, MU, FTA, cohesive_force=CA)
    np.testing.assert_allclose(m3u, c_t * (CA - MU * FNS), rtol=1e-9)
    # with bending: the reduced rectangle carries mu (ft - fn), the whole one c - mu ft
    fn, m1 = -2.0e3, 30.0
    cap = FTA - fn
    l2r = L2 - 2 * m1 / cap
    expected = float(torsion_constant(L1, l2r)) * MU * cap + c_t * C0
    assert torsion_strength(fn, L1, L2, MU, FTA, m1=m1, cohesive_force=CA) == pytest.approx(
        expected, rel=1e-9
    )


def _check(actions, **kw):
    return check_strength(actions, L1, L2, MU, FTA, cohesive_force=CA, **kw)


def test_the_check_projects_shear_and_torsion_on_the_cohesive_domain():
    for fn in FNS:
        chk = _check([[1e7, 0.0, fn, 0.0, 0.0, 0.0]])
        assert chk.flags[0] == FLAG_SHEAR_TORSION
        assert chk.projected[0, 0] == pytest.approx(CA - MU * fn, rel=1e-9)
        chk = _check([[0.0, 0.0, fn, 0.0, 0.0, 1e6]], projection="radial")
        assert chk.projected[0, 5] == pytest.approx(
            float(torsion_constant(L1, L2)) * (CA - MU * fn), rel=1e-9
        )
    inside = [[0.99 * (CA + MU * 1e3), 0.0, -1e3, 0.0, 0.0, 0.0]]
    chk = _check(inside)
    assert chk.flags[0] == 0 and chk.utilisation[0] == pytest.approx(0.99, rel=1e-9)
    np.testing.assert_array_equal(chk.projected, inside)


def test_the_tension_cap_is_vertical():
    """At fn = ft A the joint still carries the shear (c - mu ft) A; beyond it, it is
    detached (its actions projected to ft alone)."""
    chk = _check([[0.5 * C0, 0.0, FTA, 0.0, 0.0, 0.0], [2 * C0, 0.0, FTA, 0.0, 0.0, 0.0]])
    assert chk.flags.tolist() == [0, FLAG_SHEAR_TORSION]
    assert chk.projected[1, 0] == pytest.approx(C0, rel=1e-12)
    chk = _check([[0.5 * C0, 0.0, FTA * (1 + 1e-9), 0.0, 0.0, 0.0]])
    assert chk.flags[0] == FLAG_DETACHED
    np.testing.assert_array_equal(chk.projected[0], [0.0, 0.0, FTA, 0.0, 0.0, 0.0])


def test_cohesion_equal_to_mu_ft_is_the_papers_domain():
    rng = np.random.default_rng(41)
    act = rng.normal(size=(50, 6)) * [3e3, 3e3, 5e3, 200.0, 300.0, 400.0]
    paper = check_strength(act, L1, L2, MU, FTA)
    given = check_strength(act, L1, L2, MU, FTA, cohesive_force=MU * FTA)
    np.testing.assert_array_equal(given.flags, paper.flags)
    np.testing.assert_allclose(given.projected, paper.projected, rtol=1e-12, atol=1e-9)


def test_a_cohesive_force_below_mu_ft_is_refused():
    with pytest.raises(ValueError, match="cohesive_force must be at least"):
        check_strength(np.zeros(6), L1, L2, MU, FTA, cohesive_force=0.5 * MU * FTA)
    with pytest.raises(ValueError, match="cohesive_force must be finite"):
        shear_strength(0.0, MU, FTA, np.nan)


# ------------------------------------------------------------------------------------------
# the spring model


@pytest.mark.parametrize("fn", [-2.0e4, -1.0e3, 0.5 * FTA])
def test_spring_model_shear_strength_is_the_closed_form(fn):
    angles = np.array([0.0, 0.7, 1.9])
    fs = shear_strength_numeric(L1, L2, fn, MU, FT, angles=angles, n=16, cohesion=C)
    np.testing.assert_allclose(fs, shear_strength(fn, MU, FTA, CA), rtol=1e-9)


def test_spring_model_torsion_strength_is_the_closed_form():
    fn = -2.0e3
    m3 = torsion_strength_numeric(L1, L2, fn, MU, FT, n=32, cohesion=C)
    assert m3 == pytest.approx(torsion_strength(fn, L1, L2, MU, FTA, cohesive_force=CA), rel=1e-3)
    # with a bending moment (Figure 10): the reduced rectangle plus the rest at the cap
    m3 = torsion_strength_numeric(L1, L2, fn, MU, FT, n=32, cohesion=C, m1=30.0)
    closed = torsion_strength(fn, L1, L2, MU, FTA, m1=30.0, cohesive_force=CA)
    assert m3 == pytest.approx(closed, rel=2e-3)


# ------------------------------------------------------------------------------------------
# the model and the law


def _model(cohesion=C, overrides=()):
    blocks, base = add_base(single_block(0.1, L1, L2, 18e3))
    mat = InterfaceMaterial(kn=1e10, kt=4e9, friction=MU, tensile_strength=FT, cohesion=cohesion)
    return Model.build(
        blocks, mat, supports=[Support([base])], loads=[SelfWeight()], material_overrides=overrides
    )


def test_the_model_resolves_the_cohesion():
    assert _model().cohesion.tolist() == [C]
    assert _model(None).cohesion.tolist() == [MU * FT]
    assert _model(None).cohesion_beyond_friction.tolist() == [0.0]
    dry = InterfaceMaterial(kn=1e10, kt=4e9, friction=0.6, cohesion=5e3)
    assert _model(None, overrides=[([0], dry)]).cohesion.tolist() == [5e3]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"cohesion": -1.0}, "cohesion"),
        ({"cohesion": float("nan")}, "cohesion"),
        ({"cohesion": 0.1e6}, r"tensile_strength must be at most cohesion / friction = 133333"),
    ],
)
def test_a_bad_cohesion_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        InterfaceMaterial(kn=1e10, kt=4e9, friction=MU, tensile_strength=FT, **kwargs)


def test_no_friction_allows_any_tension_cap():
    mat = InterfaceMaterial(kn=1e10, kt=4e9, friction=0.0, tensile_strength=FT, cohesion=0.0)
    assert mat.cohesion == 0.0


def test_a_cracked_joint_loses_its_cohesion():
    model = _model()
    its = model.interfaces
    law = InterfaceLaw.of(model, np.tile([4e9, 4e9, 1e10, 1e10, 1e10, 1e10], (1, 1)) * its.area)
    fn = -1.0e3
    rel = np.array([[1.0, 0.0, fn / (1e10 * its.area[0]), 0.0, 0.0, 0.0]])
    zero = np.zeros((1, 6))
    whole = law.respond(rel, zero, np.array([False]))
    cracked = law.respond(rel, zero, np.array([True]))
    area = float(its.area[0])
    assert whole.actions[0, 0] == pytest.approx(C * area - MU * fn, rel=1e-9)
    assert cracked.actions[0, 0] == pytest.approx(-MU * fn, rel=1e-9)  # a dry Coulomb joint
    assert law.utilisation(cracked)[0] > law.utilisation(whole)[0]
