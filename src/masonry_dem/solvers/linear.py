"""Linear elastic static solve of the assembly."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from masonry_dem._docstrings import SHARED, fill
from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.model import Model


@dataclass(frozen=True)
class LinearSolution:
    """The displacements, actions and reactions of one linear elastic solve."""

    q: NDArray[np.float64]  # (n, 6) block displacements and rotations
    actions: NDArray[np.float64]  # (m, 6) interface actions, local order [f1, f2, fn, m1, m2, m3]
    reactions: NDArray[np.float64]  # (n, 6) support reactions (zero on free DOFs)
    relative: NDArray[np.float64]  # (m, 6) relative displacements


@fill(SHARED)
def solve_linear(
    model: Model, load_factor: float = 1.0, assembly: Assembly | None = None
) -> LinearSolution:
    """Solve K q = F_dead + load_factor F_live on the free DOFs.

    Parameters
    ----------
    model : Model
        The assembly, its joints elastic (bonded).
    load_factor : float, default 1.0
        lambda, the factor of the live load.
    assembly : Assembly, optional
        The model's assembled matrices, if already built (None: built here).

    Returns
    -------
    LinearSolution
        ``q`` (n, 6) block displacements and rotations, ``actions`` (m, 6) interface actions
        (local order [f1, f2, fn, m1, m2, m3]), ``reactions`` (n, 6) support reactions (zero
        on free DOFs), ``relative`` (m, 6) relative displacements.

    Raises
    ------
    ValueError
        If the assembly is a mechanism (the stiffness is singular).

    Examples
    --------
    %(sliding_block)s
    >>> solution = md.solve_linear(model)
    >>> solution.reactions[base, :2].round(6).tolist()  # weight and horizontal load
    [-72.0, 72.0]
    """
    asm = Assembly.of(model) if assembly is None else assembly
    F = (model.dead + load_factor * model.live).reshape(-1)
    K = asm.stiffness()
    try:
        lu = splu(K)
    except RuntimeError as exc:
        raise ValueError(f"the assembly is a mechanism: the stiffness is singular ({exc})") from exc
    q = np.zeros(model.n_dofs)
    q[asm.free_index] = lu.solve(F[asm.free_index])
    rel = asm.relative_displacements(q)
    actions = asm.kbar * rel
    reactions = asm.internal_forces(actions) - F
    reactions[asm.free_index] = 0.0
    return LinearSolution(q.reshape(-1, 6), actions, reactions.reshape(-1, 6), rel)
