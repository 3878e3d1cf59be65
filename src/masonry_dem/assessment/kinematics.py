"""A collapse mechanism as the codes' kinematic analysis reads it (NTC 2018 and Circolare 2019
C8.7.1; docs/assessment.md): the weights P_i of the blocks that move, their virtual
displacements, the multiplier alpha0, the participating mass M* and its fraction e*, and the
capacity curve alpha(d_k) of the mechanism moved through finite rotations.

A mechanism is a small-displacement mode q (n, 6) of the blocks (translation of the centre,
rotation): the pushover's collapse mode (:func:`masonry_dem.mechanism.collapse_mode`) or the
limit analysis's block velocities. Each block's mode is a twist (v0 = u - w x c at the
origin, w): the finite motion of the block is the screw motion exp(s xi) of that twist, which
for a block turning about a hinge is the rotation about the hinge by the angle s |w|, and its
virtual velocity at any configuration is v0 + w x x (the spatial twist is constant).

The DEM's joints turn about their centres (a rocking joint keeps its normal spring and loses
its bending stiffness), so the pushover's mode lifts no weight at first order: the work that
rocking does against the weights is a plastic moment there. :func:`hinged_mode` turns such a
mode into the rigid-block one, each joint turning about its compressed edge, by a
least-squares fit of the block motions to the joints' relative motions with the normal
opening that the rotation opens at the joint's centre.

Everything is vectorised over blocks (and over the configurations of the curve).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem.assessment.spectra import G
from masonry_dem.model import Model

#: a block moves in the mechanism when its largest corner motion in the mode reaches this
#: share of the largest one: its weight then counts in sum P_i (e*) and in the control
#: point. A mechanism of a wall held on an edge deforms continuously and the share sets e*
#: (default wall: e* 0.32, 0.48, 0.55, 0.59 at 0.1 %, 1 %, 5 %, 10 %); the larger the share,
#: the larger e* and the smaller a0*, so the default errs on the safe side
MOVING = 0.05
#: a live load is proportional to the weights when every block's live force is within this
#: share of the largest from c P_i d
PROPORTIONAL = 1e-6
#: the largest rotation (rad) of any block the capacity curve follows before it gives up
#: finding alpha = 0
MAX_ROTATION = 0.5 * math.pi
#: configurations of the capacity curve between the undeformed one and d_k0
CURVE_POINTS = 201


def rodrigues(axis: NDArray[np.float64], angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation matrices (..., 3, 3) about unit ``axis`` (..., 3) by ``angle`` (...)."""
    k = axis
    K = np.zeros((*k.shape[:-1], 3, 3))
    K[..., 0, 1], K[..., 0, 2] = -k[..., 2], k[..., 1]
    K[..., 1, 0], K[..., 1, 2] = k[..., 2], -k[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -k[..., 1], k[..., 0]
    s = np.sin(angle)[..., None, None]
    c = (1.0 - np.cos(angle))[..., None, None]
    return np.eye(3) + s * K + c * (K @ K)


def screw_positions(
    v0: NDArray[np.float64], w: NDArray[np.float64], x: NDArray[np.float64], s: ArrayLike
) -> NDArray[np.float64]:
    """Positions (k, n, 3) of points ``x`` (n, 3) after the screw motion exp(s xi) of the
    twists (``v0``, ``w``) (n, 3) (v0 the velocity of the point at the origin), for each
    parameter of ``s`` (k,)."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    W = np.linalg.norm(w, axis=1)  # (n,)
    turning = W > 0
    k = np.where(turning[:, None], w / np.where(turning, W, 1.0)[:, None], 0.0)
    vn = np.where(turning[:, None], v0 / np.where(turning, W, 1.0)[:, None], 0.0)
    theta = s[:, None] * W[None, :]  # (k, n)
    R = rodrigues(np.broadcast_to(k, (*theta.shape, 3)), theta)  # (k, n, 3, 3)
    rotated = np.einsum("knij,nj->kni", R, x)
    kxv = np.cross(k, vn)  # (n, 3)
    # translation of the screw: (I - R)(k x v) + k (k . v) theta, for |w| > 0
    along = (np.sum(k * vn, axis=1) * theta)[..., None]
    t_turn = kxv[None] - np.einsum("knij,nj->kni", R, kxv) + k[None] * along
    t_slide = s[:, None, None] * v0[None]
    return np.where(turning[None, :, None], rotated + t_turn, x[None] + t_slide)


def hinged_mode(model: Model, mode: ArrayLike) -> tuple[NDArray[np.float64], float]:
    """The rigid-block mechanism of a DEM mode: every joint turning about its compressed edge.

    The joints' relative motions d = H q are kept, except the normal one at each joint's
    centre, raised to the opening the relative rotation makes there when the joint turns
    about the edge (corner) it closes on: dn' = max(dn, |delta1| l2/2 + |delta2| l1/2). The
    block motions are the least-squares fit of H q' = d' on the free DOFs. Returns q' (n, 6)
    and the relative residual |H q' - d'| / |d'| (0 for a compatible chain, such as a block
    or a strip of blocks rocking)."""
    from scipy.sparse import identity
    from scipy.sparse.linalg import spsolve

    from masonry_dem.assembly.compatibility import compatibility_matrix

    q = np.asarray(mode, dtype=float).reshape(model.blocks.count, 6)
    itf = model.interfaces
    if itf.count == 0:
        return q.copy(), 0.0
    H = compatibility_matrix(model.blocks, itf).tocsc()
    d = (H @ q.ravel()).reshape(-1, 6)
    target = d.copy()
    target[:, 2] = np.maximum(d[:, 2], np.abs(d[:, 3]) * itf.l2 / 2 + np.abs(d[:, 4]) * itf.l1 / 2)
    free = ~np.asarray(model.fixed, dtype=bool).ravel()
    Hf = H[:, free]
    # least squares with a whisper of the mode itself: DOFs no joint reaches keep their motion
    eps = 1e-12 * max(float(Hf.multiply(Hf).sum()) / max(Hf.shape[1], 1), 1.0)
    A = (Hf.T @ Hf + eps * identity(Hf.shape[1], format="csc")).tocsc()
    x = spsolve(A, Hf.T @ target.ravel() + eps * q.ravel()[free])
    flat = np.zeros(q.size)
    flat[free] = x
    out = flat.reshape(-1, 6)
    norm = float(np.linalg.norm(target))
    residual = float(np.linalg.norm(H @ out.ravel() - target.ravel())) / norm if norm else 0.0
    return out, residual


@dataclass(frozen=True)
class CapacityCurve:
    """alpha against the control point's displacement d_k (m, along the load), from the
    undeformed configuration (s = 0) to alpha = 0 (s0), and its SDOF form (d*, a*)."""

    s: NDArray[np.float64]
    alpha: NDArray[np.float64]
    d_k: NDArray[np.float64]
    d_star: NDArray[np.float64]
    a_star: NDArray[np.float64]
    d_k0: float
    d0_star: float


@dataclass(frozen=True)
class Mechanism:
    """A mechanism ready for the kinematic analysis.

    ``centres`` (n, 3) block centres, ``weights`` (n,) P_i [N] (the vertical dead load of each
    block), ``dead``/``live`` (n, 6) generalised loads, ``v0``/``w`` (n, 3) each block's twist
    (oriented so that the live load does positive work), ``direction`` the live load's unit
    horizontal direction, ``moving`` (n,) the blocks that move, ``scale`` c of the model's
    live load c P_i d (1 for a weight-proportional load of unit direction): ``live`` is the
    model's divided by c, P_i d, so that every multiplier here is the seismic one, alpha =
    c lambda."""

    centres: NDArray[np.float64]
    weights: NDArray[np.float64]
    dead: NDArray[np.float64]
    live: NDArray[np.float64]
    v0: NDArray[np.float64]
    w: NDArray[np.float64]
    direction: NDArray[np.float64]
    moving: NDArray[np.bool_]
    scale: float

    @classmethod
    def of(cls, model: Model, mode: ArrayLike, moving: float = MOVING) -> Mechanism:
        """The mechanism of ``mode`` (n, 6) on ``model``, whose live load must be horizontal
        forces proportional to the weights along one direction (a ``weight_proportional``
        load): the seismic load of the codes."""
        if not 0 < moving < 1:
            raise ValueError(
                f"moving = {moving!r} out of range: must be in (0, 1) (a share of the largest motion)"
            )
        q = np.asarray(mode, dtype=float).reshape(model.blocks.count, 6)
        if not np.all(np.isfinite(q)):
            raise ValueError("the mechanism's mode holds a non-finite value")
        centres = np.asarray(model.blocks.centres, dtype=float)
        weights = np.maximum(-np.asarray(model.dead, dtype=float)[:, 1], 0.0)
        live = np.asarray(model.live, dtype=float)
        direction, scale = _seismic_direction(live, weights)
        u, w = q[:, :3], q[:, 3:]
        v0 = u - np.cross(w, centres)
        half = 0.5 * np.linalg.norm(np.asarray(model.blocks.sizes, dtype=float), axis=1)
        reach = np.linalg.norm(u, axis=1) + np.linalg.norm(w, axis=1) * half
        if reach.max(initial=0.0) <= 0:
            raise ValueError("the mode moves no block: there is no mechanism")
        power = float(np.sum(live[:, :3] * u) + np.sum(live[:, 3:] * w))
        if power == 0:
            raise ValueError("the live load does no work on the mode: it drives no mechanism")
        sign = 1.0 if power > 0 else -1.0
        return cls(
            centres=centres,
            weights=weights,
            dead=np.asarray(model.dead, dtype=float),
            live=live / scale,
            v0=sign * v0,
            w=sign * w,
            direction=direction,
            moving=reach >= moving * reach.max(),
            scale=scale,
        )

    # ------------------------------------------------------------------ linear analysis
    @property
    def dx(self) -> NDArray[np.float64]:
        """delta x_i: each centre's virtual displacement along the load, in the mode."""
        return (self.v0 + np.cross(self.w, self.centres)) @ self.direction

    @property
    def total_weight(self) -> float:
        """sum P_i over the moving blocks [N]."""
        return float(self.weights[self.moving].sum())

    def powers(self, s: ArrayLike = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Virtual work rates of the dead and live loads at the configurations ``s`` (k,):
        sum F_i . (v0_i + w_i x c_i(s)) + M_i . w_i."""
        c = screw_positions(self.v0, self.w, self.centres, s)  # (k, n, 3)
        vel = self.v0[None] + np.cross(self.w[None], c)
        dead = np.einsum("kni,ni->k", vel, self.dead[:, :3]) + np.sum(self.dead[:, 3:] * self.w)
        live = np.einsum("kni,ni->k", vel, self.live[:, :3]) + np.sum(self.live[:, 3:] * self.w)
        return dead, live

    @property
    def alpha_rigid(self) -> float:
        """alpha0 of the principle of virtual work with the loads alone (rigid blocks, hinges
        at the edges, no work of the joints): alpha0 = -W_dead / W_live (Circolare C8.7.1,
        [C8A.4.1] of 2009 without L_fi)."""
        dead, live = self.powers(0.0)
        return float(-dead[0] / live[0])

    def participating_mass(self) -> tuple[float, float]:
        """M* = (sum P_i dx_i)^2 / (g sum P_i dx_i^2) [kg] and e* = g M* / sum P_i over the
        moving blocks (Circolare [C8A.4.2], [C8A.4.3])."""
        P, dx = self.weights[self.moving], self.dx[self.moving]
        m_star = float(np.sum(P * dx) ** 2 / (G * np.sum(P * dx**2)))
        return m_star, G * m_star / self.total_weight

    # ------------------------------------------------------------------ control point
    def control_displacement(self, s: ArrayLike) -> NDArray[np.float64]:
        """d_k: the displacement along the load of the centroid of the moving weights, at
        the configurations ``s``."""
        P = self.weights[self.moving]
        c = screw_positions(self.v0[self.moving], self.w[self.moving], self.centres[self.moving], s)
        moved = (c - self.centres[self.moving][None]) @ self.direction  # (k, n)
        return np.asarray(moved @ P / P.sum(), dtype=float)

    def control_point(self) -> NDArray[np.float64]:
        """The centroid of the moving weights (3,) [m]."""
        P = self.weights[self.moving]
        return np.asarray(P @ self.centres[self.moving] / P.sum(), dtype=float)

    # ------------------------------------------------------------------ large displacements
    def alpha(self, s: ArrayLike, alpha0: float | None = None) -> NDArray[np.float64]:
        """alpha at the configurations ``s`` by virtual work: (D - W_dead(s)) / W_live(s),
        D the work rate of the joints, held at its value at s = 0 that makes alpha(0) =
        ``alpha0`` (None: the loads alone, D = 0)."""
        dead, live = self.powers(s)
        if alpha0 is None:
            joints = 0.0
        else:
            d0, l0 = self.powers(0.0)
            joints = float(alpha0 * l0[0] + d0[0])
        return np.asarray((joints - dead) / live, dtype=float)

    def capacity_curve(
        self, alpha0: float | None = None, points: int = CURVE_POINTS
    ) -> CapacityCurve:
        """alpha(d_k) through finite rotations until alpha = 0 at d_k0 (Circolare C8.7.1,
        nonlinear kinematic analysis), and the SDOF curve d* = d_k / e* ... (see
        d_k / e* and a* = alpha g / e* (Circolare [C8A.4.6], [C8A.4.7] with FC = 1; the
        confidence factor divides a* where the check is made): ``points`` configurations
        from 0 to s0."""
        from scipy.optimize import brentq

        wmax = float(np.linalg.norm(self.w, axis=1).max(initial=0.0))
        if wmax == 0:
            raise ValueError(
                "the mechanism turns no block: a sliding mechanism has no alpha = 0 in large "
                "displacements"
            )
        s_max = MAX_ROTATION / wmax
        grid = np.linspace(0.0, s_max, 2001)
        a = self.alpha(grid, alpha0)
        if not a[0] > 0:
            raise ValueError(f"alpha0 = {a[0]:.6g}: the mechanism needs a positive multiplier")
        below = np.flatnonzero(~(a > 0))
        if below.size == 0:
            raise ValueError(
                f"alpha stays positive up to rotations of {math.degrees(MAX_ROTATION):.0f} "
                "degrees: no d_k0"
            )
        k = int(below[0])
        s0 = float(
            brentq(
                lambda x: float(self.alpha(x, alpha0)[0]),
                grid[k - 1],
                grid[k],
                xtol=1e-15,
                rtol=4 * np.finfo(float).eps,
            )
        )
        s = np.linspace(0.0, s0, points)
        alpha = self.alpha(s, alpha0)
        alpha[-1] = 0.0
        d_k = self.control_displacement(s)
        e_star = self.participating_mass()[1]
        return CapacityCurve(
            s=s,
            alpha=alpha,
            d_k=d_k,
            d_star=d_k / e_star,
            a_star=alpha * G / e_star,
            d_k0=float(d_k[-1]),
            d0_star=float(d_k[-1] / e_star),
        )

    def configuration_at(self, d_k: float, s0: float) -> float:
        """The parameter s in [0, s0] at which the control point has moved by ``d_k``."""
        from scipy.optimize import brentq

        return float(
            brentq(
                lambda x: float(self.control_displacement(x)[0]) - d_k,
                0.0,
                s0,
                xtol=1e-15,
                rtol=4 * np.finfo(float).eps,
            )
        )


def _seismic_direction(
    live: NDArray[np.float64], weights: NDArray[np.float64]
) -> tuple[NDArray[np.float64], float]:
    """The unit horizontal direction d of a live load c P_i d and c; a ValueError when the
    live load is not of that form."""
    force = live[:, :3]
    total = force.sum(axis=0)
    norm = float(np.linalg.norm(total))
    why = (
        "the assessment needs the live load of the codes' seismic action: horizontal forces "
        "proportional to the weights along one direction (a weight_proportional load)"
    )
    if norm == 0 or weights.sum() <= 0:
        raise ValueError(f"{why}; this one has no resultant or the blocks no weight")
    direction = total / norm
    if abs(direction[1]) > PROPORTIONAL:
        raise ValueError(f"{why}; this one has a vertical part ({direction[1]:.3g} of it)")
    direction[1] = 0.0
    direction /= np.linalg.norm(direction)
    scale = norm / float(weights.sum())
    misfit = np.abs(force - scale * weights[:, None] * direction[None]).max()
    if misfit > PROPORTIONAL * np.abs(force).max() or np.abs(live[:, 3:]).max() > 0:
        raise ValueError(f"{why}; this one is not (largest departure {misfit:.3g} N)")
    return direction, scale
