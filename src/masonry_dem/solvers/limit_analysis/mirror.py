"""A mirror plane of the model, and the velocities that vanish on its symmetric mechanisms.

Why the associative problem may be solved on the symmetric mechanisms only. Let a
reflection R (through a plane normal to a global axis k) map the model onto itself: every
block, interface, support and load onto itself. R maps an admissible mechanism onto an
admissible one doing the same work (it maps each interface's corners onto its corners and
each friction cone onto itself), and the admissible mechanisms form a convex set, so the
mean of a mechanism and its mirror image is admissible with the same multiplier: an optimal
mechanism exists among the symmetric ones, whose velocities have ``u_k = 0`` and the
rotations about the two other axes ``w_j = 0`` (a rotation is a pseudo-vector: R keeps
``w_k`` and flips the others). A wall of one leaf loaded in its own plane is such a model:
its problem is the plane one, 3 velocities a block instead of 6.

The reduction is a guess that the solver certifies: any restricted mechanism is admissible
in the whole problem (an upper bound in any case), and ``normal_ipm`` checks the lower bound
against the equilibrium of every DOF, the dropped ones included (the forces of a symmetric
solution balance there by symmetry, to rounding).
"""

from __future__ import annotations

import numpy as np

from masonry_dem.model import Model

#: relative tolerance of the plane's detection (of the median block size; of the loads)
TOLERANCE = 1e-9


def mirror_dofs(model: Model) -> np.ndarray | None:
    """(6n,) bool: the DOFs that vanish on the mechanisms symmetric about a plane normal to a
    global axis that holds every block centre and every interface centre, with no interface
    normal to that axis and no load on those DOFs; None where the model has no such plane."""
    blocks, its = model.blocks, model.interfaces
    if blocks.count == 0 or its.count == 0:
        return None
    length = float(np.median(blocks.sizes))
    forces = np.abs(np.concatenate([model.dead.reshape(-1), model.live.reshape(-1)]))
    force = float(forces.max(initial=0.0))
    for k in range(3):
        plane = float(blocks.centres[0, k])
        off = max(
            float(np.abs(blocks.centres[:, k] - plane).max()),
            float(np.abs(its.centre[:, k] - plane).max()),
        )
        if off > TOLERANCE * length or np.any(its.axis == k):
            continue
        anti = np.zeros((blocks.count, 6), dtype=bool)
        anti[:, k] = True
        anti[:, 3 + (k + 1) % 3] = True
        anti[:, 3 + (k + 2) % 3] = True
        loaded = max(
            float(np.abs(model.dead[anti]).max(initial=0.0)),
            float(np.abs(model.live[anti]).max(initial=0.0)),
        )
        if loaded > TOLERANCE * force:
            continue
        return anti.reshape(-1)
    return None
