"""Closed-form strength domain of a rectangular interface, batched over interfaces.

Implements Section 2.1, Eqs. (9)-(14) and Eqs. (A4)-(A5) of Baraldi & Cecchi, in terms of the
resultant actions of one interface. The local action order used everywhere in the package is::

    [f1, f2, fn, m1, m2, m3]

shear along the local axis y1, shear along y2, normal force (tension positive, compression
negative), bending about y1, bending about y2 and torsion about the normal. The interface is an
``l1 x l2`` rectangle, ``l1`` along y1 and ``l2`` along y2.

Criteria, with ``ft`` the tensile force of the whole interface (tensile strength x area),
``cap = ft - fn`` and ``C = c A`` the cohesive force (cohesion x area; the paper's reading,
Eq. (10), is ``C = mu ft``, the default):

* detachment: ``fn <= ft``;
* rocking: ``|m1| <= cap * l2 / 2`` and ``|m2| <= cap * l1 / 2`` (the lever is half the side
  perpendicular to the bending axis: for the paper's horizontal running-bond joints this is
  lc1 = s/2 and lc2 = b/4);
* shear-torsion, Eq. (A5): ``(|m3| / m3u)**alpha + (f1**2 + f2**2) / fsu**2 <= 1`` with
  ``fsu = C - mu * fn = mu * cap + c0`` and ``m3u = cT * mu * cap + cT(l1, l2) * c0``, where
  ``c0 = C - mu * ft >= 0`` is the cohesion beyond the paper's (zero by default). With the
  torsion-bending interaction of Figure 10, ``cT`` is evaluated on the reduced rectangle under
  uniform compression, ``l1' = l1 - 2 |m2| / cap`` and ``l2' = l2 - 2 |m1| / cap`` (bending
  moments already clipped); the rest of the interface sits at the tension cap, where the
  shear strength is ``c - mu ft`` per unit area, hence the c0 term on the whole rectangle.

Mohr-Coulomb with a tension cap: ``|tau| <= c - mu sigma`` and ``sigma <= ft`` (sigma tension
positive), with ``ft <= c / mu``. With ``ft < c / mu`` the domain has a vertical cap: at
``fn = ft`` the joint still carries the shear ``C - mu ft = c0``; beyond it, it is detached
(its actions projected to ``[0, 0, ft, 0, 0, 0]``).

The torsion constant ``cT`` is the mean distance of the rectangle's points from its centre; the
printed Eq. (11) is garbled and the correct form is used here (see ``DESIGN.md``).

This module is the numpy API of the domain (strengths, torsion constant, Table A1, the
batched check and its validated per-interface constants, :class:`StrengthDomain`). The check
itself runs compiled, one interface at a time (:mod:`~masonry_dem.constitutive.check_kernels`:
each row is worked out alone, so the answer is the same bits on any number of threads); the
numpy version of the same operations, batched with masks, is its reference in the tests
(``tests/constitutive/numpy_reference.py``). The joint states and flags are
:mod:`~masonry_dem.constitutive.states`'.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import cached_property
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem.constitutive.check_kernels import (
    NEWTON_MAX_ITER,
    NEWTON_RTOL,
    SHEAR_TORSION_TOLERANCE,
    SNAP,
    evaluate_rows,
)
from masonry_dem.constitutive.energy_return import row_constants
from masonry_dem.constitutive.states import FACTORS_OF_FLAGS, STATE_OF_FLAGS
from masonry_dem.model import PROJECTIONS

__all__ = [
    "ALPHA_TABLE_A1",
    "DEFAULT_ALPHA",
    "DIRECTIONS",
    "PROJECTIONS",
    "SHEAR_TORSION_TOLERANCE",
    "StrengthCheck",
    "StrengthDomain",
    "alpha_from_table",
    "check_strength",
    "cohesion_beyond_friction",
    "checked_actions",
    "checked_field",
    "evaluate",
    "projection_and_flags",
    "radial_factor",
    "shear_strength",
    "torsion_constant",
    "torsion_strength",
    "writable_c",
]

logger = logging.getLogger(__name__)

#: Exponent of Eq. (A5) suggested for running-bond masonry panels.
DEFAULT_ALPHA: Final[float] = 1.5

#: Table A1: exponent alpha of (m3/m3u)^alpha + (f/fsu)^2 <= 1 by aspect ratio l1/l2. The
#: ``"f1=f2"`` column was obtained by the paper with equal relative displacements d1 = d2.
ALPHA_TABLE_A1: Final[dict[str, tuple[float, ...]]] = {
    "aspect": (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0),
    "f1": (1.00, 1.05, 1.25, 1.43, 1.92, 2.44, 2.56),
    "f2": (2.56, 2.44, 1.92, 1.43, 1.25, 1.05, 1.00),
    "f1=f2": (2.00, 1.90, 1.70, 1.43, 1.70, 1.90, 2.00),
}
DIRECTIONS: Final[tuple[str, ...]] = ("f1", "f2", "f1=f2")

# --------------------------------------------------------------------------------------------
# input checking


def checked_field(name: str, value: ArrayLike, m: int, *, minimum: float, strict: bool) -> NDArray:
    """Broadcast ``value`` to shape (m,) float64 and check ``value >= minimum`` (or ``>``)."""
    arr = np.asarray(value, dtype=float)
    try:
        arr = np.broadcast_to(arr, (m,))
    except ValueError:
        raise ValueError(
            f"{name} must be a scalar or an array of shape ({m},), got shape {arr.shape}"
        ) from None
    bad = ~np.isfinite(arr) | ((arr <= minimum) if strict else (arr < minimum))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        rel = ">" if strict else ">="
        raise ValueError(f"{name} must be finite and {rel} {minimum}, got {arr[i]!r} at index {i}")
    return arr


def checked_actions(actions: ArrayLike) -> NDArray:
    arr = np.asarray(actions, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise ValueError(f"actions must have shape (m, 6), got {np.shape(actions)}")
    finite = np.isfinite(arr)
    if not finite.all():
        i, j = (int(k[0]) for k in np.nonzero(~finite))
        raise ValueError(f"actions must be finite, got {arr[i, j]!r} at [{i}, {j}]")
    return arr


# --------------------------------------------------------------------------------------------
# torsion constant and alpha


def _asinh_ratio(x: NDArray) -> NDArray:
    """asinh(x)/x with its limit 1 at x = 0 and 0 at x = inf."""
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.arcsinh(x) / x
    out = np.where(x < 1e-8, 1.0 - x * x / 6.0, out)
    return np.where(np.isinf(x), 0.0, out)


def _torsion_constant(l1: NDArray, l2: NDArray) -> NDArray:
    """cT for sides >= 0 (degenerate rectangles allowed: cT(l, 0) = l/4, cT(0, 0) = 0)."""
    l1 = np.asarray(l1, dtype=float)
    l2 = np.asarray(l2, dtype=float)
    c = np.hypot(l1, l2)
    with np.errstate(divide="ignore", invalid="ignore"):
        # l1^2/(4 l2) ln((l2 + c)/l1) = (l1/4) asinh(l2/l1)/(l2/l1), and symmetrically.
        t1 = np.where(l1 > 0, 0.25 * l1 * _asinh_ratio(l2 / l1), 0.0)
        t2 = np.where(l2 > 0, 0.25 * l2 * _asinh_ratio(l1 / l2), 0.0)
    return (0.5 * c + t1 + t2) / 3.0


def torsion_constant(l1: ArrayLike, l2: ArrayLike) -> NDArray:
    """Torsion constant cT (m) of an ``l1 x l2`` rectangle: mean distance from its centre.

    ``cT = (1/3) [c/2 + l1^2/(4 l2) ln((l2 + c)/l1) + l2^2/(4 l1) ln((l1 + c)/l2)]`` with
    ``c = sqrt(l1^2 + l2^2)``, so that the pure-torsion strength is ``m3u = cT * fsu``
    (0.3 x 0.2 m gives 0.09681 m). Scalars or arrays, broadcast together.
    """
    a, b = np.broadcast_arrays(np.asarray(l1, dtype=float), np.asarray(l2, dtype=float))
    shape = a.shape
    a = checked_field("l1", a.ravel(), a.size, minimum=0.0, strict=True)
    b = checked_field("l2", b.ravel(), b.size, minimum=0.0, strict=True)
    return _torsion_constant(a, b).reshape(shape)


def alpha_from_table(aspect: ArrayLike, direction: str = "f1") -> NDArray:
    """Exponent alpha of Eq. (A4)/(A5) interpolated in Table A1.

    ``aspect`` is l1/l2 (scalar or array); ``direction`` is ``"f1"``, ``"f2"`` or ``"f1=f2"``.
    Interpolation is linear in log(aspect); outside [0.1, 10] the end values are used.
    """
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    arr = np.asarray(aspect, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"aspect must be finite and > 0, got {aspect!r}")
    table_x = np.log(np.asarray(ALPHA_TABLE_A1["aspect"]))
    return np.interp(np.log(arr), table_x, np.asarray(ALPHA_TABLE_A1[direction]))


# --------------------------------------------------------------------------------------------
# radial factor on the shear-torsion boundary


def radial_factor(a: NDArray, c: NDArray, alpha: NDArray | float) -> NDArray:
    """The s > 0 solving ``(s a)^alpha + (s c)^2 = 1`` for a, c >= 0 and alpha >= 1.

    ``a = |m3|/m3u`` and ``c = |f|/fsu`` (not squared, so tiny forces do not underflow). Returns
    inf where a = c = 0 and 0 where a or c is inf. With ``m = max(a, c)`` the problem is solved
    for ``t = s m`` in (0, 1] on O(1) numbers, ``(t A)^alpha + (t C)^2 = 1`` with ``A = a/m``
    and ``C = c/m``: closed forms for alpha = 1, 2 and when a or c vanishes, otherwise Newton's
    method on the logarithm of the left-hand side, in ln t. ``alpha`` is an array like ``a``
    or one float for all rows.
    """
    if np.ndim(alpha):
        a, c, alpha = np.broadcast_arrays(a, c, alpha)
    m = np.maximum(a, c)
    with np.errstate(divide="ignore", over="ignore"):
        s = 1.0 / m  # t = 1 unless both > 0: s = 1/max(a, c), inf at a = c = 0, 0 at inf
    both = np.flatnonzero((np.minimum(a, c) > 0) & (m < np.inf))
    if both.size:
        mb = m[both]
        al = np.asarray(alpha)[both] if np.ndim(alpha) else float(alpha)
        t = _radial_t(a[both] / mb, c[both] / mb, al)
        with np.errstate(over="ignore"):  # subnormal demands: s = inf, utilisation 0
            s[both] = t / mb
    return s


def _radial_t(big_a: NDArray, big_c: NDArray, alpha: NDArray | float) -> NDArray:
    """t in (0, 1] solving ``(t A)^alpha + (t C)^2 = 1`` for max(A, C) = 1, A, C > 0."""
    if not np.ndim(alpha):  # one exponent for all rows: no masks
        if alpha == 2.0:
            return 1.0 / np.hypot(big_a, big_c)
        if alpha == 1.0:
            return 2.0 / (big_a + np.sqrt(big_a * big_a + 4.0 * big_c * big_c))
        return _radial_newton(big_a, big_c, alpha)
    alpha = np.asarray(alpha)
    t = np.empty(big_a.shape)
    two = alpha == 2.0
    one = alpha == 1.0
    if two.any():
        t[two] = 1.0 / np.hypot(big_a[two], big_c[two])
    if one.any():
        a1, c1 = big_a[one], big_c[one]
        t[one] = 2.0 / (a1 + np.sqrt(a1 * a1 + 4.0 * c1 * c1))
    rest = np.flatnonzero(~(one | two))
    if rest.size:
        t[rest] = _radial_newton(big_a[rest], big_c[rest], alpha[rest])
    return t


def _radial_newton(big_a: NDArray, big_c: NDArray, alpha: NDArray | float) -> NDArray:
    """Newton on G(tau) = ln((t A)^alpha + (t C)^2), tau = ln t: G is convex, increasing and
    nearly linear (slope between 2 and alpha), G(0) >= 0, so from tau = 0 the iterates
    decrease monotonically to the root in a few steps. Each row stops at its own first step
    below the tolerance (so results do not depend on the other rows)."""
    with np.errstate(divide="ignore"):  # A or C may underflow to 0: ln = -inf is fine
        ln_a, ln_c = np.log(big_a), np.log(big_c)
    al = alpha
    t = np.empty(big_a.shape)
    rows = np.arange(big_a.size)
    tau = np.zeros(big_a.size)
    for _ in range(NEWTON_MAX_ITER):  # iterate on the rows not yet converged
        p = np.exp(al * (tau + ln_a))
        q = np.exp(2.0 * (tau + ln_c))
        total = p + q
        step = np.log(total) * total / (al * p + 2.0 * q)
        tau = tau - step
        keep = np.abs(step) > NEWTON_RTOL
        if keep.all():
            continue
        done = ~keep
        with np.errstate(over="ignore"):
            t[rows[done]] = np.exp(tau[done])
        if not keep.any():
            break
        rows, tau, ln_a, ln_c = rows[keep], tau[keep], ln_a[keep], ln_c[keep]
        if np.ndim(al):
            al = np.asarray(al)[keep]
    else:  # pragma: no cover - Newton on a convex increasing function always converges
        logger.warning("radial factor: Newton did not converge to %g", NEWTON_RTOL)
        with np.errstate(over="ignore"):
            t[rows] = np.exp(tau)
    return t


def _safe_ratio(demand: NDArray, capacity: NDArray) -> NDArray:
    """demand/capacity with 0/0 = 0 and d/0 = inf (demand >= 0, capacity >= 0)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = demand / capacity
    return np.where(demand == 0, 0.0, np.where(capacity > 0, r, np.inf))


# --------------------------------------------------------------------------------------------
# public API


@dataclass(frozen=True)
class StrengthCheck:
    """Result of :func:`check_strength` for m interfaces.

    Attributes:
        projected: (m, 6) actions projected back on the domain (unchanged where elastic).
        state: (m,) int8 damage code: 0 elastic, 1 sliding (shear and/or torsion), 2 rocking
            (bending about y1 and/or y2), 3 sliding and rocking, 4 detached (fn > ft).
        flags: (m,) uint8 bit flags: 1 shear/torsion violated, 2 rocking about y1, 4 rocking
            about y2, 8 detached (a detached interface carries only the flag 8).
        stiffness_factors: (m, 6) of 0.0/1.0 per local component, Eqs. (13)-(14): detached ->
            all zero; rocking about y1 -> m1 zero; about y2 -> m2 zero; shear/torsion -> f1, f2
            and m3 zero.
        utilisation: (m,) largest demand/capacity ratio of the trial actions (see
            :func:`check_strength`); never NaN, +inf where a non-zero demand meets a zero
            capacity.
    """

    projected: NDArray
    state: NDArray
    flags: NDArray
    stiffness_factors: NDArray
    utilisation: NDArray


def shear_strength(
    fn: ArrayLike,
    friction: ArrayLike,
    tensile_force: ArrayLike = 0.0,
    cohesive_force: ArrayLike | None = None,
) -> NDArray:
    """Shear strength of an interface (N): ``fsu = C - mu fn`` below the tension cap.

    Parameters
    ----------
    fn : array_like
        Normal force [N], tension positive.
    friction : array_like
        mu >= 0.
    tensile_force : array_like, default 0.0
        ft = tensile strength x area [N], >= 0.
    cohesive_force : array_like, optional
        C = cohesion x area [N], with ``mu ft <= C`` (None: ``mu ft``, the paper's Eq. (10),
        ``fsu = mu (ft - fn)``).

    Returns
    -------
    numpy.ndarray
        fsu [N], broadcast over the arguments: ``C - mu fn`` for ``fn <= ft`` (``mu (ft -
        fn)`` and zero from fn = ft on without ``cohesive_force``), zero where ``fn > ft``
        (detached).

    Raises
    ------
    ValueError
        If an argument is not finite, friction or a force is negative, or ``C < mu ft``.
    """
    fn_, mu, ft = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (fn, friction, tensile_force))
    )
    shape = fn_.shape
    m = fn_.size
    fn_ = fn_.ravel()
    if not np.all(np.isfinite(fn_)):
        raise ValueError(f"fn must be finite, got {fn!r}")
    mu = checked_field("friction", mu.ravel(), m, minimum=0.0, strict=False)
    ft = checked_field("tensile_force", ft.ravel(), m, minimum=0.0, strict=False)
    fsu = mu * np.maximum(ft - fn_, 0.0)
    if cohesive_force is not None:
        c0 = cohesion_beyond_friction(cohesive_force, mu, ft, shape, m)
        fsu = np.where(fn_ <= ft, fsu + c0, 0.0)
    return fsu.reshape(shape)


def cohesion_beyond_friction(
    cohesive_force: ArrayLike, mu: NDArray, ft: NDArray, shape: tuple[int, ...], m: int
) -> NDArray:
    """``c0 = C - mu ft`` (m,) of a cohesive force ``C`` broadcast to ``shape``, checked:
    finite, >= 0 and not below ``mu ft`` (beyond a relative 1e-12 of round-off)."""
    arr = np.broadcast_to(np.asarray(cohesive_force, dtype=float), shape).ravel()
    c = checked_field("cohesive_force", arr, m, minimum=0.0, strict=False)
    floor = mu * ft
    low = c < floor * (1.0 - 1e-12)
    if low.any():
        i = int(np.flatnonzero(low)[0])
        raise ValueError(
            f"cohesive_force must be at least friction x tensile_force (ft <= c / mu), got "
            f"{float(c[i])!r} < {float(floor[i])!r} at index {i}"
        )
    return np.maximum(c - floor, 0.0)


def torsion_strength(
    fn: ArrayLike,
    l1: ArrayLike,
    l2: ArrayLike,
    friction: ArrayLike,
    tensile_force: ArrayLike = 0.0,
    m1: ArrayLike = 0.0,
    m2: ArrayLike = 0.0,
    cohesive_force: ArrayLike | None = None,
) -> NDArray:
    """Pure-torsion strength m3u = cT mu (ft - fn) (N m), Eq. (12), with cohesion.

    With bending moments, cT is evaluated on the reduced rectangle of uniform compression
    ``l1' = l1 - 2|m2|/(ft - fn)``, ``l2' = l2 - 2|m1|/(ft - fn)`` (Figure 10); moments beyond
    the rocking limits give a zero reduced side. With a cohesive force ``C`` above ``mu ft``,
    ``m3u = cT(l1', l2') mu (ft - fn) + cT(l1, l2) (C - mu ft)`` for ``fn <= ft`` (the part of
    the interface outside the reduced rectangle sits at the tension cap, where the shear
    strength is ``c - mu ft``), zero where ``fn > ft``.

    Parameters
    ----------
    fn : array_like
        Normal force [N], tension positive.
    l1, l2 : array_like
        Sides [m], > 0.
    friction : array_like
        mu >= 0.
    tensile_force : array_like, default 0.0
        ft = tensile strength x area [N], >= 0.
    m1, m2 : array_like, default 0.0
        Bending moments [N m] about y1 and y2.
    cohesive_force : array_like, optional
        C = cohesion x area [N], ``mu ft <= C`` (None: ``mu ft``, the paper's reading).

    Returns
    -------
    numpy.ndarray
        m3u [N m], broadcast over the arguments.

    Raises
    ------
    ValueError
        If an argument is not finite, a side is not positive, friction or a force is
        negative, or ``C < mu ft``.
    """
    arrs = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (fn, l1, l2, friction, tensile_force, m1, m2))
    )
    shape = arrs[0].shape
    m = arrs[0].size
    fn_, l1_, l2_, mu, ft, m1_, m2_ = (x.ravel() for x in arrs)
    for name, x in (("fn", fn_), ("m1", m1_), ("m2", m2_)):
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{name} must be finite, got {x[~np.isfinite(x)][0]!r}")
    l1_ = checked_field("l1", l1_, m, minimum=0.0, strict=True)
    l2_ = checked_field("l2", l2_, m, minimum=0.0, strict=True)
    mu = checked_field("friction", mu, m, minimum=0.0, strict=False)
    ft = checked_field("tensile_force", ft, m, minimum=0.0, strict=False)
    cap = np.maximum(ft - fn_, 0.0)
    l1r, l2r = _reduced_sides(l1_, l2_, cap, np.abs(m1_), np.abs(m2_))
    m3u = _torsion_constant(l1r, l2r) * mu * cap
    if cohesive_force is not None:
        c0 = cohesion_beyond_friction(cohesive_force, mu, ft, shape, m)
        m3u = np.where(fn_ <= ft, m3u + _torsion_constant(l1_, l2_) * c0, 0.0)
    return m3u.reshape(shape)


def _reduced_sides(
    l1: NDArray, l2: NDArray, cap: NDArray, abs_m1: NDArray, abs_m2: NDArray
) -> tuple[NDArray, NDArray]:
    """Sides of the rectangle of uniform compression cap carrying the bending moments."""
    with np.errstate(divide="ignore", invalid="ignore"):
        l1r = np.where(cap > 0, l1 - 2.0 * abs_m2 / cap, 0.0)
        l2r = np.where(cap > 0, l2 - 2.0 * abs_m1 / cap, 0.0)
    # a moment clipped to its rocking limit gives l - 2 |m| / cap = 0 up to rounding: snap it
    l1r = np.where(l1r <= SNAP * l1, 0.0, np.minimum(l1r, l1))
    l2r = np.where(l2r <= SNAP * l2, 0.0, np.minimum(l2r, l2))
    return l1r, l2r


def check_strength(
    actions: ArrayLike,
    l1: ArrayLike,
    l2: ArrayLike,
    friction: ArrayLike,
    tensile_force: ArrayLike,
    alpha: ArrayLike | None = None,
    torsion_bending_interaction: bool = True,
    projection: str = "energy",
    cohesive_force: ArrayLike | None = None,
) -> StrengthCheck:
    """Check m interfaces against the closed-form domain and project the actions back on it.

    Args:
        actions: (m, 6) local actions ``[f1, f2, fn, m1, m2, m3]`` (N, N m; tension positive).
            A single (6,) row is accepted as m = 1.
        l1, l2: interface sides along y1 and y2 (m), > 0; scalars or (m,).
        friction: friction coefficient mu >= 0; scalar or (m,).
        tensile_force: ft = tensile strength x area (N) >= 0; scalar or (m,).
        alpha: exponent of Eq. (A5), >= 1 (a convex domain); None means ``DEFAULT_ALPHA``.
        torsion_bending_interaction: evaluate cT on the reduced rectangle (Figure 10).
        projection: how (f1, f2, m3) outside Eq. (A5) return to it. ``"energy"`` (default):
            the closest point in the elastic energy of the correction (kt A for shear, kt J
            for torsion; the usual return mapping), shear direction kept. ``"radial"``: the
            three scaled by one factor. They differ most where the torsion capacity vanishes
            (a joint rocking about both axes bears on a corner): the energy projection keeps
            the shear up to mu (ft - fn) and drops the torsion, as a point contact does; the
            radial one drops both, which lets a lightly loaded block spin free.
        cohesive_force: C = cohesion x area (N), ``mu ft <= C``; scalar or (m,). None means
            ``mu ft`` (the paper's reading, Eq. (10)).

    Projection order: fn > ft -> detached, projected to ``[0, 0, ft, 0, 0, 0]``; then m1, m2
    clipped to their rocking limits; then (f1, f2, m3) returned onto the shear-torsion
    boundary (see ``projection``). Actions inside the domain are returned unchanged (bitwise).

    Utilisation: the largest of the demand/capacity ratios of the trial actions, namely
    ``max(fn, 0)/ft`` (or, for ft = 0, 1 at fn = 0 and 0 in compression), ``|m1|/(cap l2/2)``,
    ``|m2|/(cap l1/2)`` and, for Eq. (A5), ``1/s`` where ``s`` scales (f1, f2, m3) onto the
    boundary (so it is |f|/fsu in pure shear and |m3|/m3u in pure torsion). It is 1 on the
    boundary, below 1 inside and above 1 outside. Ratios use 0/0 = 0 and d/0 = +inf; a detached
    interface has ``fn/ft`` (+inf when ft = 0). Never NaN.
    """
    act = checked_actions(actions)
    m = act.shape[0]
    ft = checked_field("tensile_force", tensile_force, m, minimum=0.0, strict=False)
    domain = StrengthDomain.of(m, l1, l2, friction, alpha)
    if projection not in PROJECTIONS:
        raise ValueError(f"projection must be one of {PROJECTIONS}, got {projection!r}")
    c0 = (
        None
        if cohesive_force is None
        else cohesion_beyond_friction(cohesive_force, domain.friction, ft, (m,), m)
    )
    return evaluate(act, ft, domain, torsion_bending_interaction, projection=projection, c0=c0)


# --------------------------------------------------------------------------------------------
# the batched check itself (inputs already validated)


@dataclass(frozen=True)
class StrengthDomain:
    """Per-interface constants of the check, validated once: an
    :class:`~masonry_dem.constitutive.law.InterfaceLaw` keeps one for all its calls."""

    l1: NDArray
    l2: NDArray
    friction: NDArray
    alpha: NDArray | float  # one float when every row has the same (no gathers in Newton)
    snap1: NDArray  # a reduced side at or below these is zero
    snap2: NDArray

    @classmethod
    def of(
        cls, m: int, l1: ArrayLike, l2: ArrayLike, friction: ArrayLike, alpha=None
    ) -> StrengthDomain:
        l1_ = np.array(checked_field("l1", l1, m, minimum=0.0, strict=True))
        l2_ = np.array(checked_field("l2", l2, m, minimum=0.0, strict=True))
        mu = np.array(checked_field("friction", friction, m, minimum=0.0, strict=False))
        al = checked_field(
            "alpha", DEFAULT_ALPHA if alpha is None else alpha, m, minimum=1.0, strict=False
        )
        uniform = m > 0 and bool((al == al[0]).all())
        return cls(l1_, l2_, mu, float(al[0]) if uniform else np.array(al), SNAP * l1_, SNAP * l2_)

    def take(self, rows: NDArray) -> StrengthDomain:
        al = np.asarray(self.alpha)[rows] if np.ndim(self.alpha) else self.alpha
        return StrengthDomain(
            self.l1[rows],
            self.l2[rows],
            self.friction[rows],
            al,
            self.snap1[rows],
            self.snap2[rows],
        )

    @cached_property
    def alpha_rows(self) -> NDArray:
        """alpha of every row, (m,) even when the domain holds one float (the compiled check)."""
        if np.ndim(self.alpha):
            return writable_c(np.asarray(self.alpha))
        return np.full(self.l1.shape[0], float(self.alpha))

    @cached_property
    def kernel_arrays(self) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
        """The per-row arrays of the compiled kernels, in their order: l1, l2, friction,
        alpha, snap1, snap2."""
        return (self.l1, self.l2, self.friction, self.alpha_rows, self.snap1, self.snap2)

    @cached_property
    def torsion_constant(self) -> NDArray:
        """cT of the whole rectangles (without the torsion-bending interaction)."""
        return _torsion_constant(self.l1, self.l2)

    @cached_property
    def row_constants(self) -> NDArray:
        """(m, 5) per-row constants of the forces kernel
        (:data:`~masonry_dem.constitutive.energy_return.row_constants`): cT of the whole
        rectangles and the constants of a sliding row's energy return, computed once."""
        kernel = row_constants.for_rows(self.l1.shape[0])
        return kernel(self.l1, self.l2, self.alpha_rows, self.torsion_constant)


def _run_kernel(
    act: NDArray,
    ft: NDArray,
    dom: StrengthDomain,
    torsion_bending_interaction: bool,
    projection_only: bool,
    projection: str,
    c0: NDArray | None,
) -> tuple[NDArray, NDArray, NDArray]:
    """:data:`~masonry_dem.constitutive.check_kernels.evaluate_rows` on fresh output arrays: (projected (m, 6), flags (m,), utilisation
    (m,), empty when ``projection_only``)."""
    m = act.shape[0]
    proj = np.empty((m, 6))
    flags = np.empty(m, dtype=np.uint8)
    util = np.empty(0 if projection_only else m)
    n_radial, n_energy = evaluate_rows.for_rows(m)(
        writable_c(act),
        writable_c(ft),
        np.zeros(m) if c0 is None else writable_c(c0),
        *dom.kernel_arrays,
        bool(torsion_bending_interaction),
        bool(projection_only),
        projection == "energy",
        proj,
        flags,
        util,
    )
    if n_radial:  # pragma: no cover - Newton on a convex increasing function converges
        logger.warning("radial factor: Newton did not converge to %g", NEWTON_RTOL)
    if n_energy:  # rows at round-off; they fell back to the radial return off the boundary
        logger.debug("energy projection: %d rows did not converge", n_energy)
    return proj, flags, util


def projection_and_flags(
    act: NDArray,
    ft: NDArray,
    dom: StrengthDomain,
    projection: str = "energy",
    torsion_bending_interaction: bool = True,
    c0: NDArray | None = None,
) -> tuple[NDArray, NDArray]:
    """The projected actions (m, 6) and bit flags (m,) of :func:`evaluate`, bit for bit,
    without the utilisation: the radial factor of the rows well inside Eq. (A5) is skipped.
    For the residuals of a Newton search or a time step, where only the forces count."""
    proj, flags, _ = _run_kernel(act, ft, dom, torsion_bending_interaction, True, projection, c0)
    return proj, flags


def writable_c(x: NDArray) -> NDArray:
    """``x`` as a writable C-contiguous float64 array (one compiled signature for all calls)."""
    if x.dtype == np.float64 and x.flags.c_contiguous and x.flags.writeable:
        return x
    return np.array(x, dtype=np.float64, order="C")


def evaluate(
    act: NDArray,
    ft: NDArray,
    dom: StrengthDomain,
    torsion_bending_interaction: bool = True,
    projection: str = "energy",
    c0: NDArray | None = None,
) -> StrengthCheck:
    """:func:`check_strength` on validated inputs (``act`` (m, 6), ``ft`` (m,) >= 0, ``c0``
    (m,) >= 0 the cohesive force beyond mu ft, None: zero).

    The compiled :data:`~masonry_dem.constitutive.check_kernels.evaluate_rows`, which gives what the numpy reference of the tests gives
    (the same floating-point operations row by row: the finite-difference tangent of the law
    divides differences of projections by 1e-7 and must not see a changed last bit).
    :func:`projection_and_flags` is the same check without the utilisation.
    """
    proj, flags, util = _run_kernel(
        act, ft, dom, torsion_bending_interaction, False, projection, c0
    )
    return StrengthCheck(
        projected=proj,
        state=STATE_OF_FLAGS[flags],
        flags=flags,
        stiffness_factors=FACTORS_OF_FLAGS[flags],
        utilisation=util,
    )
