"""Helpers of the certificate tests: generated tilted walls, and :func:`recheck`, which
re-checks a certified collapse without the solver's code paths."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive.law import CONTACT_BAND, DETACHED_FLAG, InterfaceLaw
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.selectors import column
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.results import History
from masonry_dem.solvers.incremental import StaticSettings
from masonry_dem.solvers.static.certificate import ADMISSIBLE_TOLERANCE, MODE_DISPLACEMENT

DRY = InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7)


def tilted_wall(
    blocks_along: int,
    courses: int,
    material: InterfaceMaterial = DRY,
    direction=(0.0, 0.0, 1.0),
    held: bool = True,
) -> Model:
    wall = running_bond_wall(blocks_along, courses, 0.081, 0.21, 0.07, 20e3)
    blocks, base = add_base(wall)
    supports = [Support([base])]
    if held:
        supports.append(Support(column(wall, "left"), ["u1", "u3"]))
    return Model.build(
        blocks,
        material,
        supports=supports,
        loads=[SelfWeight(), WeightProportional(direction)],
    )


def zero_capacity_reduced(T, response, kbar, floor: float) -> np.ndarray:
    """``T`` (m, 6, 6) with the joints of no strength at zero compression whose normal force
    is round-off (within the law's contact band of the largest: the head joints of a dry
    wall under its weight, or beside a course that tilts) reduced to their normal stiffness,
    ``floor`` x kbar on the other diagonal terms. The law's flags there, and so its raw
    tangent, are set by the sign of the round-off: read as sliding, such a joint couples its
    shear to its gap by friction x kn, though it carries nothing. Written here from the
    rule, not taken from the solver, so that the recheck stays independent of it."""
    T = T.copy()
    fn = response.trial[:, 2]
    band = CONTACT_BAND * np.abs(fn).max(initial=0.0)
    if band == 0.0:  # the undeformed start: no joint is decided by round-off
        return T
    zero = (response.tensile_force <= 0) & (np.abs(fn) <= band)
    normal = T[zero, 2, 2].copy()
    T[zero] = np.einsum("mi,ij->mij", floor * kbar[zero], np.eye(6))
    T[zero, 2, 2] = normal
    return T


def recheck(model: Model, hist: History, settings: StaticSettings) -> None:
    """Re-check a certified collapse without the solver's code paths: (a) a fresh law and
    assembly give a residual within the tolerance at the state the certificate names, its
    actions inside the strength domain; (b) a dense solve of the tangent assembled here
    gives rho = F_L.v / v.K_0 v <= mode_stiffness (K_0: the dead-load state's tangent; both
    tangents with the joints of :func:`zero_capacity_reduced` reduced) (or the curve past its
    peak is as long as stated), with positive work of the live load along the mode; (c) lambda is the
    peak of the recorded curve."""
    cert = hist.certificate
    assert hist.status == "collapse" and cert is not None and cert.holds
    assert 0 <= cert.step < len(hist.steps)
    state = hist.steps[cert.step]
    asm = Assembly.of(model)
    law = InterfaceLaw.of(model, asm.kbar)
    free = asm.free_index
    # the law state the step was found with: the joints cracked before it
    cracked = np.zeros(model.interfaces.count, dtype=bool)
    for st in hist.steps[: cert.step]:
        cracked |= (np.asarray(st.flags) & DETACHED_FLAG) > 0
    # and the plastic slip stored at the step before it (memory = "slip"; none otherwise)
    plastic = np.zeros_like(asm.kbar)
    if cert.step > 0:
        before = hist.steps[cert.step - 1]
        relative = asm.relative_displacements(before.q.reshape(-1))
        plastic = law.plastic_part(relative, before.actions)
    if state.found_plastic is not None and state.found_cracked is not None:
        # a rest of the damped motion, whose slip moved with the wall: kept with the step
        plastic, cracked = state.found_plastic, state.found_cracked
    q = state.q.reshape(-1)
    response = law.respond(asm.relative_displacements(q), plastic, cracked)
    F = model.dead.reshape(-1)[free] + state.load_factor * model.live.reshape(-1)[free]
    internal = asm.H_free.T @ response.actions.reshape(-1)
    size = float(np.median(model.blocks.sizes))
    weight = np.where(free % 6 < 3, 1.0, 1.0 / size)
    residual = np.linalg.norm(weight * (F - internal)) / np.linalg.norm(weight * F)
    assert residual <= settings.tolerance
    assert law.admissibility(response).max() <= 1.0 + ADMISSIBLE_TOLERANCE
    # (b)
    F_live = model.live.reshape(-1)[free]

    def dense(response):
        T = zero_capacity_reduced(
            law.tangent(response, settings.residual_stiffness),
            response,
            asm.kbar,
            settings.residual_stiffness,
        )
        return (asm.H_free.T @ sparse.block_diag(list(T)) @ asm.H_free).toarray()

    # the metric: the tangent of the dead-load state, joint by joint, each joint's energy
    # counted where it is positive (a semi-norm even where a joint slides under the dead load)
    first = hist.steps[0].q.reshape(-1)
    dead = law.respond(asm.relative_displacements(first), np.zeros_like(asm.kbar), cracked & False)
    T0 = zero_capacity_reduced(
        law.tangent(dead, settings.residual_stiffness),
        dead,
        asm.kbar,
        settings.residual_stiffness,
    )

    def metric(v):
        relative = (asm.H_free @ v).reshape(-1, 6)
        return float(np.maximum(np.einsum("mi,mij,mj->m", relative, T0, relative), 0).sum())

    def along_load(response):
        """v = K_t^-1 F_L by a dense solve, and rho = F_L.v / v.K_0 v."""
        v = np.linalg.solve(dense(response), F_live)
        return v, float(F_live @ v) / metric(v)

    if cert.mode.startswith("singular tangent"):
        v, rho = along_load(response)
        if cert.mode.endswith("at the end of the bracket"):  # past a kink of the law
            lam_end = state.load_factor * (1 + settings.bracket_tolerance)
            probe = q.copy()
            probe[free] += (lam_end - state.load_factor) * v
            beyond = law.respond(
                asm.relative_displacements(probe), np.zeros_like(asm.kbar), cracked
            )
            v, rho = along_load(beyond)
        assert rho <= settings.mode_stiffness
        assert rho == pytest.approx(cert.mode_rayleigh, rel=1e-3, abs=1e-12)
    else:
        assert cert.mode == "flat curve"
        assert cert.curve_displacement >= MODE_DISPLACEMENT
    mode = cert.mode_vector.reshape(-1)[free]
    assert float(F_live @ mode) > 0  # the live load does work along the mode
    # (c) the multiplier is the highest lambda of the curve
    assert hist.collapse_multiplier == pytest.approx(hist.load_factors.max(), rel=1e-12)
