"""A collapse mechanism as the codes' kinematic analysis reads it (NTC 2018 and Circolare 2019
C8.7.1.2.1; docs/assessment.md): the weights P_i of the blocks that move, their virtual
displacements, the multiplier alpha0, the participating mass M* and its fraction e*, and the
capacity curve alpha(d_k) of the mechanism moved through finite rotations.

A mechanism is a small-displacement mode q (n, 6) of the blocks (translation of the centre,
rotation): the pushover's collapse mode (:func:`masonry_dem.mechanism.collapse_mode`) or the
limit analysis's block velocities. Each block's mode is a twist xi = (v0 = u - w x c at the
origin, w). The finite motion scales the mode along a spanning tree of the joints rooted at
the ground (:func:`spanning_tree`): each block moves as its parent does, composed with the
screw motion exp(s (xi_i - xi_parent)) of its twist relative to the parent (the product of
exponentials of a robot's kinematic chain). A block turning about a hinge on the ground turns
about it by s |w|; a hinge between two moving blocks is a line of the parent and stays closed
at any rotation; a joint outside the tree (a closed loop of blocks) keeps its first-order
motion only. The incremental kinematics (:class:`IncrementalPath`) integrates the motion in
steps instead, the twists projected at each configuration onto the joints' contacts, which
keeps closed loops closed.

The DEM's joints turn about their centres (a rocking joint keeps its normal spring and loses
its bending stiffness), so the pushover's mode lifts no weight at first order: the work that
rocking does against the weights is a plastic moment there. :func:`hinged_mode` turns such a
mode into the rigid-block one, each joint turning about its compressed edge, by a
least-squares fit of the block motions to the joints' relative motions with the normal
opening that the rotation opens at the joint's centre.

Everything is vectorised over blocks (and over the configurations of the curve).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem.assessment.incremental import LOCKED, STEP, IncrementalPath
from masonry_dem.assessment.screws import screw_transform
from masonry_dem.assessment.spectra import G
from masonry_dem.model import Model

log = logging.getLogger(__name__)

#: a block moves in the mechanism when its largest corner motion in the mode reaches this
#: share of the largest one: its weight then counts in sum P_i (e*) and in the control
#: point. A mechanism of a wall held on an edge deforms continuously and the share sets e*
#: (default wall: e* 0.32, 0.48, 0.55, 0.59 at 0.1 %, 1 %, 5 %, 10 %); the larger the share,
#: the larger e* and the smaller a0*, so the default errs on the safe side
MOVING = 0.05
#: a live load is proportional to the weights when every block's live force is within this
#: share of the largest from c P_i d
PROPORTIONAL = 1e-6
#: the rotation (rad) of the block that turns fastest up to which the capacity curve looks
#: for alpha = 0 (a block of a wall held on an edge may turn past 90 degrees before the
#: weights of the mechanism come down: the limit analysis's mechanism of the default wall
#: reaches alpha = 0 at about 125 degrees of its top blocks)
MAX_ROTATION = math.pi
#: configurations of the capacity curve between the undeformed one and d_k0
CURVE_POINTS = 201
#: configurations of the grid on which the capacity curve looks for alpha = 0, scanned at once
SCAN = 100
#: block configurations (blocks x values of s) whose motions are held in memory at once
CHUNK = 200_000
#: how the blocks' finite motions are composed (:meth:`Mechanism.of`)
KINEMATICS = ("chain", "independent", "incremental")


def spanning_tree(model: Model, mode: NDArray[np.float64]) -> NDArray[np.intp]:
    """The parent of each block (-1: the ground) in the tree along which the mechanism's
    finite motion is composed: the minimum spanning tree of the joints, weighted by the
    relative motion across each in ``mode`` (the blocks that move together are joined
    first, a hinge next, the sliding joints last), rooted at the ground, which holds the
    fixed blocks. A block that touches nothing hangs from the ground."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, minimum_spanning_tree

    from masonry_dem.assembly.compatibility import compatibility_matrix

    n = model.blocks.count
    itf = model.interfaces
    ground = n
    fixed = np.flatnonzero(np.asarray(model.fixed, dtype=bool).any(axis=1))
    rows, cols, vals = [fixed], [np.full(fixed.size, ground)], [np.zeros(fixed.size)]
    if itf.count:
        d = (compatibility_matrix(model.blocks, itf) @ mode.ravel()).reshape(-1, 6)
        size = np.maximum(itf.l1, itf.l2)
        rows.append(itf.block_i)
        cols.append(itf.block_j)
        vals.append(np.linalg.norm(d[:, :3], axis=1) + np.linalg.norm(d[:, 3:], axis=1) * size)
    # the tree keeps no edge of weight 0: every weight is raised by a share of the largest
    weight = np.concatenate(vals)
    weight = weight + 1e-9 * max(float(weight.max(initial=0.0)), 1.0) + 1e-300
    graph = coo_matrix(
        (weight, (np.concatenate(rows), np.concatenate(cols))), shape=(n + 1, n + 1)
    ).tocsr()
    tree = minimum_spanning_tree(graph + graph.T)
    _, pred = breadth_first_order(tree + tree.T, ground, directed=False)
    parent = np.asarray(pred[:n], dtype=np.intp)
    parent[(parent == ground) | (parent < 0)] = -1  # the ground, or no path to it
    return parent


def tree_levels(parent: NDArray[np.intp]) -> tuple[NDArray[np.intp], ...]:
    """The blocks by depth in the tree of ``parent``: roots (parent -1) first."""
    depth = np.zeros(parent.size, dtype=np.intp)
    known = parent < 0
    while not known.all():
        ready = ~known & known[np.where(parent < 0, 0, parent)]
        if not ready.any():
            raise ValueError("the mechanism's tree has a cycle")
        depth[ready] = depth[parent[ready]] + 1
        known |= ready
    return tuple(np.flatnonzero(depth == k) for k in range(int(depth.max(initial=0)) + 1))


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
    #: why the curve stops short of alpha = 0 ("" when it reaches it; then d_k0 is nan)
    reason: str = ""
    #: the largest rotation of a block at the curve's end [rad]
    rotation: float = 0.0

    @property
    def complete(self) -> bool:
        return not self.reason


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
    parent: NDArray[np.intp]
    #: the integrated motion of ``"incremental"`` kinematics (None: composed in closed form)
    path: IncrementalPath | None = field(default=None, compare=False, repr=False)

    @classmethod
    def of(
        cls,
        model: Model,
        mode: ArrayLike,
        moving: float = MOVING,
        kinematics: str = "chain",
        step: float = STEP,
    ) -> Mechanism:
        """The mechanism of ``mode`` (n, 6) on ``model``, whose live load must be horizontal
        forces proportional to the weights along one direction (a ``weight_proportional``
        load): the seismic load of the codes. ``kinematics``: ``"chain"`` composes the
        finite motion along the joints' spanning tree (:func:`spanning_tree`),
        ``"independent"`` moves each block by the screw motion of its own twist,
        ``"incremental"`` integrates it in steps of ``step`` radians of the fastest block, the
        twists projected at each step onto the joints' contacts (:class:`IncrementalPath`;
        its mode is the given one projected at s = 0)."""
        if kinematics not in KINEMATICS:
            raise ValueError(f"kinematics = {kinematics!r}: must be one of {', '.join(KINEMATICS)}")
        if not 0 < moving < 1:
            raise ValueError(
                f"moving = {moving!r} out of range: must be in (0, 1) (a share of the largest motion)"
            )
        if not 0 < step <= 0.1:
            raise ValueError(
                f"step = {step!r} out of range: must be in (0, 0.1] (radians of the fastest block)"
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
        v0, w = sign * v0, sign * w
        path = None
        if kinematics == "incremental":
            path = IncrementalPath(model, v0, w, step)
            v0, w = path.xi[0][:, :3].copy(), path.xi[0][:, 3:].copy()
            u = v0 + np.cross(w, centres)
            reach = np.linalg.norm(u, axis=1) + np.linalg.norm(w, axis=1) * half
            if float(np.sum(live[:, :3] * u) + np.sum(live[:, 3:] * w)) <= 0:
                raise ValueError(
                    "the mode held at the joints' contacts does no work against the live load: "
                    "kinematics = 'incremental' has no mechanism"
                )
        return cls(
            centres=centres,
            weights=weights,
            dead=np.asarray(model.dead, dtype=float),
            live=live / scale,
            v0=v0,
            w=w,
            direction=direction,
            moving=reach >= moving * reach.max(),
            scale=scale,
            parent=(
                spanning_tree(model, q)
                if kinematics == "chain"
                else np.full(model.blocks.count, -1, dtype=np.intp)
            ),
            path=path,
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

    def motion(
        self, s: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The blocks' finite motions at the configurations ``s`` (k,): rotations R (k, n, 3,
        3), translations t (k, n, 3) (a point x of block i goes to R_i x + t_i) and spatial
        twists, velocity of the origin V (k, n, 3) and angular velocity O (k, n, 3).

        Each block's motion is its parent's composed with the screw motion of its twist
        relative to the parent (product of exponentials): g_i(s) = g_p(s) exp(s (xi_i -
        xi_p)), so a hinge to the parent is a line of the parent and stays closed at any
        rotation; V_i = V_p + Ad(g_p) (xi_i - xi_p). Vectorised over the blocks of one depth
        of the tree."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        if self.path is not None:
            return self.path.motion(s)
        n = self.centres.shape[0]
        has = self.parent >= 0
        up = np.where(has, self.parent, 0)
        v_rel = self.v0 - np.where(has[:, None], self.v0[up], 0.0)
        w_rel = self.w - np.where(has[:, None], self.w[up], 0.0)
        R_rel, t_rel = screw_transform(v_rel, w_rel, s)
        R = np.empty((s.size, n, 3, 3))
        t = np.empty((s.size, n, 3))
        V = np.empty((s.size, n, 3))
        O = np.empty((s.size, n, 3))
        for level in tree_levels(self.parent):  # a loop over the tree's depth, not its blocks
            roots = level[~has[level]]
            R[:, roots], t[:, roots] = R_rel[:, roots], t_rel[:, roots]
            V[:, roots], O[:, roots] = v_rel[roots], w_rel[roots]
            kids = level[has[level]]
            if kids.size:
                p = self.parent[kids]
                Rp, tp = R[:, p], t[:, p]
                R[:, kids] = Rp @ R_rel[:, kids]
                t[:, kids] = np.einsum("knij,knj->kni", Rp, t_rel[:, kids]) + tp
                w_now = np.einsum("knij,nj->kni", Rp, w_rel[kids])
                O[:, kids] = O[:, p] + w_now
                V[:, kids] = (
                    V[:, p] + np.einsum("knij,nj->kni", Rp, v_rel[kids]) + np.cross(tp, w_now)
                )
        return R, t, V, O

    def positions(self, points: ArrayLike, blocks: ArrayLike, s: ArrayLike) -> NDArray[np.float64]:
        """Where ``points`` (m, 3) of ``blocks`` (m,) are at the configurations ``s``: (k, m, 3)."""
        R, t, _, _ = self.motion(s)
        b = np.asarray(blocks, dtype=np.intp)
        x = np.asarray(points, dtype=float).reshape(-1, 3)
        return np.einsum("kmij,mj->kmi", R[:, b], x) + t[:, b]

    def powers(self, s: ArrayLike = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Virtual work rates of the dead and live loads at the configurations ``s`` (k,):
        sum F_i . (V_i + O_i x c_i(s)) + M_i . O_i, the loads keeping their directions.
        Computed :data:`CHUNK` block configurations at a time."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        dead, live = np.empty(s.size), np.empty(s.size)
        for part in self._chunks(s.size):
            R, t, V, O = self.motion(s[part])
            c = np.einsum("knij,nj->kni", R, self.centres) + t
            vel = V + np.cross(O, c)
            dead[part] = np.einsum("kni,ni->k", vel, self.dead[:, :3]) + np.einsum(
                "kni,ni->k", O, self.dead[:, 3:]
            )
            live[part] = np.einsum("kni,ni->k", vel, self.live[:, :3]) + np.einsum(
                "kni,ni->k", O, self.live[:, 3:]
            )
        return dead, live

    def _chunks(self, count: int) -> list[slice]:
        """Slices of ``count`` configurations, each of at most :data:`CHUNK` blocks x
        configurations (the motion of one holds 4 x 9 floats per block)."""
        step = max(1, CHUNK // max(self.centres.shape[0], 1))
        return [slice(k, min(k + step, count)) for k in range(0, count, step)]

    @property
    def alpha_rigid(self) -> float:
        """alpha0 of the principle of virtual work with the loads alone (rigid blocks, hinges
        at the edges, no work of the joints): alpha0 = -W_dead / W_live (Circolare 2019
        [C8.7.1.1] with L_i = 0)."""
        dead, live = self.powers(0.0)
        return float(-dead[0] / live[0])

    def participating_mass(self) -> tuple[float, float]:
        """M* = (sum P_i dx_i)^2 / (g sum P_i dx_i^2) [kg] and e* = g M* / sum P_i over the
        moving blocks: e* = (sum P_i dx_i)^2 / (sum P_i sum P_i dx_i^2), Circolare 2019
        [C8.7.1.5]."""
        P, dx = self.weights[self.moving], self.dx[self.moving]
        m_star = float(np.sum(P * dx) ** 2 / (G * np.sum(P * dx**2)))
        return m_star, G * m_star / self.total_weight

    # ------------------------------------------------------------------ control point
    def control_displacement(self, s: ArrayLike) -> NDArray[np.float64]:
        """d_k: the displacement along the load of the centroid of the moving weights, at
        the configurations ``s``."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        P = self.weights[self.moving]
        idx = np.flatnonzero(self.moving)
        out = np.empty(s.size)
        for part in self._chunks(s.size):
            c = self.positions(self.centres[idx], idx, s[part])
            moved = (c - self.centres[idx][None]) @ self.direction  # (k, m)
            out[part] = moved @ P / P.sum()
        return out

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
        d_k / e* and a* = alpha g / e* (Circolare 2019 [C8.7.1.4], [C8.7.1.3] with FC = 1;
        the confidence factor divides a* where the check is made): ``points`` configurations
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
        # the grid scanned a part at a time, up to the first part where alpha or the live
        # load's work stops being positive: an incremental path is integrated no further
        # than that (the closed-form motions find the same first indices)
        a, live, locked = np.empty(0), np.empty(0), np.empty(0, dtype=bool)
        for start in range(0, grid.size, SCAN):
            part = grid[start : start + SCAN]
            _, l_part = self.powers(part)
            a = np.concatenate([a, self.alpha(part, alpha0)])
            live = np.concatenate([live, l_part])
            locked = np.concatenate([locked, self._locked(part)])
            if not (a > 0).all() or not (live > 0).all() or locked.any():
                break
        if not a[0] > 0:
            raise ValueError(f"alpha0 = {a[0]:.6g}: the mechanism needs a positive multiplier")
        below = np.flatnonzero(~(a > 0))
        pole = np.flatnonzero(~(live > 0) | locked)
        end = min(below[0] if below.size else grid.size, pole[0] if pole.size else grid.size)
        reason = ""
        if not below.size or (pole.size and pole[0] <= below[0]):
            if pole.size and locked[pole[0]]:
                reason = (
                    "alpha stays positive until the incremental motion locks: the joints' "
                    f"contacts leave its twists less than {LOCKED:.0%} of the mode's (at d_k = "
                    f"{1e3 * float(self.control_displacement(grid[pole[0]])[0]):.3g} mm: the "
                    "mode is no finite mechanism of blocks that keep their contacts): no d_k0"
                )
            elif pole.size and pole[0] < grid.size:
                reason = (
                    "alpha stays positive until the live load does no more work on the "
                    "mechanism (its blocks have turned away from the load): no d_k0"
                )
            else:
                reason = (
                    f"alpha stays positive until a block has turned "
                    f"{math.degrees(MAX_ROTATION):.0f} degrees: no d_k0"
                )
            s_end = float(grid[end - 1])
        else:
            k = int(below[0])
            s_end = float(
                brentq(
                    lambda x: float(self.alpha(x, alpha0)[0]),
                    grid[k - 1],
                    grid[k],
                    xtol=1e-15,
                    rtol=4 * np.finfo(float).eps,
                )
            )
        if self.path is not None:
            log.info(
                "incremental path: %d steps of %.3g rad to s = %.4g%s",
                len(self.path.xi_mid),
                self.path.ds * wmax,
                s_end,
                f" ({reason})" if reason else "",
            )
        s = np.linspace(0.0, s_end, points)
        alpha = self.alpha(s, alpha0)
        if not reason:
            alpha[-1] = 0.0
        d_k = self.control_displacement(s)
        e_star = self.participating_mass()[1]
        R = self.motion(s_end)[0][0]
        turned = float(np.arccos(np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1)).max())
        return CapacityCurve(
            s=s,
            alpha=alpha,
            d_k=d_k,
            d_star=d_k / e_star,
            a_star=alpha * G / e_star,
            d_k0=float("nan") if reason else float(d_k[-1]),
            d0_star=float("nan") if reason else float(d_k[-1] / e_star),
            reason=reason,
            rotation=turned,
        )

    def _locked(self, s: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Whether the incremental motion has locked at the configurations ``s``
        (:meth:`IncrementalPath.kinetic`, :data:`LOCKED`); never for the closed-form ones."""
        if self.path is None:
            return np.zeros(s.size, dtype=bool)
        return np.asarray(self.path.kinetic(s) < LOCKED)

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


# ---------------------------------------------------------------------------- incremental


def live_load_scale(model: Model) -> float:
    """c of the model's live load c P_i d (the codes' seismic action), with no mode: the
    alpha0 = c lambda of a run that stood at lambda; a ValueError when the live load is not
    of that form."""
    weights = np.maximum(-np.asarray(model.dead, dtype=float)[:, 1], 0.0)
    return _seismic_direction(np.asarray(model.live, dtype=float), weights)[1]


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


def support_drift(mechanism: Mechanism, model: Model, s: float) -> float:
    """The largest motion [m] at the configuration ``s`` along a DOF a support holds, of the
    blocks held in some DOFs and free in others (a roller, a floor that lets a block rise):
    the translation of the block's centre along each held axis, and the turn about each held
    axis times the block's largest half size. The mode keeps them still to first order; a
    finite motion composed from it may move them, which no overlap shows."""
    fixed = np.asarray(model.fixed, dtype=bool)
    partial = np.flatnonzero(fixed.any(axis=1) & ~fixed.all(axis=1))
    if partial.size == 0:
        return 0.0
    R, t, _, _ = mechanism.motion(np.array([s]))
    centres = model.blocks.centres[partial]
    moved = np.einsum("mij,mj->mi", R[0, partial], centres) + t[0, partial] - centres
    Rp = R[0, partial]
    # the turn about each axis: the rotation vector of R (small or not: arcsin of the
    # skew part's entries bounds it from below, enough to tell a drift from none)
    skew = 0.5 * np.stack(
        [Rp[:, 2, 1] - Rp[:, 1, 2], Rp[:, 0, 2] - Rp[:, 2, 0], Rp[:, 1, 0] - Rp[:, 0, 1]], axis=1
    )
    turn = (
        np.arcsin(np.clip(np.abs(skew), 0.0, 1.0))
        * 0.5
        * model.blocks.sizes[partial].max(axis=1, keepdims=True)
    )
    drift = np.concatenate([np.abs(moved) * fixed[partial, :3], turn * fixed[partial, 3:]], axis=1)
    return float(drift.max(initial=0.0))


def interpenetration(mechanism: Mechanism, model: Model, s: float) -> float:
    """The largest overlap [m] of two blocks across a joint at the configuration ``s``: the
    normal gap at each corner of each joint, the corner moved as a point of either block,
    along the normal turned with the first block; 0 when every joint is closed or open.
    A kinematically admissible finite motion has none; the composed motions are admissible
    to first order only where the tree of :func:`spanning_tree` leaves a closed loop."""
    itf = model.interfaces
    if itf.count == 0:
        return 0.0
    m = itf.count
    corners = itf.corner_points().reshape(-1, 3)
    xi = mechanism.positions(corners, np.repeat(itf.block_i, 4), s)[0].reshape(m, 4, 3)
    xj = mechanism.positions(corners, np.repeat(itf.block_j, 4), s)[0].reshape(m, 4, 3)
    R = mechanism.motion(s)[0][0][itf.block_i]  # (m, 3, 3)
    normal = R[np.arange(m), :, itf.axis]  # the turned e_axis: column `axis` of R
    gap = np.einsum("mki,mi->mk", xj - xi, normal)
    return float(max(-gap.min(), 0.0))
