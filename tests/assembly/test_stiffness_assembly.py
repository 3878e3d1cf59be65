"""Interface stiffness Kbar and K = H^T Kbar H on the free DOFs.

Proves: Kbar is Eq. (4) (K A with the areas and inertias of Eq. (5); shear and torsion use kt,
normal and bending use kn) in our local order [f1, f2, fn, m1, m2, m3]; K is symmetric,
equals H_f^T diag(Kbar) H_f, stores the elastic energy sum(Kbar d^2) / 2, is positive definite
once a base is fixed; fixed DOFs are removed; per-component factors scale Kbar.
"""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.assembly.stiffness import Assembly, interface_stiffness
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.selectors import column
from masonry_dem.model import InterfaceMaterial, Model, Support

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0
KN, KT = 2.4e9, 1.0e9
MAT = InterfaceMaterial(kn=KN, kt=KT, friction=0.7)


@pytest.fixture(scope="module")
def model():
    blocks, ib = add_base(running_bond_wall(4, 3, A, B, S, GAMMA))
    return Model.build(blocks, MAT, [Support([ib])])


def _global_rows(axis: int) -> np.ndarray:
    pos = (np.arange(3) - axis - 1) % 3
    return np.concatenate([pos, 3 + pos])


def test_kbar_is_eq4_with_eq5_in_global_order(model):
    kbar = interface_stiffness(model)
    its = model.interfaces
    S_h, I_h1, I_h3 = B * S / 2, B * S**3 / 24, B**3 * S / 96
    S_v, I_v2, I_v3 = A * S, A * S**3 / 12, A**3 * S / 12
    # paper, global order (1, 2, 3): K_h = diag(kt, kn, kt, kn, kt, kn) x A_h and
    # K_v = diag(kn, kt, kt, kt, kn, kn) x A_v (normal/bending: kn; shear/torsion: kt)
    expect_h = [KT * S_h, KN * S_h, KT * S_h, KN * I_h1, KT * (I_h1 + I_h3), KN * I_h3]
    expect_v = [KN * S_v, KT * S_v, KT * S_v, KT * (I_v2 + I_v3), KN * I_v2, KN * I_v3]
    base = its.block_i == model.blocks.count - 1
    n_checked = 0
    for k in range(its.count):
        if base[k]:
            continue
        glob = kbar[k][_global_rows(its.axis[k])]
        expect = expect_h if its.axis[k] == 1 else expect_v
        np.testing.assert_allclose(glob, expect, rtol=1e-12)
        n_checked += 1
    assert n_checked == its.count - base.sum() > 0
    # local order formula
    np.testing.assert_allclose(
        kbar,
        np.stack(
            [
                KT * its.area,
                KT * its.area,
                KN * its.area,
                KN * its.inertia1,
                KN * its.inertia2,
                KT * its.polar,
            ],
            1,
        ),
        rtol=1e-15,
    )


def test_K_is_HT_Kbar_H_on_free_dofs(model):
    asm = Assembly.of(model)
    H = asm.H.toarray()
    free = model.free
    np.testing.assert_array_equal(asm.free_index, np.flatnonzero(free))
    assert asm.n_free == free.sum() == 6 * (model.blocks.count - 1)
    np.testing.assert_array_equal(asm.H_free.toarray(), H[:, free])
    K = asm.stiffness().toarray()
    K_ref = H[:, free].T @ np.diag(asm.kbar.ravel()) @ H[:, free]
    np.testing.assert_allclose(K, K_ref, rtol=1e-12, atol=1e-12 * np.abs(K_ref).max())
    np.testing.assert_array_equal(K, K.T)
    # positive definite with the base fixed
    np.linalg.cholesky(K)
    assert asm.stiffness().format == "csc"


def test_energy_and_internal_forces(model):
    asm = Assembly.of(model)
    rng = np.random.default_rng(2)
    q = np.zeros(model.n_dofs)
    q[asm.free_index] = rng.normal(size=asm.n_free) * 1e-4
    K = asm.stiffness()
    d = asm.relative_displacements(q)
    energy = 0.5 * np.sum(asm.kbar * d**2)
    qf = q[asm.free_index]
    assert 0.5 * qf @ (K @ qf) == pytest.approx(energy, rel=1e-12)
    f = asm.kbar * d
    np.testing.assert_allclose(
        asm.internal_forces(f)[asm.free_index],
        K @ qf,
        rtol=1e-10,
        atol=1e-10 * np.abs(K @ qf).max(),
    )


def test_factors_scale_each_component(model):
    asm = Assembly.of(model)
    factors = np.ones_like(asm.kbar)
    factors[:, 2] = 0.0  # e.g. a detached joint: no normal stiffness
    factors[::2, 5] = 0.5
    K = asm.stiffness(factors).toarray()
    Hf = asm.H_free.toarray()
    K_ref = Hf.T @ np.diag((asm.kbar * factors).ravel()) @ Hf
    np.testing.assert_allclose(K, K_ref, rtol=1e-12, atol=1e-12 * np.abs(K_ref).max())


def test_partially_fixed_dofs_are_removed():
    blocks = running_bond_wall(4, 3, A, B, S, GAMMA)
    left = column(blocks, "left")
    model = Model.build(blocks, MAT, [Support(left, "translations")])
    asm = Assembly.of(model)
    assert asm.n_free == 6 * blocks.count - 3 * left.size
    fixed_dofs = (6 * left[:, None] + np.arange(3)).ravel()
    assert not np.isin(fixed_dofs, asm.free_index).any()


def test_material_override_changes_the_base_joints_only():
    blocks, ib = add_base(running_bond_wall(3, 2, A, B, S, GAMMA))
    soft = InterfaceMaterial(kn=KN / 10, kt=KT / 10, friction=0.5)
    model = Model.build(blocks, MAT, [Support([ib])], material_overrides=[([ib], soft)])
    kbar = interface_stiffness(model)
    its = model.interfaces
    on_base = its.block_i == ib
    np.testing.assert_allclose(model.kn[on_base], KN / 10)
    np.testing.assert_allclose(model.kn[~on_base], KN)
    np.testing.assert_allclose(kbar[on_base, 2], KN / 10 * its.area[on_base], rtol=1e-15)
    np.testing.assert_allclose(kbar[~on_base, 0], KT * its.area[~on_base], rtol=1e-15)


def _held_model():
    """A base and a left column held in u1 and u3 only: blocks with some DOFs fixed."""
    wall = running_bond_wall(5, 4, A, B, S, GAMMA)
    blocks, ib = add_base(wall)
    return Model.build(blocks, MAT, [Support([ib]), Support(column(wall, "left"), ["u1", "u3"])])


@pytest.mark.parametrize("which", ["base", "held column"])
def test_the_solver_assembles_per_interface_tangents_as_the_sparse_product(model, which):
    """The static solver's compiled assembly of H_f^T T H_f (T: one unsymmetric 6 x 6 block per
    interface, its entries summed in a pattern built once, worked out on block pairs) against
    the sparse product, in the numbering of the free DOFs (the sparse LU backends order the
    matrix themselves), also where blocks have only some DOFs fixed; the pattern is a
    canonical CSC (sorted rows, no duplicates, every diagonal entry stored)."""
    from masonry_dem.solvers.static.problem import TangentAssembler

    if which == "held column":
        model = _held_model()
    asm = Assembly.of(model)
    rng = np.random.default_rng(4)
    T = rng.normal(size=(model.interfaces.count, 6, 6)) * KN
    reference = asm.tangent_stiffness(T).toarray()
    K = TangentAssembler(asm, model).matrix(T)
    assert K.shape == reference.shape
    scale = np.abs(reference).max()
    assert np.abs(K.toarray() - reference).max() <= 1e-12 * scale
    assert np.abs(K.toarray() - K.toarray().T).max() > 1e-3 * scale  # unsymmetric, as T
    pattern = TangentAssembler(asm, model)
    assert pattern.nnz == np.count_nonzero(np.abs(reference) > 0)
    csc = pattern.matrix(T)
    assert csc.has_canonical_format
    assert np.all(np.diff(pattern.indptr) > 0)
    assert np.all(np.abs(csc.diagonal()) > 0)
