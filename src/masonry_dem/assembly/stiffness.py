"""Interface stiffness Kbar (diagonal, local components) and the assembled stiffness
K = H^T Kbar H on the free DOFs; internal forces and reactions."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from masonry_dem.assembly.compatibility import compatibility_matrix
from masonry_dem.model import Model


def interface_stiffness(model: Model) -> NDArray[np.float64]:
    """(m, 6) elastic stiffness per local component:
    [kt A, kt A, kn A, kn I1, kn I2, kt J] (shear, normal, bending, torsion)."""
    its = model.interfaces
    area = its.area
    return np.stack(
        [
            model.kt * area,
            model.kt * area,
            model.kn * area,
            model.kn * its.inertia1,
            model.kn * its.inertia2,
            model.kt * its.polar,
        ],
        axis=1,
    )


@dataclass(frozen=True)
class Assembly:
    """Matrices of one model: H on all DOFs, its free-DOF columns, and the elastic Kbar."""

    H: sparse.csr_matrix  # (6m, 6n)
    H_free: sparse.csr_matrix  # (6m, nf)
    free_index: NDArray[np.intp]  # (nf,) global DOF numbers of the free DOFs
    kbar: NDArray[np.float64]  # (m, 6) elastic interface stiffness

    @classmethod
    def of(cls, model: Model) -> Assembly:
        H = compatibility_matrix(model.blocks, model.interfaces)
        free_index = np.flatnonzero(model.free)
        H_free = H.tocsc()[:, free_index].tocsr()
        return cls(H, H_free, free_index, interface_stiffness(model))

    @cached_property
    def H_free_T(self) -> sparse.csr_matrix:
        """(nf, 6m) H_f^T as its own CSR matrix: ``H_free.T`` is a new CSC view at every use,
        whose construction cost more than the product in a Newton residual."""
        return self.H_free.T.tocsr()

    @property
    def n_free(self) -> int:
        return int(self.free_index.size)

    def stiffness(self, factors: NDArray[np.float64] | None = None) -> sparse.csc_matrix:
        """K_ff = H_f^T diag(kbar * factors) H_f (factors (m, 6) scale each component)."""
        k = self.kbar if factors is None else self.kbar * factors
        D = sparse.diags(k.reshape(-1), format="csr")
        K = (self.H_free.T @ D @ self.H_free).tocsc()
        return K

    def tangent_stiffness(self, blocks6: NDArray[np.float64]) -> sparse.csc_matrix:
        """K_ff = H_f^T T H_f for per-interface 6x6 tangents T (m, 6, 6), in one sparse build."""
        m = blocks6.shape[0]
        base = 6 * np.arange(m)[:, None, None]
        rows = np.broadcast_to(base + np.arange(6)[None, :, None], (m, 6, 6))
        cols = np.broadcast_to(base + np.arange(6)[None, None, :], (m, 6, 6))
        T = sparse.csr_matrix((blocks6.ravel(), (rows.ravel(), cols.ravel())), shape=(6 * m, 6 * m))
        return (self.H_free.T @ (T @ self.H_free)).tocsc()

    def internal_forces(self, actions: NDArray[np.float64]) -> NDArray[np.float64]:
        """Generalised forces on all block DOFs (6n,) from interface actions (m, 6): H^T f."""
        return np.asarray(self.H.T @ actions.reshape(-1), dtype=np.float64)

    def relative_displacements(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """(m, 6) local relative displacements from all block DOFs q (6n,)."""
        return np.asarray(self.H @ q, dtype=np.float64).reshape(-1, 6)
