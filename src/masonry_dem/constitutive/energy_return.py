"""The energy return of a sliding row (Section 2.1, Eq. (A5)): the closest point of the
shear-torsion curve (z/b)^alpha + (r/a)^2 = 1 to a trial outside it, in the metric of the
elastic energy, for one row or two rows at once, and the constants of that return that depend
on the interface alone (:data:`row_constants`, stored once per interface).

Scalar numba functions compiled into the kernels of :mod:`~masonry_dem.constitutive.check_kernels`
that call them, transcribed operation for operation from the numpy reference of the tests (no
fast-math), so that a row keeps the reference's bits.
"""

from __future__ import annotations

import math
from typing import Final

import numba
import numpy as np

from masonry_dem.jit import kernel

__all__ = [
    "PROJECTION_MAX_ITER",
    "PROJECTION_TOL",
    "ROW_RHO",
    "ROW_SHEAR_HI",
    "ROW_TA_SWITCH",
    "ROW_TORSION",
    "ROW_T_SWITCH",
    "nb_energy_radius",
    "nb_slide_constants",
    "row_constants",
]

#: safeguarded Newton of the energy projection: iteration cap, and the relative step below
#: which the last step is taken and the row stops (Newton's quadratic convergence leaves an
#: error of the order of its square, at round-off)
PROJECTION_MAX_ITER: Final[int] = 100
PROJECTION_TOL: Final[float] = 1e-9

#: the row functions: compiled into the kernels that call them (x/0 = inf or nan, as numpy)
_jit = numba.njit(error_model="numpy")
#: the parts of the return: inlined into the functions that call them
_part = numba.njit(error_model="numpy", inline="always")


@_jit
def _nb_safe_ratio(demand: float, capacity: float) -> float:
    """:func:`_safe_ratio` of one row."""
    if demand == 0:
        return 0.0
    if capacity > 0:
        return demand / capacity
    return math.inf


@_jit
def _nb_shear_terms(tau, t, ta, a, b, r0, z0, alpha, power) -> tuple[float, float]:
    """:func:`_nb_shear_half` at ``t = tau^power`` with ``ta = t^alpha`` given: the caller
    that knows them (the switch point's constants, :func:`nb_slide_constants`) skips their
    powers."""
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
def _nb_power(x: float, p: float) -> float:
    """``x ** p``, without the call where p = 1 (pow(x, 1) is x exactly: its result is
    representable and the libm's pow errs by less than one unit in the last place)."""
    return x if p == 1.0 else x**p


@_jit
def _nb_shear_half(tau, a, b, r0, z0, alpha, power) -> tuple[float, float]:
    """g = d/dt of half the squared distance from (a sqrt(1 - t^alpha), b t) to (r0, z0) at
    t = tau^power, and dg/dtau; smooth on t in [0, 2^(-1/alpha)]. One row."""
    t = _nb_power(tau, power)
    return _nb_shear_terms(tau, t, t**alpha, a, b, r0, z0, alpha, power)


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


@_part
def _nb_bracket_start(hi: float, start: float) -> float:
    """The first iterate of :func:`_nb_bracketed_newton`: ``start``, mid-bracket if outside."""
    x = 0.5 * hi
    if start > 0.0 and start < hi:
        x = start
    return x


@_part
def _nb_bracket_step(
    torsion, a, b, r0, z0, alpha, power, lo, hi, x
) -> tuple[float, float, float, bool]:
    """One step of :func:`_nb_bracketed_newton`: ``(lo, hi, x, stop)``."""
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
    done = abs(step) <= PROJECTION_TOL * (x if x > 1e-300 else 1e-300)
    inside = newton > lo and newton < hi and math.isfinite(newton)
    x = newton if (inside or done) else 0.5 * (lo + hi)
    stop = done or hi - lo <= 4.0 * np.spacing(hi)  # converged, or bracket at round-off
    return lo, hi, x, stop


@_jit
def _nb_bracketed_newton(torsion, a, b, r0, z0, alpha, power, hi, start) -> tuple[float, bool]:
    """Root of g on [0, hi] (g(0) < 0 < g(hi), one sign change) for one row, g being
    :func:`_nb_torsion_half` if ``torsion`` else :func:`_nb_shear_half`: Newton's method from
    ``start`` (mid-bracket if outside it) kept inside the shrinking bracket (bisection where a
    step would leave it); False if it did not converge."""
    lo = 0.0
    x = _nb_bracket_start(hi, start)
    for _ in range(PROJECTION_MAX_ITER):
        lo, hi, x, stop = _nb_bracket_step(torsion, a, b, r0, z0, alpha, power, lo, hi, x)
        if stop:
            return x, True
    return x, False


@_part
def _nb_closest_setup(
    r0, z0, a, b, alpha, radial, t_switch, ta_switch, shear_hi
) -> tuple[bool, bool, float, float, float, float]:
    """The part of :func:`_nb_energy_closest_point` before Newton: ``(newton, torsion,
    power, hi, start, r)``, whether Newton runs and on which half of the curve, its power,
    bracket and start, and r where it does not run (a vertex)."""
    newton = False
    torsion = False
    power = 1.0
    hi = 0.0
    start = 0.0
    r = 0.0
    if r0 > 0 and z0 > 0 and a > 0 and b > 0:
        power = 2.0 if alpha < 2.0 else 1.0
        g_switch = _nb_shear_terms(t_switch, t_switch, ta_switch, a, b, r0, z0, alpha, 1.0)[0]
        near_shear = g_switch >= 0.0
        # alpha = 1 has a vertex on the shear axis; points in its normal cone return to it
        vertex = alpha == 1.0 and (r0 - a) * 0.5 * a >= z0 * b
        if vertex:
            r = a
        if near_shear and not vertex:
            newton = True
            start = _nb_power(radial * z0 / b, 1 / power)
            hi = shear_hi
        if not near_shear:  # (after the vertex, as the numpy version does)
            newton = True
            torsion = True
            start = radial * r0 / a
            hi = math.sqrt(0.5)
            power = 1.0
    return newton, torsion, power, hi, start, r


@_part
def _nb_closest_finish(newton, torsion, x, r0, z0, a, b, alpha, power, r) -> tuple[float, float]:
    """The part of :func:`_nb_energy_closest_point` after Newton (``x`` its root): (r, z)."""
    z = 0.0
    if newton and not torsion:
        t = _nb_power(x, power)
        r = a * math.sqrt(max(1.0 - t**alpha, 0.0))
        z = b * t
    if newton and torsion:
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
    return r, z


@_jit
def _nb_energy_closest_point(
    r0, z0, a, b, alpha, radial, t_switch, ta_switch, shear_hi
) -> tuple[float, float, bool]:
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
    Newton at the radial point, usually a few steps from the answer. ``t_switch``,
    ``ta_switch`` and ``shear_hi`` are the switch point's constants of the row's alpha
    (:func:`nb_slide_constants`).
    Degenerate capacities: b = 0 (no torsion, e.g. a joint rocking on a corner) keeps
    the shear up to a and drops the torsion; a = 0 drops both. One row; False if Newton did not converge."""
    newton, torsion, power, hi, start, r = _nb_closest_setup(
        r0, z0, a, b, alpha, radial, t_switch, ta_switch, shear_hi
    )
    x = 0.0
    ok = True
    if newton:
        x, ok = _nb_bracketed_newton(torsion, a, b, r0, z0, alpha, power, hi, start)
    r, z = _nb_closest_finish(newton, torsion, x, r0, z0, a, b, alpha, power, r)
    return r, z, ok


@_jit
def _nb_energy_closest_points(first, second) -> tuple[float, float, bool, float, float, bool]:
    """:func:`_nb_energy_closest_point` of two rows, each given as the tuple of its
    arguments: ``(r1, z1, ok1, r2, z2, ok2)``, the same bits. Where both run Newton their
    steps alternate in one loop, each row stopping at its own convergence (see
    :func:`nb_radial_factors`)."""
    r01, z01, a1, b1, alpha1, radial1, t_switch1, ta_switch1, shear_hi1 = first
    r02, z02, a2, b2, alpha2, radial2, t_switch2, ta_switch2, shear_hi2 = second
    newton1, torsion1, power1, hi1, start1, r1 = _nb_closest_setup(
        r01, z01, a1, b1, alpha1, radial1, t_switch1, ta_switch1, shear_hi1
    )
    newton2, torsion2, power2, hi2, start2, r2 = _nb_closest_setup(
        r02, z02, a2, b2, alpha2, radial2, t_switch2, ta_switch2, shear_hi2
    )
    x1 = 0.0
    x2 = 0.0
    ok1 = True
    ok2 = True
    if newton1 and newton2:
        lo1 = 0.0
        lo2 = 0.0
        x1 = _nb_bracket_start(hi1, start1)
        x2 = _nb_bracket_start(hi2, start2)
        stop1 = False
        stop2 = False
        for _ in range(PROJECTION_MAX_ITER):
            if not stop1:
                lo1, hi1, x1, stop1 = _nb_bracket_step(
                    torsion1, a1, b1, r01, z01, alpha1, power1, lo1, hi1, x1
                )
            if not stop2:
                lo2, hi2, x2, stop2 = _nb_bracket_step(
                    torsion2, a2, b2, r02, z02, alpha2, power2, lo2, hi2, x2
                )
            if stop1 and stop2:
                break
        ok1 = stop1
        ok2 = stop2
    elif newton1:
        x1, ok1 = _nb_bracketed_newton(torsion1, a1, b1, r01, z01, alpha1, power1, hi1, start1)
    elif newton2:
        x2, ok2 = _nb_bracketed_newton(torsion2, a2, b2, r02, z02, alpha2, power2, hi2, start2)
    r1, z1 = _nb_closest_finish(newton1, torsion1, x1, r01, z01, a1, b1, alpha1, power1, r1)
    r2, z2 = _nb_closest_finish(newton2, torsion2, x2, r02, z02, a2, b2, alpha2, power2, r2)
    return r1, z1, ok1, r2, z2, ok2


@_jit
def nb_energy_radius(l1: float, l2: float) -> float:
    """rho = sqrt(J / A) of an l1 x l2 rectangle: z = |m3| / rho puts torsion in the units of
    shear so that distance in (|f|, z) is the elastic energy of a correction (kt A, kt J)."""
    return math.sqrt((l1 * l1 + l2 * l2) / 12.0)


#: the columns of a row's constants (:data:`row_constants`): the torsion constant of the
#: whole rectangle, and :func:`nb_slide_constants`
ROW_TORSION, ROW_T_SWITCH, ROW_TA_SWITCH, ROW_SHEAR_HI, ROW_RHO = range(5)


@_jit
def nb_slide_constants(l1: float, l2: float, alpha: float) -> tuple[float, float, float, float]:
    """The constants of a sliding row's energy return that depend on the interface alone:
    the switch point between the two halves of the curve, ``t_switch = 2^(-1/alpha)``, its
    ``t_switch^alpha``, the shear half's bracket ``t_switch^(1/power)`` and the energy
    radius rho (:func:`nb_energy_radius`). The expressions the return used to evaluate at
    every call, so a row gets the same bits whether they are stored or computed here."""
    t_switch = 0.5 ** (1.0 / alpha)
    power = 2.0 if alpha < 2.0 else 1.0
    shear_hi = _nb_power(t_switch, 1 / power)
    return t_switch, t_switch**alpha, shear_hi, nb_energy_radius(l1, l2)


@kernel(error_model="numpy")
def row_constants(l1, l2, alpha, torsion):
    """(m, 5) constants of every row, columns :data:`ROW_TORSION` .. :data:`ROW_RHO`:
    ``torsion`` (cT of the whole rectangles) and :func:`nb_slide_constants`, stored once per
    interface so that the forces kernel does not recompute their powers at every call."""
    m = l1.shape[0]
    out = np.empty((m, 5))
    for i in range(m):
        out[i, ROW_TORSION] = torsion[i]
        t_switch, ta_switch, shear_hi, rho = nb_slide_constants(l1[i], l2[i], alpha[i])
        out[i, ROW_T_SWITCH] = t_switch
        out[i, ROW_TA_SWITCH] = ta_switch
        out[i, ROW_SHEAR_HI] = shear_hi
        out[i, ROW_RHO] = rho
    return out
