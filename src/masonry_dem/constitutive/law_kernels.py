"""The interface law's compiled kernels (numba): the forces of a Newton residual or a time
step in one pass (:data:`forces`), the consistent tangent (:data:`law_tangent`, with the
analytic derivative of the energy projection, :func:`_nb_row_tangent`) and the forward
difference of the projection (:data:`fd_tangent_rows`). They call the strength check's row
function of :mod:`~masonry_dem.constitutive.check_kernels`; their disk cache is keyed on both
files (see :mod:`masonry_dem.jit`). Compiled on first use; importing compiles nothing.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from masonry_dem.constitutive.check_kernels import (
    SHEAR_TORSION_TOLERANCE,
    TINY_CAPACITY,
    nb_evaluate_row,
    nb_project_rows,
    nb_radial_factor,
    nb_reduced_side,
    nb_torsion_constant,
)
from masonry_dem.constitutive.energy_return import (
    ROW_RHO,
    ROW_SHEAR_HI,
    ROW_T_SWITCH,
    ROW_TA_SWITCH,
    ROW_TORSION,
    nb_energy_radius,
)
from masonry_dem.constitutive.states import (
    FLAG_DETACHED,
    FLAG_ROCKING_1,
    FLAG_ROCKING_2,
    FLAG_SHEAR_TORSION,
)
from masonry_dem.jit import kernel

__all__ = [
    "ROW_CHECK",
    "ROW_DETACHED",
    "ROW_ELASTIC",
    "SETTLED_ELASTIC_BELOW",
    "fd_tangent_rows",
    "forces",
    "law_tangent",
    "nb_plain_row",
]

#: the row functions: compiled into the kernels that call them (x/0 = inf or nan, as numpy)
_jit = numba.njit(error_model="numpy")


@_jit
def _nb_fd_probes(t, h, ft, c0, rows, l1, l2, friction, alpha, snap1, snap2, normal_only):
    """The trials ``t`` (n, 6) of the rows ``rows`` of a domain and their forward-difference
    probes ``t_r + h_rp e_p``, with the row constants, as the input arrays of the strength
    check's rows (n first, then the probes), and ``probe_row`` (n, 6): the row of each probe,
    -1 where a row with ``normal_only`` is not probed (see :func:`_nb_fd_collect`)."""
    n = t.shape[0]
    probe_row = np.full((n, 6), -1, np.int64)
    total = n
    for r in range(n):
        for p in range(6):
            if p == 2 or not normal_only[r]:
                probe_row[r, p] = total
                total += 1
    act = np.empty((total, 6))
    consts = np.empty((8, total))  # ft, l1, l2, friction, alpha, snap1, snap2, c0
    for r in range(n):
        for p in range(-1, 6):  # -1: the trial itself
            row = r if p < 0 else probe_row[r, p]
            if row < 0:
                continue
            i = rows[r]
            for j in range(6):
                act[row, j] = t[r, j]
            if p >= 0:
                act[row, p] += h[r, p]
            consts[0, row] = ft[r]
            consts[1, row] = l1[i]
            consts[2, row] = l2[i]
            consts[3, row] = friction[i]
            consts[4, row] = alpha[i]
            consts[5, row] = snap1[i]
            consts[6, row] = snap2[i]
            consts[7, row] = c0[r]
    return act, consts, probe_row


@_jit
def _nb_fd_collect(proj, h, k, probe_row, out) -> None:
    """Forward-difference derivative of the projection into ``out`` (n, 6, 6):
    ``out[r, a, p] = (proj(t_r + h_rp e_p)_a - proj(t_r)_a) / h_rp * k_rp`` (the chain rule
    through the elastic trial ``k * relative``), from the projections ``proj`` of the rows of
    :func:`_nb_fd_probes`: the result the batched numpy difference over the same probes gives,
    bit for bit. Rows not probed along an action (``normal_only``: a joint at zero capacity,
    fn = ft, projects every other action to zero, and a probe of any of them leaves it there)
    get zero columns."""
    n = out.shape[0]
    for r in range(n):
        for a in range(6):
            for p in range(6):
                row = probe_row[r, p]
                if row < 0:
                    out[r, a, p] = 0.0
                else:
                    d = (proj[row, a] - proj[r, a]) / h[r, p]
                    out[r, a, p] = d * k[r, p]


@kernel(parallel=True, eager=False, error_model="numpy")  # most analyses never call it
def fd_tangent_rows(
    t, h, ft, c0, rows, l1, l2, friction, alpha, snap1, snap2, energy, k, normal_only, out
):
    """Forward-difference derivative of the projection at the rows ``rows`` of a domain
    (:func:`_nb_fd_probes`, the strength check of every probe, :func:`_nb_fd_collect`)."""
    act, c, probe_row = _nb_fd_probes(
        t, h, ft, c0, rows, l1, l2, friction, alpha, snap1, snap2, normal_only
    )
    proj = np.empty((act.shape[0], 6))
    flags = np.empty(act.shape[0], dtype=np.uint8)
    util = np.empty(0)
    on = act.shape[0] >= 0  # True, as a variable: a literal would compile the row again
    for j in numba.prange(act.shape[0]):
        nb_evaluate_row(j, act, c[0], c[7], c[1], c[2], c[3], c[4], c[5], c[6], on, on, energy, proj, flags, util)  # fmt: skip
    _nb_fd_collect(proj, h, k, probe_row, out)


@_jit
def _nb_contact_side(trial, fti, fd_step, t, h) -> None:
    """The point ``t`` (6,) where the tangent of a row is taken, and the forward difference's
    steps ``h`` (6,) there: the trial with fn at most ft (a joint in the contact band is
    differentiated on the contact side), steps of ``fd_step`` of each action plus 1e-2 of the
    row's largest, the one along fn towards compression."""
    big = 0.0
    for j in range(6):
        t[j] = trial[j]
    t[2] = min(t[2], fti)
    for j in range(6):
        big = max(big, abs(t[j]))
    for j in range(6):
        h[j] = fd_step * (abs(t[j]) + 1e-2 * big) + 1e-300
    h[2] = -h[2]


@_jit
def _nb_torsion_constant_slope(l1: float, l2: float) -> float:
    """d cT / d l1 of an ``l1 x l2`` rectangle (sides >= 0): with x = l2 / l1,
    ``(1/3) [(sqrt(1 + x^2) - x^2 asinh(1/x)) / 4 + asinh(x) / (2 x)]``; 1/4 at x = 0 (a
    segment, cT = l1/4), 0 at l1 = 0 (its limit). The bracket cancels for large x: there its
    series ``2/(3x) - 1/(5x^3)``."""
    if not l1 > 0.0:
        return 0.0
    x = l2 / l1
    if x == 0.0:
        return 0.25
    if x > 1e3:
        g = 2.0 / (3.0 * x) - 1.0 / (5.0 * x * x * x)
    else:
        g = math.sqrt(1.0 + x * x) - x * x * math.asinh(1.0 / x)
    return (0.25 * g + 0.5 * math.asinh(x) / x) / 3.0


@_jit
def _nb_contact_tangent(t, fti, mu, l1, l2, al, snap1, snap2, k, fd_step, out, g) -> bool:
    """Derivative of the projection of a detached joint in the contact band, taken at zero
    capacity (fn = ft) towards compression: only fn moves it, and every action it returns
    grows in proportion to a small capacity ``cap = ft - fn``.

    "Small" is the capacity of the forward difference's probe (``fd_step`` of the row's
    scale), so that the rows come out as that difference gives them: a bending moment above
    that probe's rocking limit is clipped, m' = sign(m) cap l / 2; one below it (round-off
    in a symmetric wall) is kept and shortens the other side of the torsion rectangle by
    2 |m| / probe. The shear-torsion return from a trial far outside a domain of size cap
    lands where the curve's normal points at the trial: with u = r0 mu and
    v = z0 cT mu / rho, the point (R, Z) of Z^alpha + R^2 = 1 that maximises u R + v Z,
    R = s u / 2, Z = (s v / alpha)^(1/(alpha-1)) with s from (s u/2)^2 + (s v/alpha)^beta = 1,
    beta = alpha / (alpha - 1) (the radial factor's equation). False (differenced) for
    alpha = 1. ``out`` and the scratch ``g`` as :func:`_nb_row_tangent`."""
    if not al > 1.0:
        return False
    m1 = t[3]
    m2 = t[4]
    _nb_contact_side(t, fti, fd_step, g[0], g[1])
    probe = -g[1, 2]
    rock1 = abs(m1) > probe * 0.5 * l2
    rock2 = abs(m2) > probe * 0.5 * l1
    for a in range(6):
        for q in range(6):
            out[a, q] = 0.0
    k2 = k[2]
    out[2, 2] = k2
    if rock1:
        out[3, 2] = -math.copysign(0.5 * l2, m1) * k2
    if rock2:
        out[4, 2] = -math.copysign(0.5 * l1, m2) * k2
    l1r = 0.0 if rock2 else nb_reduced_side(l1, abs(m2), probe, snap1)
    l2r = 0.0 if rock1 else nb_reduced_side(l2, abs(m1), probe, snap2)
    c_t = nb_torsion_constant(l1r, l2r)
    rho = nb_energy_radius(l1, l2)
    r0 = math.hypot(t[0], t[1])
    u = r0 * mu
    v = abs(t[5]) / rho * c_t * mu / rho
    if not (u > 0.0 or v > 0.0):
        return True  # nothing to return: no shear, no torsion
    s, ok = nb_radial_factor(v / al, 0.5 * u, al / (al - 1.0))
    if not ok:
        return False
    big_r = s * 0.5 * u
    big_z = (s * v / al) ** (1.0 / (al - 1.0))
    if r0 > 0.0:  # f' = f / r0 mu cap R
        out[0, 2] = -t[0] / r0 * mu * big_r * k2
        out[1, 2] = -t[1] / r0 * mu * big_r * k2
    out[5, 2] = -math.copysign(c_t * mu * big_z, t[5]) * k2  # m3' = sign(m3) cT mu cap Z
    for a in range(6):
        if not math.isfinite(out[a, 2]):
            return False
    return True


@_jit
def _nb_row_tangent(t, p, fti, c0, l1, l2, mu, al, snap1, snap2, flag, k, fd_step, out, g) -> bool:
    """Analytic derivative of the energy projection of one live row, ``out[a, q] =
    d p_a / d t_q * k_q`` (the chain rule through the trial ``k * relative``), at the trial
    ``t`` (6,) whose projection is ``p`` (6,) and flags ``flag``; ``g`` (9, 6) is scratch;
    ``fd_step`` is the relative step of the forward difference (see
    :func:`_nb_contact_tangent`).

    The rocking clip gives m' = sign(m) (ft - fn) l / 2. A sliding row is differentiated
    through its closest point: on the curve (z/b)^alpha + (r/a)^2 = 1 written as
    (a R(theta), b Z(theta)), the stationarity of the distance to (r0, z0),
    ``phi = (a R - r0) a R' + (b Z - z0) b Z' = 0``, gives d theta by the implicit function
    theorem; a = mu (ft - fn) and b = cT(l1', l2') a / rho carry the capacities' dependence on
    fn, m1 and m2 (the reduced sides of the torsion-bending interaction).
    Returns False, with ``out`` undefined, where the row needs the finite difference: zero
    capacity, alpha = 1 (a vertex), no shear (r0 = 0), capacities near the subnormal range,
    or a projection that is not the closest point (the radial fallback), and a sliding or
    detached row with cohesion beyond mu ft (``c0 > 0``: its capacities are not
    proportional to ft - fn)."""
    f1 = t[0]
    f2 = t[1]
    fn = t[2]
    m1 = t[3]
    m2 = t[4]
    m3 = t[5]
    if c0 > 0.0 and flag & (FLAG_DETACHED | FLAG_SHEAR_TORSION):
        return False
    if flag & FLAG_DETACHED:
        return _nb_contact_tangent(t, fti, mu, l1, l2, al, snap1, snap2, k, fd_step, out, g)
    cap = fti - fn
    if not cap > 0.0 or not al > 1.0:
        return False
    for a in range(6):
        for q in range(6):
            out[a, q] = 0.0
        out[a, a] = 1.0
    # a moment at its rocking limit to round-off (a hinge pinned there by the mechanism)
    # takes the elastic side, as a shear within SHEAR_TORSION_TOLERANCE of Eq. (A5) does: a
    # zero stiffness chosen by round-off makes Newton cycle between the two sides
    lean = 1.0 + SHEAR_TORSION_TOLERANCE
    rock1 = (flag & FLAG_ROCKING_1) > 0 and abs(m1) > lean * (0.5 * cap * l2)
    rock2 = (flag & FLAG_ROCKING_2) > 0 and abs(m2) > lean * (0.5 * cap * l1)
    sign1 = math.copysign(1.0, m1)  # +0: the forward difference's side
    sign2 = math.copysign(1.0, m2)
    if rock1:  # m1' = sign(m1) (ft - fn) l2 / 2
        out[3, 3] = 0.0
        out[3, 2] = -sign1 * 0.5 * l2
    if rock2:
        out[4, 4] = 0.0
        out[4, 2] = -sign2 * 0.5 * l1
    if flag & FLAG_SHEAR_TORSION:
        fsu = mu * cap
        r0 = math.hypot(f1, f2)
        if fsu < TINY_CAPACITY or not r0 > 0.0:
            return False
        rho = nb_energy_radius(l1, l2)
        # gradients over the six trial actions: 0 cap, 1 |m1'|, 2 |m2'|, 3 l1', 4 l2',
        # 5 a, 6 b, 7 r0, 8 z0
        for j in range(9):
            for q in range(6):
                g[j, q] = 0.0
        g[0, 2] = -1.0
        abs_m1c = abs(p[3])
        abs_m2c = abs(p[4])
        if rock1:
            g[1, 2] = -0.5 * l2
        else:
            g[1, 3] = sign1
        if rock2:
            g[2, 2] = -0.5 * l1
        else:
            g[2, 4] = sign2
        l1r = nb_reduced_side(l1, abs_m2c, cap, snap1)
        l2r = nb_reduced_side(l2, abs_m1c, cap, snap2)
        pinned1 = l1r == 0.0  # snapped to zero: stays there under a small change
        pinned2 = l2r == 0.0
        for q in range(6):
            if not pinned1:
                g[3, q] = -2.0 * g[2, q] / cap + 2.0 * abs_m2c / (cap * cap) * g[0, q]
            if not pinned2:
                g[4, q] = -2.0 * g[1, q] / cap + 2.0 * abs_m1c / (cap * cap) * g[0, q]
        c_t = nb_torsion_constant(l1r, l2r)
        d1 = _nb_torsion_constant_slope(l1r, l2r)
        d2 = _nb_torsion_constant_slope(l2r, l1r)
        big_a = fsu
        big_b = c_t * fsu / rho
        for q in range(6):
            g[5, q] = mu * g[0, q]
            g[6, q] = (fsu * (d1 * g[3, q] + d2 * g[4, q]) + c_t * g[5, q]) / rho
        g[7, 0] = f1 / r0
        g[7, 1] = f2 / r0
        sign3 = math.copysign(1.0, m3)
        g[8, 5] = sign3 / rho
        z0 = abs(m3) / rho
        r = math.hypot(p[0], p[1])
        z = abs(p[5]) / rho
        if big_b == 0.0:  # no torsion capacity (on a corner): torsion dropped, |f| <= a
            for q in range(6):
                out[5, q] = 0.0
            if r0 > big_a:  # f' = f a / r0
                for a in range(2):
                    fa = t[a]
                    for q in range(6):
                        out[a, q] = fa * (g[5, q] / r0 - big_a * g[7, q] / (r0 * r0))
                    out[a, a] += big_a / r0
        else:
            unit_r = r / big_a
            unit_z = z / big_b
            if z0 == 0.0:  # pure shear: the radial return, at (a, 0) of the same curve
                unit_r = 1.0
                unit_z = 0.0
            elif not abs(unit_z**al + unit_r * unit_r - 1.0) <= 1e-9:
                return False  # not on the curve
            if unit_z**al <= 0.5:  # shear half, theta = Z: R = sqrt(1 - Z^alpha)
                za = unit_z ** (al - 1.0)
                rp = -0.5 * al * za / unit_r
                rpp = -0.5 * al * (al - 1.0) * unit_z ** (al - 2.0) / unit_r + (
                    0.5 * al * za * rp / (unit_r * unit_r)
                )
                zp = 1.0
                zpp = 0.0
            else:  # torsion half, theta = R: Z = (1 - R^2)^(1/alpha)
                w = 1.0 - unit_r * unit_r
                pw = 1.0 / al
                rp = 1.0
                rpp = 0.0
                zp = -2.0 * pw * unit_r * w ** (pw - 1.0)
                zpp = -2.0 * pw * w ** (pw - 1.0) + 4.0 * pw * (pw - 1.0) * unit_r * unit_r * w ** (
                    pw - 2.0
                )
            res_r = big_a * unit_r - r0
            res_z = big_b * unit_z - z0
            # the closest point, not the radial fallback of an energy return that failed:
            # the correction is normal to the curve
            tan_r = big_a * rp
            tan_z = big_b * zp
            dot = res_r * tan_r + res_z * tan_z
            if z0 > 0.0 and not abs(dot) <= 1e-6 * math.hypot(res_r, res_z) * math.hypot(
                tan_r, tan_z
            ):
                return False
            phi_t = (
                big_a * big_a * rp * rp + res_r * big_a * rpp + big_b * big_b * zp * zp
            ) + res_z * big_b * zpp
            if not phi_t > 0.0:  # (+inf is fine: infinite curvature, d theta = 0)
                return False
            for q in range(6):
                dphi = (
                    -big_a * rp * g[7, q]
                    - big_b * zp * g[8, q]
                    + (2.0 * big_a * unit_r - r0) * rp * g[5, q]
                    + (2.0 * big_b * unit_z - z0) * zp * g[6, q]
                )
                dtheta = -dphi / phi_t  # 0 where the curvature is infinite (phi_t = inf)
                dr = unit_r * g[5, q] + big_a * rp * dtheta
                dz = unit_z * g[6, q] + big_b * zp * dtheta
                # f' = f r / r0, m3' = sign(m3) rho z
                out[0, q] = f1 * (dr / r0 - r * g[7, q] / (r0 * r0))
                out[1, q] = f2 * (dr / r0 - r * g[7, q] / (r0 * r0))
                out[5, q] = sign3 * rho * dz
            out[0, 0] += r / r0
            out[1, 1] += r / r0
    for a in range(6):
        for q in range(6):
            out[a, q] *= k[q]
            if not math.isfinite(out[a, q]):
                return False
    return True


#: a row is settled elastic without the strength check when the upper bound of its
#: shear-torsion demand, a + c^2, is below this: under the check's own threshold (0.999) by
#: far more than the bound's round-off, so the check would find it elastic too
SETTLED_ELASTIC_BELOW = 0.998


#: what :func:`nb_plain_row` finds: the strength check must run, the row is elastic (its
#: actions are its trial) or detached
ROW_CHECK, ROW_ELASTIC, ROW_DETACHED = 0, 1, 2


@_jit
def nb_plain_row(f1, f2, fn, m1, m2, m3, fti, c0, l1, l2, mu, snap1, snap2, torsion) -> int:
    """Whether the strength check of a row (trial actions ``f1 .. m3``, the row's constants)
    has a plain answer: :data:`ROW_DETACHED` (fn > ft: the check returns zero actions but
    fn = ft, with the one flag), :data:`ROW_ELASTIC` (inside the domain by a margin: the
    check returns the trial, no flag) or :data:`ROW_CHECK` (run it).

    Inside means: no rocking (the check's own comparisons) and ``a + c^2`` below
    :data:`SETTLED_ELASTIC_BELOW`, with ``a = |m3| / (cT(l1', l2') fsu)`` bounded from above
    through a lower bound of the torsion constant of the reduced sides: cT is the mean
    distance from the centre, so it grows with each side and is homogeneous of degree one,
    ``cT(l1', l2') >= s cT(l1, l2)`` with ``s = min(l1'/l1, l2'/l2)``; ``torsion`` is
    cT(l1, l2); with the cohesion beyond mu ft, ``c0``, the bound holds as well (m3u =
    cT(l1', l2') mu cap + cT c0 >= s cT (mu cap + c0)). A NaN fails the comparisons and leaves the row to the check. Scalars in and
    out, as :func:`~masonry_dem.constitutive.check_kernels.nb_check_row`."""
    if fn > fti:
        return ROW_DETACHED
    cap = fti - fn
    half = 0.5 * cap
    abs_m1 = abs(m1)
    abs_m2 = abs(m2)
    if not (abs_m1 <= half * l2 and abs_m2 <= half * l1):
        return ROW_CHECK
    fsu = mu * cap
    if c0 > 0:
        fsu += c0
    shear = math.hypot(f1, f2)
    c = shear / fsu if shear > 0 else 0.0
    abs_m3 = abs(m3)
    a = 0.0
    if abs_m3 > 0:
        l1r = nb_reduced_side(l1, abs_m2, cap, snap1)
        l2r = nb_reduced_side(l2, abs_m1, cap, snap2)
        s = min(l1r / l1, l2r / l2)
        a = abs_m3 / (s * torsion * fsu)
    return ROW_ELASTIC if a + c * c < SETTLED_ELASTIC_BELOW else ROW_CHECK


@numba.njit(error_model="numpy", inline="always")
def _row_product(idx, val, v, start, end):
    """One row of a sparse product: the sum of ``val[t] * v[idx[t]]`` over the stored entries
    ``start`` to ``end`` of the row, in stored order (``t`` unsigned, as the index arrays:
    see :func:`forces`)."""
    total = 0.0
    t = start
    while t < end:
        total += val[t] * v[idx[t]]
        t += np.uint32(1)
    return total


@numba.njit(error_model="numpy", inline="always")
def _row(i, trial, ft, c0, l1, l2, friction, alpha, snap1, snap2, constants):
    """Row ``i``'s trial actions and constants, as :func:`nb_project_rows` takes them."""
    t = trial[i]
    c = constants[i]
    return (
        t[0], t[1], t[2], t[3], t[4], t[5], ft[i], c0[i], l1[i], l2[i], friction[i], alpha[i],
        snap1[i], snap2[i], c[ROW_T_SWITCH], c[ROW_TA_SWITCH], c[ROW_SHEAR_HI], c[ROW_RHO],
    )  # fmt: skip


@kernel(parallel=True, error_model="numpy")
def forces(
    x, h_ptr, h_idx, h_val, kbar, plastic, cracked, tensile_force, cohesion,
    l1, l2, friction, alpha, snap1, snap2, constants, energy, brittle, t_ptr, t_idx, t_val, n_out,
):  # fmt: skip
    """Relative displacements ``H x``, trial actions, their projection (flags) and the
    generalised forces ``H^T actions`` in one pass: the operations of the sparse products
    (row by row, from 0, in stored order) and of :meth:`InterfaceLaw.respond`, so the same
    bits. Rows with a plain answer skip the strength check (:func:`nb_plain_row`, the same
    bits), and sliding rows read their interface's constants from ``constants``
    (:data:`~masonry_dem.constitutive.energy_return.row_constants`, the same bits as
    computing them). The index arrays are unsigned (views of scipy's): a signed index costs a
    wraparound test per gather, which doubled the time of the products. The last value is
    False, with nothing projected, if a trial action is not finite."""
    m = kbar.shape[0]
    rel = np.empty((m, 6))
    trial = np.empty((m, 6))
    ft = np.empty(m)
    c0 = np.empty(m)
    actions = np.empty((m, 6))
    flags = np.zeros(m, dtype=np.uint8)
    internal = np.zeros(n_out)
    rel_flat = rel.reshape(-1)
    trial_flat = trial.reshape(-1)
    kbar_flat = kbar.reshape(-1)
    plastic_flat = plastic.reshape(-1)
    for i in range(m):
        ft[i] = 0.0 if cracked[i] else tensile_force[i]
        c0[i] = 0.0 if cracked[i] else cohesion[i]  # a crack takes the cohesion with ft
    finite = 0.0  # stays 0 unless a trial is inf or NaN (0 * inf = NaN)
    start = h_ptr[0]
    for r in range(6 * m):
        end = h_ptr[r + 1]
        total = _row_product(h_idx, h_val, x, start, end)
        start = end
        rel_flat[r] = total
        value = kbar_flat[r] * (total - plastic_flat[r])
        trial_flat[r] = value
        finite += 0.0 * value
    if not finite == 0.0:
        return rel, trial, ft, actions, flags, internal, False
    checked = np.zeros(m, dtype=np.bool_)
    for i in numba.prange(m):
        plain = nb_plain_row(
            trial[i, 0], trial[i, 1], trial[i, 2], trial[i, 3], trial[i, 4], trial[i, 5],
            ft[i], c0[i], l1[i], l2[i], friction[i], snap1[i], snap2[i],
            constants[i, ROW_TORSION],
        )  # fmt: skip
        if plain == ROW_ELASTIC:
            for j in range(6):
                actions[i, j] = trial[i, j]
        elif plain == ROW_DETACHED:  # flags are zero until set
            for j in range(6):
                actions[i, j] = 0.0
            actions[i, 2] = ft[i]
            flags[i] = FLAG_DETACHED
        else:
            checked[i] = True
    # the other rows two by two: their iterations overlap (nb_project_rows)
    rows = np.flatnonzero(checked)
    n = rows.shape[0]
    for k in numba.prange((n + 1) // 2):
        i = rows[2 * k]
        j = rows[2 * k + 1] if 2 * k + 1 < n else i  # the last row alone: twice
        first = _row(i, trial, ft, c0, l1, l2, friction, alpha, snap1, snap2, constants)
        second = _row(j, trial, ft, c0, l1, l2, friction, alpha, snap1, snap2, constants)
        p, flag, q, flag2 = nb_project_rows(first, second, energy)
        for c in range(6):
            actions[i, c] = p[c]
            actions[j, c] = q[c]
        flags[i] = flag
        flags[j] = flag2
    if brittle:
        for i in range(m):
            if flags[i] & FLAG_DETACHED:
                for j in range(6):
                    actions[i, j] = 0.0
    flat = actions.reshape(-1)
    start = t_ptr[0]
    for r in range(n_out):
        end = t_ptr[r + 1]
        internal[r] = _row_product(t_idx, t_val, flat, start, end)
        start = end
    return rel, trial, ft, actions, flags, internal, True


@kernel(error_model="numpy")
def law_tangent(
    trial, ft, c0, flags, actions, k, floor, contact_band, fd_step, l1, l2, friction, alpha, snap1,
    snap2, energy, analytic,
):  # fmt: skip
    """:meth:`InterfaceLaw.tangent` in one compiled call: diag(kbar), zero for open joints,
    the derivative of the projection at yielded rows (taken at the contact side) and floor x
    kbar. The derivative is analytic (:func:`_nb_row_tangent`) where ``analytic`` and the row
    allows it; the other yielded rows are returned for the forward difference
    (:data:`fd_tangent_rows`, the operations of the batched numpy version, so the same bits),
    with their trials ``t``, steps ``h``, ``ft``, ``c0``, ``k`` and ``normal_only``, and without the
    floor (their caller adds it after the difference). One thread: the rows are cheap."""
    m = k.shape[0]
    T = np.zeros((m, 6, 6))
    peak = 0.0
    for i in range(m):
        peak = max(peak, abs(trial[i, 2]))
    band = contact_band * peak
    block = np.empty((6, 6))
    scratch = np.empty((9, 6))
    differenced = np.zeros(m, np.bool_)
    count = 0
    for i in range(m):
        open_ = trial[i, 2] > ft[i] + band
        for j in range(6):
            T[i, j, j] = 0.0 if open_ else k[i, j]
        if flags[i] == 0 or open_:
            continue
        done = analytic and energy and _nb_row_tangent(
            trial[i], actions[i], ft[i], c0[i], l1[i], l2[i], friction[i], alpha[i], snap1[i],
            snap2[i], flags[i], k[i], fd_step, block, scratch,
        )  # fmt: skip
        # (a detached row in the contact band is taken at fn = ft: _nb_contact_tangent reads
        # neither its fn nor its actions)
        if done:
            for a in range(6):
                for b in range(6):
                    T[i, a, b] = block[a, b]
        else:
            differenced[i] = True
            count += 1
    rows = np.empty(count, np.int64)
    t = np.empty((count, 6))
    h = np.empty((count, 6))
    ft_rows = np.empty(count)
    c0_rows = np.empty(count)
    k_rows = np.empty((count, 6))
    normal_only = np.empty(count, np.bool_)
    count = 0
    for i in range(m):
        if differenced[i]:
            rows[count] = i
            for j in range(6):
                k_rows[count, j] = k[i, j]
            _nb_contact_side(trial[i], ft[i], fd_step, t[count], h[count])
            ft_rows[count] = ft[i]
            c0_rows[count] = c0[i]
            # detached joints in the contact band sit at zero capacity (fn = ft): only fn
            # moves their projection (a cohesive one keeps a shear capacity c0 there)
            normal_only[count] = flags[i] == FLAG_DETACHED and not c0[i] > 0.0
            count += 1
        else:
            for j in range(6):
                T[i, j, j] += floor * k[i, j]
    return T, rows, t, h, ft_rows, c0_rows, k_rows, normal_only
