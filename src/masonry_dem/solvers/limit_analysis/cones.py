"""Second-order cones SOC(3) for the interior point method of ``normal_ipm``, as compiled
loops over the cones (one cone is three numbers: numpy's batched 3 x 3 products cost more
than the factorization on the ladder's walls).

Notation of CVXOPT's cone solvers (Vandenberghe, "The CVXOPT linear and quadratic cone
program solvers", 2010): ``J = diag(1, -1, -1)``; the Jordan product ``x o y = (x . y,
x0 y1 + y0 x1)``, with identity ``e = (1, 0, 0)``; the Nesterov-Todd scaling of a pair of
interior points ``s, z`` is ``W = beta Wbar``, ``Wbar = [[w0, w1^T], [w1, I + w1 w1^T /
(1 + w0)]]`` with the scaling point ``w`` (``w^T J w = 1``) and ``beta = (det z / det s)^(1/4)``
(``det x = x^T J x``), so that ``W s = W^-1 z = lam``; ``Wbar^-1 = J Wbar J``.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def nt_scaling(s: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(w, beta, lam) of every cone: the scaling point (p, 3), the factor (p,) and the
    scaled point ``lam = W s`` (p, 3)."""
    p = s.shape[0]
    w = np.empty((p, 3))
    beta = np.empty(p)
    lam = np.empty((p, 3))
    for k in range(p):
        ds = math.sqrt(max(s[k, 0] ** 2 - s[k, 1] ** 2 - s[k, 2] ** 2, 1e-300))
        dz = math.sqrt(max(z[k, 0] ** 2 - z[k, 1] ** 2 - z[k, 2] ** 2, 1e-300))
        sb0, sb1, sb2 = s[k, 0] / ds, s[k, 1] / ds, s[k, 2] / ds
        zb0, zb1, zb2 = z[k, 0] / dz, z[k, 1] / dz, z[k, 2] / dz
        gamma = math.sqrt(0.5 * (1.0 + sb0 * zb0 + sb1 * zb1 + sb2 * zb2))
        w[k, 0] = (sb0 + zb0) / (2.0 * gamma)
        w[k, 1] = (zb1 - sb1) / (2.0 * gamma)
        w[k, 2] = (zb2 - sb2) / (2.0 * gamma)
        beta[k] = math.sqrt(dz / ds)
    apply_w(w, beta, s, 1, lam)
    return w, beta, lam


@numba.njit(cache=True)
def apply_w(w: np.ndarray, beta: np.ndarray, x: np.ndarray, power: int, out: np.ndarray) -> None:
    """out = W^power x per cone, power in (1, 2, -1)."""
    for k in range(w.shape[0]):
        w0, w1, w2 = w[k, 0], w[k, 1], w[k, 2]
        x0, x1, x2 = x[k, 0], x[k, 1], x[k, 2]
        times = 2 if power == 2 else 1
        if power == -1:  # Wbar^-1 = J Wbar J
            x1, x2 = -x1, -x2
        for _ in range(times):
            d = w1 * x1 + w2 * x2
            y0 = w0 * x0 + d
            f = x0 + d / (1.0 + w0)
            x0, x1, x2 = y0, x1 + f * w1, x2 + f * w2
        if power == -1:
            out[k, 0], out[k, 1], out[k, 2] = x0 / beta[k], -x1 / beta[k], -x2 / beta[k]
        else:
            b = beta[k] ** times
            out[k, 0], out[k, 1], out[k, 2] = b * x0, b * x1, b * x2


@numba.njit(cache=True)
def jordan(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """x o y per cone."""
    out = np.empty_like(x)
    for k in range(x.shape[0]):
        out[k, 0] = x[k, 0] * y[k, 0] + x[k, 1] * y[k, 1] + x[k, 2] * y[k, 2]
        out[k, 1] = x[k, 0] * y[k, 1] + y[k, 0] * x[k, 1]
        out[k, 2] = x[k, 0] * y[k, 2] + y[k, 0] * x[k, 2]
    return out


@numba.njit(cache=True)
def jordan_solve(lam: np.ndarray, r: np.ndarray) -> np.ndarray:
    """v with ``lam o v = r`` per cone (lam interior: its arrow matrix inverted in closed
    form)."""
    v = np.empty_like(r)
    for k in range(lam.shape[0]):
        l0, l1, l2 = lam[k, 0], lam[k, 1], lam[k, 2]
        det = l0 * l0 - l1 * l1 - l2 * l2
        v0 = (l0 * r[k, 0] - l1 * r[k, 1] - l2 * r[k, 2]) / det
        v[k, 0] = v0
        v[k, 1] = (r[k, 1] - v0 * l1) / l0
        v[k, 2] = (r[k, 2] - v0 * l2) / l0
    return v


@numba.njit(cache=True)
def centrality_correction(
    w: np.ndarray,
    beta: np.ndarray,
    s: np.ndarray,
    z: np.ndarray,
    ds: np.ndarray,
    dz: np.ndarray,
    alpha: float,
    lo: float,
    hi: float,
) -> np.ndarray:
    """Gondzio's centrality correction of every cone at the trial point ``s + alpha ds``,
    ``z + alpha dz``: the scaled product ``v = (W s_t) o (W^-1 z_t)`` has the spectral
    values ``v0 +- |v1|``; each is moved into [lo, hi], a decrease capped at -hi, and the
    correction ``t`` (p, 3) is the move in the same spectral frame."""
    p = s.shape[0]
    t = np.empty((p, 3))
    a = np.empty(3)
    b = np.empty(3)
    for k in range(p):
        w0, w1, w2 = w[k, 0], w[k, 1], w[k, 2]
        bt = beta[k]
        for sign in range(2):
            if sign == 0:
                x0 = s[k, 0] + alpha * ds[k, 0]
                x1 = s[k, 1] + alpha * ds[k, 1]
                x2 = s[k, 2] + alpha * ds[k, 2]
                f = bt
            else:  # W^-1 = (1/beta) J Wbar J
                x0 = z[k, 0] + alpha * dz[k, 0]
                x1 = -(z[k, 1] + alpha * dz[k, 1])
                x2 = -(z[k, 2] + alpha * dz[k, 2])
                f = 1.0 / bt
            dot = w1 * x1 + w2 * x2
            y0 = w0 * x0 + dot
            c = x0 + dot / (1.0 + w0)
            y1 = x1 + c * w1
            y2 = x2 + c * w2
            if sign == 1:
                y1, y2 = -y1, -y2
            out = a if sign == 0 else b
            out[0], out[1], out[2] = f * y0, f * y1, f * y2
        v0 = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
        v1 = a[0] * b[1] + b[0] * a[1]
        v2 = a[0] * b[2] + b[0] * a[2]
        norm = math.sqrt(v1 * v1 + v2 * v2)
        e1, e2 = v0 + norm, v0 - norm
        t1 = max(min(max(e1, lo), hi) - e1, -hi)
        t2 = max(min(max(e2, lo), hi) - e2, -hi)
        t[k, 0] = 0.5 * (t1 + t2)
        if norm > 0:
            t[k, 1] = 0.5 * (t1 - t2) * v1 / norm
            t[k, 2] = 0.5 * (t1 - t2) * v2 / norm
        else:
            t[k, 1] = 0.0
            t[k, 2] = 0.0
    return t


@numba.njit(cache=True)
def max_step(x: np.ndarray, d: np.ndarray) -> float:
    """The largest alpha with x + alpha d in every cone (x interior): the smallest positive
    root of ``det(x + alpha d) = a alpha^2 + 2 b alpha + c``, written without cancellation
    (``c / (-b + sqrt(b^2 - a c))``); the cone is left only where a < 0, or b < 0 with real
    roots."""
    alpha = np.inf
    for k in range(x.shape[0]):
        a = d[k, 0] ** 2 - d[k, 1] ** 2 - d[k, 2] ** 2
        b = x[k, 0] * d[k, 0] - x[k, 1] * d[k, 1] - x[k, 2] * d[k, 2]
        c = max(x[k, 0] ** 2 - x[k, 1] ** 2 - x[k, 2] ** 2, 0.0)
        disc = b * b - a * c
        if a < 0 or (b < 0 and disc >= 0):
            alpha = min(alpha, c / (-b + math.sqrt(max(disc, 0.0))))
    return alpha


@numba.njit(cache=True)
def normal_entries(
    local: np.ndarray, w: np.ndarray, beta: np.ndarray, slot: np.ndarray, nnz: int
) -> np.ndarray:
    """The entries of the upper triangle of ``G^T W^2 G`` in its CSR pattern: per interface
    i and corner k, ``(W_k G_ik)^T (W_k G_ik)`` with ``G_ik = local[i, k]`` (3 x C, the
    corner's rows on the C solved velocities of the interface's two blocks), summed into
    ``data[slot[i, a, b]]`` for a <= b (``slot``: the entry of the pair's upper-triangle
    position; -1 for a fixed DOF)."""
    m, K, C = local.shape[0], local.shape[1], local.shape[3]
    data = np.zeros(nnz)
    wg = np.empty((3, C))
    block = np.empty((C, C))
    for i in range(m):
        block[:] = 0.0
        for k in range(K):
            c = i * K + k
            w0, w1, w2, bt = w[c, 0], w[c, 1], w[c, 2], beta[c]
            for j in range(C):
                x0, x1, x2 = local[i, k, 0, j], local[i, k, 1, j], local[i, k, 2, j]
                d = w1 * x1 + w2 * x2
                f = x0 + d / (1.0 + w0)
                wg[0, j] = bt * (w0 * x0 + d)
                wg[1, j] = bt * (x1 + f * w1)
                wg[2, j] = bt * (x2 + f * w2)
            for a in range(C):
                for b in range(a, C):
                    block[a, b] += wg[0, a] * wg[0, b] + wg[1, a] * wg[1, b] + wg[2, a] * wg[2, b]
        for a in range(C):
            for b in range(a, C):
                t = slot[i, a, b]
                if t >= 0:
                    data[t] += block[a, b]
    return data


@numba.njit(cache=True)
def local_rows(
    indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, cols: np.ndarray, rows: int
) -> np.ndarray:
    """Each interface's ``rows`` rows of a CSR matrix G (interface-major: rows ``i * rows``
    to ``(i + 1) * rows``) on its solved columns ``cols[i]`` (-1: none), as (m, rows, C)."""
    m, C = cols.shape
    local = np.zeros((m, rows, C))
    for i in range(m):
        for r in range(rows):
            row = i * rows + r
            for j in range(indptr[row], indptr[row + 1]):
                col = indices[j]
                for q in range(C):
                    if cols[i, q] == col:
                        local[i, r, q] += data[j]
                        break
    return local


@numba.njit(cache=True)
def normal_pattern(
    cols: np.ndarray,
    col_block: np.ndarray,
    start: np.ndarray,
    count: np.ndarray,
    bptr: np.ndarray,
    bnbr: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The upper-triangular CSR pattern of ``N = G^T S G`` and every interface's slots, with
    no sort: the columns of a block are contiguous (``start``, ``count``) and increase with
    the block, so row c of block b holds b's columns from c on, then those of b's neighbours
    above it (``bptr``, ``bnbr``: sorted), in that order. Returns (indptr, indices, slot),
    ``slot[i, a, b]`` the entry of interface i's pair (a <= b) of solved columns, -1 where
    either is not solved."""
    n = col_block.size
    nb = start.size
    above = np.zeros(nb, dtype=np.int64)  # columns of a block's neighbours above it
    prefix = np.zeros(bnbr.size, dtype=np.int64)  # of the neighbours before each pair
    for b in range(nb):
        total = 0
        for p in range(bptr[b], bptr[b + 1]):
            prefix[p] = total
            total += count[bnbr[p]]
        above[b] = total
    indptr = np.zeros(n + 1, dtype=np.int64)
    for c in range(n):
        b = col_block[c]
        indptr[c + 1] = indptr[c] + (start[b] + count[b] - c) + above[b]
    indices = np.empty(indptr[n], dtype=np.int32)
    for c in range(n):
        b = col_block[c]
        t = indptr[c]
        for x in range(c, start[b] + count[b]):
            indices[t] = x
            t += 1
        for p in range(bptr[b], bptr[b + 1]):
            nbr = bnbr[p]
            for x in range(start[nbr], start[nbr] + count[nbr]):
                indices[t] = x
                t += 1
    m, C = cols.shape
    slot = np.full((m, C, C), -1, dtype=np.int64)
    for i in range(m):
        for a in range(C):
            ca = cols[i, a]
            if ca < 0:
                continue
            for b2 in range(a, C):
                cb = cols[i, b2]
                if cb < 0:
                    continue
                lo, hi = min(ca, cb), max(ca, cb)
                blo, bhi = col_block[lo], col_block[hi]
                if blo == bhi:
                    slot[i, a, b2] = indptr[lo] + hi - lo
                    continue
                for p in range(bptr[blo], bptr[blo + 1]):
                    if bnbr[p] == bhi:
                        slot[i, a, b2] = (
                            indptr[lo]
                            + (start[blo] + count[blo] - lo)
                            + prefix[p]
                            + hi
                            - start[bhi]
                        )
                        break
    return indptr, indices, slot
