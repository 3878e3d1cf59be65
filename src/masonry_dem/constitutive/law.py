"""The elastic-perfectly-plastic interface law used by the panel solvers.

Trial actions come from the elastic stiffness and the plastic relative displacements of the
last converged state; the closed-form domain of Section 2.1 projects them back (force
correction) and gives the damage state and the stiffness factors of Eqs. (13)-(14).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from masonry_dem.constitutive.strength import check_strength
from masonry_dem.model import Model

DETACHED_FLAG = 8


@dataclass(frozen=True)
class LawResponse:
    trial: np.ndarray  # (m, 6) elastic trial actions
    tensile_force: np.ndarray  # (m,) ft in force at this iterate (0 once cracked)
    actions: np.ndarray  # (m, 6) corrected actions
    tangent: np.ndarray  # (m, 6) stiffness factors in [0, 1]
    state: np.ndarray  # (m,) damage code
    flags: np.ndarray  # (m,) violated-criteria bit flags
    utilisation: np.ndarray  # (m,)


@dataclass(frozen=True)
class InterfaceLaw:
    """Batched law for all interfaces of a model.

    tension: ``"brittle"`` (a joint that opens loses its tensile strength for good, as a cracked
    mortar joint does) or ``"plastic"`` (it keeps carrying ft, perfectly plastic).
    """

    kbar: np.ndarray  # (m, 6) elastic stiffness
    l1: np.ndarray
    l2: np.ndarray
    friction: np.ndarray
    tensile_force: np.ndarray  # (m,) ft = tensile strength x area
    alpha: np.ndarray
    tension: str = "brittle"

    @classmethod
    def of(cls, model: Model, kbar: np.ndarray, tension: str = "brittle") -> InterfaceLaw:
        if tension not in ("brittle", "plastic"):
            raise ValueError(f"tension must be 'brittle' or 'plastic', got {tension!r}")
        its = model.interfaces
        return cls(
            kbar,
            its.l1,
            its.l2,
            model.friction,
            model.tensile_strength * its.area,
            model.alpha,
            tension,
        )

    def respond(
        self, relative: np.ndarray, plastic: np.ndarray, cracked: np.ndarray
    ) -> LawResponse:
        """Actions for relative displacements (m, 6) given the plastic part (m, 6) and the
        joints already cracked in tension (m,) bool."""
        trial = self.kbar * (relative - plastic)
        ft = np.where(cracked, 0.0, self.tensile_force)
        chk = check_strength(trial, self.l1, self.l2, self.friction, ft, alpha=self.alpha)
        actions = chk.projected
        if self.tension == "brittle":
            opened = (chk.flags & DETACHED_FLAG) > 0
            actions = np.where(opened[:, None], 0.0, actions)
        return LawResponse(
            trial, ft, actions, chk.stiffness_factors, chk.state, chk.flags, chk.utilisation
        )

    def tangent(self, r: LawResponse, floor: float = 1e-9) -> np.ndarray:
        """(m, 6, 6) consistent tangent of the corrected actions w.r.t. relative displacements.

        Eqs. (13)-(14) zero the stiffness of the yielded components; the capacities of the
        Mohr-Coulomb domain grow with compression (fsu = mu (ft - fn), rocking limit
        (ft - fn) lc), so yielded actions keep a coupling to the normal displacement. Without
        it a sliding joint looks free in Newton's matrix and the iterations jump far away.
        On the shear-torsion surface the return is radial: the tangent keeps the transverse
        part s (I - n n^T) of the elastic stiffness in the scaled space (f1/fsu, f2/fsu, m3/m3u).
        """
        m = self.kbar.shape[0]
        k = self.kbar
        T = np.zeros((m, 6, 6))
        idx = np.arange(6)
        T[:, idx, idx] = k
        flags = r.flags
        detached = (flags & DETACHED_FLAG) > 0
        rock1 = (flags & 2) > 0
        rock2 = (flags & 4) > 0
        sliding = (flags & 1) > 0
        fn = r.actions[:, 2]
        cap = np.maximum(r.tensile_force - fn, 0.0)
        kn = k[:, 2]
        T[rock1, 3, 3] = 0.0
        T[rock1, 3, 2] = -np.sign(r.trial[rock1, 3]) * 0.5 * self.l2[rock1] * kn[rock1]
        T[rock2, 4, 4] = 0.0
        T[rock2, 4, 2] = -np.sign(r.trial[rock2, 4]) * 0.5 * self.l1[rock2] * kn[rock2]
        rows = np.flatnonzero(sliding & ~detached)
        if rows.size:
            sub = np.array([0, 1, 5])
            t = r.trial[np.ix_(rows, sub)]
            p = r.actions[np.ix_(rows, sub)]
            c = np.abs(p) + 1e-300  # scale of each component on the surface
            scale = np.maximum(np.abs(t), c)
            x_t = t / scale
            x_p = p / scale
            nt = np.linalg.norm(x_t, axis=1, keepdims=True)
            s = np.linalg.norm(x_p, axis=1, keepdims=True) / np.maximum(nt, 1e-300)
            n = x_t / np.maximum(nt, 1e-300)
            proj = np.eye(3)[None] - n[:, :, None] * n[:, None, :]
            block = (
                scale[:, :, None] * (s[:, :, None] * proj) / scale[:, None, :] * k[rows][:, sub][:, None, :]
            )
            T[rows[:, None, None], sub[None, :, None], sub[None, None, :]] = block
            with np.errstate(divide="ignore", invalid="ignore"):
                coupling = np.where(cap[rows, None] > 0, -p / cap[rows, None], 0.0)
            T[rows[:, None], sub[None, :], 2] = coupling * kn[rows, None]
        T[detached] = 0.0
        T[:, idx, idx] += floor * k
        return T

    def plastic_part(self, relative: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Plastic relative displacements consistent with converged actions."""
        return relative - actions / self.kbar

    def cracked_after(self, cracked: np.ndarray, response: LawResponse) -> np.ndarray:
        if self.tension != "brittle":
            return cracked
        return cracked | ((response.flags & DETACHED_FLAG) > 0)
