"""The constants of a sliding row that the forces kernel reads from its interface
(``StrengthDomain.row_constants``) give the bits the energy return gets by computing them.

The energy return of a sliding row (``energy_return._nb_energy_closest_point``) needs the
switch point between the two halves of the curve (a^alpha + r^2 = 1 split at
t^alpha = x^2 = 1/2), the shear half's bracket and the energy radius rho = sqrt(J / A): they
depend on the interface alone (alpha, l1, l2). ``InterfaceLaw.forces`` reads them, stored once
per interface; ``respond`` (and ``check_strength``) computes them in the row. Both must give
the same bits: the stored values are the return's own expressions (checked here against
those expressions written out), and the projected rows agree bit for bit over alphas from 1
to 3 (the shear half's parameter is t = tau^2 below alpha = 2 and tau above), aspect ratios
from 1/5 to 5, frictions 0.3 to 1.2, shear in each direction, torsion of each sign, with and
without bending (which shrinks the torsion rectangle), and the radial projection.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from scipy import sparse

from masonry_dem.constitutive.energy_return import (
    ROW_RHO,
    ROW_SHEAR_HI,
    ROW_T_SWITCH,
    ROW_TA_SWITCH,
    ROW_TORSION,
)
from masonry_dem.constitutive.law import InterfaceLaw
from masonry_dem.constitutive.states import FLAG_SHEAR_TORSION
from masonry_dem.constitutive.strength import StrengthDomain, torsion_constant

ALPHAS = (1.0, 1.05, 1.25, 1.43, 1.5, 1.7, 1.92, 2.0, 2.44, 2.56, 3.0)
SIDES = ((0.04, 0.2), (0.1, 0.2), (0.2, 0.2), (0.3, 0.2), (0.5, 0.1))  # l1/l2 from 1/5 to 5
FRICTIONS = (0.3, 0.7, 1.2)


@numba.njit(error_model="numpy")
def _written_out(l1, l2, alpha):
    """The expressions the energy return evaluated at every call before they were stored,
    as it wrote them (compiled, so the same libm as the kernels)."""
    n = l1.shape[0]
    out = np.empty((n, 4))
    for i in range(n):
        al = alpha[i]
        t_switch = 0.5 ** (1.0 / al)
        p = 2.0 if al < 2.0 else 1.0
        out[i, 0] = t_switch
        out[i, 1] = (t_switch**1.0) ** al  # t^alpha of _nb_shear_half(t_switch, ..., 1.0)
        out[i, 2] = t_switch ** (1 / p)
        out[i, 3] = math.sqrt((l1[i] * l1[i] + l2[i] * l2[i]) / 12.0)
    return out


def _interfaces():
    """(l1, l2, friction, alpha) of every combination."""
    rows = [
        (l1, l2, mu, al) for al in ALPHAS for l1, l2 in SIDES for mu in FRICTIONS
    ]  # fmt: skip
    return (np.array(c, dtype=float) for c in zip(*rows, strict=True))


def test_stored_constants_are_the_return_s_expressions_bit_for_bit():
    l1, l2, mu, alpha = _interfaces()
    dom = StrengthDomain.of(l1.size, l1, l2, mu, alpha)
    stored = dom.row_constants
    assert stored.shape == (l1.size, 5)
    assert stored[:, ROW_TORSION].tobytes() == dom.torsion_constant.tobytes()
    cols = [ROW_T_SWITCH, ROW_TA_SWITCH, ROW_SHEAR_HI, ROW_RHO]
    assert np.ascontiguousarray(stored[:, cols]).tobytes() == _written_out(l1, l2, alpha).tobytes()
    # and what they are: 2^(-1/alpha), 1/2, the bracket in tau, sqrt(J / A)
    np.testing.assert_allclose(stored[:, ROW_T_SWITCH], 2.0 ** (-1.0 / alpha), rtol=1e-15)
    np.testing.assert_allclose(stored[:, ROW_TA_SWITCH], 0.5, rtol=1e-15)
    power = np.where(alpha < 2.0, 2.0, 1.0)
    np.testing.assert_allclose(stored[:, ROW_SHEAR_HI], 2.0 ** (-1.0 / (alpha * power)), rtol=1e-15)
    np.testing.assert_allclose(stored[:, ROW_RHO], np.sqrt((l1**2 + l2**2) / 12.0), rtol=1e-15)


def _sliding_trials(l1, l2, mu, alpha, rng):
    """Trial actions outside Eq. (A5) of each interface: pure shear, pure torsion and mixed,
    in each direction and sign, with and without bending, 1.001 to 5 times the capacity."""
    fn = -100.0
    cap = -fn
    rows, owner = [], []
    directions = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.6, -0.8), (-0.8, -0.6)]
    for i in range(l1.size):
        fsu = mu[i] * cap
        for share1, share2 in ((0.0, 0.0), (0.3, 0.0), (0.2, 0.35)):
            m1 = share1 * cap * l2[i]
            m2 = share2 * cap * l1[i]
            l1r, l2r = l1[i] - 2.0 * m2 / cap, l2[i] - 2.0 * m1 / cap
            m3u = float(torsion_constant(l1r, l2r)) * fsu
            for d1, d2 in directions:
                for a_share in (0.0, 0.05, 0.3, 0.7, 0.95, 1.0):  # torsion's share of a^alpha
                    k = rng.uniform(1.001, 5.0)
                    c = math.sqrt(1.0 - a_share)
                    a = a_share ** (1.0 / alpha[i])
                    sign = rng.choice((-1.0, 1.0))
                    rows.append(
                        [d1 * c * fsu * k, d2 * c * fsu * k, fn, m1, -m2, sign * a * m3u * k]
                    )
                    owner.append(i)
    owner = np.array(owner)
    return np.array(rows), owner


@pytest.mark.parametrize("projection", ["energy", "radial"])
@pytest.mark.parametrize("one_alpha", [False, True])
def test_forces_with_stored_constants_give_respond_s_bits_on_sliding_rows(projection, one_alpha):
    rng = np.random.default_rng(7)
    l1, l2, mu, alpha = _interfaces()
    if one_alpha:  # the domain then holds one float, spread to the rows for the kernels
        keep = alpha == 1.43
        l1, l2, mu, alpha = l1[keep], l2[keep], mu[keep], alpha[keep]
    trial, owner = _sliding_trials(l1, l2, mu, alpha, rng)
    m = trial.shape[0]
    law = InterfaceLaw(
        np.ones((m, 6)), l1[owner], l2[owner], mu[owner], 0.0, alpha[owner], "brittle", "none",
        projection,
    )  # fmt: skip
    H = sparse.identity(6 * m, format="csr")
    plastic = np.zeros((m, 6))
    cracked = np.zeros(m, dtype=bool)
    _, got, internal = law.forces(H, trial.reshape(-1), plastic, cracked, H)
    # respond computes the constants in each row; of H x, whose sums turn -0 into +0
    ref = law.respond((H @ trial.reshape(-1)).reshape(m, 6), plastic, cracked)
    sliding = (ref.flags & FLAG_SHEAR_TORSION) > 0
    assert sliding.mean() > 0.95  # the rows meant to slide do (the rest sit on the curve)
    assert got.flags.tobytes() == ref.flags.tobytes()
    assert got.actions.tobytes() == ref.actions.tobytes()
    assert internal.tobytes() == (0.0 + ref.actions.reshape(-1)).tobytes()  # H^T sums from 0
    # the projections moved the rows: torsion and shear both returned somewhere
    moved = np.abs(got.actions - trial).max(axis=1) > 0
    assert moved[sliding].all()
