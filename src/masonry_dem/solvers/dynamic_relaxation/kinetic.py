"""The time steps of a relaxation with kinetic damping at a fixed load, compiled: the inner
loop of :meth:`~masonry_dem.solvers.dynamic_relaxation.integrator.Relaxation._relax` in one
numba function that calls the interface law's kernel itself and runs until the Python side
has something to do (a kinetic-energy peak where a probe or a creep measurement is due) or
the relaxation ends.

It performs the operations of the Python loop in the same order (the dot products through
the same BLAS ``ddot`` numpy calls, elementwise operations one by one), so the same bits:
the same time steps, states and endings. Measured in docs/history/solvers_record.md ("One compiled
time step"); ``DRSettings.compiled_steps=False`` selects the Python loop.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from masonry_dem.constitutive import law_kernels
from masonry_dem.jit import calling_kernel

#: how a call of :func:`kinetic_steps` ended
PEAK, CONVERGED, STALLED, BUDGET, BLOWUP, MECHANISM, MAX_CYCLES, NOT_FINITE = range(8)

# the scalar state carried between calls, as indices into its float and int arrays
KE_PREV, KE_PEAK, BEST_BEFORE, BEST_NOW, COURANT, RNORM = range(6)
CYCLE, OVER, RESTART, PROBED, PEAK_COUNT, STEPS, RESETS, EVALUATIONS = range(8)

_forces: Any = law_kernels.forces.serial  # in each variant, that variant of the law's kernel


def _steps(  # type: ignore[no-untyped-def]  # numba types the arguments
    x, v, fint, R, F, M, W, keep, has_keep, peak_sum, creeping, asking, trans, origin,
    fs, ints, dt, Fn, fscale, tolerance, energy_tolerance, limit, window, max_cycles,
    steps_left, probe_every, blowup_patience,
    rel, trial, ft, actions, flags,
    h_ptr, h_idx, h_val, kbar, plastic, cracked, tensile_force, cohesion,
    l1, l2, friction, alpha, snap1, snap2, constants, energy, brittle, t_ptr, t_idx, t_val, n_out,
):  # fmt: skip
    """Time steps from cycle ``ints[CYCLE] + 1`` on; ``x``, ``v``, ``fint``, ``R``,
    ``peak_sum`` and the scalar state ``fs``, ``ints`` are updated in place. Returns (how it
    ended, and the law's rel, trial, ft, actions, flags at ``x``)."""
    n = x.shape[0]
    v_old = np.empty(n)
    dx = np.empty(n)
    df = np.empty(n)
    a = np.empty(n)
    wr = np.empty(n)
    mv = np.empty(n)
    mkeep = M * keep
    ke_prev, ke_peak = fs[KE_PREV], fs[KE_PEAK]
    best_before, best_now, courant = fs[BEST_BEFORE], fs[BEST_NOW], fs[COURANT]
    over, restart, peak_count = ints[OVER], ints[RESTART] != 0, ints[PEAK_COUNT]
    steps, resets, evaluations = ints[STEPS], ints[RESETS], ints[EVALUATIONS]
    code = MAX_CYCLES
    rnorm = fs[RNORM]
    cycle = ints[CYCLE]
    while cycle < max_cycles:
        cycle += 1
        steps += 1
        if steps > steps_left:
            code = BUDGET
            break
        for i in range(n):
            wr[i] = W[i] * R[i]
        rnorm = np.sqrt(np.dot(wr, wr)) / Fn
        best_now = min(best_now, rnorm)
        if cycle % window == 0:
            if best_now > 0.5 * best_before:
                code = STALLED
                break
            best_before, best_now = best_now, np.inf
        for i in range(n):
            mv[i] = M[i] * v[i]
        ke = 0.5 * np.dot(v, mv)
        ke_peak = max(ke_peak, ke)
        if rnorm <= tolerance and ke <= energy_tolerance * max(ke_peak, 1e-300):
            code = CONVERGED
            cycle -= 1
            break
        h = 0.5 * dt if restart else dt
        for i in range(n):
            a[i] = R[i] / M[i]
            v_old[i] = v[i]
            v[i] = v[i] + h * a[i]
        restart = False
        for i in range(n):
            mv[i] = M[i] * v[i]
        ke_new = 0.5 * np.dot(v, mv)
        if ke_new < ke_prev:  # a peak of the kinetic energy has passed
            resets += 1
            forward = np.dot(v_old, mkeep) if has_keep else 0.0
            if has_keep and forward > 0.0:
                for i in range(n):
                    v[i] = forward * keep[i]
                ke_prev = 0.5 * forward * forward
            else:
                v[:] = 0.0
                ke_prev = 0.0
            restart = True
            h = 0.5 * dt
            for i in range(n):
                x[i] = x[i] - h * v_old[i]
            out = _forces(x, h_ptr, h_idx, h_val, kbar, plastic, cracked, tensile_force, cohesion, l1, l2, friction, alpha, snap1, snap2, constants, energy, brittle, t_ptr, t_idx, t_val, n_out)  # fmt: skip  # noqa: E501
            rel, trial, ft, actions, flags, internal, finite = out
            if not finite:
                code = NOT_FINITE
                break
            evaluations += 1
            for i in range(n):
                fint[i] = internal[i]
                R[i] = F[i] - fint[i]
            if creeping:
                for i in range(n):
                    peak_sum[i] += x[i]
                peak_count += 1
            if asking and cycle - ints[PROBED] >= probe_every:
                code = PEAK
                break
            continue
        ke_prev = ke_new
        for i in range(n):
            dx[i] = dt * v[i]
            x[i] = x[i] + dx[i]
        out = _forces(x, h_ptr, h_idx, h_val, kbar, plastic, cracked, tensile_force, cohesion, l1, l2, friction, alpha, snap1, snap2, constants, energy, brittle, t_ptr, t_idx, t_val, n_out)  # fmt: skip  # noqa: E501
        rel, trial, ft, actions, flags, internal, finite = out
        if not finite:
            code = NOT_FINITE
            break
        evaluations += 1
        for i in range(n):
            df[i] = internal[i] - fint[i]
            fint[i] = internal[i]
            R[i] = F[i] - fint[i]
        for i in range(n):
            mv[i] = M[i] * dx[i]
        dmd = np.dot(dx, mv)
        omega2 = np.dot(dx, df) / dmd if dmd > 0 else 0.0
        if omega2 * dt * dt > courant:
            courant = omega2 * dt * dt
        if omega2 * dt * dt > 4.0:
            over += 1
        rabs = np.sqrt(np.dot(R, R))
        if not np.isfinite(rabs) or over >= blowup_patience or rabs > 1e8 * fscale:
            code = BLOWUP
            break
        umax = 0.0
        for k in range(trans.shape[0]):
            umax = max(umax, abs(x[trans[k]] - origin[k]))
        if umax > limit:
            code = MECHANISM
            break
    fs[KE_PREV], fs[KE_PEAK] = ke_prev, ke_peak
    fs[BEST_BEFORE], fs[BEST_NOW], fs[COURANT], fs[RNORM] = best_before, best_now, courant, rnorm
    ints[CYCLE], ints[OVER], ints[RESTART], ints[PEAK_COUNT] = cycle, over, restart, peak_count
    ints[STEPS], ints[RESETS], ints[EVALUATIONS] = steps, resets, evaluations
    return code, rel, trial, ft, actions, flags


#: the serial variant calls the law's serial kernel, the parallel one its parallel kernel
#: (picked by :meth:`~masonry_dem.jit.Kernel.for_rows`, like the law's); compiled on its
#: first call (announced then; an analysis that never relaxes does not pay it) or by
#: ``masonry-dem warmup`` with the other lazy kernels
kinetic_steps = calling_kernel(
    "kinetic_steps", _steps, "_forces", law_kernels.forces, error_model="numpy"
)
