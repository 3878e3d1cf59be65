"""Model no more than a scene needs: the in-plane reduction and the cost of a model.

**In-plane reduction.** A single-leaf wall whose interfaces all have their centres on the
mid-plane of both blocks (no contact normal to e3, every block spanning the same thickness)
and whose dead and live loads have no out-of-plane part (u3, w1, w2) is an in-plane scene.
Its compatibility matrix then splits exactly: with arms r = (r1, r2, 0), the in-plane
components of the relative displacement (the shear and normal along e1, e2 and the rotation
about e3) depend on (u1, u2, w3) only and the others on (u3, w1, w2) only; the interface
stiffness is diagonal in local axes that are global axes, so K splits too; and the interface
law maps zero out-of-plane relative displacements to zero out-of-plane actions (the Mohr-Coulomb
circle, the rocking and torsion limits are all scaled radially or clipped). Starting from rest
the out-of-plane DOFs of the full model therefore stay exactly zero and the 6-DOF and the
3-DOF problems have the same solution, step by step. :func:`in_plane_model` builds the 3-DOF
model by fixing u3, w1, w2 of every block (the solvers assemble free DOFs only, so those DOFs
are never assembled) and drops the interfaces that then join two fully fixed blocks.

**Fixed blocks.** :class:`~masonry_dem.assembly.stiffness.Assembly` keeps only the free
columns of H, so the DOFs of supported blocks never enter K; :func:`model_cost` and
:func:`measure_fixed_dofs` count and time what that saves against the textbook alternative
(assemble every DOF, then pin the fixed ones with a penalty).

:func:`cheapest_model` picks the reduced model when the scene allows it and says why not when
it does not; :func:`measure_reduction` runs both models and reports lambda and time.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from masonry_dem.assembly.compatibility import compatibility_matrix
from masonry_dem.assembly.stiffness import Assembly, interface_stiffness
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.model import Model, dof_mask

log = logging.getLogger(__name__)

IN_PLANE_DOFS = dof_mask("in_plane")  # u1, u2, w3
OUT_OF_PLANE_DOFS = dof_mask("out_of_plane")  # u3, w1, w2


@dataclass(frozen=True)
class SceneCheck:
    """Whether a model is an in-plane scene, and if not, the first reason why not."""

    in_plane: bool
    reason: str


def in_plane_check(model: Model, rtol: float = 1e-9) -> SceneCheck:
    """Check the three conditions of an exact in-plane reduction (module docstring)."""
    its = model.interfaces
    blocks = model.blocks
    if model.meta.get("reduction") == "in_plane":
        return SceneCheck(True, "already reduced to the in-plane DOFs")
    if np.any(its.axis == 2):
        k = int(np.flatnonzero(its.axis == 2)[0])
        return SceneCheck(
            False,
            f"interface {k} has its normal along e3 (a multi-leaf or layered scene couples "
            "in-plane and out-of-plane motion)",
        )
    tol = rtol * float(np.max(blocks.sizes)) + 1e-12
    zc = its.centre[:, 2]
    off = np.maximum(
        np.abs(zc - blocks.centres[its.block_i, 2]), np.abs(zc - blocks.centres[its.block_j, 2])
    )
    if off.size and off.max() > tol:
        k = int(np.argmax(off))
        return SceneCheck(
            False,
            f"interface {k} lies {off[k]:.3g} m off the mid-plane of its blocks (blocks of "
            "different thickness or out-of-plane offset)",
        )
    for name, loads in (("dead", model.dead), ("live", model.live)):
        scale = float(np.abs(loads).max(initial=0.0))
        oop = float(np.abs(loads[:, OUT_OF_PLANE_DOFS]).max(initial=0.0))
        if oop > rtol * max(scale, 1e-300):
            return SceneCheck(
                False, f"the {name} load has out-of-plane components (u3, w1, w2): {oop:.3g}"
            )
    return SceneCheck(True, "single leaf, mid-plane interfaces, in-plane loads")


def in_plane_model(model: Model) -> Model:
    """The same scene on the in-plane DOFs (u1, u2, w3) only.

    Raises ValueError, naming the reason, when the scene is not in-plane.
    """
    check = in_plane_check(model)
    if not check.in_plane:
        raise ValueError(f"in-plane reduction refused: {check.reason}")
    if model.meta.get("reduction") == "in_plane":
        return model
    fixed = model.fixed | OUT_OF_PLANE_DOFS[None, :]
    fully = np.asarray(fixed.all(axis=1), dtype=bool)
    its = model.interfaces
    keep = np.flatnonzero(~(fully[its.block_i] & fully[its.block_j]))
    meta = dict(model.meta)
    meta["reduction"] = "in_plane"
    meta["interfaces_dropped"] = int(its.count - keep.size)
    reduced = replace(
        model,
        interfaces=its.subset(keep),
        kn=model.kn[keep],
        kt=model.kt[keep],
        friction=model.friction[keep],
        tensile_strength=model.tensile_strength[keep],
        cohesion=model.cohesion[keep] if model.cohesion is not None else None,
        alpha=model.alpha[keep],
        fixed=fixed,
        name=f"{model.name} [in-plane]",
        meta=meta,
    )
    log.info(
        "%s: in-plane reduction, %d -> %d free DOFs",
        model.name,
        int(model.free.sum()),
        int(reduced.free.sum()),
    )
    return reduced


def cheapest_model(model: Model) -> tuple[Model, str]:
    """The cheapest model that answers the scene's question, and why it was chosen."""
    check = in_plane_check(model)
    if check.in_plane:
        return in_plane_model(model), f"in-plane reduction: {check.reason}"
    return model, f"full 6-DOF model: {check.reason}"


# ---------------------------------------------------------------------------- costs
def model_cost(model: Model) -> dict:
    """DOF and matrix sizes of a model as the solvers assemble it."""
    asm = Assembly.of(model)
    K = asm.stiffness()
    fixed_blocks = int(model.fixed.all(axis=1).sum())
    return {
        "blocks": model.blocks.count,
        "interfaces": model.interfaces.count,
        "dofs": model.n_dofs,
        "free_dofs": asm.n_free,
        "fixed_dofs": int(model.fixed.sum()),
        "fully_fixed_blocks": fixed_blocks,
        "nnz_K": int(K.nnz),
    }


def _best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(max(repeats, 1)):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return float(best)


def measure_fixed_dofs(model: Model, repeats: int = 5) -> dict:
    """What never assembling the fixed DOFs saves, against assembling every DOF and pinning the
    fixed ones with a penalty (the alternative a code without DOF partition would use), and
    what dropping the interfaces between two fully fixed blocks saves."""
    asm = Assembly.of(model)
    kbar = asm.kbar.reshape(-1)
    D = sparse.diags(kbar, format="csr")

    def free_only():
        K = (asm.H_free.T @ D @ asm.H_free).tocsc()
        return splu(K, permc_spec="COLAMD")

    fixed = model.fixed.reshape(-1)

    def everything():
        K = (asm.H.T @ D @ asm.H).tocsr()
        big = 1e8 * float(np.abs(K.diagonal()).max(initial=1.0))
        K = (K + sparse.diags(np.where(fixed, big, 0.0))).tocsc()
        return splu(K, permc_spec="COLAMD")

    t_free = _best_time(free_only, repeats)
    t_all = _best_time(everything, repeats)
    all_its = detect_interfaces(model.blocks).count
    H_all = compatibility_matrix(model.blocks, model.interfaces)
    return {
        "dofs_all": model.n_dofs,
        "dofs_free": asm.n_free,
        "dofs_saved": model.n_dofs - asm.n_free,
        "nnz_K_all": int((H_all.T @ D @ H_all).nnz),
        "nnz_K_free": int(asm.stiffness().nnz),
        "interfaces_detected": int(all_its),
        "interfaces_kept": model.interfaces.count,
        "seconds_factor_free": t_free,
        "seconds_factor_all_penalty": t_all,
        "time_ratio": t_all / max(t_free, 1e-12),
    }


def measure_reduction(model: Model, settings=None, repeats: int = 3) -> dict:
    """Run the static solver on the full and on the in-plane model; lambda and best time."""
    from masonry_dem.solvers.incremental import StaticSolver

    reduced = in_plane_model(model)
    out: dict = {}
    for label, m in (("full", model), ("in_plane", reduced)):
        best, hist = np.inf, None
        for _ in range(max(repeats, 1)):
            t0 = time.perf_counter()
            hist = StaticSolver(m, settings).run()
            best = min(best, time.perf_counter() - t0)
        assert hist is not None
        lam = hist.collapse_multiplier
        out[label] = {
            "free_dofs": int(m.free.sum()),
            "interfaces": m.interfaces.count,
            "nnz_K": int(Assembly.of(m).stiffness().nnz),
            "status": hist.status,
            "lambda": None if lam is None else float(lam),
            "seconds": float(best),
            "iterations": hist.iterations,
        }
    lf, lr = out["full"]["lambda"], out["in_plane"]["lambda"]
    out["lambda_relative_difference"] = (
        None if lf is None or lr is None else abs(lr - lf) / max(abs(lf), 1e-300)
    )
    out["time_ratio"] = out["full"]["seconds"] / max(out["in_plane"]["seconds"], 1e-12)
    return out


def measure_strength_model(model: Model, springs_per_side: int = 32, repeats: int = 5) -> dict:
    """Cost of one evaluation of the panel's interfaces: the closed-form domain (the default)
    against the spring (fibre) model of Section 2.1, n x n springs per interface."""
    from masonry_dem.constitutive.law import InterfaceLaw
    from masonry_dem.constitutive.springs import SpringInterface

    m = model.interfaces.count
    kbar = interface_stiffness(model)
    law = InterfaceLaw.of(model, kbar)
    rng = np.random.default_rng(0)
    rel = 1e-6 * rng.standard_normal((m, 6))
    rel[:, 2] = -np.abs(rel[:, 2]) * 10
    zeros = np.zeros((m, 6))
    cracked = np.zeros(m, dtype=bool)
    t_closed = _best_time(lambda: law.respond(rel, zeros, cracked), repeats)
    its = model.interfaces
    spring = SpringInterface(
        float(np.median(its.l1)),
        float(np.median(its.l2)),
        springs_per_side,
        float(np.median(model.kn)),
        float(np.median(model.kt)),
        float(np.median(model.friction)),
    )
    path = rel[:, None, :]  # (m, 1 step, 6): one evaluation of every interface, batched
    t_spring = _best_time(lambda: spring.run(path), repeats)
    return {
        "interfaces": m,
        "springs_per_interface": springs_per_side**2,
        "seconds_closed_form": t_closed,
        "seconds_spring_model": t_spring,
        "time_ratio": t_spring / max(t_closed, 1e-12),
    }


__all__ = [
    "IN_PLANE_DOFS",
    "OUT_OF_PLANE_DOFS",
    "SceneCheck",
    "cheapest_model",
    "in_plane_check",
    "in_plane_model",
    "measure_fixed_dofs",
    "measure_reduction",
    "measure_strength_model",
    "model_cost",
]
