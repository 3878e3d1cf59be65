"""The optimised batched check and interface law give the results of the plain formulas.

``_reference_check`` and ``_ReferenceLaw`` below are the straightforward implementation that
``check_strength`` and ``InterfaceLaw`` had before they were optimised (every criterion on every
row, ``np.where`` over full arrays). Projected actions, state, flags, stiffness factors,
utilisation and the finite-difference tangent must agree to a relative 1e-12 (in practice bit
for bit: the tangent divides differences of projections by 1e-7 and would show any changed
last bit). The reference returns (f1, f2, m3) radially, so the comparison is made with
``projection="radial"``; the default energy return is tested in test_strength.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.constitutive import check_strength
from masonry_dem.constitutive.law import InterfaceLaw

RTOL = 1e-12
#: The tangents are divided differences with probe steps down to 1e-9 of a row's largest
#: action (law._FD_STEP = 1e-7 of 1e-2 of it), so a last-bit difference between the compiled
#: projection and numpy's (another libm or fused multiply-add on another CPU) comes out up to
#: ~1e-7 of the row's scale: tangents are compared against each interface's largest entry.
TANGENT_RTOL = 1e-6
SLIDE = np.array([True, True, False, False, False, True])


# ------------------------------------------------------------------------------------------
# reference implementation (the formulas written out, no shortcuts)


def _asinh_ratio(x):
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.arcsinh(x) / x
    out = np.where(x < 1e-8, 1.0 - x * x / 6.0, out)
    return np.where(np.isinf(x), 0.0, out)


def _torsion_constant(l1, l2):
    c = np.hypot(l1, l2)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.where(l1 > 0, 0.25 * l1 * _asinh_ratio(l2 / l1), 0.0)
        t2 = np.where(l2 > 0, 0.25 * l2 * _asinh_ratio(l1 / l2), 0.0)
    return (0.5 * c + t1 + t2) / 3.0


def _radial_factor(a, c, alpha):
    m = np.maximum(a, c)
    both = (a > 0) & (c > 0) & np.isfinite(m)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        big_a = np.where(both, a / m, 0.0)
        big_c = np.where(both, c / m, 0.0)
        t = np.ones(m.shape)
        two = both & (alpha == 2.0)
        t = np.where(two, 1.0 / np.hypot(big_a, big_c), t)
        one = both & (alpha == 1.0)
        t = np.where(one, 2.0 / (big_a + np.sqrt(big_a * big_a + 4.0 * big_c * big_c)), t)
        s = t / m
    idx = np.flatnonzero(both & ~one & ~two)
    if idx.size:
        with np.errstate(divide="ignore"):
            ln_a, ln_c, al = np.log(big_a[idx]), np.log(big_c[idx]), alpha[idx]
        tau = np.zeros(idx.size)
        for _ in range(60):
            p = np.exp(al * (tau + ln_a))
            q = np.exp(2.0 * (tau + ln_c))
            total = p + q
            step = np.log(total) * total / (al * p + 2.0 * q)
            tau = tau - step
            with np.errstate(over="ignore"):
                s[idx] = np.exp(tau) / m[idx]
            keep = np.abs(step) > 1e-13
            if not keep.any():
                break
            idx, tau, ln_a, ln_c, al = idx[keep], tau[keep], ln_a[keep], ln_c[keep], al[keep]
    return s


def _safe_ratio(demand, capacity):
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = demand / capacity
    return np.where(demand == 0, 0.0, np.where(capacity > 0, r, np.inf))


def _reference_check(act, l1, l2, mu, ft, alpha, interaction=True):
    act = np.asarray(act, dtype=float)
    m = act.shape[0]
    l1, l2, mu, ft, alpha = (
        np.broadcast_to(np.asarray(x, float), (m,)) for x in (l1, l2, mu, ft, alpha)
    )
    f1, f2, fn, m1, m2, m3 = np.ascontiguousarray(act.T)
    detached = fn > ft
    cap = np.where(detached, 0.0, ft - fn)
    m1_lim = 0.5 * cap * l2
    m2_lim = 0.5 * cap * l1
    abs_m1, abs_m2 = np.abs(m1), np.abs(m2)
    rock1 = ~detached & (abs_m1 > m1_lim)
    rock2 = ~detached & (abs_m2 > m2_lim)
    m1_c = np.where(rock1, np.copysign(m1_lim, m1), m1)
    m2_c = np.where(rock2, np.copysign(m2_lim, m2), m2)
    fsu = mu * cap
    if interaction:
        with np.errstate(divide="ignore", invalid="ignore"):
            l1r = np.where(cap > 0, l1 - 2.0 * np.abs(m2_c) / cap, 0.0)
            l2r = np.where(cap > 0, l2 - 2.0 * np.abs(m1_c) / cap, 0.0)
        l1r = np.where(l1r <= 1e-12 * l1, 0.0, np.minimum(l1r, l1))
        l2r = np.where(l2r <= 1e-12 * l2, 0.0, np.minimum(l2r, l2))
        c_t = _torsion_constant(l1r, l2r)
    else:
        c_t = _torsion_constant(l1, l2)
    a = _safe_ratio(np.abs(m3), c_t * fsu)
    c = _safe_ratio(np.hypot(f1, f2), fsu)
    s = _radial_factor(a, c, alpha)
    with np.errstate(divide="ignore"):
        u_st = 1.0 / s
    sliding = ~detached & (u_st > 1.0 + 1e-9)
    scale = np.where(sliding, s, 1.0)
    proj = act.copy()
    proj[:, 0] = np.where(sliding, f1 * scale, f1)
    proj[:, 1] = np.where(sliding, f2 * scale, f2)
    proj[:, 3] = m1_c
    proj[:, 4] = m2_c
    proj[:, 5] = np.where(sliding, m3 * scale, m3)
    proj[detached] = 0.0
    proj[detached, 2] = ft[detached]
    flags = (sliding * 1 | rock1 * 2 | rock2 * 4 | detached * 8).astype(np.uint8)
    state = (sliding * 1 + (rock1 | rock2) * 2).astype(np.int8)
    state[detached] = 4
    factors = np.ones((m, 6))
    factors[sliding[:, None] & SLIDE] = 0.0
    factors[rock1, 3] = 0.0
    factors[rock2, 4] = 0.0
    factors[detached] = 0.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        u_tension = np.where(ft > 0, np.maximum(fn, 0.0) / ft, np.where(fn >= 0, 1.0, 0.0))
        u_tension = np.where(detached & (ft == 0), np.inf, u_tension)
    u_rock = np.maximum(_safe_ratio(abs_m1, m1_lim), _safe_ratio(abs_m2, m2_lim))
    util = np.where(detached, u_tension, np.maximum(np.maximum(u_tension, u_rock), u_st))
    return {
        "projected": proj,
        "state": state,
        "flags": flags,
        "stiffness_factors": factors,
        "utilisation": util,
    }


class _ReferenceLaw:
    """respond() and tangent() of InterfaceLaw written with the reference check."""

    def __init__(self, law: InterfaceLaw):
        self.law = law
        m = law.kbar.shape[0]
        self.l1, self.l2, self.mu, self.alpha = (
            np.broadcast_to(np.asarray(x, float), (m,))
            for x in (law.l1, law.l2, law.friction, law.alpha)
        )

    def _check(self, trial, ft, rows=slice(None)):
        return _reference_check(
            trial, self.l1[rows], self.l2[rows], self.mu[rows], ft, self.alpha[rows]
        )

    def respond(self, relative, plastic, cracked):
        trial = self.law.kbar * (relative - plastic)
        ft = np.where(cracked, 0.0, self.law.tensile_force)
        chk = self._check(trial, ft)
        actions = chk["projected"]
        if self.law.tension == "brittle":
            actions = np.where((chk["flags"][:, None] & 8) > 0, 0.0, actions)
        return {
            "trial": trial,
            "tensile_force": ft,
            "actions": actions,
            "tangent": chk["stiffness_factors"],
            "state": chk["state"],
            "flags": chk["flags"],
            "utilisation": chk["utilisation"],
        }

    def tangent(self, r, floor=1e-9, compiled_probes=False):
        """The forward difference of the law's tangent; ``compiled_probes``: the probes
        projected by the compiled check instead of the numpy reference."""
        k = self.law.kbar
        m = k.shape[0]
        idx = np.arange(6)
        T = np.zeros((m, 6, 6))
        T[:, idx, idx] = k
        trial, ft = r["trial"], r["tensile_force"]
        band = 1e-8 * float(np.abs(trial[:, 2]).max(initial=0.0))
        open_ = trial[:, 2] > ft + band
        T[open_] = 0.0
        rows = np.flatnonzero((r["flags"] > 0) & ~open_)
        if rows.size:
            n = rows.size
            t = trial[rows].copy()
            t[:, 2] = np.minimum(t[:, 2], ft[rows])
            big = np.abs(t).max(axis=1, keepdims=True)
            h = 1e-7 * (np.abs(t) + 1e-2 * big) + 1e-300
            h[:, 2] = -h[:, 2]
            probe = np.repeat(t[None], 7, axis=0)
            probe[idx + 1, :, idx] += h.T
            ftr = np.tile(ft[rows], 7)
            rows7 = np.tile(rows, 7)
            if compiled_probes:
                proj = check_strength(
                    probe.reshape(-1, 6),
                    self.l1[rows7],
                    self.l2[rows7],
                    self.mu[rows7],
                    ftr,
                    alpha=self.alpha[rows7],
                    projection=self.law.projection,
                ).projected
            else:
                proj = self._check(probe.reshape(-1, 6), ftr, rows7)["projected"]
            proj = proj.reshape(7, n, 6)
            D = (proj[1:] - proj[:1]) / h.T[:, :, None]
            T[rows] = np.transpose(D, (1, 2, 0)) * k[rows][:, None, :]
        T[:, idx, idx] += floor * k
        return T


# ------------------------------------------------------------------------------------------
# inputs


def _max_rel_diff(x, y) -> float:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    assert x.shape == y.shape
    same = x == y  # also inf == inf
    if same.all():
        return 0.0
    assert not (np.isnan(x) | np.isnan(y)).any()
    return float(np.max(np.abs(x - y)[~same] / np.abs(y)[~same]))


def _max_tangent_diff(T, T_ref) -> float:
    """Largest |T - T_ref| of each interface's 6 x 6 block over that block's largest entry."""
    T, T_ref = np.asarray(T, dtype=float), np.asarray(T_ref, dtype=float)
    assert T.shape == T_ref.shape and T.shape[1:] == (6, 6)
    assert np.isfinite(T).all() and np.isfinite(T_ref).all()
    scale = np.abs(T_ref).max(axis=(1, 2))
    diff = np.abs(T - T_ref).max(axis=(1, 2))
    return float(np.max(np.where(diff == 0.0, 0.0, diff / np.maximum(scale, 1e-300))))


def _interfaces(m: int, rng: np.random.Generator):
    """Sides, friction, tensile force (half the rows cracked, ft = 0) and alpha per row."""
    l1 = rng.uniform(0.05, 0.4, m)
    l2 = rng.uniform(0.05, 0.3, m)
    mu = rng.choice([0.0, 0.6, 0.7, 0.9], m, p=[0.05, 0.35, 0.3, 0.3])
    ft = np.where(rng.random(m) < 0.5, 0.0, rng.uniform(10.0, 400.0, m))
    return l1, l2, mu, ft


def _kbar(m: int) -> np.ndarray:
    """(m, 6) elastic joint stiffness of the law tests (shear, normal, bending, torsion)."""
    return np.column_stack(
        [
            np.full(m, 1e9),
            np.full(m, 1e9),
            np.full(m, 2.4e9),
            np.full(m, 1e6),
            np.full(m, 3e5),
            np.full(m, 5e5),
        ]
    )


def _actions(m: int, l1, l2, mu, ft, rng: np.random.Generator) -> np.ndarray:
    """Random trials around the domain plus the edge cases, scaled to the capacity."""
    fn = -rng.uniform(0.0, 800.0, m)
    fn[rng.random(m) < 0.1] *= -0.5  # tension: detached or within ft
    cap = np.maximum(ft - fn, 1.0)
    act = np.empty((m, 6))
    act[:, 2] = fn
    act[:, 0] = rng.normal(0.0, 0.6, m) * mu * cap
    act[:, 1] = rng.normal(0.0, 0.6, m) * mu * cap
    act[:, 3] = rng.normal(0.0, 0.4, m) * cap * l2
    act[:, 4] = rng.normal(0.0, 0.4, m) * cap * l1
    act[:, 5] = rng.normal(0.0, 0.1, m) * mu * cap * np.hypot(l1, l2)
    kind = rng.integers(0, 10, m)
    act[kind == 0, 2] = 0.0  # zero normal force
    act[kind == 1, 2] = ft[kind == 1]  # exactly at the tension cut-off
    pure = kind == 2  # pure torsion
    act[np.ix_(pure, [0, 1, 3, 4])] = 0.0
    shear = kind == 3  # pure shear
    act[np.ix_(shear, [3, 4, 5])] = 0.0
    limit = kind == 4  # bending exactly at the rocking limits, with torsion
    cap_l = ft[limit] - act[limit, 2]
    act[limit, 3] = np.copysign(0.5 * cap_l * l2[limit], act[limit, 3])
    act[limit, 4] = np.copysign(0.5 * cap_l * l1[limit], act[limit, 4])
    act[kind == 5] = 0.0  # nothing at all
    act[kind == 6, 5] *= 1e-9  # a side much shorter than the other after the reduction
    act[kind == 6, 3] = np.copysign(0.5 * (ft - act[:, 2]) * l2, 1.0)[kind == 6] * (1 - 1e-10)
    return act


# ------------------------------------------------------------------------------------------
# tests


@pytest.mark.parametrize("interaction", [True, False])
@pytest.mark.parametrize("alpha", ["uniform", "mixed"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_check_strength_matches_reference(seed, alpha, interaction):
    rng = np.random.default_rng(seed)
    m = 3000
    l1, l2, mu, ft = _interfaces(m, rng)
    al = 1.5 if alpha == "uniform" else rng.choice([1.0, 1.43, 1.5, 2.0, 2.56], m)
    act = _actions(m, l1, l2, mu, ft, rng)
    ref = _reference_check(act, l1, l2, mu, ft, al, interaction)
    # trials exactly on the boundary: the projections themselves
    on = ref["projected"]
    ref_on = _reference_check(on, l1, l2, mu, ft, al, interaction)
    for trial, expected in ((act, ref), (on, ref_on)):
        got = check_strength(
            trial,
            l1,
            l2,
            mu,
            ft,
            alpha=al,
            torsion_bending_interaction=interaction,
            projection="radial",
        )
        for name, value in expected.items():
            assert getattr(got, name).dtype == value.dtype, name
            assert _max_rel_diff(getattr(got, name), value) < RTOL, name
    states = np.bincount(ref["state"], minlength=5)
    assert (states > 0.03 * m).all(), states  # every state is exercised


def test_check_strength_single_row_and_scalars():
    trial = [10.0, -20.0, -300.0, 12.0, -8.0, 3.0]
    ref = _reference_check(np.array([trial]), 0.21, 0.07, 0.7, 0.0, 1.5)
    got = check_strength(trial, 0.21, 0.07, 0.7, 0.0, projection="radial")
    for name, value in ref.items():
        assert _max_rel_diff(getattr(got, name), value) < RTOL, name


@pytest.mark.parametrize(
    "tension, memory", [("brittle", "none"), ("plastic", "none"), ("brittle", "slip")]
)
@pytest.mark.parametrize("seed", [3, 4])
def test_interface_law_matches_reference(seed, tension, memory):
    rng = np.random.default_rng(seed)
    m = 1500
    l1, l2, mu, ft = _interfaces(m, rng)
    kbar = _kbar(m) * rng.uniform(0.5, 2.0, (m, 1))
    alpha = rng.choice([1.5, 2.0], m) if seed % 2 else 1.5
    law = InterfaceLaw(kbar, l1, l2, mu, ft, alpha, tension, memory, projection="radial")
    ref_law = _ReferenceLaw(law)
    relative = _actions(m, l1, l2, mu, ft, rng) / kbar
    relative[rng.random(m) < 0.03, 2] = 0.0  # zero gap, zero force (the contact band)
    plastic = np.zeros((m, 6))
    if memory == "slip":
        plastic[:, SLIDE] = 0.3 * relative[:, SLIDE] * rng.random((m, 1))
    cracked = rng.random(m) < 0.2
    got = law.respond(relative, plastic, cracked)
    ref = ref_law.respond(relative, plastic, cracked)
    for name, value in ref.items():
        assert getattr(got, name).dtype == value.dtype, name
        assert _max_rel_diff(getattr(got, name), value) < RTOL, name
    assert (got.flags > 0).mean() > 0.3  # many rows go through the finite differences
    T, T_ref = law.tangent(got), ref_law.tangent(ref)
    assert _max_tangent_diff(T, T_ref) < TANGENT_RTOL
    # the same differences of the compiled projection: the kernel's probes, steps and chain
    # rule, to round-off
    assert _max_rel_diff(T, ref_law.tangent(ref, compiled_probes=True)) < RTOL
    # again on the converged actions (on the boundary) and with another floor
    again = law.respond(got.actions / kbar + plastic, plastic, cracked)
    ref_again = ref_law.respond(got.actions / kbar + plastic, plastic, cracked)
    T, T_ref = law.tangent(again, 1e-6), ref_law.tangent(ref_again, 1e-6)
    assert _max_tangent_diff(T, T_ref) < TANGENT_RTOL
    assert _max_rel_diff(T, ref_law.tangent(ref_again, 1e-6, compiled_probes=True)) < RTOL


def test_interface_law_rejects_non_finite_trials():
    law = InterfaceLaw(np.ones((2, 6)), 0.2, 0.1, 0.7, 0.0, 1.5)
    rel = np.zeros((2, 6))
    rel[1, 3] = np.nan
    with pytest.raises(ValueError, match="finite"):
        law.respond(rel, np.zeros((2, 6)), np.zeros(2, dtype=bool))


@pytest.mark.parametrize("projection", ["energy", "radial"])
@pytest.mark.parametrize("seed", [5, 6])
def test_response_without_utilisation_is_the_same_bits(seed, projection):
    """The residuals of the solvers ask for no utilisation (the radial factor of rows well
    inside Eq. (A5) is skipped): actions, flags, states and stiffness factors are those of
    the full response bit for bit, and the utilisation computed later is the full one."""
    rng = np.random.default_rng(seed)
    m = 1500
    l1, l2, mu, ft = _interfaces(m, rng)
    kbar = _kbar(m)
    law = InterfaceLaw(kbar, l1, l2, mu, ft, 1.5, "brittle", "none", projection=projection)
    relative = _actions(m, l1, l2, mu, ft, rng) / kbar
    plastic = np.zeros((m, 6))
    cracked = rng.random(m) < 0.2
    full = law.respond(relative, plastic, cracked)
    lean = law.respond(relative, plastic, cracked, utilisation=False)
    assert lean.utilisation is None
    for name in ("trial", "actions", "tangent", "state", "flags"):
        assert np.array_equal(getattr(lean, name), getattr(full, name)), name
    assert np.array_equal(law.utilisation(lean), full.utilisation)
    assert (full.flags & 1).mean() > 0.1  # many rows slide: the skipped factor matters
    with pytest.raises(ValueError, match="finite"):
        bad = relative.copy()
        bad[0, 0] = np.inf
        law.respond(bad, plastic, cracked, utilisation=False)


@pytest.mark.parametrize("tension", ["brittle", "plastic"])
def test_fused_forces_are_the_response_and_the_sparse_products_bit_for_bit(tension):
    """``InterfaceLaw.forces`` (one compiled pass for a residual) gives the relative
    displacements, the response and the generalised forces of ``H @ x``, ``respond`` and
    ``H_T @ actions`` to the last bit, and names a non-finite trial as ``respond`` does."""
    from scipy import sparse

    rng = np.random.default_rng(8)
    m, n = 800, 900
    l1, l2, mu, ft = _interfaces(m, rng)
    kbar = _kbar(m)
    law = InterfaceLaw(kbar, l1, l2, mu, ft, 1.5, tension, "none")
    H = sparse.random(6 * m, n, density=0.01, random_state=rng, format="csr")
    target = _actions(m, l1, l2, mu, ft, rng) / kbar  # relative displacements to aim at
    x = sparse.linalg.lsqr(H, target.reshape(-1), iter_lim=50)[0]
    plastic = rng.normal(size=(m, 6)) * 1e-9
    cracked = rng.random(m) < 0.2
    H_T = H.T.tocsr()
    rel, resp, internal = law.forces(H, x, plastic, cracked, H_T)
    rel_ref = (H @ x).reshape(-1, 6)
    ref = law.respond(rel_ref, plastic, cracked, utilisation=False)
    assert rel.tobytes() == rel_ref.tobytes()
    for name in ("trial", "tensile_force", "actions", "flags"):
        assert getattr(resp, name).tobytes() == getattr(ref, name).tobytes(), name
    assert internal.tobytes() == (H_T @ ref.actions.reshape(-1)).tobytes()
    assert resp.flags.any() and (resp.flags == 0).any()  # some rows yield, some do not
    x[np.flatnonzero(H[0].toarray())[0]] = np.nan
    with pytest.raises(ValueError, match="finite"):
        law.forces(H, x, plastic, cracked, H_T)
