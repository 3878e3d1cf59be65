"""The compiled strength check (``_evaluate``, numba) against the numpy reference
(``_evaluate_numpy``), and a few exact values of its own."""

from __future__ import annotations

import subprocess
import sys

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers.numpy_reference import _evaluate_numpy, fd_tangent_numpy, law_tangent_numpy
from masonry_dem.constitutive import law as law_module
from masonry_dem.constitutive.law import InterfaceLaw, fd_tangent
from masonry_dem.constitutive.states import FLAG_DETACHED, FLAG_SHEAR_TORSION, STATE_ELASTIC
from masonry_dem.constitutive.strength import StrengthDomain as _Domain
from masonry_dem.constitutive.strength import evaluate as _evaluate
from masonry_dem.constitutive.strength import projection_and_flags as _projection_and_flags
from masonry_dem.constitutive.strength import (
    shear_strength,
    torsion_constant,
    torsion_strength,
)

ALPHAS = (1.0, 1.43, 1.5, 2.0, 2.56)
PROJECTIONS = ("energy", "radial")
# the numpy reference squares huge demand ratios (zero or subnormal capacities) to inf
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered in multiply:RuntimeWarning")

KINDS = ("elastic", "sliding", "rocking", "detached", "torsion", "shear", "corner", "random")


# ------------------------------------------------------------------------------------------
# random interfaces: one row = (actions, l1, l2, friction, ft, alpha)

fraction = st.floats(0.0, 1.0)
side = st.one_of(st.floats(1e-3, 2.0), st.sampled_from([1e-9, 1e-30]))
friction = st.one_of(st.floats(0.0, 1.5), st.sampled_from([0.0, 1e-300]))
tensile = st.one_of(st.just(0.0), st.floats(0.0, 500.0))


@st.composite
def interface(draw) -> tuple:
    kind = draw(st.sampled_from(KINDS))
    l1, l2, mu, ft = draw(side), draw(side), draw(friction), draw(tensile)
    alpha = draw(st.sampled_from(ALPHAS))
    if kind == "random":
        act = draw(st.lists(st.floats(-1e3, 1e3), min_size=6, max_size=6))
        return np.array(act), l1, l2, mu, ft, alpha
    if kind == "detached":
        fn = ft + draw(st.floats(0.0, 100.0).filter(lambda x: x > 0))
    else:
        fn = ft - draw(st.one_of(st.floats(1.0, 1e3), st.just(0.0)))  # cap = 0 included
    cap = ft - fn
    fsu = mu * cap
    m3u = float(torsion_constant(l1, l2)) * fsu
    # demand/capacity ratios (of the whole rectangle) of shear, torsion and both bendings
    lo, hi = {
        "elastic": ((0.0, 0.4), (0.0, 0.5)),
        "sliding": ((0.5, 30.0), (0.0, 1.0)),
        "rocking": ((0.0, 2.0), (0.5, 5.0)),
        "detached": ((0.0, 3.0), (0.0, 3.0)),
        "torsion": ((0.0, 5.0), (0.0, 1.0)),
        "shear": ((0.0, 5.0), (0.0, 1.0)),
        "corner": ((0.0, 3.0), (1.0, 3.0)),
    }[kind]
    ratio = st.floats(*lo)
    r_shear, r_tor = draw(ratio), draw(ratio)
    r_m1, r_m2 = draw(st.floats(*hi)), draw(st.floats(*hi))
    if kind == "torsion":
        r_shear = 0.0
    if kind == "shear":
        r_tor = 0.0
    ang = draw(st.floats(0.0, 2 * np.pi))
    signs = draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3))
    act = np.array(
        [
            r_shear * fsu * np.cos(ang),
            r_shear * fsu * np.sin(ang),
            fn,
            signs[0] * r_m1 * 0.5 * cap * l2,
            signs[1] * r_m2 * 0.5 * cap * l1,
            signs[2] * r_tor * m3u,
        ]
    )
    if kind in ("torsion", "detached") and m3u == 0:
        act[5] = signs[2] * draw(st.floats(0.0, 10.0))  # torsion demand at zero capacity
    return act, l1, l2, mu, ft, alpha


batch = st.lists(interface(), min_size=1, max_size=30)


def _arrays(rows):
    act = np.array([r[0] for r in rows])
    l1, l2, mu, ft, alpha = (np.array([r[k] for r in rows]) for k in range(1, 6))
    return act, l1, l2, mu, ft, alpha


def _assert_agree(act, ft, dom, interaction, projection):
    got = _evaluate(act, ft, dom, interaction, projection=projection)
    ref = _evaluate_numpy(act, ft, dom, interaction, projection=projection)
    # flags may differ only for rows exactly at a tolerance boundary
    same = got.flags == ref.flags
    boundary = (np.abs(ref.utilisation - 1.0) < 1e-8) | (act[:, 2] == ft)
    assert (same | boundary).all(), (got.flags, ref.flags)
    np.testing.assert_array_equal(got.state[same], ref.state[same])
    np.testing.assert_array_equal(got.stiffness_factors[same], ref.stiffness_factors[same])
    assert got.state.dtype == ref.state.dtype and got.flags.dtype == ref.flags.dtype
    assert got.projected.shape == ref.projected.shape == act.shape
    # projected actions: 1e-12 relative to the entry, or to the row where an entry vanishes
    g, r = got.projected[same], ref.projected[same]
    scale = np.maximum(np.abs(act[same]).max(axis=1), ft[same])[:, None]
    assert (np.abs(g - r) <= 1e-12 * np.abs(r) + 1e-12 * scale).all(), np.abs(g - r).max()
    gu, ru = got.utilisation[same], ref.utilisation[same]
    assert not np.isnan(got.utilisation).any()
    np.testing.assert_array_equal(np.isinf(gu), np.isinf(ru))
    fin = np.isfinite(ru)
    np.testing.assert_allclose(gu[fin], ru[fin], rtol=1e-12, atol=0)
    # actions inside the domain come back unchanged, bitwise
    inside = ref.flags == 0
    assert got.projected[inside].tobytes() == act[inside].tobytes()
    # the projection-only path of the residuals gives the same actions and flags
    only, only_flags = _projection_and_flags(act, ft, dom, projection, interaction)
    assert only.tobytes() == got.projected.tobytes()
    np.testing.assert_array_equal(only_flags, got.flags)
    only_ref = _evaluate_numpy(act, ft, dom, interaction, True, projection)
    assert (np.abs(only - only_ref) <= 1e-12 * np.abs(only_ref) + 1e-12 * np.abs(act).max()).all()
    return got


@pytest.mark.slow
@settings(max_examples=300, deadline=None, derandomize=True)
@given(batch, st.booleans(), st.sampled_from(PROJECTIONS))
def test_kernel_agrees_with_numpy_per_row_alpha(rows, interaction, projection):
    act, l1, l2, mu, ft, alpha = _arrays(rows)
    dom = _Domain.of(act.shape[0], l1, l2, mu, alpha)
    _assert_agree(act, ft, dom, interaction, projection)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(batch, st.sampled_from(ALPHAS), st.booleans(), st.sampled_from(PROJECTIONS))
def test_kernel_agrees_with_numpy_one_alpha(rows, alpha, interaction, projection):
    act, l1, l2, mu, ft, _ = _arrays(rows)
    dom = _Domain.of(act.shape[0], l1, l2, mu, alpha)
    assert not np.ndim(dom.alpha)  # the numpy reference takes its scalar-alpha branches
    _assert_agree(act, ft, dom, interaction, projection)


@pytest.mark.parametrize("projection", PROJECTIONS)
@pytest.mark.parametrize("alpha", ALPHAS)
def test_kernel_agrees_with_numpy_on_many_rows(alpha, projection):
    rng = np.random.default_rng(7)
    m = 3000
    act = rng.normal(size=(m, 6)) * [300.0, 300.0, 400.0, 20.0, 20.0, 30.0]
    act[::7, [0, 1]] = 0.0  # pure torsion
    act[1::7, 5] = 0.0  # pure shear
    ft = np.where(rng.random(m) < 0.5, 0.0, rng.uniform(0, 100, m))
    mu = np.where(rng.random(m) < 0.1, 0.0, rng.uniform(0.3, 1.0, m))
    l1, l2 = rng.uniform(0.05, 0.5, m), rng.uniform(0.05, 0.5, m)
    got = _assert_agree(act, ft, _Domain.of(m, l1, l2, mu, alpha), True, projection)
    assert {0, 1, 2, 3, 4} <= set(got.state.tolist())
    # the rows are shared among the threads: one thread gives the same bits
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        alone = _evaluate(act, ft, _Domain.of(m, l1, l2, mu, alpha), projection=projection)
    finally:
        numba.set_num_threads(threads)
    for field in ("projected", "flags", "utilisation"):
        assert getattr(alone, field).tobytes() == getattr(got, field).tobytes()


# ------------------------------------------------------------------------------------------
# exact values

L1, L2, MU, FN = 0.3, 0.2, 0.7, -240.0


def _phi(p, alpha):
    """Eq. (A5) on the reduced rectangle, from the public helpers."""
    f1, f2, fn, m1, m2, m3 = p.T
    fsu = shear_strength(fn, MU)
    m3u = torsion_strength(fn, L1, L2, MU, 0.0, m1, m2)
    return (np.abs(m3) / m3u) ** alpha + (f1**2 + f2**2) / fsu**2


@pytest.mark.parametrize("projection", PROJECTIONS)
@pytest.mark.parametrize("alpha", ALPHAS)
def test_projected_point_lies_on_eq_a5(alpha, projection):
    rng = np.random.default_rng(3)
    m = 400
    act = np.zeros((m, 6))
    act[:, [0, 1, 5]] = rng.normal(size=(m, 3)) * [200.0, 200.0, 20.0]
    act[:, 2] = FN
    act[:, [3, 4]] = rng.uniform(-0.4, 0.4, (m, 2)) * [-FN * L2, -FN * L1]  # inside rocking
    dom = _Domain.of(m, L1, L2, MU, alpha)
    r = _evaluate(act, np.zeros(m), dom, projection=projection)
    sl = r.flags == FLAG_SHEAR_TORSION
    assert sl.sum() > 100
    np.testing.assert_allclose(_phi(r.projected[sl], alpha), 1.0, atol=1e-9)
    again = _evaluate(r.projected, np.zeros(m), dom, projection=projection)
    assert (again.state == STATE_ELASTIC).all()


def test_closed_forms():
    fsu = MU * -FN
    m3u = float(torsion_constant(L1, L2)) * fsu
    act = np.array(
        [
            [3 * fsu, 4 * fsu, FN, 0, 0, 0],  # pure shear: |f| back to fsu
            [0, 0, FN, 0, 0, -2.5 * m3u],  # pure torsion: m3 back to -m3u
            [0.6 * fsu, 0.8 * fsu, FN, 0, 0, m3u],  # alpha = 2, radial: divide by hypot
            [5.0, 0, 12.0, 1.0, 2.0, 3.0],  # detached (ft = 10)
            [0, 0, 0.0, 0, 0, 1.0],  # torsion demand at zero capacity (ft = 0): dropped
        ]
    )
    ft = np.array([0, 0, 0, 10.0, 0])
    r = _evaluate(act, ft, _Domain.of(5, L1, L2, MU, 2.0), projection="radial")
    np.testing.assert_allclose(r.projected[0], [0.6 * fsu, 0.8 * fsu, FN, 0, 0, 0], rtol=1e-14)
    np.testing.assert_allclose(r.projected[1], [0, 0, FN, 0, 0, -m3u], rtol=1e-14)
    radial = act[2] * [1, 1, 0, 0, 0, 1] / np.sqrt(2) + [0, 0, FN, 0, 0, 0]
    np.testing.assert_allclose(r.projected[2], radial, rtol=1e-14)
    np.testing.assert_array_equal(r.projected[3], [0, 0, 10.0, 0, 0, 0])
    np.testing.assert_array_equal(r.projected[4], 0.0)
    np.testing.assert_allclose(r.utilisation[:4], [5.0, 2.5, np.sqrt(2), 1.2], rtol=1e-14)
    assert r.utilisation[4] == np.inf
    np.testing.assert_array_equal(r.flags, [1, 1, 1, FLAG_DETACHED, 1])


def test_alpha_one_vertex_and_corner_contact():
    fsu = MU * -FN
    # alpha = 1: a trial in the normal cone of the vertex (fsu, 0) of the shear axis returns to it
    act = np.array([[3 * fsu, 0, FN, 0, 0, 0.01 * fsu], [50.0, 0, FN, 100.0, 100.0, 10.0]])
    r = _evaluate(act, np.zeros(2), _Domain.of(2, L1, L2, MU, 1.0))
    np.testing.assert_allclose(r.projected[0], [fsu, 0, FN, 0, 0, 0], rtol=1e-15)
    # rocking on a corner: no torsion capacity, the shear is kept (energy projection)
    np.testing.assert_allclose(r.projected[1], [50, 0, FN, 24.0, 36.0, 0], rtol=1e-14)


def test_tiny_capacity_falls_back_to_radial():
    act = np.array([[1e-290, 1e-290, -1.0, 0, 0, 1e-290]])
    dom = _Domain.of(1, L1, L2, 1e-300, 1.5)
    energy = _evaluate(act, np.zeros(1), dom)
    radial = _evaluate(act, np.zeros(1), dom, projection="radial")
    assert energy.flags[0] == FLAG_SHEAR_TORSION
    np.testing.assert_array_equal(energy.projected, radial.projected)


# ------------------------------------------------------------------------------------------
# the law's tangent and the compile-free import


def test_law_tangent_matches_the_numpy_reference(monkeypatch):
    rng = np.random.default_rng(5)
    m = 200
    kbar = np.tile([1e9, 1e9, 2e9, 1e6, 2e6, 5e5], (m, 1))
    law = InterfaceLaw(
        kbar, rng.uniform(0.1, 0.4, m), rng.uniform(0.1, 0.3, m), np.full(m, 0.6),
        np.where(rng.random(m) < 0.5, 0.0, 500.0), np.full(m, 1.5),
    )  # fmt: skip
    rel = rng.normal(size=(m, 6)) * [2e-7, 2e-7, 3e-7, 2e-5, 2e-5, 4e-5]
    rel[:, 2] -= 2e-7
    zero, cracked = np.zeros((m, 6)), np.zeros(m, dtype=bool)
    resp = law.respond(rel, zero, cracked)
    assert ((resp.flags > 0) & (resp.flags < FLAG_DETACHED)).sum() > 50
    tangent = law.tangent(resp, method="difference")
    # the compiled tangent is its batched numpy version through the compiled difference, bits
    assert tangent.tobytes() == law_tangent_numpy(law, resp, fd=fd_tangent).tobytes()
    monkeypatch.setattr(law_module, "evaluate", _evaluate_numpy)
    ref_law = InterfaceLaw(law.kbar, law.l1, law.l2, law.friction, law.tensile_force, law.alpha)
    ref = ref_law.respond(rel, zero, cracked)
    np.testing.assert_array_equal(resp.flags, ref.flags)
    assert np.abs(resp.actions - ref.actions).max() <= 1e-12 * np.abs(ref.actions).max()
    ref_tangent = law_tangent_numpy(ref_law, ref)
    scale = kbar.max(axis=1)[:, None, None]
    assert (np.abs(tangent - ref_tangent) <= 1e-6 * np.abs(ref_tangent) + 1e-9 * scale).all()


def _random_domain(m: int, rng: np.random.Generator) -> _Domain:
    return _Domain.of(m, rng.uniform(0.05, 0.4, m), rng.uniform(0.05, 0.3, m),
                      rng.uniform(0.0, 0.9, m), rng.choice([1.0, 1.5, 2.56], m))  # fmt: skip


def _fd_steps(t: np.ndarray) -> np.ndarray:
    """The law's finite-difference steps for trials ``t`` (fn towards compression)."""
    big = np.abs(t).max(axis=1, keepdims=True)
    h = 1e-7 * (np.abs(t) + 1e-2 * big) + 1e-300
    h[:, 2] = -h[:, 2]
    return h


def _compiled_projection(act, ft, dom, projection_only, projection):
    """The compiled projection, with the reference check's signature (probes only)."""
    assert projection_only
    return _projection_and_flags(act, ft, dom, projection)[0]


@pytest.mark.parametrize("projection", ["energy", "radial"])
def test_compiled_tangent_is_the_batched_difference_bit_for_bit(projection):
    """The compiled tangent evaluates the same 7 probes per row as the batched numpy
    difference through the compiled check, so it gives the same bits (a changed last bit
    would be amplified 1e7 times by the difference)."""
    rng = np.random.default_rng(11)
    m = 300
    dom = _random_domain(m, rng)
    rows = np.flatnonzero(rng.random(m) < 0.6)
    n = rows.size
    t = rng.normal(size=(n, 6)) * [300, 300, 400, 20, 20, 30]
    t[:, 2] = -np.abs(t[:, 2])
    ft = np.where(rng.random(n) < 0.5, 0.0, 50.0)
    h = _fd_steps(t)
    kbar = rng.uniform(1e5, 1e9, (n, 6))
    compiled = fd_tangent(t, h, ft, rows, dom, kbar, projection)
    batched = fd_tangent_numpy(t, h, ft, rows, dom, kbar, projection, evaluate=_compiled_projection)
    np.testing.assert_array_equal(compiled, batched)
    assert np.abs(compiled).max() > 0


@pytest.mark.parametrize("projection", ["energy", "radial"])
def test_a_joint_at_zero_capacity_moves_only_with_fn(projection):
    """Rows at fn = ft (a detached joint taken at the contact side) probed along fn alone
    give the tangent of all six probes: the other columns are zero, the fn column the same."""
    rng = np.random.default_rng(13)
    m = 200
    dom = _random_domain(m, rng)
    rows = np.arange(m)
    t = rng.normal(size=(m, 6)) * [300, 300, 400, 20, 20, 30]
    ft = np.where(rng.random(m) < 0.5, 0.0, 50.0)
    at_zero = rng.random(m) < 0.5
    t[:, 2] = np.where(at_zero, ft, -np.abs(t[:, 2]))
    h = _fd_steps(t)
    kbar = rng.uniform(1e5, 1e9, (m, 6))
    full = fd_tangent(t, h, ft, rows, dom, kbar, projection)
    lean = fd_tangent(t, h, ft, rows, dom, kbar, projection, normal_only=at_zero)
    np.testing.assert_array_equal(lean, full)
    assert np.abs(full[at_zero][:, :, 2]).max() > 0  # fn does move them
    assert np.abs(full[~at_zero][:, :, [0, 1, 3, 4, 5]]).max() > 0


def test_import_compiles_nothing():
    code = (
        "import masonry_dem, masonry_dem.constitutive.law\n"
        "from masonry_dem import jit\n"
        "compiled = [k.name for k in jit.kernels() for _, d in k.variants if d.signatures]\n"
        "assert not compiled, compiled\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
