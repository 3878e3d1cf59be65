"""The numpy version of the interface strength check, kept as the reference of the compiled
one (``masonry_dem.constitutive.strength.evaluate``): the same floating-point operations,
batched over rows with masks instead of one row at a time. Used by the tests only."""

from __future__ import annotations

import logging

import numpy as np
from numpy.typing import NDArray

from masonry_dem.constitutive.check_kernels import TINY_CAPACITY as _TINY_CAPACITY
from masonry_dem.constitutive.energy_return import PROJECTION_MAX_ITER as _PROJECTION_MAX_ITER
from masonry_dem.constitutive.energy_return import PROJECTION_TOL as _PROJECTION_TOL
from masonry_dem.constitutive.states import FACTORS_OF_FLAGS as _FACTORS_OF_FLAGS
from masonry_dem.constitutive.states import SLIDE_COLUMNS as _SLIDE_COLUMNS
from masonry_dem.constitutive.states import STATE_OF_FLAGS as _STATE_OF_FLAGS
from masonry_dem.constitutive.strength import (
    SHEAR_TORSION_TOLERANCE,
    StrengthCheck,
    _safe_ratio,
)
from masonry_dem.constitutive.strength import StrengthDomain as _Domain
from masonry_dem.constitutive.strength import radial_factor as _radial_factor

logger = logging.getLogger(__name__)


def _torsion_constant_fast(l1: NDArray, l2: NDArray) -> NDArray:
    """:func:`_torsion_constant` with the same arithmetic, bit for bit, in fewer array passes
    (the limits of asinh(x)/x are patched in only where a side is below 1e-8 of the other)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        x = l2 / l1
        y = l1 / l2
        r1 = np.arcsinh(x)
        r1 /= x
        r2 = np.arcsinh(y)
        r2 /= y
    odd = ~((x >= 1e-8) & (y >= 1e-8))  # a tiny or zero side, or both zero (NaN ratios)
    if odd.any():
        for ratio, r in ((x, r1), (y, r2)):
            small = ratio < 1e-8
            r[small] = 1.0 - ratio[small] * ratio[small] / 6.0
            r[ratio == np.inf] = 0.0  # that side is zero: its term vanishes
    c = np.hypot(l1, l2)
    c *= 0.5
    c += (0.25 * l1) * r1
    c += (0.25 * l2) * r2
    c /= 3.0
    if odd.any():
        c[np.isnan(x)] = 0.0  # both sides zero
    return c


def _energy_closest_point(
    r0: NDArray,
    z0: NDArray,
    a: NDArray,
    b: NDArray,
    alpha: NDArray | float,
    radial: NDArray | None = None,
) -> tuple[NDArray, NDArray]:
    """Closest point (r, z) of the curve (z/b)^alpha + (r/a)^2 = 1 to (r0, z0) outside it.

    r = |f| and z = |m3| / rho, with rho^2 = J / A: Euclidean distance in (r, z) is the
    elastic energy of the correction (kt A for shear, kt J for torsion), so this is the
    textbook return mapping. The squared distance is unimodal along the convex curve
    (alpha >= 1). Each half of the curve gets the parameter in which it is smooth: near pure
    shear z = b t, r = a sqrt(1 - t^alpha); near pure torsion (where sqrt(1 - t^alpha) is
    singular) r = a x, z = b (1 - x^2)^(1/alpha). The sign of the distance's derivative at the
    switch point x^2 = t^alpha = 1/2 says which half holds the minimum; there Newton's method
    is kept inside the bracket (bisection where a step would leave it), a few steps each.
    ``radial`` (the factor that takes the trial radially onto the curve), if given, starts
    Newton at the radial point, usually a few steps from the answer.
    Degenerate capacities: b = 0 (no torsion, e.g. a joint rocking on a corner) keeps
    the shear up to a and drops the torsion; a = 0 drops both.
    """
    n = r0.shape[0]
    al = np.broadcast_to(np.asarray(alpha, dtype=float), (n,))
    r = np.zeros(n)
    z = np.zeros(n)
    rows = np.flatnonzero((r0 > 0) & (z0 > 0) & (a > 0) & (b > 0))
    if rows.size:
        ar, br, r0r, z0r, alr = a[rows], b[rows], r0[rows], z0[rows], al[rows]
        t_switch = 0.5 ** (1.0 / alr)
        x_switch = np.sqrt(0.5)
        # the shear half in tau with t = tau^p: p = 2 below alpha = 2 makes t^alpha and its
        # derivatives smooth at t = 0 (sqrt-like in t for alpha near 1.5)
        power = np.where(alr < 2.0, 2.0, 1.0)
        ones = np.ones_like(alr)
        near_shear = _shear_half(t_switch, ar, br, r0r, z0r, alr, ones)[0] >= 0.0
        # alpha = 1 has a vertex on the shear axis; points in its normal cone return to it
        vertex = (alr == 1.0) & ((r0r - ar) * 0.5 * ar >= z0r * br)
        r[rows[vertex]] = ar[vertex]
        sh = np.flatnonzero(near_shear & ~vertex)
        to = np.flatnonzero(~near_shear)
        if sh.size:
            p = power[sh]
            args = (ar[sh], br[sh], r0r[sh], z0r[sh], alr[sh], p)
            start = None if radial is None else (radial[rows[sh]] * z0r[sh] / br[sh]) ** (1 / p)
            tau = _bracketed_newton(_shear_half, args, t_switch[sh] ** (1 / p), start)
            t = tau**p
            r[rows[sh]] = ar[sh] * np.sqrt(np.maximum(1.0 - t ** alr[sh], 0.0))
            z[rows[sh]] = br[sh] * t
        if to.size:
            args = (ar[to], br[to], r0r[to], z0r[to], alr[to])
            start = None if radial is None else radial[rows[to]] * r0r[to] / ar[to]
            x = _bracketed_newton(_torsion_half, args, np.full(to.size, x_switch), start)
            r[rows[to]] = ar[to] * x
            z[rows[to]] = br[to] * np.maximum(1.0 - x * x, 0.0) ** (1.0 / alr[to])
    # one of r0, z0 zero: the point is on an axis and so is its closest point
    pure_torsion = (r0 == 0) & (b > 0)
    z = np.where(pure_torsion, b * np.minimum(1.0, _safe_ratio(z0, b)), z)
    r = np.where(z0 == 0, np.minimum(r0, a), r)
    r = np.where(b == 0, np.minimum(r0, a), r)
    z = np.where(b == 0, 0.0, z)
    return r, z


def _shear_half(
    tau: NDArray,
    a: NDArray,
    b: NDArray,
    r0: NDArray,
    z0: NDArray,
    alpha: NDArray,
    power: NDArray,
):
    """g = d/dt of half the squared distance from (a sqrt(1 - t^alpha), b t) to (r0, z0) at
    t = tau^power, and dg/dtau; smooth on t in [0, 2^(-1/alpha)]."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = tau**power
        ta = t**alpha
        u = 1.0 - ta
        su = np.sqrt(u)
        du = -alpha * ta / t
        d2u = du * (alpha - 1.0) / t
        r = a * su
        dr = 0.5 * a * du / su
        d2r = a * (0.5 * d2u / su - 0.25 * du * du / (u * su))
        g = (r - r0) * dr + (b * t - z0) * b
        dg = (dr * dr + (r - r0) * d2r + b * b) * power * t / tau
    return g, dg


def _torsion_half(x: NDArray, a: NDArray, b: NDArray, r0: NDArray, z0: NDArray, alpha: NDArray):
    """g = d/dx of half the squared distance from (a x, b (1 - x^2)^(1/alpha)) to (r0, z0),
    and g'; smooth on x in [0, sqrt(1/2)]."""
    w = 1.0 - x * x
    p = 1.0 / alpha
    wp = w**p
    z = b * wp
    dz = -2.0 * p * b * x * wp / w
    d2z = 2.0 * p * b * wp / w * (2.0 * (p - 1.0) * x * x / w - 1.0)
    g = (a * x - r0) * a + (z - z0) * dz
    dg = a * a + dz * dz + (z - z0) * d2z
    return g, dg


def _bracketed_newton(fun, args: tuple, hi: NDArray, start: NDArray | None = None) -> NDArray:
    """Root of g = fun(x, *args) on [0, hi] (g(0) < 0 < g(hi), one sign change), by Newton's
    method from ``start`` (default: mid-bracket) kept inside the shrinking bracket; each row
    stops on its own."""
    n = hi.shape[0]
    out = np.empty(n)
    lo = np.zeros(n)
    hi = hi.copy()
    x = 0.5 * hi
    if start is not None:
        inside = (start > 0.0) & (start < hi)
        x[inside] = start[inside]
    rows = np.arange(n)
    for _ in range(_PROJECTION_MAX_ITER):
        g, dg = fun(x, *args)
        up = g > 0
        hi = np.where(up, x, hi)
        lo = np.where(up, lo, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = g / dg
        newton = x - step
        # a step below tolerance is taken even where it rounds onto the bracket's end
        done = np.abs(step) <= _PROJECTION_TOL * np.maximum(x, 1e-300)
        inside = (newton > lo) & (newton < hi) & np.isfinite(newton)
        x_new = np.where(inside | done, newton, 0.5 * (lo + hi))
        done |= hi - lo <= 4.0 * np.spacing(hi)  # bracket at round-off
        out[rows] = x_new
        if done.all():
            return out
        keep = ~done
        rows, x, lo, hi = rows[keep], x_new[keep], lo[keep], hi[keep]
        args = tuple(v[keep] for v in args)
    # rows at round-off; the caller falls back to the radial return off the boundary
    logger.debug("energy projection: %d rows did not converge", rows.size)
    return out


def _evaluate_numpy(
    act: NDArray,
    ft: NDArray,
    dom: _Domain,
    torsion_bending_interaction: bool = True,
    projection_only: bool = False,
    projection: str = "energy",
    c0: NDArray | None = None,
) -> StrengthCheck | NDArray:
    """:func:`check_strength` on validated inputs (``act`` (m, 6), ``ft`` (m,) >= 0), in numpy:
    the reference of the compiled :func:`_evaluate` (used by the tests).

    Every projected value comes out of the same floating-point operations as the plain
    formulas (the finite-difference tangent of the law divides their differences by 1e-7 and
    must not see a changed last bit); the work is only restricted to the rows that need it.
    ``projection_only`` returns just the projected actions and skips the radial factor of
    rows well inside Eq. (A5), where it is only needed for the utilisation.
    """
    # the reference is the paper's domain, c = mu ft (no cohesion beyond it)
    assert c0 is None or not np.any(c0)
    m = act.shape[0]
    f1, f2, fn, m1, m2, m3 = np.ascontiguousarray(act.T)

    # detachment
    detached = fn > ft
    live = ~detached
    cap = ft - fn
    cap[detached] = 0.0

    # rocking: clip the bending moments to the eccentricity limits
    half = 0.5 * cap
    m1_lim = half * dom.l2
    m2_lim = half * dom.l1
    abs_m1, abs_m2 = np.abs(m1), np.abs(m2)
    rock1 = abs_m1 > m1_lim
    rock1 &= live
    rock2 = abs_m2 > m2_lim
    rock2 &= live
    abs_m1c = np.minimum(abs_m1, m1_lim)  # |clipped moment|: the limit itself where rocking
    abs_m2c = np.minimum(abs_m2, m2_lim)

    # shear and torsion: demand/capacity ratios a = |m3|/m3u, c = |f|/fsu
    fsu = dom.friction * cap
    abs_m3 = np.abs(m3)
    m3u = np.zeros(m)
    # m3u only matters where m3 != 0; with cap = 0 it is 0 (a = inf)
    tor = np.flatnonzero((abs_m3 > 0) & (cap > 0))
    if tor.size:
        if torsion_bending_interaction:
            c_t = _torsion_constant_fast(
                *_reduced_sides_fast(dom, tor, cap[tor], abs_m1c[tor], abs_m2c[tor])
            )
        else:
            c_t = dom.torsion_constant[tor]
        m3u[tor] = c_t * fsu[tor]
    shear = np.hypot(f1, f2)
    with np.errstate(divide="ignore", over="ignore"):  # 0/0 = 0, d/0 = inf (no capacity)
        a = np.divide(abs_m3, m3u, out=np.zeros(m), where=abs_m3 > 0)
        c = np.divide(shear, fsu, out=np.zeros(m), where=shear > 0)

    if projection_only:
        # a + c^2 >= a^alpha + c^2 for a, c <= 1 and alpha >= 1: below 1 no row slides
        rows = np.flatnonzero(live & ~(a + c * c < 0.999))
        al = dom.alpha[rows] if np.ndim(dom.alpha) else dom.alpha
        s = _radial_factor(a[rows], c[rows], al)
        with np.errstate(divide="ignore"):
            slide = 1.0 / s > 1.0 + SHEAR_TORSION_TOLERANCE
        sliding_rows, scale = rows[slide], s[slide]
    else:
        # s = 0 (all of f1, f2, m3 dropped) where m3 != 0 meets a zero torsion or shear
        # capacity: the limit of the radial projection as the capacity vanishes
        s = _radial_factor(a, c, dom.alpha)
        with np.errstate(divide="ignore"):
            u_st = 1.0 / s  # radial demand/capacity ratio of Eq. (A5)
        sliding = u_st > 1.0 + SHEAR_TORSION_TOLERANCE
        sliding &= live
        sliding_rows = np.flatnonzero(sliding)
        scale = s[sliding_rows]

    # projection (untouched entries are kept bitwise)
    proj = act.copy()
    proj[:, 3] = np.copysign(abs_m1c, m1)
    proj[:, 4] = np.copysign(abs_m2c, m2)
    if sliding_rows.size and projection == "radial":
        flat = proj.reshape(-1)
        entries = (6 * sliding_rows)[:, None] + _SLIDE_COLUMNS
        flat[entries] *= scale[:, None]
    elif sliding_rows.size:
        rows = sliding_rows
        rho = np.sqrt((dom.l1[rows] ** 2 + dom.l2[rows] ** 2) / 12.0)  # sqrt(J / A)
        r0 = shear[rows]
        al = dom.alpha[rows] if np.ndim(dom.alpha) else dom.alpha
        r, z = _energy_closest_point(
            r0, abs_m3[rows] / rho, fsu[rows], m3u[rows] / rho, al, radial=scale
        )
        shear_scale = _safe_ratio(r, r0)
        shear_scale[~np.isfinite(shear_scale)] = 0.0
        m3_new = np.copysign(z * rho, m3[rows])
        # capacities at the edge of floating point (subnormal friction or sides): the
        # radial return, which lands on the boundary by construction
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            phi = _safe_ratio(z * rho, m3u[rows]) ** al + _safe_ratio(r, fsu[rows]) ** 2
        off = ~(np.abs(phi - 1.0) <= 1e-9) & (m3u[rows] > 0) & (fsu[rows] > 0)
        off |= abs_m3[rows] == 0  # pure shear: the same point, with the radial round-off
        off |= fsu[rows] < _TINY_CAPACITY
        if off.any():
            shear_scale[off] = scale[off]
            m3_new[off] = m3[rows][off] * scale[off]
        proj[rows, 0] = f1[rows] * shear_scale
        proj[rows, 1] = f2[rows] * shear_scale
        proj[rows, 5] = m3_new
    det = np.flatnonzero(detached)
    if det.size:
        proj[det] = 0.0
        proj[det, 2] = ft[det]
    if projection_only:
        return proj

    # codes
    u8 = np.uint8
    flags = sliding.view(u8) | (rock1.view(u8) << 1) | (rock2.view(u8) << 2)
    flags |= detached.view(u8) << 3

    # utilisation
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        u_tension = np.maximum(fn, 0.0) / ft  # ft = 0: inf in tension, NaN otherwise
        u_rock = np.divide(abs_m1, m1_lim, out=np.zeros(m), where=abs_m1 > 0)
        u_rock2 = np.divide(abs_m2, m2_lim, out=np.zeros(m), where=abs_m2 > 0)
    zero_ft = np.isnan(u_tension)
    if zero_ft.any():  # ft = 0: 1 at fn = 0, 0 in compression
        u_tension[zero_ft] = fn[zero_ft] >= 0
    np.maximum(u_rock, u_rock2, out=u_rock)
    np.maximum(u_rock, u_tension, out=u_rock)
    util = np.maximum(u_rock, u_st, out=u_rock)
    if det.size:
        util[det] = u_tension[det]
    return StrengthCheck(
        projected=proj,
        state=_STATE_OF_FLAGS[flags],
        flags=flags,
        stiffness_factors=_FACTORS_OF_FLAGS[flags],
        utilisation=util,
    )


def _reduced_sides_fast(
    dom: _Domain, rows: NDArray, cap: NDArray, abs_m1: NDArray, abs_m2: NDArray
) -> tuple[NDArray, NDArray]:
    """:func:`_reduced_sides` on ``rows`` with cap > 0 (same arithmetic)."""
    l1, l2 = dom.l1[rows], dom.l2[rows]
    l1r = l1 - 2.0 * abs_m2 / cap
    l2r = l2 - 2.0 * abs_m1 / cap
    # a moment clipped to its rocking limit gives l - 2 |m| / cap = 0 up to rounding: snap it
    np.minimum(l1r, l1, out=l1r)
    np.minimum(l2r, l2, out=l2r)
    l1r[l1r <= dom.snap1[rows]] = 0.0
    l2r[l2r <= dom.snap2[rows]] = 0.0
    return l1r, l2r


def fd_tangent_numpy(
    trial, h, ft, rows, dom, kbar, projection="energy", evaluate=None, normal_only=None
):
    """The law's forward-difference tangent as one batched numpy difference over the 7 probes
    of every row (the library's version before it was compiled): row 0 the base point, rows
    1-6 each component perturbed by ``h``. ``evaluate``: the check used for the probes
    (default the numpy reference; the compiled ``_projection_and_flags`` gives the same bits).
    ``normal_only`` is ignored: every row gets all its probes (the library's shortcut for
    rows at zero capacity must give the same numbers)."""
    evaluate = evaluate or _evaluate_numpy
    n = trial.shape[0]
    idx = np.arange(6)
    probe = np.repeat(trial[None], 7, axis=0)
    probe[idx + 1, :, idx] += h.T
    domain = dom.take(np.tile(rows, 7))
    proj = evaluate(
        probe.reshape(-1, 6), np.tile(ft, 7), domain, projection_only=True, projection=projection
    ).reshape(7, n, 6)
    D = (proj[1:] - proj[:1]) / h.T[:, :, None]  # (6 perturbed, n, 6 actions)
    return np.transpose(D, (1, 2, 0)) * kbar[:, None, :]


def law_tangent_numpy(law, r, floor=1e-9, fd=None):
    """``InterfaceLaw.tangent`` as batched numpy operations (the library's version before it was
    compiled into one call): diag(kbar), zero for open joints, the forward difference ``fd``
    (default :func:`fd_tangent_numpy`; the compiled ``fd_tangent`` gives the library's bits)
    at yielded rows taken at the contact side, and floor x kbar."""
    from masonry_dem.constitutive.law import _FD_STEP, CONTACT_BAND, DETACHED_FLAG

    fd = fd or fd_tangent_numpy
    k = law.kbar
    m = k.shape[0]
    T = np.zeros((m, 6, 6))
    diagonal = T.reshape(m, 36)[:, ::7]  # a view on T[:, i, i]
    diagonal[...] = k
    trial, ft = r.trial, r.tensile_force
    band = CONTACT_BAND * float(np.abs(trial[:, 2]).max(initial=0.0))
    open_ = trial[:, 2] > ft + band
    diagonal[open_] = 0.0
    rows = np.flatnonzero((r.flags > 0) & ~open_)
    if rows.size:
        t = trial[rows].copy()
        t[:, 2] = np.minimum(t[:, 2], ft[rows])
        big = np.abs(t).max(axis=1, keepdims=True)
        h = _FD_STEP * (np.abs(t) + 1e-2 * big) + 1e-300
        h[:, 2] = -h[:, 2]
        normal_only = r.flags[rows] == DETACHED_FLAG
        T[rows] = fd(
            t, h, ft[rows], rows, law._domain, k[rows], law.projection, normal_only=normal_only
        )
    diagonal += floor * k
    return T
