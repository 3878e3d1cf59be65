"""The strength check of Section 2.1 compiled (numba), one interface (row) at a time.

Each ``_nb_`` function is the scalar transcription of the numpy function of the same name
without the prefix (:mod:`masonry_dem.constitutive.strength`, or the reference of the tests in
tests/constitutive/numpy_reference.py), operation for operation and in the same order (no
fast-math, so no reassociation or fused multiply-adds), so that a row comes out as the numpy
reference gives it up to the last bit of the libm functions. :data:`evaluate_rows` runs the
row function over all rows; the kernels of the interface law
(:mod:`~masonry_dem.constitutive.law_kernels`) call the row function in their own loops.
Compiled on first use and cached on disk (see :mod:`masonry_dem.jit`); importing compiles nothing.
"""

from __future__ import annotations

import math
from typing import Final

import numba

from masonry_dem.constitutive.energy_return import (
    _nb_energy_closest_point,
    _nb_energy_closest_points,
    _nb_safe_ratio,
    nb_slide_constants,
)
from masonry_dem.constitutive.states import (
    FLAG_DETACHED,
    FLAG_ROCKING_1,
    FLAG_ROCKING_2,
    FLAG_SHEAR_TORSION,
)
from masonry_dem.jit import kernel

__all__ = [
    "NEWTON_MAX_ITER",
    "NEWTON_RTOL",
    "SHEAR_TORSION_TOLERANCE",
    "SNAP",
    "TINY_CAPACITY",
    "evaluate_rows",
    "nb_check_row",
    "nb_evaluate_row",
    "nb_project_rows",
    "nb_radial_factor",
    "nb_radial_factors",
    "nb_reduced_side",
    "nb_torsion_constant",
]

#: capacities near the subnormal range lose digits in the energy return: radial there
TINY_CAPACITY: Final[float] = 1e-280
#: A trial violates Eq. (A5) only if its radial demand/capacity ratio (see ``check_strength``)
#: exceeds 1 by more than this. The radial projection lands on the boundary to ~1e-13, so
#: re-checking projected actions reports them elastic (and returns them unchanged).
SHEAR_TORSION_TOLERANCE: Final[float] = 1e-9
#: Newton on the radial factor: iteration cap and relative step of convergence
NEWTON_MAX_ITER: Final[int] = 60
NEWTON_RTOL: Final[float] = 1e-13
#: relative size below which a reduced side of the torsion rectangle is zero
SNAP: Final[float] = 1e-12

#: the row functions: compiled into the kernels that call them (x/0 = inf or nan, as numpy)
_jit = numba.njit(error_model="numpy")
#: the parts of the row check: inlined into the functions that call them
_part = numba.njit(error_model="numpy", inline="always")


@_jit
def nb_torsion_constant(l1: float, l2: float) -> float:
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


@_part
def _nb_radial_step(tau: float, ln_a: float, ln_c: float, alpha: float) -> tuple[float, bool]:
    """One step of :func:`_radial_newton` on one row: the next tau, and whether the step was
    below the tolerance (the row stops there)."""
    p = math.exp(alpha * (tau + ln_a))
    q = math.exp(2.0 * (tau + ln_c))
    total = p + q
    step = math.log(total) * total / (alpha * p + 2.0 * q)
    tau = tau - step
    return tau, not abs(step) > NEWTON_RTOL


@_jit
def _nb_radial_t(big_a: float, big_c: float, alpha: float) -> tuple[float, bool]:
    """:func:`_radial_newton` of one row (alpha other than 1 and 2); False if Newton did not
    converge."""
    ln_a = math.log(big_a)  # -inf where A underflowed to 0
    ln_c = math.log(big_c)
    tau = 0.0
    for _ in range(NEWTON_MAX_ITER):
        tau, done = _nb_radial_step(tau, ln_a, ln_c, alpha)
        if done:
            return math.exp(tau), True
    return math.exp(tau), False


@_part
def _nb_radial_closed(a: float, c: float, alpha: float) -> tuple[float, bool, float, float, float]:
    """The radial factor of one row where it has a closed form, ``(s, newton, m, A, C)``:
    ``newton`` says it has none (both demands, alpha other than 1 and 2), and then
    ``s = t / m`` with t from :func:`_nb_radial_t` of ``A, C`` (see :func:`_radial_t`)."""
    m = max(a, c)
    s = 1.0 / m  # inf at a = c = 0, 0 at inf
    newton = False
    big_a = 0.0
    big_c = 0.0
    if min(a, c) > 0 and m < math.inf:
        big_a = a / m
        big_c = c / m
        if alpha == 2.0:
            s = 1.0 / math.hypot(big_a, big_c) / m
        elif alpha == 1.0:
            s = 2.0 / (big_a + math.sqrt(big_a * big_a + 4.0 * big_c * big_c)) / m
        else:
            newton = True
    return s, newton, m, big_a, big_c


@_jit
def nb_radial_factor(a: float, c: float, alpha: float) -> tuple[float, bool]:
    """:func:`_radial_factor` of one row."""
    s, newton, m, big_a, big_c = _nb_radial_closed(a, c, alpha)
    ok = True
    if newton:
        t, ok = _nb_radial_t(big_a, big_c, alpha)
        s = t / m
    return s, ok


@_jit
def nb_radial_factors(a1, c1, alpha1, a2, c2, alpha2) -> tuple[float, bool, float, bool]:
    """:func:`nb_radial_factor` of two rows, ``(s1, ok1, s2, ok2)``, the same bits: where
    both need Newton their steps alternate in one loop, each row stopping at its own
    convergence, so that the processor overlaps the two chains of exp and log (a row's
    steps wait on each other; the two rows' do not)."""
    s1, newton1, m1, big_a1, big_c1 = _nb_radial_closed(a1, c1, alpha1)
    s2, newton2, m2, big_a2, big_c2 = _nb_radial_closed(a2, c2, alpha2)
    ok1 = True
    ok2 = True
    if newton1 and newton2:
        ln_a1 = math.log(big_a1)
        ln_c1 = math.log(big_c1)
        ln_a2 = math.log(big_a2)
        ln_c2 = math.log(big_c2)
        tau1 = 0.0
        tau2 = 0.0
        done1 = False
        done2 = False
        for _ in range(NEWTON_MAX_ITER):
            if not done1:
                tau1, done1 = _nb_radial_step(tau1, ln_a1, ln_c1, alpha1)
            if not done2:
                tau2, done2 = _nb_radial_step(tau2, ln_a2, ln_c2, alpha2)
            if done1 and done2:
                break
        s1 = math.exp(tau1) / m1
        s2 = math.exp(tau2) / m2
        ok1 = done1
        ok2 = done2
    elif newton1:
        t1, ok1 = _nb_radial_t(big_a1, big_c1, alpha1)
        s1 = t1 / m1
    elif newton2:
        t2, ok2 = _nb_radial_t(big_a2, big_c2, alpha2)
        s2 = t2 / m2
    return s1, ok1, s2, ok2


@_jit
def nb_reduced_side(side: float, abs_moment: float, cap: float, snap: float) -> float:
    """Side of the rectangle of uniform compression ``cap`` carrying the bending moment
    ``abs_moment`` about the other axis (:func:`_reduced_sides` of one row): zero at or
    below ``snap`` (a moment clipped to its rocking limit leaves round-off)."""
    reduced = side - 2.0 * abs_moment / cap
    reduced = min(reduced, side)
    if reduced <= snap:
        reduced = 0.0
    return reduced


@_part
def _nb_demands(f1, f2, fn, m1, m2, m3, fti, c0, l1, l2, mu, snap1, snap2, torsion_bending_interaction):  # fmt: skip
    """The first part of :func:`nb_check_row`: detachment, the rocking clip and the
    shear-torsion demand/capacity ratios of one row, ``(detached, rock1, rock2, abs_m1,
    abs_m2, m1_lim, m2_lim, abs_m1c, abs_m2c, fsu, abs_m3, m3u, shear, a, c)``.

    ``c0`` is the cohesive force beyond mu ft, ``(c - mu ft) A`` >= 0: the Mohr-Coulomb
    strength c A - mu fn = mu (ft - fn) + c0 below the tension cap. Where the rocking leaves
    the rectangle of uniform compression ``l1' x l2'``, the rest of the interface sits at the
    cap (stress ft), where the shear strength is c - mu ft: so m3u = cT(l1', l2') mu (ft - fn)
    + cT(l1, l2) c0. With c0 = 0 (the paper's c = mu ft) the operations are the paper's."""
    # detachment
    detached = fn > fti
    live = not detached
    cap = 0.0 if detached else fti - fn

    # rocking: clip the bending moments to the eccentricity limits
    half = 0.5 * cap
    m1_lim = half * l2
    m2_lim = half * l1
    abs_m1 = abs(m1)
    abs_m2 = abs(m2)
    rock1 = abs_m1 > m1_lim and live
    rock2 = abs_m2 > m2_lim and live
    abs_m1c = min(abs_m1, m1_lim)
    abs_m2c = min(abs_m2, m2_lim)

    # shear and torsion: demand/capacity ratios a = |m3|/m3u, c = |f|/fsu
    fsu = mu * cap
    cohesive = c0 > 0 and live
    abs_m3 = abs(m3)
    m3u = 0.0
    if abs_m3 > 0 and cap > 0:
        if torsion_bending_interaction:
            l1r = nb_reduced_side(l1, abs_m2c, cap, snap1)
            l2r = nb_reduced_side(l2, abs_m1c, cap, snap2)
            c_t = nb_torsion_constant(l1r, l2r)
        else:
            c_t = nb_torsion_constant(l1, l2)
        m3u = c_t * fsu
    if cohesive:
        fsu += c0
        if abs_m3 > 0:
            m3u += nb_torsion_constant(l1, l2) * c0
    shear = math.hypot(f1, f2)
    a = abs_m3 / m3u if abs_m3 > 0 else 0.0  # 0/0 = 0, d/0 = inf (no capacity)
    c = shear / fsu if shear > 0 else 0.0
    return detached, rock1, rock2, abs_m1, abs_m2, m1_lim, m2_lim, abs_m1c, abs_m2c, fsu, abs_m3, m3u, shear, a, c  # fmt: skip


@_part
def _nb_energy_actions(f1, f2, m3, shear, abs_m3, fsu, m3u, al, s, rho, r, z):
    """(f1', f2', m3') of a sliding row from the closest point (r, z) of its energy return
    (the radial return ``s`` at capacities on the edge of floating point)."""
    shear_scale = _nb_safe_ratio(r, shear)
    if not math.isfinite(shear_scale):
        shear_scale = 0.0
    m3_new = math.copysign(z * rho, m3)
    # capacities at the edge of floating point (subnormal friction or sides): the
    # radial return, which lands on the boundary by construction
    phi = _nb_safe_ratio(z * rho, m3u) ** al + _nb_safe_ratio(r, fsu) ** 2
    off = not abs(phi - 1.0) <= 1e-9 and m3u > 0 and fsu > 0
    off = off or abs_m3 == 0  # pure shear: the same point, with the radial round-off
    off = off or fsu < TINY_CAPACITY
    if off:
        shear_scale = s
        m3_new = m3 * s
    return f1 * shear_scale, f2 * shear_scale, m3_new


@_part
def _nb_row_flags(sliding, rock1, rock2, detached) -> int:
    """The bit flags of a checked row."""
    return (
        (FLAG_SHEAR_TORSION if sliding else 0)
        | (FLAG_ROCKING_1 if rock1 else 0)
        | (FLAG_ROCKING_2 if rock2 else 0)
        | (FLAG_DETACHED if detached else 0)
    )


@_jit
def nb_check_row(
    f1, f2, fn, m1, m2, m3, fti, c0, l1, l2, mu, al, snap1, snap2,
    torsion_bending_interaction, projection_only, energy,
    stored, t_switch, ta_switch, shear_hi, rho,
):  # fmt: skip
    """The strength check of one row, scalars in and out: the trial actions ``f1 .. m3`` and
    the row's constants (``fti`` the tensile force, ``c0`` the cohesive force beyond mu ft) (``t_switch`` .. ``rho``: :func:`nb_slide_constants`, computed here
    unless ``stored``) give ``(p1, p2, pn, p4, p5, p6, flags, utilisation, radial_failed,
    energy_failed)``: the projection, its flags, the utilisation (0 with
    ``projection_only``) and whether the radial factor and the energy projection did not
    converge (0 or 1 each). Scalars, not the arrays: every array a compiled row function
    takes adds the cost of its reference to each call (docs/history/solvers_record.md, "One
    evaluation of the interface law")."""
    n_radial = 0
    n_energy = 0
    (
        detached,
        rock1,
        rock2,
        abs_m1,
        abs_m2,
        m1_lim,
        m2_lim,
        abs_m1c,
        abs_m2c,
        fsu,
        abs_m3,
        m3u,
        shear,
        a,
        c,
    ) = _nb_demands(  # fmt: skip  # noqa: E501
        f1, f2, fn, m1, m2, m3, fti, c0, l1, l2, mu, snap1, snap2, torsion_bending_interaction
    )
    live = not detached

    u_st = 0.0
    s = 1.0
    sliding = False
    if projection_only:
        # a + c^2 >= a^alpha + c^2 for a, c <= 1 and alpha >= 1: below 1 no row slides
        if live and not a + c * c < 0.999:
            s, ok = nb_radial_factor(a, c, al)
            n_radial += 0 if ok else 1
            sliding = 1.0 / s > 1.0 + SHEAR_TORSION_TOLERANCE
    else:
        s, ok = nb_radial_factor(a, c, al)
        n_radial += 0 if ok else 1
        u_st = 1.0 / s  # radial demand/capacity ratio of Eq. (A5)
        sliding = u_st > 1.0 + SHEAR_TORSION_TOLERANCE and live

    # projection (untouched entries are kept bitwise)
    p1 = f1
    p2 = f2
    pn = fn
    p4 = math.copysign(abs_m1c, m1)
    p5 = math.copysign(abs_m2c, m2)
    p6 = m3
    if sliding and not energy:
        p1 *= s
        p2 *= s
        p6 *= s
    elif sliding:
        if not stored:
            t_switch, ta_switch, shear_hi, rho = nb_slide_constants(l1, l2, al)
        r, z, ok = _nb_energy_closest_point(
            shear, abs_m3 / rho, fsu, m3u / rho, al, s, t_switch, ta_switch, shear_hi
        )
        n_energy += 0 if ok else 1
        p1, p2, p6 = _nb_energy_actions(f1, f2, m3, shear, abs_m3, fsu, m3u, al, s, rho, r, z)
    if detached:
        p1 = 0.0
        p2 = 0.0
        pn = fti
        p4 = 0.0
        p5 = 0.0
        p6 = 0.0

    flags = _nb_row_flags(sliding, rock1, rock2, detached)
    util = 0.0
    if projection_only:
        return p1, p2, pn, p4, p5, p6, flags, util, n_radial, n_energy

    # utilisation
    u_tension = max(fn, 0.0) / fti  # ft = 0: inf in tension, NaN otherwise
    if math.isnan(u_tension):  # ft = 0: 1 at fn = 0, 0 in compression
        u_tension = 1.0 if fn >= 0 else 0.0
    if detached:
        util = u_tension
    else:
        u_rock = abs_m1 / m1_lim if abs_m1 > 0 else 0.0
        u_rock2 = abs_m2 / m2_lim if abs_m2 > 0 else 0.0
        util = max(max(max(u_rock, u_rock2), u_tension), u_st)
    return p1, p2, pn, p4, p5, p6, flags, util, n_radial, n_energy


@_jit
def nb_project_rows(first, second, energy):
    """The projection and flags of two rows (:func:`nb_check_row` with the torsion-bending
    interaction, ``projection_only`` and the rows' stored constants), the same bits: each
    row is a tuple ``(f1, f2, fn, m1, m2, m3, ft, c0, l1, l2, mu, alpha, snap1, snap2, t_switch,
    ta_switch, shear_hi, rho)``; returns ``(p1 .. p6)`` and the flags of each. The iterations
    of the two rows' radial factors and energy returns alternate in one loop
    (:func:`nb_radial_factors`, :func:`_nb_energy_closest_points`): one row's steps wait on
    each other, the two rows' do not, so the processor overlaps them."""
    f1, f2, fn, m1, m2, m3, fti, c0, l1, l2, mu, al, snap1, snap2, t_switch, ta_switch, shear_hi, rho = first  # fmt: skip  # noqa: E501
    f1_b, f2_b, fn_b, m1_b, m2_b, m3_b, fti_b, c0_b, l1_b, l2_b, mu_b, al_b, snap1_b, snap2_b, t_switch_b, ta_switch_b, shear_hi_b, rho_b = second  # fmt: skip  # noqa: E501
    on = True
    detached, rock1, rock2, _, _, _, _, abs_m1c, abs_m2c, fsu, abs_m3, m3u, shear, a, c = _nb_demands(f1, f2, fn, m1, m2, m3, fti, c0, l1, l2, mu, snap1, snap2, on)  # fmt: skip  # noqa: E501
    detached_b, rock1_b, rock2_b, _, _, _, _, abs_m1c_b, abs_m2c_b, fsu_b, abs_m3_b, m3u_b, shear_b, a_b, c_b = _nb_demands(f1_b, f2_b, fn_b, m1_b, m2_b, m3_b, fti_b, c0_b, l1_b, l2_b, mu_b, snap1_b, snap2_b, on)  # fmt: skip  # noqa: E501
    # a + c^2 >= a^alpha + c^2 for a, c <= 1 and alpha >= 1: below 1 no row slides
    check = not detached and not a + c * c < 0.999
    check_b = not detached_b and not a_b + c_b * c_b < 0.999
    s = 1.0
    s_b = 1.0
    if check and check_b:
        s, _, s_b, _ = nb_radial_factors(a, c, al, a_b, c_b, al_b)
    elif check:
        s = nb_radial_factor(a, c, al)[0]
    elif check_b:
        s_b = nb_radial_factor(a_b, c_b, al_b)[0]
    sliding = check and 1.0 / s > 1.0 + SHEAR_TORSION_TOLERANCE
    sliding_b = check_b and 1.0 / s_b > 1.0 + SHEAR_TORSION_TOLERANCE

    # projection (untouched entries are kept bitwise)
    p1, p2, pn, p4, p5, p6 = f1, f2, fn, math.copysign(abs_m1c, m1), math.copysign(abs_m2c, m2), m3  # fmt: skip  # noqa: E501
    p1_b, p2_b, pn_b, p4_b, p5_b, p6_b = f1_b, f2_b, fn_b, math.copysign(abs_m1c_b, m1_b), math.copysign(abs_m2c_b, m2_b), m3_b  # fmt: skip  # noqa: E501
    if not energy:
        if sliding:
            p1 *= s
            p2 *= s
            p6 *= s
        if sliding_b:
            p1_b *= s_b
            p2_b *= s_b
            p6_b *= s_b
    elif sliding or sliding_b:
        point = (shear, abs_m3 / rho, fsu, m3u / rho, al, s, t_switch, ta_switch, shear_hi)
        point_b = (shear_b, abs_m3_b / rho_b, fsu_b, m3u_b / rho_b, al_b, s_b, t_switch_b, ta_switch_b, shear_hi_b)  # fmt: skip  # noqa: E501
        if sliding and sliding_b:
            r, z, _, r_b, z_b, _ = _nb_energy_closest_points(point, point_b)
        elif sliding:
            r, z, _ = _nb_energy_closest_point(*point)
            r_b = z_b = 0.0
        else:
            r_b, z_b, _ = _nb_energy_closest_point(*point_b)
            r = z = 0.0
        if sliding:
            p1, p2, p6 = _nb_energy_actions(f1, f2, m3, shear, abs_m3, fsu, m3u, al, s, rho, r, z)
        if sliding_b:
            p1_b, p2_b, p6_b = _nb_energy_actions(f1_b, f2_b, m3_b, shear_b, abs_m3_b, fsu_b, m3u_b, al_b, s_b, rho_b, r_b, z_b)  # fmt: skip  # noqa: E501
    if detached:
        p1, p2, pn, p4, p5, p6 = 0.0, 0.0, fti, 0.0, 0.0, 0.0
    if detached_b:
        p1_b, p2_b, pn_b, p4_b, p5_b, p6_b = 0.0, 0.0, fti_b, 0.0, 0.0, 0.0
    flags = _nb_row_flags(sliding, rock1, rock2, detached)
    flags_b = _nb_row_flags(sliding_b, rock1_b, rock2_b, detached_b)
    return (p1, p2, pn, p4, p5, p6), flags, (p1_b, p2_b, pn_b, p4_b, p5_b, p6_b), flags_b


@_jit
def nb_evaluate_row(
    i,
    act,
    ft,
    c0,
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
    """Row ``i`` of :func:`_nb_evaluate` (:func:`nb_check_row` of the row, which computes the
    constants of a sliding row, written into ``proj``, ``flags`` and, unless
    ``projection_only``, ``util``); returns whether its radial factor and its energy
    projection did not converge (0 or 1 each)."""
    stored = act.shape[0] < 0  # False, as a variable: a literal would compile the row again
    p1, p2, pn, p4, p5, p6, flag, u, n_radial, n_energy = nb_check_row(
        act[i, 0], act[i, 1], act[i, 2], act[i, 3], act[i, 4], act[i, 5], ft[i], c0[i], l1[i], l2[i],
        friction[i], alpha[i], snap1[i], snap2[i], torsion_bending_interaction, projection_only,
        energy, stored, 0.0, 0.0, 0.0, 0.0,
    )  # fmt: skip
    proj[i, 0] = p1
    proj[i, 1] = p2
    proj[i, 2] = pn
    proj[i, 3] = p4
    proj[i, 4] = p5
    proj[i, 5] = p6
    flags[i] = flag
    if not projection_only:
        util[i] = u
    return n_radial, n_energy


@kernel(parallel=True, error_model="numpy")
def evaluate_rows(
    act, ft, c0, l1, l2, friction, alpha, snap1, snap2, torsion_bending_interaction,
    projection_only, energy, proj, flags, util,
):  # fmt: skip
    """The strength check (see :func:`~masonry_dem.constitutive.strength.check_strength`) row
    by row, into ``proj`` (m, 6), ``flags`` (m,) uint8 and (unless ``projection_only``)
    ``util`` (m,). Returns the numbers of rows whose radial factor and whose energy
    projection did not converge."""
    n_radial = 0
    n_energy = 0
    for i in numba.prange(act.shape[0]):
        # one compiled row function: the parallel loop stays small to compile
        radial_failed, energy_failed = nb_evaluate_row(
            i, act, ft, c0, l1, l2, friction, alpha, snap1, snap2, torsion_bending_interaction,
            projection_only, energy, proj, flags, util,
        )  # fmt: skip
        n_radial += radial_failed
        n_energy += energy_failed
    return n_radial, n_energy
