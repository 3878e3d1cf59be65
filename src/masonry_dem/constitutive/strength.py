"""Closed-form strength domain of a rectangular interface, batched over interfaces.

Implements Section 2.1, Eqs. (9)-(14) and Eqs. (A4)-(A5) of Baraldi & Cecchi, in terms of the
resultant actions of one interface. The local action order used everywhere in the package is::

    [f1, f2, fn, m1, m2, m3]

shear along the local axis y1, shear along y2, normal force (tension positive, compression
negative), bending about y1, bending about y2 and torsion about the normal. The interface is an
``l1 x l2`` rectangle, ``l1`` along y1 and ``l2`` along y2.

Criteria, with ``ft`` the tensile force of the whole interface (tensile strength x area) and
``cap = ft - fn``:

* detachment: ``fn <= ft``;
* rocking: ``|m1| <= cap * l2 / 2`` and ``|m2| <= cap * l1 / 2`` (the lever is half the side
  perpendicular to the bending axis: for the paper's horizontal running-bond joints this is
  lc1 = s/2 and lc2 = b/4);
* shear-torsion, Eq. (A5): ``(|m3| / m3u)**alpha + (f1**2 + f2**2) / fsu**2 <= 1`` with
  ``fsu = mu * cap`` and ``m3u = cT * mu * cap``. With the torsion-bending interaction of
  Figure 10, ``cT`` is evaluated on the reduced rectangle under uniform compression,
  ``l1' = l1 - 2 |m2| / cap`` and ``l2' = l2 - 2 |m1| / cap`` (bending moments already clipped).

The torsion constant ``cT`` is the mean distance of the rectangle's points from its centre; the
printed Eq. (11) is garbled and the correct form is used here (see ``DESIGN.md``).

The batched check runs compiled (numba), one interface at a time, the rows shared among the
threads (``_nb_evaluate``: each row is worked out alone, so the answer is the same bits on any
number of threads); the numpy version of the same operations, batched with masks, is its
reference in the tests (``tests/constitutive/numpy_reference.py``). The kernel is compiled on
the first check and cached on disk (a few seconds, once per machine).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Final

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ALPHA_TABLE_A1",
    "DEFAULT_ALPHA",
    "FLAG_DETACHED",
    "FLAG_ROCKING_1",
    "FLAG_ROCKING_2",
    "FLAG_SHEAR_TORSION",
    "SHEAR_TORSION_TOLERANCE",
    "STATE_DETACHED",
    "STATE_ELASTIC",
    "STATE_ROCKING",
    "STATE_SLIDING",
    "STATE_SLIDING_ROCKING",
    "StrengthCheck",
    "alpha_from_table",
    "check_strength",
    "shear_strength",
    "stiffness_factors_of_flags",
    "torsion_constant",
    "torsion_strength",
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

#: ways back onto the shear-torsion boundary (see ``check_strength``)
PROJECTIONS: Final[tuple[str, ...]] = ("energy", "radial")
#: safeguarded Newton of the energy projection: iteration cap, and the relative step below
#: which the last step is taken and the row stops (Newton's quadratic convergence leaves an
#: error of the order of its square, at round-off)
_PROJECTION_MAX_ITER: Final[int] = 100
_PROJECTION_TOL: Final[float] = 1e-9
#: capacities near the subnormal range lose digits in the energy return: radial there
_TINY_CAPACITY: Final[float] = 1e-280

#: A trial violates Eq. (A5) only if its radial demand/capacity ratio (see ``check_strength``)
#: exceeds 1 by more than this. The radial projection lands on the boundary to ~1e-13, so
#: re-checking projected actions reports them elastic (and returns them unchanged).
SHEAR_TORSION_TOLERANCE: Final[float] = 1e-9

STATE_ELASTIC: Final[int] = 0
STATE_SLIDING: Final[int] = 1
STATE_ROCKING: Final[int] = 2
STATE_SLIDING_ROCKING: Final[int] = 3
STATE_DETACHED: Final[int] = 4

FLAG_SHEAR_TORSION: Final[int] = 1
FLAG_ROCKING_1: Final[int] = 2
FLAG_ROCKING_2: Final[int] = 4
FLAG_DETACHED: Final[int] = 8

_NEWTON_MAX_ITER = 60
_SNAP = 1e-12  # relative size below which a reduced side is zero
_NEWTON_RTOL = 1e-13


# --------------------------------------------------------------------------------------------
# input checking


def _field(name: str, value: ArrayLike, m: int, *, minimum: float, strict: bool) -> NDArray:
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


def _actions(actions: ArrayLike) -> NDArray:
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
    a = _field("l1", a.ravel(), a.size, minimum=0.0, strict=True)
    b = _field("l2", b.ravel(), b.size, minimum=0.0, strict=True)
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


def _radial_factor(a: NDArray, c: NDArray, alpha: NDArray | float) -> NDArray:
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
    for _ in range(_NEWTON_MAX_ITER):  # iterate on the rows not yet converged
        p = np.exp(al * (tau + ln_a))
        q = np.exp(2.0 * (tau + ln_c))
        total = p + q
        step = np.log(total) * total / (al * p + 2.0 * q)
        tau = tau - step
        keep = np.abs(step) > _NEWTON_RTOL
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
        logger.warning("radial factor: Newton did not converge to %g", _NEWTON_RTOL)
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


def shear_strength(fn: ArrayLike, friction: ArrayLike, tensile_force: ArrayLike = 0.0) -> NDArray:
    """Shear strength fsu = mu (ft - fn) of Eq. (10), zero when fn >= ft (N)."""
    fn_, mu, ft = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (fn, friction, tensile_force))
    )
    shape = fn_.shape
    m = fn_.size
    fn_ = fn_.ravel()
    if not np.all(np.isfinite(fn_)):
        raise ValueError(f"fn must be finite, got {fn!r}")
    mu = _field("friction", mu.ravel(), m, minimum=0.0, strict=False)
    ft = _field("tensile_force", ft.ravel(), m, minimum=0.0, strict=False)
    return (mu * np.maximum(ft - fn_, 0.0)).reshape(shape)


def torsion_strength(
    fn: ArrayLike,
    l1: ArrayLike,
    l2: ArrayLike,
    friction: ArrayLike,
    tensile_force: ArrayLike = 0.0,
    m1: ArrayLike = 0.0,
    m2: ArrayLike = 0.0,
) -> NDArray:
    """Pure-torsion strength m3u = cT mu (ft - fn) (N m), Eq. (12).

    With bending moments, cT is evaluated on the reduced rectangle of uniform compression
    ``l1' = l1 - 2|m2|/(ft - fn)``, ``l2' = l2 - 2|m1|/(ft - fn)`` (Figure 10); moments beyond
    the rocking limits give a zero reduced side.
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
    l1_ = _field("l1", l1_, m, minimum=0.0, strict=True)
    l2_ = _field("l2", l2_, m, minimum=0.0, strict=True)
    mu = _field("friction", mu, m, minimum=0.0, strict=False)
    ft = _field("tensile_force", ft, m, minimum=0.0, strict=False)
    cap = np.maximum(ft - fn_, 0.0)
    l1r, l2r = _reduced_sides(l1_, l2_, cap, np.abs(m1_), np.abs(m2_))
    return (_torsion_constant(l1r, l2r) * mu * cap).reshape(shape)


def _reduced_sides(
    l1: NDArray, l2: NDArray, cap: NDArray, abs_m1: NDArray, abs_m2: NDArray
) -> tuple[NDArray, NDArray]:
    """Sides of the rectangle of uniform compression cap carrying the bending moments."""
    with np.errstate(divide="ignore", invalid="ignore"):
        l1r = np.where(cap > 0, l1 - 2.0 * abs_m2 / cap, 0.0)
        l2r = np.where(cap > 0, l2 - 2.0 * abs_m1 / cap, 0.0)
    # a moment clipped to its rocking limit gives l - 2 |m| / cap = 0 up to rounding: snap it
    l1r = np.where(l1r <= _SNAP * l1, 0.0, np.minimum(l1r, l1))
    l2r = np.where(l2r <= _SNAP * l2, 0.0, np.minimum(l2r, l2))
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
    act = _actions(actions)
    m = act.shape[0]
    ft = _field("tensile_force", tensile_force, m, minimum=0.0, strict=False)
    domain = _Domain.of(m, l1, l2, friction, alpha)
    if projection not in PROJECTIONS:
        raise ValueError(f"projection must be one of {PROJECTIONS}, got {projection!r}")
    return _evaluate(act, ft, domain, torsion_bending_interaction, projection=projection)


# --------------------------------------------------------------------------------------------
# the batched check itself (inputs already validated)

_SLIDE_COLUMNS: Final = np.array([0, 1, 5])  # f1, f2, m3: scaled by sliding


def _flag_tables() -> tuple[NDArray, NDArray]:
    """State code and stiffness factors of every combination of the bit flags."""
    flags = np.arange(16)
    sliding = (flags & FLAG_SHEAR_TORSION) > 0
    rock1 = (flags & FLAG_ROCKING_1) > 0
    rock2 = (flags & FLAG_ROCKING_2) > 0
    detached = (flags & FLAG_DETACHED) > 0
    state = sliding * STATE_SLIDING + (rock1 | rock2) * STATE_ROCKING
    state[detached] = STATE_DETACHED
    factors = np.ones((16, 6))
    factors[np.ix_(sliding, _SLIDE_COLUMNS)] = 0.0
    factors[rock1, 3] = 0.0
    factors[rock2, 4] = 0.0
    factors[detached] = 0.0
    return state.astype(np.int8), factors


_STATE_OF_FLAGS, _FACTORS_OF_FLAGS = _flag_tables()


def stiffness_factors_of_flags(flags: ArrayLike) -> NDArray:
    """(m, 6) stiffness factors of Eqs. (13)-(14) (0 or 1) for the bit flags of m interfaces."""
    return _FACTORS_OF_FLAGS[np.asarray(flags, dtype=np.int64)]


@dataclass(frozen=True)
class _Domain:
    """Per-interface constants of the check, validated once: an
    :class:`~masonry_dem.constitutive.law.InterfaceLaw` keeps one for all its calls."""

    l1: NDArray
    l2: NDArray
    friction: NDArray
    alpha: NDArray | float  # one float when every row has the same (no gathers in Newton)
    snap1: NDArray  # a reduced side at or below these is zero
    snap2: NDArray

    @classmethod
    def of(cls, m: int, l1: ArrayLike, l2: ArrayLike, friction: ArrayLike, alpha=None) -> _Domain:
        l1_ = np.array(_field("l1", l1, m, minimum=0.0, strict=True))
        l2_ = np.array(_field("l2", l2, m, minimum=0.0, strict=True))
        mu = np.array(_field("friction", friction, m, minimum=0.0, strict=False))
        al = _field(
            "alpha", DEFAULT_ALPHA if alpha is None else alpha, m, minimum=1.0, strict=False
        )
        uniform = m > 0 and bool((al == al[0]).all())
        return cls(
            l1_, l2_, mu, float(al[0]) if uniform else np.array(al), _SNAP * l1_, _SNAP * l2_
        )

    def take(self, rows: NDArray) -> _Domain:
        al = np.asarray(self.alpha)[rows] if np.ndim(self.alpha) else self.alpha
        return _Domain(
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
            return _writable_c(np.asarray(self.alpha))
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


# --------------------------------------------------------------------------------------------
# the same check compiled, one interface at a time
#
# Each function below is the scalar transcription of the numpy function of the same name
# without the ``_nb`` prefix (this module's, or the reference's in
# tests/constitutive/numpy_reference.py), operation for operation and in the same order (no fast-math, so no
# reassociation or fused multiply-adds), so that a row comes out as the numpy reference gives it
# up to the last bit of the libm functions. Compiled on the first call (cache=True: once per
# machine); importing this module compiles nothing.

_jit = numba.njit(cache=True, error_model="numpy")  # x/0 = inf or nan, as numpy gives
_pjit = numba.njit(cache=True, error_model="numpy", parallel=True)  # rows over threads


@_jit
def _nb_torsion_constant(l1: float, l2: float) -> float:
    """:func:`_torsion_constant` of one rectangle (sides >= 0; asinh(x)/x patched to its
    limits where a side is below 1e-8 of the other)."""
    x = l2 / l1
    y = l1 / l2
    r1 = math.asinh(x) / x
    r2 = math.asinh(y) / y
    odd = not (x >= 1e-8 and y >= 1e-8)  # a tiny or zero side, or both zero (NaN ratios)
    if odd:
        if x < 1e-8:
            r1 = 1.0 - x * x / 6.0
        if x == math.inf:
            r1 = 0.0  # l1 = 0: its term vanishes
        if y < 1e-8:
            r2 = 1.0 - y * y / 6.0
        if y == math.inf:
            r2 = 0.0
    c = math.hypot(l1, l2)
    c *= 0.5
    c += (0.25 * l1) * r1
    c += (0.25 * l2) * r2
    c /= 3.0
    if odd and math.isnan(x):
        c = 0.0  # both sides zero
    return c


@_jit
def _nb_radial_t(big_a: float, big_c: float, alpha: float) -> tuple[float, bool]:
    """:func:`_radial_t` and :func:`_radial_newton` of one row; False if Newton did not
    converge."""
    if alpha == 2.0:
        return 1.0 / math.hypot(big_a, big_c), True
    if alpha == 1.0:
        return 2.0 / (big_a + math.sqrt(big_a * big_a + 4.0 * big_c * big_c)), True
    ln_a = math.log(big_a)  # -inf where A underflowed to 0
    ln_c = math.log(big_c)
    tau = 0.0
    for _ in range(_NEWTON_MAX_ITER):
        p = math.exp(alpha * (tau + ln_a))
        q = math.exp(2.0 * (tau + ln_c))
        total = p + q
        step = math.log(total) * total / (alpha * p + 2.0 * q)
        tau = tau - step
        if not abs(step) > _NEWTON_RTOL:
            return math.exp(tau), True
    return math.exp(tau), False


@_jit
def _nb_radial_factor(a: float, c: float, alpha: float) -> tuple[float, bool]:
    """:func:`_radial_factor` of one row."""
    m = max(a, c)
    s = 1.0 / m  # inf at a = c = 0, 0 at inf
    ok = True
    if min(a, c) > 0 and m < math.inf:
        t, ok = _nb_radial_t(a / m, c / m, alpha)
        s = t / m
    return s, ok


@_jit
def _nb_safe_ratio(demand: float, capacity: float) -> float:
    """:func:`_safe_ratio` of one row."""
    if demand == 0:
        return 0.0
    if capacity > 0:
        return demand / capacity
    return math.inf


@_jit
def _nb_shear_half(tau, a, b, r0, z0, alpha, power) -> tuple[float, float]:
    """g = d/dt of half the squared distance from (a sqrt(1 - t^alpha), b t) to (r0, z0) at
    t = tau^power, and dg/dtau; smooth on t in [0, 2^(-1/alpha)]. One row."""
    t = tau**power
    ta = t**alpha
    u = 1.0 - ta
    su = math.sqrt(u)
    du = -alpha * ta / t
    d2u = du * (alpha - 1.0) / t
    r = a * su
    dr = 0.5 * a * du / su
    d2r = a * (0.5 * d2u / su - 0.25 * du * du / (u * su))
    g = (r - r0) * dr + (b * t - z0) * b
    dg = (dr * dr + (r - r0) * d2r + b * b) * power * t / tau
    return g, dg


@_jit
def _nb_torsion_half(x, a, b, r0, z0, alpha) -> tuple[float, float]:
    """g = d/dx of half the squared distance from (a x, b (1 - x^2)^(1/alpha)) to (r0, z0),
    and g'; smooth on x in [0, sqrt(1/2)]. One row."""
    w = 1.0 - x * x
    p = 1.0 / alpha
    wp = w**p
    z = b * wp
    dz = -2.0 * p * b * x * wp / w
    d2z = 2.0 * p * b * wp / w * (2.0 * (p - 1.0) * x * x / w - 1.0)
    g = (a * x - r0) * a + (z - z0) * dz
    dg = a * a + dz * dz + (z - z0) * d2z
    return g, dg


@_jit
def _nb_bracketed_newton(torsion, a, b, r0, z0, alpha, power, hi, start) -> tuple[float, bool]:
    """Root of g on [0, hi] (g(0) < 0 < g(hi), one sign change) for one row, g being
    :func:`_nb_torsion_half` if ``torsion`` else :func:`_nb_shear_half`: Newton's method from
    ``start`` (mid-bracket if outside it) kept inside the shrinking bracket (bisection where a
    step would leave it); False if it did not converge."""
    lo = 0.0
    x = 0.5 * hi
    if start > 0.0 and start < hi:
        x = start
    for _ in range(_PROJECTION_MAX_ITER):
        if torsion:
            g, dg = _nb_torsion_half(x, a, b, r0, z0, alpha)
        else:
            g, dg = _nb_shear_half(x, a, b, r0, z0, alpha, power)
        if g > 0:
            hi = x
        else:
            lo = x
        step = g / dg
        newton = x - step
        # a step below tolerance is taken even where it rounds onto the bracket's end
        done = abs(step) <= _PROJECTION_TOL * (x if x > 1e-300 else 1e-300)
        inside = newton > lo and newton < hi and math.isfinite(newton)
        x = newton if (inside or done) else 0.5 * (lo + hi)
        if done or hi - lo <= 4.0 * np.spacing(hi):  # converged, or bracket at round-off
            return x, True
    return x, False


@_jit
def _nb_energy_closest_point(r0, z0, a, b, alpha, radial) -> tuple[float, float, bool]:
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
    the shear up to a and drops the torsion; a = 0 drops both. One row; False if Newton did not converge."""
    r = 0.0
    z = 0.0
    ok = True
    if r0 > 0 and z0 > 0 and a > 0 and b > 0:
        t_switch = 0.5 ** (1.0 / alpha)
        x_switch = math.sqrt(0.5)
        power = 2.0 if alpha < 2.0 else 1.0
        near_shear = _nb_shear_half(t_switch, a, b, r0, z0, alpha, 1.0)[0] >= 0.0
        # alpha = 1 has a vertex on the shear axis; points in its normal cone return to it
        vertex = alpha == 1.0 and (r0 - a) * 0.5 * a >= z0 * b
        if vertex:
            r = a
        if near_shear and not vertex:
            p = power
            start = (radial * z0 / b) ** (1 / p)
            tau, ok = _nb_bracketed_newton(
                False, a, b, r0, z0, alpha, p, t_switch ** (1 / p), start
            )
            t = tau**p
            r = a * math.sqrt(max(1.0 - t**alpha, 0.0))
            z = b * t
        if not near_shear:  # (after the vertex, as the numpy version does)
            start = radial * r0 / a
            x, ok = _nb_bracketed_newton(True, a, b, r0, z0, alpha, 1.0, x_switch, start)
            r = a * x
            z = b * max(1.0 - x * x, 0.0) ** (1.0 / alpha)
    # one of r0, z0 zero: the point is on an axis and so is its closest point
    if r0 == 0 and b > 0:
        z = b * min(1.0, _nb_safe_ratio(z0, b))
    if z0 == 0:
        r = min(r0, a)
    if b == 0:
        r = min(r0, a)
        z = 0.0
    return r, z, ok


@_jit
def _nb_energy_radius(l1: float, l2: float) -> float:
    """rho = sqrt(J / A) of an l1 x l2 rectangle: z = |m3| / rho puts torsion in the units of
    shear so that distance in (|f|, z) is the elastic energy of a correction (kt A, kt J)."""
    return math.sqrt((l1 * l1 + l2 * l2) / 12.0)


@_jit
def _nb_reduced_side(side: float, abs_moment: float, cap: float, snap: float) -> float:
    """Side of the rectangle of uniform compression ``cap`` carrying the bending moment
    ``abs_moment`` about the other axis (:func:`_reduced_sides` of one row): zero at or
    below ``snap`` (a moment clipped to its rocking limit leaves round-off)."""
    reduced = side - 2.0 * abs_moment / cap
    reduced = min(reduced, side)
    if reduced <= snap:
        reduced = 0.0
    return reduced


@_jit
def _nb_evaluate_row(
    i,
    act,
    ft,
    l1,
    l2,
    friction,
    alpha,
    snap1,
    snap2,
    torsion_bending_interaction,
    projection_only,
    energy,
    proj,
    flags,
    util,
):
    """Row ``i`` of :func:`_nb_evaluate`; returns whether its radial factor and its energy
    projection did not converge (0 or 1 each)."""
    n_radial = 0
    n_energy = 0
    f1 = act[i, 0]
    f2 = act[i, 1]
    fn = act[i, 2]
    m1 = act[i, 3]
    m2 = act[i, 4]
    m3 = act[i, 5]
    fti = ft[i]
    al = alpha[i]

    # detachment
    detached = fn > fti
    live = not detached
    cap = 0.0 if detached else fti - fn

    # rocking: clip the bending moments to the eccentricity limits
    half = 0.5 * cap
    m1_lim = half * l2[i]
    m2_lim = half * l1[i]
    abs_m1 = abs(m1)
    abs_m2 = abs(m2)
    rock1 = abs_m1 > m1_lim and live
    rock2 = abs_m2 > m2_lim and live
    abs_m1c = min(abs_m1, m1_lim)
    abs_m2c = min(abs_m2, m2_lim)

    # shear and torsion: demand/capacity ratios a = |m3|/m3u, c = |f|/fsu
    fsu = friction[i] * cap
    abs_m3 = abs(m3)
    m3u = 0.0
    if abs_m3 > 0 and cap > 0:
        if torsion_bending_interaction:
            l1r = _nb_reduced_side(l1[i], abs_m2c, cap, snap1[i])
            l2r = _nb_reduced_side(l2[i], abs_m1c, cap, snap2[i])
            c_t = _nb_torsion_constant(l1r, l2r)
        else:
            c_t = _nb_torsion_constant(l1[i], l2[i])
        m3u = c_t * fsu
    shear = math.hypot(f1, f2)
    a = abs_m3 / m3u if abs_m3 > 0 else 0.0  # 0/0 = 0, d/0 = inf (no capacity)
    c = shear / fsu if shear > 0 else 0.0

    u_st = 0.0
    s = 1.0
    sliding = False
    if projection_only:
        # a + c^2 >= a^alpha + c^2 for a, c <= 1 and alpha >= 1: below 1 no row slides
        if live and not a + c * c < 0.999:
            s, ok = _nb_radial_factor(a, c, al)
            n_radial += 0 if ok else 1
            sliding = 1.0 / s > 1.0 + SHEAR_TORSION_TOLERANCE
    else:
        s, ok = _nb_radial_factor(a, c, al)
        n_radial += 0 if ok else 1
        u_st = 1.0 / s  # radial demand/capacity ratio of Eq. (A5)
        sliding = u_st > 1.0 + SHEAR_TORSION_TOLERANCE and live

    # projection (untouched entries are kept bitwise)
    for j in range(6):
        proj[i, j] = act[i, j]
    proj[i, 3] = math.copysign(abs_m1c, m1)
    proj[i, 4] = math.copysign(abs_m2c, m2)
    if sliding and not energy:
        proj[i, 0] *= s
        proj[i, 1] *= s
        proj[i, 5] *= s
    elif sliding:
        rho = _nb_energy_radius(l1[i], l2[i])
        r, z, ok = _nb_energy_closest_point(shear, abs_m3 / rho, fsu, m3u / rho, al, s)
        n_energy += 0 if ok else 1
        shear_scale = _nb_safe_ratio(r, shear)
        if not math.isfinite(shear_scale):
            shear_scale = 0.0
        m3_new = math.copysign(z * rho, m3)
        # capacities at the edge of floating point (subnormal friction or sides): the
        # radial return, which lands on the boundary by construction
        phi = _nb_safe_ratio(z * rho, m3u) ** al + _nb_safe_ratio(r, fsu) ** 2
        off = not abs(phi - 1.0) <= 1e-9 and m3u > 0 and fsu > 0
        off = off or abs_m3 == 0  # pure shear: the same point, with the radial round-off
        off = off or fsu < _TINY_CAPACITY
        if off:
            shear_scale = s
            m3_new = m3 * s
        proj[i, 0] = f1 * shear_scale
        proj[i, 1] = f2 * shear_scale
        proj[i, 5] = m3_new
    if detached:
        for j in range(6):
            proj[i, j] = 0.0
        proj[i, 2] = fti

    flags[i] = (
        (FLAG_SHEAR_TORSION if sliding else 0)
        | (FLAG_ROCKING_1 if rock1 else 0)
        | (FLAG_ROCKING_2 if rock2 else 0)
        | (FLAG_DETACHED if detached else 0)
    )
    if projection_only:
        return n_radial, n_energy

    # utilisation
    u_tension = max(fn, 0.0) / fti  # ft = 0: inf in tension, NaN otherwise
    if math.isnan(u_tension):  # ft = 0: 1 at fn = 0, 0 in compression
        u_tension = 1.0 if fn >= 0 else 0.0
    if detached:
        util[i] = u_tension
        return n_radial, n_energy
    u_rock = abs_m1 / m1_lim if abs_m1 > 0 else 0.0
    u_rock2 = abs_m2 / m2_lim if abs_m2 > 0 else 0.0
    util[i] = max(max(max(u_rock, u_rock2), u_tension), u_st)
    return n_radial, n_energy


@_pjit
def _nb_evaluate(
    act,
    ft,
    l1,
    l2,
    friction,
    alpha,
    snap1,
    snap2,
    torsion_bending_interaction,
    projection_only,
    energy,
    proj,
    flags,
    util,
):
    """The strength check (see :func:`check_strength`) row by row, into ``proj`` (m, 6), ``flags`` (m,) uint8 and
    (unless ``projection_only``) ``util`` (m,). Returns the numbers of rows whose radial
    factor and whose energy projection did not converge."""
    n_radial = 0
    n_energy = 0
    for i in numba.prange(act.shape[0]):
        # one compiled row function: the parallel loop stays small to compile
        radial_failed, energy_failed = _nb_evaluate_row(
            i, act, ft, l1, l2, friction, alpha, snap1, snap2, torsion_bending_interaction,
            projection_only, energy, proj, flags, util,
        )  # fmt: skip
        n_radial += radial_failed
        n_energy += energy_failed
    return n_radial, n_energy


@_jit
def _nb_fd_tangent(
    t, h, ft, rows, l1, l2, friction, alpha, snap1, snap2, energy, k, normal_only, out
):
    """Forward-difference derivative of the projection at the rows ``rows`` of a domain, into
    ``out`` (n, 6, 6): ``out[r, a, p] = (proj(t_r + h_rp e_p)_a - proj(t_r)_a) / h_rp * k_rp``
    (the chain rule through the elastic trial ``k * relative``). The trials and their probes
    go through one call of :func:`_nb_evaluate`, so the result is the one the batched numpy
    difference over the same probes gives, bit for bit. Rows with ``normal_only`` are probed
    along fn alone (their other columns are zero): a joint at zero capacity (fn = ft) projects
    every other action to zero, and a probe of any of them leaves it there."""
    n = t.shape[0]
    probe_row = np.full((n, 6), -1, np.int64)
    total = n
    for r in range(n):
        for p in range(6):
            if p == 2 or not normal_only[r]:
                probe_row[r, p] = total
                total += 1
    act = np.empty((total, 6))
    ft_ = np.empty(total)
    l1_ = np.empty(total)
    l2_ = np.empty(total)
    mu_ = np.empty(total)
    al_ = np.empty(total)
    s1_ = np.empty(total)
    s2_ = np.empty(total)
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
            ft_[row] = ft[r]
            l1_[row] = l1[i]
            l2_[row] = l2[i]
            mu_[row] = friction[i]
            al_[row] = alpha[i]
            s1_[row] = snap1[i]
            s2_[row] = snap2[i]
    proj = np.empty((total, 6))
    flags = np.empty(total, dtype=np.uint8)
    util = np.empty(0)
    on = total >= 0  # True, as a variable: a literal True would compile _nb_evaluate again
    _nb_evaluate(act, ft_, l1_, l2_, mu_, al_, s1_, s2_, on, on, energy, proj, flags, util)
    for r in range(n):
        for a in range(6):
            for p in range(6):
                row = probe_row[r, p]
                if row < 0:
                    out[r, a, p] = 0.0
                else:
                    d = (proj[row, a] - proj[r, a]) / h[r, p]
                    out[r, a, p] = d * k[r, p]


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
    l1r = 0.0 if rock2 else _nb_reduced_side(l1, abs(m2), probe, snap1)
    l2r = 0.0 if rock1 else _nb_reduced_side(l2, abs(m1), probe, snap2)
    c_t = _nb_torsion_constant(l1r, l2r)
    rho = _nb_energy_radius(l1, l2)
    r0 = math.hypot(t[0], t[1])
    u = r0 * mu
    v = abs(t[5]) / rho * c_t * mu / rho
    if not (u > 0.0 or v > 0.0):
        return True  # nothing to return: no shear, no torsion
    s, ok = _nb_radial_factor(v / al, 0.5 * u, al / (al - 1.0))
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
def _nb_row_tangent(t, p, fti, l1, l2, mu, al, snap1, snap2, flag, k, fd_step, out, g) -> bool:
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
    or a projection that is not the closest point (the radial fallback)."""
    f1 = t[0]
    f2 = t[1]
    fn = t[2]
    m1 = t[3]
    m2 = t[4]
    m3 = t[5]
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
    # takes the elastic side, as a shear within SHEAR_TORSION_TOLERANCE of Eq. (A5) does: the
    # rocking side's zero stiffness made S34 take 3.5x the iterations
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
        if fsu < _TINY_CAPACITY or not r0 > 0.0:
            return False
        rho = _nb_energy_radius(l1, l2)
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
        l1r = _nb_reduced_side(l1, abs_m2c, cap, snap1)
        l2r = _nb_reduced_side(l2, abs_m1c, cap, snap2)
        pinned1 = l1r == 0.0  # snapped to zero: stays there under a small change
        pinned2 = l2r == 0.0
        for q in range(6):
            if not pinned1:
                g[3, q] = -2.0 * g[2, q] / cap + 2.0 * abs_m2c / (cap * cap) * g[0, q]
            if not pinned2:
                g[4, q] = -2.0 * g[1, q] / cap + 2.0 * abs_m1c / (cap * cap) * g[0, q]
        c_t = _nb_torsion_constant(l1r, l2r)
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


# the interface law's kernels (masonry_dem.constitutive.law), here beside the check they call:
# numba's disk cache is renewed when a function's own file changes, not its callees' files


@_jit
def _nb_forces(
    x, h_ptr, h_idx, h_val, kbar, plastic, cracked, tensile_force,
    l1, l2, friction, alpha, snap1, snap2, energy, brittle, t_ptr, t_idx, t_val, n_out,
):  # fmt: skip
    """Relative displacements ``H x``, trial actions, their projection (flags) and the
    generalised forces ``H^T actions`` in one pass: the operations of the sparse products
    (row by row, from 0, in stored order) and of :meth:`InterfaceLaw.respond`, so the same
    bits. The last value is False, with nothing projected, if a trial action is not finite."""
    m = kbar.shape[0]
    rel = np.empty((m, 6))
    trial = np.empty((m, 6))
    ft = np.empty(m)
    actions = np.empty((m, 6))
    flags = np.zeros(m, dtype=np.uint8)
    internal = np.zeros(n_out)
    bad = 0
    for i in range(m):
        ft[i] = 0.0 if cracked[i] else tensile_force[i]
        for j in range(6):
            r = 6 * i + j
            total = 0.0
            for t in range(h_ptr[r], h_ptr[r + 1]):
                total += h_val[t] * x[h_idx[t]]
            rel[i, j] = total
            trial[i, j] = kbar[i, j] * (total - plastic[i, j])
            bad += 0 if math.isfinite(trial[i, j]) else 1
    if bad:
        return rel, trial, ft, actions, flags, internal, False
    util = np.empty(0)
    on = bad == 0  # True, as a variable: a literal True would compile _nb_evaluate again
    _nb_evaluate(
        trial, ft, l1, l2, friction, alpha, snap1, snap2, on, on, energy, actions, flags, util
    )
    if brittle:
        for i in range(m):
            if flags[i] & FLAG_DETACHED:
                for j in range(6):
                    actions[i, j] = 0.0
    flat = actions.reshape(-1)
    for r in range(n_out):
        total = 0.0
        for t in range(t_ptr[r], t_ptr[r + 1]):
            total += t_val[t] * flat[t_idx[t]]
        internal[r] = total
    return rel, trial, ft, actions, flags, internal, True


@_jit
def _nb_law_tangent(
    trial, ft, flags, actions, k, floor, contact_band, fd_step, l1, l2, friction, alpha, snap1,
    snap2, energy, analytic,
):  # fmt: skip
    """:meth:`InterfaceLaw.tangent` in one compiled call: diag(kbar), zero for open joints,
    the derivative of the projection at yielded rows (taken at the contact side) and floor x
    kbar. The derivative is analytic (:func:`_nb_row_tangent`) where ``analytic`` and the row
    allows it, else the forward difference (the operations of the batched numpy version, so
    the same bits)."""
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
            trial[i], actions[i], ft[i], l1[i], l2[i], friction[i], alpha[i], snap1[i],
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
    count = 0
    for i in range(m):
        if differenced[i]:
            rows[count] = i
            count += 1
    if count:
        t = np.empty((count, 6))
        h = np.empty((count, 6))
        ft_rows = np.empty(count)
        k_rows = np.empty((count, 6))
        normal_only = np.empty(count, np.bool_)
        for r in range(count):
            i = rows[r]
            for j in range(6):
                k_rows[r, j] = k[i, j]
            _nb_contact_side(trial[i], ft[i], fd_step, t[r], h[r])
            ft_rows[r] = ft[i]
            # detached joints in the contact band sit at zero capacity (fn = ft): only fn
            # moves their projection
            normal_only[r] = flags[i] == FLAG_DETACHED
        out = np.empty((count, 6, 6))
        _nb_fd_tangent(
            t, h, ft_rows, rows, l1, l2, friction, alpha, snap1, snap2, energy, k_rows,
            normal_only, out,
        )  # fmt: skip
        for r in range(count):
            for a in range(6):
                for b in range(6):
                    T[rows[r], a, b] = out[r, a, b]
    for i in range(m):
        for j in range(6):
            T[i, j, j] += floor * k[i, j]
    return T


def fd_tangent(
    trial: NDArray,
    h: NDArray,
    ft: NDArray,
    rows: NDArray,
    dom: _Domain,
    kbar: NDArray,
    projection: str = "energy",
    normal_only: NDArray | None = None,
) -> NDArray:
    """(n, 6, 6) forward-difference tangent of the projection at ``trial`` (n, 6), steps ``h``
    (n, 6), for the rows ``rows`` of ``dom`` (``ft`` and ``kbar`` already taken at those rows);
    ``normal_only`` (n,) marks rows at zero capacity, probed along fn alone; see
    :func:`_nb_fd_tangent`."""
    n = trial.shape[0]
    out = np.empty((n, 6, 6))
    _nb_fd_tangent(
        _writable_c(trial),
        _writable_c(h),
        _writable_c(ft),
        np.ascontiguousarray(rows, dtype=np.int64),
        *dom.kernel_arrays,
        projection == "energy",
        _writable_c(kbar),
        np.zeros(n, dtype=np.bool_) if normal_only is None else np.asarray(normal_only, bool),
        out,
    )
    return out


def _run_kernel(
    act: NDArray,
    ft: NDArray,
    dom: _Domain,
    torsion_bending_interaction: bool,
    projection_only: bool,
    projection: str,
) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`_nb_evaluate` on fresh output arrays: (projected (m, 6), flags (m,), utilisation
    (m,), empty when ``projection_only``)."""
    m = act.shape[0]
    proj = np.empty((m, 6))
    flags = np.empty(m, dtype=np.uint8)
    util = np.empty(0 if projection_only else m)
    n_radial, n_energy = _nb_evaluate(
        _writable_c(act),
        _writable_c(ft),
        *dom.kernel_arrays,
        bool(torsion_bending_interaction),
        bool(projection_only),
        projection == "energy",
        proj,
        flags,
        util,
    )
    if n_radial:  # pragma: no cover - Newton on a convex increasing function converges
        logger.warning("radial factor: Newton did not converge to %g", _NEWTON_RTOL)
    if n_energy:  # rows at round-off; they fell back to the radial return off the boundary
        logger.debug("energy projection: %d rows did not converge", n_energy)
    return proj, flags, util


def _projection_and_flags(
    act: NDArray,
    ft: NDArray,
    dom: _Domain,
    projection: str = "energy",
    torsion_bending_interaction: bool = True,
) -> tuple[NDArray, NDArray]:
    """The projected actions (m, 6) and bit flags (m,) of :func:`_evaluate`, bit for bit,
    without the utilisation: the radial factor of the rows well inside Eq. (A5) is skipped.
    For the residuals of a Newton search or a time step, where only the forces count."""
    proj, flags, _ = _run_kernel(act, ft, dom, torsion_bending_interaction, True, projection)
    return proj, flags


def _writable_c(x: NDArray) -> NDArray:
    """``x`` as a writable C-contiguous float64 array (one compiled signature for all calls)."""
    if x.dtype == np.float64 and x.flags.c_contiguous and x.flags.writeable:
        return x
    return np.array(x, dtype=np.float64, order="C")


def _evaluate(
    act: NDArray,
    ft: NDArray,
    dom: _Domain,
    torsion_bending_interaction: bool = True,
    projection: str = "energy",
) -> StrengthCheck:
    """:func:`check_strength` on validated inputs (``act`` (m, 6), ``ft`` (m,) >= 0).

    The compiled :func:`_nb_evaluate`, which gives what the numpy reference of the tests gives
    (the same floating-point operations row by row: the finite-difference tangent of the law
    divides differences of projections by 1e-7 and must not see a changed last bit).
    :func:`_projection_and_flags` is the same check without the utilisation.
    """
    proj, flags, util = _run_kernel(act, ft, dom, torsion_bending_interaction, False, projection)
    return StrengthCheck(
        projected=proj,
        state=_STATE_OF_FLAGS[flags],
        flags=flags,
        stiffness_factors=_FACTORS_OF_FLAGS[flags],
        utilisation=util,
    )
