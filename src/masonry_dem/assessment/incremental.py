"""The incremental kinematics of a block mechanism (``kinematics = "incremental"`` of
:class:`~masonry_dem.assessment.kinematics.Mechanism`): the finite motion integrated in steps,
the blocks' twists projected at each configuration onto the joints' contacts, which keeps
closed loops closed (docs/assessment.md, "Nonlinear kinematic analysis")."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from masonry_dem._progress import listening, report
from masonry_dem.assessment.screws import moved_by, screw_transform
from masonry_dem.assessment.spectra import G
from masonry_dem.model import Model

#: the rotation [rad] of the block that turns fastest over one step of the incremental
#: motion: the explicit midpoint rule's error is O(step^2) (0.005: 2.8e-7 of alpha on the
#: two-block chain, 1.1e-6 at 0.01; tests/assessment/test_kinematics.py)
STEP = 0.005
#: a joint's corner is in contact when its overlap-signed gap is at most this share of the
#: joint's smaller side (far above the O(step^3) drift per step of a hinge that stays closed)
CONTACT_GAP = 1e-3
#: the incremental motion locks when the projections onto the contacts have left its twists
#: less than this share of the mode's norm in the kinetic metric: the capacity curve stops
#: there. alpha holds the joints' work rate D at its value on the mode, so on a motion that
#: kept a share k of the mode's norm D weighs 1/k times what it would on the mode: past the
#: lock alpha is biased upwards and a d_k0 found there would lie too far. The share is ours;
#: measured, the verdicts do not depend on it: the limit analysis's mechanisms of the
#: default, U and windowed U walls keep 0.84-0.98 down to alpha = 0, the pushover's of the
#: default and U walls fall below 0.5 within two steps (to 0.06 and 0.42 by 180 degrees, with
#: alpha still positive), and d0* and the verdicts of all five are the same for 0.1, 0.25,
#: 0.5 and 0.75 (docs/history/assessment_record.md)
LOCKED = 0.5
#: a corner in contact sticks (its tangential relative velocity held at 0 as well) when the
#: mode slides it by at most this share of the largest corner speed at s = 0 (0: none sticks)
STICK = 0.01
#: a corner in contact is taken as not opening when its normal velocity is below this share
#: of the largest corner speed (a hinge of the mode opens by round-off only)
OPENING = 1e-8
#: penalty of the augmented-Lagrangian projection, relative to the mean of diag(A^T A)
PENALTY = 1e8
#: augmented-Lagrangian sweeps (each divides the constraints' residual by about PENALTY) and
#: rounds of the active set (a corner in contact that the projection turns to closing joins)
SWEEPS, ROUNDS = 4, 4


@dataclass(frozen=True)
class IncrementalProgress:
    """One step of the incremental kinematics, reported while the path is integrated
    (:mod:`masonry_dem._progress`): ``step`` its number from 1, ``rotation`` the largest
    rotation of a block [rad] at its end, ``kinetic`` the kinetic norm of its twists over
    the mode's (the lock test's measure, :data:`LOCKED`)."""

    step: int
    rotation: float
    kinetic: float


def spd_lu(matrix: Any) -> Any:
    """SuperLU of a sparse symmetric positive definite matrix: the ordering of A^T + A and
    the diagonal pivots, as SuperLU's user guide sets it for a symmetric matrix: 20-25 % less
    time a step than the default COLAMD with partial pivoting on the U walls' mechanisms (327
    and 766 blocks), the same on the 46-block default wall, d0* the same to 1e-10
    (benchmarks/bench_incremental.py)."""
    from scipy.sparse.linalg import splu

    return splu(
        matrix.tocsc(),
        permc_spec="MMD_AT_PLUS_A",
        diag_pivot_thresh=0.0,
        options={"SymmetricMode": True},
    )


class IncrementalPath:
    """The finite motion of a mechanism integrated in steps of s, the blocks' twists
    projected at each configuration onto the joints' contacts: the incremental kinematic
    analysis of a block mechanism ("per incrementi finiti"), the velocities found anew at
    each configuration, here by velocity projection.

    At a configuration g = (R, t) the twists xi (spatial: v0 the velocity of the point at
    the origin, w) are the closest to a reference (:meth:`predict`: the previous step's
    relative motions carried with the blocks; at s = 0 the mode) in the blocks' kinetic
    metric, sum m_i |u_i - u_i'|^2 + J_i |w_i - w_i'|^2 (u the velocity of the block's
    current centre, J_i = m_i |sizes_i|^2 / 12), subject to no relative normal velocity at
    the joints' corners that are in contact (gap at most :data:`CONTACT_GAP` of the joint's
    smaller side, an overlap included) and that the mode keeps closed or the reference does
    not open (normal velocity at most :data:`OPENING` of the largest corner speed): a hinge
    of the mode keeps closed, a corner the mode would push into its neighbour is held at
    contact, a corner the mode opens lifts off, and one that closes during the motion joins
    when it touches. A corner in contact that the projection turns to closing joins and the
    projection is made again (:data:`ROUNDS`). At a corner in contact that the mode does not
    slide (:data:`STICK`) the tangential relative velocity is held at 0 too (Circolare 2019
    C8.7.1.2.1: "scorrimento tra i blocchi, assente"); a corner the mode slides slides
    freely.

    Steps of ``ds`` (``step`` radians of the projected mode's fastest block) are taken by the
    explicit midpoint rule on the group: the twist at the
    start moves the configuration half a step, the twist projected there moves the step
    from its start by the screw motions exp(ds xi_mid) g, and the twist is projected at the
    end: O(ds^2) over a path (the two-block chain's alpha to 2.8e-7 at ds |w| = 0.005). The
    path is integrated lazily, as far as a configuration is asked for. Between two nodes a
    block moves by the step's screw motion and its twist is interpolated linearly between
    the nodes' projected twists (both O(ds^2)). Each projection factorizes one sparse
    matrix of the free DOFs (augmented Lagrangian, :data:`PENALTY`, :data:`SWEEPS`), the
    prediction another."""

    def __init__(
        self, model: Model, v0: NDArray[np.float64], w: NDArray[np.float64], step: float = STEP
    ):
        itf = model.interfaces
        self.bi = np.asarray(itf.block_i, dtype=np.intp)
        self.bj = np.asarray(itf.block_j, dtype=np.intp)
        self.axis = np.asarray(itf.axis, dtype=np.intp)
        self.corners = itf.corner_points() if itf.count else np.zeros((0, 4, 3))
        self.tol_gap = CONTACT_GAP * np.minimum(itf.l1, itf.l2)[:, None]  # (m, 1)
        self.joint_centres = np.asarray(itf.centre, dtype=float).reshape(-1, 3)
        self.joint_size = np.maximum(itf.l1, itf.l2).astype(float)
        self.centres = np.asarray(model.blocks.centres, dtype=float)
        n = self.centres.shape[0]
        sizes = np.asarray(model.blocks.sizes, dtype=float)
        mass = np.asarray(model.blocks.weights, dtype=float) / G
        # a weightless block still has a metric: the mean mass of the weighted ones
        mass = np.where(mass > 0, mass, mass[mass > 0].mean() if (mass > 0).any() else 1.0)
        inertia = mass * np.sum(sizes**2, axis=1) / 12.0
        self.metric = np.column_stack(
            [np.repeat(mass[:, None], 3, 1), np.repeat(inertia[:, None], 3, 1)]
        )
        free = ~np.asarray(model.fixed, dtype=bool)  # (n, 6): fixed DOFs stay at 0
        self.col = np.flatnonzero(free.ravel())
        self.place = np.full(n * 6, -1)
        self.place[self.col] = np.arange(self.col.size)
        self.scale = np.sqrt(self.metric.ravel()[self.col])
        self.s = [0.0]
        self.R = [np.broadcast_to(np.eye(3), (n, 3, 3)).copy()]
        self.t = [np.zeros((n, 3))]
        # a bound on the mode's corner speeds: the scale of the opening test
        u = v0 + np.cross(w, self.centres)
        half = 0.5 * np.linalg.norm(sizes, axis=1)
        self.speed = float((np.linalg.norm(u, axis=1) + np.linalg.norm(w, axis=1) * half).max())
        # the corners the mode does not slide: the codes' hinges, "assenza di scorrimento"
        rel = np.hstack([v0, w])[self.bj] - np.hstack([v0, w])[self.bi]
        dv = rel[:, None, :3] + np.cross(rel[:, None, 3:], self.corners)
        normal = np.eye(3)[self.axis]
        slide = dv - np.einsum("mki,mi->mk", dv, normal)[..., None] * normal[:, None]
        self.stick = np.linalg.norm(slide, axis=2) <= STICK * self.speed  # (m, 4)
        # the corners the mode keeps closed (its hinges, the joints it does not open): held
        # closed while in contact, whatever a step's prediction says (bilateral)
        self.hinge = np.einsum("mki,mi->mk", dv, normal) <= OPENING * self.speed
        self.xi = [self.project(self.R[0], self.t[0], np.hstack([v0, w]))]
        # ``step`` radians of the fastest block of the mechanism: the projected mode, which
        # may turn its fastest block more slowly than the mode given does
        wmax = float(np.linalg.norm(self.xi[0][:, 3:], axis=1).max(initial=0.0))
        if not wmax > 0:
            raise ValueError(
                "kinematics = 'incremental': the mode held at the joints' contacts turns no "
                "block, so no step of rotation"
            )
        self.ds = float(step) / wmax
        self.xi_mid: list[NDArray[np.float64]] = []
        self.norms: list[float] = []

    # -------------------------------------------------------------- one configuration
    def _corners(
        self, R: NDArray[np.float64], t: NDArray[np.float64], xi: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """At the configuration (R, t), for every joint's corners (m, 4): the gap of the
        corner as a point of block j from block i's face (whose corner it was), along the
        normal turned with block i (negative: overlap, as :func:`interpenetration` measures
        it); its rate in the twists ``xi`` (n, 6), n . (v_j - v_i) at the corner of block j
        (the terms of the turning normal cancel those of the corner of block i); the
        corners of block j (m, 4, 3) and the normals (m, 3)."""
        pi = np.einsum("mij,mkj->mki", R[self.bi], self.corners) + t[self.bi][:, None]
        pj = np.einsum("mij,mkj->mki", R[self.bj], self.corners) + t[self.bj][:, None]
        normal = R[self.bi, :, self.axis]  # column `axis` of R_i
        gap = np.einsum("mki,mi->mk", pj - pi, normal)
        rel = xi[self.bj] - xi[self.bi]
        dv = rel[:, None, :3] + np.cross(rel[:, None, 3:], pj)
        return gap, np.einsum("mki,mi->mk", dv, normal), pj, normal

    def _to_free(self, xi: NDArray[np.float64], c: NDArray[np.float64]) -> NDArray[np.float64]:
        """Spatial twists (n, 6) as the free DOFs (centre velocity, rotation) scaled by the
        square root of the metric."""
        x = np.hstack([xi[:, :3] + np.cross(xi[:, 3:], c), xi[:, 3:]])
        return x.ravel()[self.col] * self.scale

    def _from_free(self, z: NDArray[np.float64], c: NDArray[np.float64]) -> NDArray[np.float64]:
        flat = np.zeros(c.shape[0] * 6)
        flat[self.col] = z / self.scale
        x = flat.reshape(-1, 6)
        return np.hstack([x[:, :3] - np.cross(x[:, 3:], c), x[:, 3:]])

    def project(
        self, R: NDArray[np.float64], t: NDArray[np.float64], ref: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The twists (n, 6) closest to ``ref`` (n, 6) at the configuration (R, t) that
        keep the contacts: see the class."""
        from scipy.sparse import coo_matrix, identity

        if self.bi.size == 0:
            return ref
        c = np.einsum("nij,nj->ni", R, self.centres) + t
        z0 = self._to_free(ref, c)
        gap, vn, p, normal = self._corners(R, t, ref)
        contact = gap <= self.tol_gap
        active = contact & (self.hinge | (vn <= OPENING * self.speed))
        xi = ref
        for _ in range(ROUNDS):
            jm, corner = np.nonzero(active)
            js, cs = np.nonzero(active & self.stick)
            # the normal at every active corner, the two tangents turned with block i at the
            # sticking ones (the rate of the tangential offset of block j's corner from block
            # i's is the relative velocity there too)
            e = np.concatenate(
                [
                    normal[jm],
                    R[self.bi[js], :, (self.axis[js] + 1) % 3],
                    R[self.bi[js], :, (self.axis[js] + 2) % 3],
                ]
            )
            pt = np.concatenate([p[jm, corner], p[js, cs], p[js, cs]])
            jm = np.concatenate([jm, js, js])
            k = jm.size
            if k == 0:
                break
            # e . (u + w x (p - c)) = e . u + w . ((p - c) x e): block j's minus block i's
            bi, bj = self.bi[jm], self.bj[jm]
            coef = np.concatenate(
                [-np.hstack([e, np.cross(pt - c[bi], e)]), np.hstack([e, np.cross(pt - c[bj], e)])]
            ).ravel()
            dofs = self.place[(np.concatenate([bi, bj])[:, None] * 6 + np.arange(6)).ravel()]
            rows = np.tile(np.repeat(np.arange(k), 6), 2)
            keep = dofs >= 0  # a fixed DOF's velocity is 0
            A = coo_matrix(
                (coef[keep] / self.scale[dofs[keep]], (rows[keep], dofs[keep])),
                shape=(k, self.col.size),
            ).tocsr()
            AtA = (A.T @ A).tocsc()
            rho = PENALTY / max(float(AtA.diagonal().mean()), 1e-300)
            lu = spd_lu(identity(self.col.size, format="csc") + rho * AtA)
            # augmented Lagrangian on the change d = z - z0: min |d|^2, A d = -A z0 (an
            # admissible z0 comes back unchanged; redundant contacts need no special care)
            r = -(A @ z0)
            lam = np.zeros(k)
            d = np.zeros_like(z0)
            for _ in range(SWEEPS):
                d = lu.solve(A.T @ (rho * r - lam))
                lam = lam + rho * (A @ d - r)
            xi = self._from_free(z0 + d, c)
            joining = contact & ~active & (self._corners(R, t, xi)[1] < -OPENING * self.speed)
            if not joining.any():
                break
            active |= joining
        return xi

    def predict(
        self,
        R: NDArray[np.float64],
        t: NDArray[np.float64],
        xi: NDArray[np.float64],
        move: NDArray[np.float64],
        ds: float,
    ) -> NDArray[np.float64]:
        """The twists (n, 6) at the configuration (R, t) reached from the one of ``xi`` by
        the screw motions exp(ds ``move``), before the projection: each joint's relative
        twist xi_j - xi_i carried with block i (Ad(exp(ds move_i)), as a hinge's line is
        carried by both of its blocks), the blocks' twists the least-squares fit of those
        relative ones (relative velocity at the joint's centre and relative rotation times
        the joint's larger side), with a whisper (1e-9) of ``xi`` itself for the blocks no
        joint reaches. On an open chain the fit is exact and the relative motions stay
        fixed in the parents, as :meth:`Mechanism.motion` composes them; around a closed
        loop it spreads the loop's misfit over its joints."""
        from scipy.sparse import coo_matrix, identity

        if self.bi.size == 0:
            return xi
        Rs, ts = screw_transform(move[:, :3], move[:, 3:], ds)
        Ri, ti = Rs[0][self.bi], ts[0][self.bi]
        rel = xi[self.bj] - xi[self.bi]
        w_rel = np.einsum("mij,mj->mi", Ri, rel[:, 3:])
        v_rel = np.einsum("mij,mj->mi", Ri, rel[:, :3]) + np.cross(ti, w_rel)
        c = np.einsum("nij,nj->ni", R, self.centres) + t
        p = np.einsum("mij,mj->mi", R[self.bi], self.joint_centres) + t[self.bi]
        size = self.joint_size[:, None]
        target = np.hstack([v_rel + np.cross(w_rel, p), size * w_rel]).ravel()
        # rows: u_j + w_j x (p - c_j) - (u_i + w_i x (p - c_i)) and L (w_j - w_i), 6 per joint
        m = self.bi.size
        blocks = np.concatenate([self.bi, self.bj])
        sign = np.concatenate([-np.ones(m), np.ones(m)])
        arm = np.concatenate([p, p]) - c[blocks]  # (2m, 3)
        skew = np.zeros((2 * m, 3, 3))  # w x arm = -[arm]x w
        skew[:, 0, 1], skew[:, 0, 2] = arm[:, 2], -arm[:, 1]
        skew[:, 1, 0], skew[:, 1, 2] = -arm[:, 2], arm[:, 0]
        skew[:, 2, 0], skew[:, 2, 1] = arm[:, 1], -arm[:, 0]
        local = np.zeros((2 * m, 6, 6))
        local[:, :3, :3] = np.eye(3)
        local[:, :3, 3:] = skew
        local[:, 3:, 3:] = np.eye(3) * np.concatenate([size, size])[:, :, None]
        local *= sign[:, None, None]
        joint = np.concatenate([np.arange(m), np.arange(m)])
        rows = np.broadcast_to((joint[:, None] * 6 + np.arange(6))[:, :, None], local.shape)
        dofs = self.place[
            np.broadcast_to((blocks[:, None] * 6 + np.arange(6))[:, None, :], local.shape)
        ]
        keep = dofs >= 0  # a fixed DOF's velocity is 0
        D = coo_matrix(
            (local[keep] / self.scale[dofs[keep]], (rows[keep], dofs[keep])),
            shape=(6 * m, self.col.size),
        ).tocsr()
        DtD = (D.T @ D).tocsc()
        eps = 1e-9 * max(float(DtD.diagonal().mean()), 1e-300)
        z = spd_lu(DtD + eps * identity(self.col.size, format="csc")).solve(
            D.T @ target + eps * self._to_free(xi, c)
        )
        return self._from_free(np.asarray(z, dtype=float), c)

    def _advance(self) -> None:
        """One step of the explicit midpoint rule from the last node."""
        R, t, xi = self.R[-1], self.t[-1], self.xi[-1]
        Rh, th = moved_by(R, t, xi, 0.5 * self.ds)
        mid = self.project(Rh, th, self.predict(Rh, th, xi, xi, 0.5 * self.ds))
        R1, t1 = moved_by(R, t, mid, self.ds)
        self.xi_mid.append(mid)
        self.R.append(R1)
        self.t.append(t1)
        self.xi.append(self.project(R1, t1, self.predict(R1, t1, xi, mid, self.ds)))
        self.s.append(self.s[-1] + self.ds)
        if listening():
            turned = np.arccos(np.clip((np.trace(R1, axis1=1, axis2=2) - 1) / 2, -1.0, 1.0))
            report(IncrementalProgress(len(self.xi_mid), float(turned.max()), self._last_kinetic()))

    def kinetic(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        """The norm of the twists in the kinetic metric at the node at or before each of
        ``s``, over the mode's (at s = 0)."""
        self._reach(float(s.max(initial=0.0)))
        k = np.minimum((s / self.ds).astype(np.intp), len(self.xi) - 1)
        return self._norms()[k]

    def _norms(self) -> NDArray[np.float64]:
        """The kinetic norm of each node's twists over the mode's, as far as integrated."""
        self._measure()
        norms = np.asarray(self.norms)
        return norms / norms[0] if norms[0] > 0 else np.ones(norms.size)

    def _last_kinetic(self) -> float:
        """The last node's kinetic norm over the mode's (what the lock test reads)."""
        self._measure()
        return self.norms[-1] / self.norms[0] if self.norms[0] > 0 else 1.0

    def _measure(self) -> None:
        """The kinetic norm of the twists of each node integrated since the last call."""
        while len(self.norms) < len(self.xi):
            j = len(self.norms)
            c = np.einsum("nij,nj->ni", self.R[j], self.centres) + self.t[j]
            self.norms.append(float(np.linalg.norm(self._to_free(self.xi[j], c))))

    def _reach(self, last: float) -> None:
        """Integrate to the node past ``last`` (the twist interpolates between nodes), or to
        the first node where the motion has locked (:data:`LOCKED`): past it the capacity
        curve ends, and a configuration asked for there is the last step's, continued."""
        while self.s[-1] <= last and self._last_kinetic() >= LOCKED:
            self._advance()

    def motion(
        self, s: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """R, t, V, O at the configurations ``s`` (k,), as :meth:`Mechanism.motion`."""
        if s.size and s.min() < 0:
            raise ValueError(f"s = {float(s.min())!r}: the incremental motion starts at s = 0")
        self._reach(float(s.max(initial=0.0)))
        k = np.minimum((s / self.ds).astype(np.intp), len(self.xi_mid) - 1)
        tau = s - np.asarray(self.s)[k]
        R0, t0 = np.asarray(self.R)[k], np.asarray(self.t)[k]
        mid = np.asarray(self.xi_mid)[k]  # (k, n, 6)
        Rs, ts = screw_transform(mid[..., :3], mid[..., 3:], tau)
        R = Rs @ R0
        t = np.einsum("knij,knj->kni", Rs, t0) + ts
        a = (tau / self.ds)[:, None, None]
        xi = np.asarray(self.xi)
        twist = (1 - a) * xi[k] + a * xi[k + 1]
        return R, t, twist[..., :3], twist[..., 3:]
