"""The analytic tangent of the interface law against differences of the projection it
differentiates.

``InterfaceLaw.tangent(method="analytic")`` differentiates the energy return of the closed-form
domain by the implicit function theorem (``law_kernels._nb_row_tangent``). Here it is checked
against central differences of :func:`check_strength` itself, row by row, on joints in every
state (sliding, rocking about either axis or both, sliding while rocking, pure shear), for
several exponents alpha, away from the kinks of the domain (where no derivative exists and
the two one-sided ones differ).
"""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.constitutive import check_strength, torsion_constant, torsion_strength
from masonry_dem.constitutive.law import InterfaceLaw
from masonry_dem.constitutive.law_kernels import _nb_torsion_constant_slope
from masonry_dem.constitutive.states import (
    FLAG_DETACHED,
    FLAG_ROCKING_1,
    FLAG_ROCKING_2,
    FLAG_SHEAR_TORSION,
)
from masonry_dem.solvers.incremental import StaticSettings

#: central differences with steps of 1e-6 of each action: truncation ~1e-12, round-off
#: ~1e-10 of a block's largest entry
CENTRAL_STEP = 1e-6
RTOL = 1e-6
KBAR = np.array([1e9, 1.2e9, 2e9, 1e6, 2e6, 5e5])


def _joints(m: int, rng: np.random.Generator, alpha=(1.25, 1.5, 2.0, 2.56)):
    """Trial actions of m compressed joints in every state, and their law."""
    l1 = rng.uniform(0.1, 0.4, m)
    l2 = rng.uniform(0.05, 0.3, m)
    mu = rng.uniform(0.3, 0.9, m)
    ft = np.where(rng.random(m) < 0.5, 0.0, 50.0)
    al = rng.choice(alpha, m)
    fn = -rng.uniform(100.0, 1000.0, m)
    cap = ft - fn
    sign = lambda: rng.choice([-1.0, 1.0], m)  # noqa: E731
    # rocking ratios below or above 1, never near it (kinks) nor near zero (|m| kinks)
    ratio1 = np.where(rng.random(m) < 0.5, rng.uniform(0.1, 0.9, m), rng.uniform(1.1, 3.0, m))
    ratio2 = np.where(rng.random(m) < 0.5, rng.uniform(0.1, 0.9, m), rng.uniform(1.1, 3.0, m))
    m1 = sign() * ratio1 * cap * l2 / 2
    m2 = sign() * ratio2 * cap * l1 / 2
    inside = rng.random(m) < 0.4  # well inside Eq. (A5), or mostly outside it
    shear = np.where(inside, rng.uniform(0.05, 0.4, m), rng.uniform(0.1, 3.0, m)) * mu * cap
    angle = rng.uniform(0, 2 * np.pi, m)
    torsion = np.where(inside, rng.uniform(0.05, 0.3, m), rng.uniform(0.05, 3.0, m))
    m3 = sign() * torsion * mu * cap * torsion_constant(l1, l2)
    m3[rng.random(m) < 0.1] = 0.0  # pure shear
    t = np.column_stack([shear * np.cos(angle), shear * np.sin(angle), fn, m1, m2, m3])
    law = InterfaceLaw(np.tile(KBAR, (m, 1)), l1, l2, mu, ft, al)
    return t, law


def _respond(law: InterfaceLaw, t: np.ndarray):
    m = t.shape[0]
    return law.respond(t / law.kbar, np.zeros((m, 6)), np.zeros(m, dtype=bool))


def _central(law: InterfaceLaw, t: np.ndarray, step: float):
    """(m, 6, 6) central differences of the projection times kbar, and a mask of the rows
    whose probes all keep the flags of the trial (no kink crossed)."""
    m = t.shape[0]
    big = np.abs(t).max(axis=1, keepdims=True)
    h = step * (np.abs(t) + 1e-2 * big)
    base = check_strength(t, law.l1, law.l2, law.friction, law.tensile_force, law.alpha)
    D = np.empty((m, 6, 6))
    smooth = np.ones(m, dtype=bool)
    for p in range(6):
        plus, minus = t.copy(), t.copy()
        plus[:, p] += h[:, p]
        minus[:, p] -= h[:, p]
        hi, lo = (
            check_strength(x, law.l1, law.l2, law.friction, law.tensile_force, law.alpha)
            for x in (plus, minus)
        )
        D[:, :, p] = (hi.projected - lo.projected) / (2 * h[:, p : p + 1]) * law.kbar[:, p : p + 1]
        smooth &= (hi.flags == base.flags) & (lo.flags == base.flags)
    return D, smooth, base.flags


def _block_error(T: np.ndarray, T_ref: np.ndarray) -> np.ndarray:
    """Per joint: largest |T - T_ref| over the largest entry of T_ref's block."""
    return np.abs(T - T_ref).max(axis=(1, 2)) / np.abs(T_ref).max(axis=(1, 2))


@pytest.mark.parametrize("seed", [0, 1])
def test_analytic_tangent_is_the_derivative_of_the_projection(seed):
    rng = np.random.default_rng(seed)
    t, law = _joints(3000, rng)
    T = law.tangent(_respond(law, t), floor=0.0)
    D, smooth, flags = _central(law, t, CENTRAL_STEP)
    # every state is covered, away from the kinks (rocking about both axes, a joint bears on
    # a corner with no torsion capacity: it slides)
    for state in (
        FLAG_SHEAR_TORSION,
        FLAG_ROCKING_1,
        FLAG_ROCKING_2,
        FLAG_SHEAR_TORSION | FLAG_ROCKING_1,
        FLAG_SHEAR_TORSION | FLAG_ROCKING_2,
        FLAG_SHEAR_TORSION | FLAG_ROCKING_1 | FLAG_ROCKING_2,
    ):
        assert ((flags == state) & smooth).sum() >= 50, state
    sliding_pure_shear = smooth & (flags & FLAG_SHEAR_TORSION > 0) & (t[:, 5] == 0)
    assert sliding_pure_shear.sum() >= 20
    yielded = smooth & (flags > 0)
    # pure shear: the curve's curvature at the shear axis goes as z^(alpha - 2), so the
    # difference in m3 does not converge there (see the next test); the rest of the block does
    pure = (t[:, 5] == 0)[:, None, None] & (np.arange(6) == 5)
    err = _block_error(np.where(pure, 0, T)[yielded], np.where(pure, 0, D)[yielded])
    assert err.max() < RTOL, err.max()
    # the elastic joints keep diag(kbar)
    elastic = flags == 0
    np.testing.assert_array_equal(T[elastic], np.tile(np.diag(KBAR), (elastic.sum(), 1, 1)))


def test_torsion_stiffness_of_a_joint_sliding_in_pure_shear():
    """At m3 = 0 the return lands on the shear axis, (r, z) = (a, 0), where the curve
    (z/b)^alpha + (r/a)^2 = 1 has the curvature radius 0 for alpha < 2, b^2/a for alpha = 2
    and infinity for alpha > 2: a small torsion is returned to 0, to b^2/(b^2 + a(r0 - a))
    of itself, or kept whole (the trial is kbar x relative: T[5, 5] / kbar of 0, that
    fraction, or 1)."""
    rng = np.random.default_rng(2)
    t, law = _joints(600, rng)
    t[:, 5] = 0.0
    r = _respond(law, t)
    rows = np.flatnonzero(r.flags & FLAG_SHEAR_TORSION)
    assert rows.size > 100
    T = law.tangent(r, floor=0.0)[rows]
    cap = law.tensile_force[rows] - t[rows, 2]
    a = law.friction[rows] * cap
    rho = np.sqrt((law.l1[rows] ** 2 + law.l2[rows] ** 2) / 12)
    b = torsion_strength(
        t[rows, 2], law.l1[rows], law.l2[rows], law.friction[rows], law.tensile_force[rows],
        t[rows, 3], t[rows, 4],
    ) / rho  # fmt: skip
    r0 = np.hypot(t[rows, 0], t[rows, 1])
    al = law.alpha[rows]
    expected = np.where(al < 2, 0.0, np.where(al == 2, b**2 / (b**2 + a * (r0 - a)), 1.0))
    expected[b == 0] = 0.0  # rocking about both axes: on a corner, no torsion capacity
    assert set(np.unique(al[b > 0])) >= {1.25, 2.0, 2.56}
    np.testing.assert_allclose(T[:, 5, 5] / KBAR[5], expected, rtol=1e-10, atol=1e-12)


def test_analytic_tangent_agrees_with_the_forward_difference():
    """The forward difference the solver used before (one-sided, steps 1e-7) gives the same
    tangent to its own truncation error."""
    rng = np.random.default_rng(7)
    t, law = _joints(2000, rng)
    r = _respond(law, t)
    _, smooth, _ = _central(law, t, CENTRAL_STEP)
    yielded = smooth & (r.flags > 0)
    err = _block_error(law.tangent(r)[yielded], law.tangent(r, method="difference")[yielded])
    assert err.max() < 1e-5, err.max()


def test_a_detached_joint_in_the_contact_band_closes_on_a_corner():
    """A joint at zero gap, taken at the contact side: only fn moves it, and a little
    compression cap gives it m1 = sign(m1) cap l2/2, m2 = sign(m2) cap l1/2, no torsion and
    a shear of mu cap along the trial shear: the same as the forward difference."""
    rng = np.random.default_rng(3)
    t, law = _joints(400, rng)
    far = t.copy()
    far[:, 2] = -1e4  # sets the contact band (1e-8 of the largest |fn|) to 1e-4
    contact = np.zeros(far.shape[0], dtype=bool)
    contact[::2] = True
    far[contact, 2] = law.tensile_force[contact] + 1e-6  # detached, inside the band
    r = _respond(law, far)
    assert (r.flags[contact] == FLAG_DETACHED).all()
    T = law.tangent(r, floor=0.0)[contact]
    ref = law.tangent(r, floor=0.0, method="difference")[contact]
    assert _block_error(T, ref).max() < 1e-6
    # exactly: fn column only
    k2 = KBAR[2]
    shear = np.hypot(t[contact, 0], t[contact, 1])
    mu = law.friction[contact]
    np.testing.assert_allclose(T[:, 0, 2], -t[contact, 0] * mu / shear * k2, rtol=1e-12)
    np.testing.assert_allclose(
        T[:, 3, 2], -np.sign(t[contact, 3]) * law.l2[contact] / 2 * k2, rtol=1e-12
    )
    np.testing.assert_allclose(
        T[:, 4, 2], -np.sign(t[contact, 4]) * law.l1[contact] / 2 * k2, rtol=1e-12
    )
    assert (T[:, 5] == 0).all()
    assert (T[:, :, [0, 1, 3, 4, 5]] == 0).all()


def test_rows_outside_the_closed_form_are_differenced():
    """alpha = 1 (a vertex on the shear axis), no shear at all (pure torsion) and the radial
    return are left to the forward difference: the same bits as ``method="difference"``."""
    rng = np.random.default_rng(5)
    t, law = _joints(600, rng, alpha=(1.0, 1.5))
    t[::3, :2] = 0.0  # pure torsion
    r = _respond(law, t)
    T, ref = law.tangent(r), law.tangent(r, method="difference")
    left = (law.alpha == 1.0) | ((t[:, 0] == 0) & (t[:, 1] == 0) & (r.flags & 1 > 0))
    assert left.sum() > 100
    np.testing.assert_array_equal(T[left], ref[left])
    radial = InterfaceLaw(law.kbar, law.l1, law.l2, law.friction, law.tensile_force, law.alpha,
                          projection="radial")  # fmt: skip
    rr = _respond(radial, t)
    np.testing.assert_array_equal(radial.tangent(rr), radial.tangent(rr, method="difference"))


def test_torsion_constant_slope():
    """d cT / d l1 against central differences from slender to squat rectangles, Euler's
    identity of a function homogeneous of degree 1 (l1 dcT/dl1 + l2 dcT/dl2 = cT), and the
    segments: cT(l, 0) = l/4."""
    for x in np.logspace(-6, 6, 49):
        l1, l2 = 1.0, float(x)
        d1 = _nb_torsion_constant_slope(l1, l2)
        d2 = _nb_torsion_constant_slope(l2, l1)
        h = 1e-6
        fd1 = (torsion_constant(l1 + h, l2) - torsion_constant(l1 - h, l2)) / (2 * h)
        # the difference's round-off: 1e-16 of cT over the step
        c = float(torsion_constant(l1, l2))
        assert d1 == pytest.approx(float(fd1), rel=1e-7, abs=1e-15 * c / h)
        assert l1 * d1 + l2 * d2 == pytest.approx(c, rel=1e-12)
    # the series of the squat side meets the closed form where it takes over (x = 1e3)
    below, above = (_nb_torsion_constant_slope(1.0, x) for x in (1e3 * (1 - 1e-12), 1e3))
    assert above == pytest.approx(below, rel=1e-9)
    assert _nb_torsion_constant_slope(0.3, 0.0) == 0.25
    assert _nb_torsion_constant_slope(0.0, 0.3) == 0.0


def test_tangent_method_is_checked():
    rng = np.random.default_rng(0)
    t, law = _joints(5, rng)
    with pytest.raises(ValueError, match="method.*'exact'"):
        law.tangent(_respond(law, t), method="exact")
    with pytest.raises(ValueError, match="tangent.*'exact'"):
        StaticSettings(tangent="exact")


def test_tangent_of_cohesive_joints_is_the_derivative_of_the_projection():
    """With a cohesion beyond mu ft, c0 = (c - mu ft) A, the sliding rows are differenced
    (their capacities are not proportional to ft - fn): the tangent is still the derivative
    of the projection."""
    rng = np.random.default_rng(41)
    t, paper = _joints(1500, rng)
    c0 = rng.uniform(50.0, 500.0, t.shape[0])
    law = InterfaceLaw(
        paper.kbar, paper.l1, paper.l2, paper.friction, paper.tensile_force, paper.alpha,
        cohesion=c0,
    )  # fmt: skip
    T = law.tangent(_respond(law, t), floor=0.0)
    cohesive = law.friction * law.tensile_force + c0

    def project(x):
        return check_strength(
            x, law.l1, law.l2, law.friction, law.tensile_force, law.alpha, cohesive_force=cohesive
        )

    big = np.abs(t).max(axis=1, keepdims=True)
    h = CENTRAL_STEP * (np.abs(t) + 1e-2 * big)
    base = project(t)
    D = np.empty_like(T)
    smooth = np.ones(t.shape[0], dtype=bool)
    for p in range(6):
        plus, minus = t.copy(), t.copy()
        plus[:, p] += h[:, p]
        minus[:, p] -= h[:, p]
        hi, lo = project(plus), project(minus)
        D[:, :, p] = (hi.projected - lo.projected) / (2 * h[:, p : p + 1]) * law.kbar[:, p : p + 1]
        smooth &= (hi.flags == base.flags) & (lo.flags == base.flags)
    sliding = smooth & (base.flags & FLAG_SHEAR_TORSION > 0) & (t[:, 5] != 0)
    assert sliding.sum() >= 100
    # the forward difference of the law against the central one (measured: 9e-8)
    assert _block_error(T[sliding], D[sliding]).max() < 1e-6
