"""Screw motions of rigid blocks: the finite motion exp(s xi) of a twist xi = (v0, w) (v0
the velocity of the point at the origin, w the angular velocity), vectorised over blocks and
parameters (Murray, Li & Sastry 1994, *A Mathematical Introduction to Robotic
Manipulation*, 2.3)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


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


def screw_transform(
    v0: NDArray[np.float64], w: NDArray[np.float64], s: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The screw motions exp(s xi) of the twists (``v0``, ``w``) (v0 the velocity of the
    point at the origin) for each parameter of ``s`` (k,): the same twists (n, 3) for every
    parameter, or twists of their own (k, n, 3) for each; rotations R (k, n, 3, 3) and
    translations t (k, n, 3), a point x going to R x + t."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    shape = (s.size, *np.shape(w)[-2:])
    v0, w = np.broadcast_to(v0, shape), np.broadcast_to(w, shape)
    W = np.linalg.norm(w, axis=-1)  # (k, n)
    turning = W > 0
    safe = np.where(turning, W, 1.0)[..., None]
    k = np.where(turning[..., None], w / safe, 0.0)
    vn = np.where(turning[..., None], v0 / safe, 0.0)
    theta = s[:, None] * W
    R = rodrigues(k, theta)  # (k, n, 3, 3); I if not turning
    kxv = np.cross(k, vn)
    # translation of the screw: (I - R)(k x v) + k (k . v) theta, for |w| > 0
    along = (np.sum(k * vn, axis=-1) * theta)[..., None]
    t_turn = kxv - np.einsum("knij,knj->kni", R, kxv) + k * along
    return R, np.where(turning[..., None], t_turn, s[:, None, None] * v0)


def screw_positions(
    v0: NDArray[np.float64], w: NDArray[np.float64], x: NDArray[np.float64], s: ArrayLike
) -> NDArray[np.float64]:
    """Positions (k, n, 3) of points ``x`` (n, 3) after the screw motions exp(s xi) of the
    twists (``v0``, ``w``) (n, 3), for each parameter of ``s`` (k,)."""
    R, t = screw_transform(v0, w, s)
    return np.einsum("knij,nj->kni", R, x) + t


def moved_by(
    R: NDArray[np.float64], t: NDArray[np.float64], xi: NDArray[np.float64], ds: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The configuration (R, t) moved by the screw motions exp(ds xi) of the spatial twists
    ``xi`` (n, 6): R' = Rs R, t' = Rs t + ts."""
    Rs, ts = screw_transform(xi[:, :3], xi[:, 3:], ds)
    return Rs[0] @ R, np.einsum("nij,nj->ni", Rs[0], t) + ts[0]
