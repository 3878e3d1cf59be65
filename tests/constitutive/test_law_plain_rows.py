"""The forces kernel's early-out (``law_kernels.nb_plain_row``) gives what the strength check
gives, bit for bit, on rows just inside and just outside each surface of the domain.

The early-out settles a detached row (fn > ft) and a row inside the domain by a margin
(no rocking, ``a + c^2 < SETTLED_ELASTIC_BELOW`` through a lower bound of the torsion
constant) without running the check; every other row runs it. Each surface is approached
from both sides at relative distances down to 1e-15: detachment (fn = ft), rocking about
each axis (|m| = (ft - fn) l / 2), the shear-torsion curve of Eq. (A5) (a^alpha + c^2 = 1,
in pure shear, pure torsion and mixed, with and without bending, which shrinks the torsion
rectangle) and the early-out's own margin (a + c^2 = 0.998).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse

from masonry_dem.constitutive.law import InterfaceLaw
from masonry_dem.constitutive.law_kernels import (
    ROW_CHECK,
    ROW_DETACHED,
    ROW_ELASTIC,
    SETTLED_ELASTIC_BELOW,
    nb_plain_row,
)
from masonry_dem.constitutive.strength import torsion_constant

L1, L2, MU, ALPHA = 0.3, 0.2, 0.7, 1.5
SIDES = (-1e-6, -1e-9, -1e-12, -1e-15, 0.0, 1e-15, 1e-12, 1e-9, 1e-8, 1e-6)  # relative offsets
# (Eq. (A5) has a tolerance of 1e-9: a trial outside by less is elastic)


def _surface_rows(ft: float) -> np.ndarray:
    """Trial actions (n, 6) on both sides of every surface of the domain of a joint with
    tensile force ``ft``."""
    rows = []
    fn = -100.0
    cap = ft - fn
    fsu = MU * cap
    for eps in SIDES:
        k = 1.0 + eps
        # detachment: fn = ft (and around zero when ft = 0)
        rows.append([1.0, 0.5, ft * k if ft else eps, 0.1, 0.1, 0.01])
        # rocking about each axis, with the other actions small
        rows.append([1.0, 0.0, fn, 0.5 * cap * L2 * k, 0.0, 0.01])
        rows.append([0.0, 1.0, fn, 0.0, -0.5 * cap * L1 * k, 0.01])
        for m1_share, m2_share in ((0.0, 0.0), (0.3, 0.0), (0.2, 0.35)):
            m1 = m1_share * cap * L2
            m2 = m2_share * cap * L1
            l1r = L1 - 2.0 * m2 / cap
            l2r = L2 - 2.0 * m1 / cap
            m3u = float(torsion_constant(l1r, l2r)) * fsu
            # Eq. (A5): pure shear, pure torsion, mixed (a = 0.5)
            rows.append([fsu * k, 0.0, fn, m1, m2, 0.0])
            rows.append([0.0, 0.0, fn, m1, -m2, -m3u * k])
            c = np.sqrt(1.0 - 0.5**ALPHA)
            rows.append([0.6 * c * fsu * k, -0.8 * c * fsu * k, fn, -m1, m2, 0.5 * m3u * k])
            # the early-out's margin: a + c^2 = SETTLED_ELASTIC_BELOW, a = 0.3
            c = np.sqrt(SETTLED_ELASTIC_BELOW - 0.3)
            rows.append([c * fsu * np.sqrt(k), 0.0, fn, m1, m2, 0.3 * m3u * k])
    return np.array(rows)


@pytest.mark.parametrize("tension", ["brittle", "plastic"])
@pytest.mark.parametrize("ft", [0.0, 25.0])
def test_rows_at_each_surface_give_the_check_s_actions_bit_for_bit(ft, tension):
    trial = _surface_rows(ft)
    m = trial.shape[0]
    law = InterfaceLaw(np.ones((m, 6)), L1, L2, MU, ft, ALPHA, tension, "none")
    H = sparse.identity(6 * m, format="csr")
    plastic = np.zeros((m, 6))
    cracked = np.zeros(m, dtype=bool)
    rel, resp, internal = law.forces(H, trial.reshape(-1), plastic, cracked, H)
    # the check on every row (with the utilisation) of H x, whose sums turn -0 into +0
    ref = law.respond((H @ trial.reshape(-1)).reshape(-1, 6), plastic, cracked)
    assert rel.tobytes() == (H @ trial.reshape(-1)).tobytes()
    assert resp.actions.tobytes() == ref.actions.tobytes()
    assert resp.flags.tobytes() == ref.flags.tobytes()
    assert internal.tobytes() == ref.actions.reshape(-1).tobytes()
    # both sides of every surface are there: the early-out settles some rows, not all
    dom = law._domain
    plain = np.array(
        [
            nb_plain_row(
                *t, ft, 0.0, L1, L2, MU, dom.snap1[0], dom.snap2[0], dom.torsion_constant[0]
            )
            for t in trial
        ]
    )
    assert {ROW_CHECK, ROW_ELASTIC, ROW_DETACHED} <= set(plain.tolist())
    assert (ref.flags[plain == ROW_CHECK] > 0).any() and (ref.flags[plain == ROW_CHECK] == 0).any()


def test_the_early_out_is_conservative_on_random_rows():
    """A row the early-out calls elastic is one the check leaves alone (no flag, actions
    = trial), over rows spread across the domain's surfaces; and it calls most rows well
    inside elastic (the bound of the torsion constant is not so loose that it never helps)."""
    rng = np.random.default_rng(3)
    n = 20_000
    ft = 10.0
    fn = -rng.uniform(0.0, 200.0, n)
    cap = ft - fn
    scale = rng.uniform(0.0, 1.1, (n, 1)) ** 2  # many rows near and inside the surfaces
    t = rng.uniform(-1.0, 1.0, (n, 6)) * scale
    t[:, 0:2] *= MU * cap[:, None] * 0.8
    t[:, 2] = fn
    t[:, 3] *= 0.5 * cap * L2
    t[:, 4] *= 0.5 * cap * L1
    t[:, 5] *= MU * cap * 0.1
    law = InterfaceLaw(np.ones((n, 6)), L1, L2, MU, ft, ALPHA, "plastic", "none")
    ref = law.respond(t, np.zeros((n, 6)), np.zeros(n, dtype=bool))
    dom = law._domain
    plain = np.array(
        [
            nb_plain_row(
                *row, ft, 0.0, L1, L2, MU, dom.snap1[0], dom.snap2[0], dom.torsion_constant[0]
            )
            for row in t
        ]
    )
    elastic = plain == ROW_ELASTIC
    assert (ref.flags[elastic] == 0).all()
    assert (ref.actions[elastic] == t[elastic]).all()
    inside = ref.flags == 0
    assert elastic.sum() > 0.8 * inside.sum()
    assert (ref.flags > 0).sum() > 0.1 * n  # many rows outside too


def test_torsion_constant_bound_of_the_reduced_rectangle():
    """cT is the mean distance from the centre: it grows with each side and scales with
    both, so cT(l1', l2') >= min(l1'/l1, l2'/l2) cT(l1, l2) for l1' <= l1, l2' <= l2."""
    rng = np.random.default_rng(5)
    l1 = rng.uniform(0.01, 1.0, 10_000)
    l2 = l1 * 10.0 ** rng.uniform(-3.0, 3.0, l1.size)
    l1r = l1 * rng.uniform(0.0, 1.0, l1.size)
    l2r = l2 * rng.uniform(0.0, 1.0, l1.size)
    s = np.minimum(l1r / l1, l2r / l2)
    lower = s * torsion_constant(l1, l2)
    assert (torsion_constant(l1r, l2r) >= lower * (1.0 - 1e-14)).all()
    # equality along the rectangle's own shape (homogeneous of degree one)
    np.testing.assert_allclose(
        torsion_constant(0.5 * l1, 0.5 * l2), 0.5 * torsion_constant(l1, l2), rtol=1e-14
    )
