"""One relaxation: the damped explicit time integration of the block equations of motion
at a fixed load (or along a ramp) until the motion dies out, with its masses and time step.

The block equations of motion with fictitious masses and rotational inertias,

    M qdd + C qd = F_D + lambda F_L - H_f^T f(H_f q),

are integrated by central differences (leapfrog) until the motion dies out; the state where it
stops is the static equilibrium. The interface actions f come from the same
:class:`~masonry_dem.constitutive.law.InterfaceLaw` as the static solver, through the
:class:`~masonry_dem.solvers.static.problem.DiscreteProblem` they share, so both solvers
answer the same discrete problem and must find the same collapse multiplier.

Masses (``mass``):

* ``"stiffness"`` (default): M_ii = sum_j |K_ij| sqrt(K_ii / K_jj) from the elastic stiffness,
  a scale-invariant Gershgorin bound, so lambda_max(M^-1 K) <= 1 and the stable step is the
  same (dt = 2) for every DOF and every wall: translations and rotations, small and large
  blocks, stiff and soft joints alike.
* ``"density"``: the physical masses rho V and inertias rho V (b^2 + c^2) / 12 of the blocks
  (scaled by a common factor). The stable step is then set by the stiffest, lightest block.

Time step (``dt_rule``): a fraction ``dt_fraction`` of the stability limit 2 / sqrt(lambda_max)
of M^-1 K, with lambda_max from the Gershgorin bound (``"gershgorin"``, safe, may be
pessimistic for density masses) or from a few power iterations (``"power"``, sharp, 5 % margin).
``stability="current"`` takes the limit of the secant stiffness of the last converged state
(larger steps once joints have yielded; a joint that closes again can then push the step above
the limit, which the blow-up check catches). ``dt`` sets the step by hand.

Damping (``damping``): ``"kinetic"`` (default; velocities zeroed at every peak of the kinetic
energy, with the Topping-Barnes correction of the positions back to the peak) or ``"viscous"``
(C = c M with c = 2 xi omega_min, omega_min from the Rayleigh quotient of the current increment,
the adaptive rule of Underwood).

Convergence: relative residual ||F_ext - F_int|| / ||F_ext|| <= ``tolerance`` (moments
measured as forces at the median block size, as in the static solver) and kinetic
energy below ``energy_tolerance`` times its peak in the step.

A relaxation ends without an equilibrium as

* a mechanism: displacements beyond ``displacement_limit`` (default half the smallest size
  of the blocks that can move);
* stalled: a residual that does not halve within ``stall_factor`` times the time steps of
  the slowest converged step;
* blow-up (the time step is above the stability limit): a stable central-difference step
  never meets a Rayleigh quotient of the increment with omega^2 dt^2 > 4 (omega^2 <=
  lambda_max). Such steps are counted (``blowup_patience`` of them end the relaxation; not in
  a row, since a contact chattering above the limit separates every other step and bounds
  the growth), and a failure met after even one is a blow-up, not evidence of collapse. An
  exploding residual or a non-finite value is a blow-up too. ``on_blowup="cut"`` halves dt
  and repeats from the same start (at most ``max_cuts`` times); ``"refuse"`` gives up;
* budget: ``max_time_steps`` of the whole run spent.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from masonry_dem._signals import check_stop
from masonry_dem.constitutive.law import LawResponse
from masonry_dem.model import Model
from masonry_dem.solvers.dynamic_relaxation import kinetic as kin
from masonry_dem.solvers.dynamic_relaxation.settings import DRSettings, DRStats
from masonry_dem.solvers.static.problem import DiscreteProblem

log = logging.getLogger(__name__)

#: how one relaxation ended
RelaxKind = Literal["converged", "mechanism", "stalled", "blowup", "limit", "budget"]
#: outcomes of a relaxation that end the whole run (no lambda is reported)
FATAL: tuple[RelaxKind, ...] = ("blowup", "budget")

#: called at each quasi-static state a ramp passes: (x, lambda, response, plastic, cracked)
Checkpoint = Callable[
    [NDArray[np.float64], float, LawResponse, NDArray[np.float64], NDArray[np.bool_]], None
]
#: asked at a peak of the kinetic energy (the state moved back to that peak): is there an
#: equilibrium near x? (e.g. Newton from x); True ends the relaxation as converged
Probe = Callable[[NDArray[np.float64]], bool]


@dataclass
class Relaxed:
    """Outcome of one relaxation: converged, mechanism, stalled or blown up."""

    ok: bool
    kind: RelaxKind
    x: NDArray[np.float64]  # (nf,) free DOFs
    load_factor: float
    response: LawResponse
    cycles: int
    reason: str = ""
    courant: float = 0.0  # largest omega^2 dt^2 seen (4 is the stability limit)


@dataclass
class RelaxationStart:
    """A converged state to restart from: free DOFs (nf,), plastic part (m, 6), cracked
    joints (m,), its lambda and stiffness factors (m, 6)."""

    x: NDArray[np.float64]
    plastic: NDArray[np.float64]
    cracked: NDArray[np.bool_]
    load_factor: float
    factors: NDArray[np.float64]


def _converged_creep(
    creep: NDArray[np.float64],
    before: NDArray[np.float64] | None,
    mass: NDArray[np.float64],
    cos_min: float,
) -> NDArray[np.float64] | None:
    """The direction of ``creep`` (unit in the mass norm) if it points the way the creep
    ``before`` it did (mass-weighted cosine above ``cos_min``), else None."""
    if before is None:
        return None
    norm = math.sqrt(float(creep @ (mass * creep)))
    norm_before = math.sqrt(float(before @ (mass * before)))
    if norm <= 0.0 or norm_before <= 0.0:
        return None
    if float(creep @ (mass * before)) / (norm * norm_before) <= cos_min:
        return None
    return creep / norm


@dataclass
class _Creep:
    """The creep of a relaxation (see :meth:`Relaxation._relax`): the mean state of the
    kinetic-energy peaks of the last window, the last window's creep, and the direction kept
    undamped (None while the creeps do not point the same way)."""

    mean_before: NDArray[np.float64]
    before: NDArray[np.float64] | None = None
    keep: NDArray[np.float64] | None = None

    def measure(
        self, peak_sum: NDArray[np.float64], count: int, mass: NDArray[np.float64], cos_min: float
    ) -> None:
        """A window ends: its mean state of the peaks (their sum and count) against the last."""
        mean = peak_sum / count
        creep = mean - self.mean_before
        self.keep = _converged_creep(creep, self.before, mass, cos_min)
        self.before, self.mean_before = creep, mean


class Relaxation:
    """The relaxations of one model: keeps the assembly, the masses and the time step.
    :class:`~masonry_dem.solvers.dynamic_relaxation.solver.DynamicRelaxation` follows the load
    path with it."""

    def __init__(self, model: Model, settings: DRSettings | None = None) -> None:
        self.model = model
        self.settings = s = settings or DRSettings()
        # the discrete problem of the static solver: the same loads, law, residual norm
        # (moments as forces at the median block size) and displacement limit
        self.problem = DiscreteProblem(model, displacement_limit=s.displacement_limit)
        self.asm = self.problem.asm
        self.law = self.problem.law
        self.Hf = self.asm.H_free.tocsr()
        self.F_dead = self.problem.F_dead
        self.F_live = self.problem.F_live
        self.load_scale = self.problem.load_scale
        self.limit = self.problem.limit
        self._translation = self.problem.translation
        self._weight = self.problem.weight
        self.m = model.interfaces.count
        self.K_elastic = self.asm.stiffness().tocsr()
        self.mass = self._masses()
        self.stats = DRStats()
        self.dt_limit, self.lambda_max = self._stability_limit(self.K_elastic)
        self.dt = s.dt if s.dt is not None else s.dt_fraction * self.dt_limit
        self.stats.dt, self.stats.dt_limit, self.stats.lambda_max = (
            self.dt,
            self.dt_limit,
            self.lambda_max,
        )
        self._slowest = 0
        self._courant = 0.0
        self._ramp_fail = math.inf  # first failure met by a ramp (refined in steps after it)

    # ------------------------------------------------------------------ masses and time step
    def _masses(self) -> NDArray[np.float64]:
        """(nf,) diagonal fictitious masses of the free DOFs."""
        K = self.K_elastic
        diag = K.diagonal()
        if self.settings.mass == "stiffness":
            d = np.sqrt(np.maximum(diag, 1e-300))
            absK = abs(K)
            return np.asarray(d * (absK @ (1.0 / d)), dtype=np.float64)
        blocks = self.model.blocks
        mass = blocks.weights / 9.81
        mass = np.where(mass > 0, mass, max(float(mass.max(initial=0.0)), 1.0) * 1e-3)
        sz = blocks.sizes
        inertia = np.stack(
            [
                sz[:, 1] ** 2 + sz[:, 2] ** 2,
                sz[:, 0] ** 2 + sz[:, 2] ** 2,
                sz[:, 0] ** 2 + sz[:, 1] ** 2,
            ],
            axis=1,
        ) * (mass[:, None] / 12.0)
        full = np.concatenate([np.repeat(mass[:, None], 3, axis=1), inertia], axis=1).reshape(-1)
        m = full[self.asm.free_index]
        # common scale: the stiffest DOF gets the stiffness-scaled mass (dt of order one)
        scale = float(np.max(diag / m)) if m.size else 1.0
        return m * scale

    def _stability_limit(self, K: sparse.csr_matrix) -> tuple[float, float]:
        """(dt_limit, lambda_max) of central differences for M^-1 K."""
        s = self.settings
        minv_sqrt = 1.0 / np.sqrt(self.mass)
        if s.dt_rule == "gershgorin":
            # rows of M^-1/2 |K| M^-1/2: lambda_max <= max row sum (scale invariant)
            lam = float(np.max(minv_sqrt * (abs(K) @ minv_sqrt))) if K.shape[0] else 1.0
        else:
            x = self._rng_vector(K.shape[0])
            lam = 0.0
            for _ in range(s.power_iterations):
                y = minv_sqrt * (K @ (minv_sqrt * x))
                lam = float(x @ y)
                norm = float(np.linalg.norm(y))
                if norm == 0.0:
                    break
                x = y / norm
            lam *= 1.05  # power iterations approach lambda_max from below
        lam = max(lam, 1e-300)
        return 2.0 / math.sqrt(lam), lam

    def _rng_vector(self, n: int) -> NDArray[np.float64]:
        x = np.random.default_rng(1).standard_normal(n)
        return x / max(float(np.linalg.norm(x)), 1e-300)

    # ------------------------------------------------------------------ forces
    def _forces(
        self, x: NDArray[np.float64], plastic: NDArray[np.float64], cracked: NDArray[np.bool_]
    ) -> tuple[NDArray[np.float64], LawResponse, NDArray[np.float64]]:
        rel, resp, internal = self.law.forces(self.Hf, x, plastic, cracked, self.asm.H_free_T)
        self.stats.law_evaluations += 1
        return rel, resp, internal

    # ------------------------------------------------------------------ one relaxation
    def _relax(
        self,
        start: RelaxationStart,
        target: float,
        dt: float,
        ramp_to: float | None = None,
        on_checkpoint: Checkpoint | None = None,
        from_start: bool = False,
        probe: Probe | None = None,
        probe_every: int = 0,
        creep_cos: float = 0.0,
    ) -> Relaxed:
        """Integrate from ``start`` at rest until equilibrium under lambda = ``target``.

        With ``ramp_to`` lambda grows from ``start.load_factor`` at ``ramp_rate`` (capped at
        ``ramp_to``), the plastic state is updated every time step, and ``on_checkpoint`` is
        called at each quasi-static state (residual below tolerance) passed on the way.
        The displacement limit is measured from the unloaded wall, or with ``from_start``
        from ``start`` (a search of the static path, which measures its steps so).
        ``probe(x)``: asked at the first peak of the kinetic energy at least ``probe_every``
        time steps after the last question (a state of the motion at rest for an instant);
        True ends the relaxation as converged at x (the probe found the equilibrium from
        there). At a peak of the kinetic energy the state is momentarily at rest, the
        nearest the motion comes to an equilibrium, which is where Newton is likeliest to
        converge from (docs/history/solvers_record.md, "The corner check on by default", compares it
        with asking at a new lowest residual).

        ``creep_cos`` > 0 (kinetic damping at a fixed load): the motion along a converged
        creep is not damped. Kinetic damping zeroes every velocity at each peak of the
        wall's kinetic energy, and the fast modes peak every few time steps, so a slow mode
        (a wall snapping through along a mechanism towards a fold's rest) only creeps: its
        velocity is killed long before it has moved. The creep is measured between the
        probes' times (every ``probe_every`` time steps): the mean of the states at the
        kinetic-energy peaks, window against window. Where two successive creeps point the
        same way (mass-weighted cosine above ``creep_cos``), the component of the velocity
        along that creep is kept at each peak as long as it points forward, and only the
        rest is damped: the slow mode moves at its own pace, the fast ones are damped as
        before. A rest state along it is then reached in fewer time steps; where the
        motion turns (an overshoot past the rest, or a new direction) the forward
        component vanishes and the damping is the usual one.
        """
        s = self.settings
        if s.compiled_steps and s.damping == "kinetic" and ramp_to is None:
            return self._relax_compiled(
                start, target, dt, from_start, probe, probe_every, creep_cos
            )
        M = self.mass
        W = self._weight
        x = start.x.copy()
        plastic = start.plastic.copy()
        cracked = start.cracked.copy()
        v = np.zeros_like(x)
        ramp = ramp_to is not None
        top = ramp_to if ramp_to is not None else target
        lam = start.load_factor if ramp else target
        rate = s.ramp_rate * self.load_scale
        F = self.F_dead + lam * self.F_live
        rel, resp, fint = self._forces(x, plastic, cracked)
        R = F - fint
        x0, f0 = x.copy(), fint.copy()
        origin = x0[self._translation] if from_start else 0.0
        ke_prev = 0.0
        ke_peak = 0.0
        restart = True
        c = 0.0
        over = 0
        self._courant = 0.0
        fscale = max(
            float(np.linalg.norm(self.F_dead + max(abs(target), 1e-12) * self.F_live)), 1e-30
        )
        window = self._stall_window()
        best_before, best_now = math.inf, math.inf
        probed = 0  # the time step of the last probe (or creep measure)
        # the creep: mean state of the kinetic-energy peaks per window, the last window's
        # creep, and the direction (unit in the mass norm) kept undamped
        creeping = creep_cos > 0.0 and s.damping == "kinetic" and not ramp
        peak_sum = np.zeros_like(x)
        peak_count = 0
        tracked = _Creep(x.copy())
        # a ramp runs until a mechanism forms or lambda reaches its top: only the budget ends it
        for cycle in range(1, (s.max_time_steps if ramp else s.max_cycles) + 1):
            self.stats.time_steps += 1
            check_stop()
            if self.stats.time_steps > s.max_time_steps:
                return self._spent(start, lam, resp, cycle)
            Fn = max(float(np.linalg.norm(W * F)), 1e-30)
            rnorm = float(np.linalg.norm(W * R)) / Fn
            best_now = min(best_now, rnorm)
            if not ramp and cycle % window == 0:
                if best_now > 0.5 * best_before:
                    return self._stalled(x, lam, resp, cycle, best_now, window)
                best_before, best_now = best_now, math.inf
            ke = 0.5 * float(v @ (M * v))
            ke_peak = max(ke_peak, ke)
            if (
                not ramp
                and rnorm <= s.tolerance
                and ke <= s.energy_tolerance * max(ke_peak, 1e-300)
            ):
                return Relaxed(True, "converged", x, lam, resp, cycle - 1)
            if ramp and cycle % s.check_every == 0 and rnorm <= s.ramp_tolerance and on_checkpoint:
                on_checkpoint(x, lam, resp, plastic, cracked)
            if ramp and lam >= top and rnorm <= s.tolerance:
                return Relaxed(True, "limit", x, lam, resp, cycle - 1)
            a = R / M
            if s.damping == "kinetic":
                v_old = v
                v = v + (0.5 * dt if restart else dt) * a
                restart = False
                ke_new = 0.5 * float(v @ (M * v))
                if ke_new < ke_prev:  # a peak of the kinetic energy has passed
                    self.stats.kinetic_resets += 1
                    keep = tracked.keep
                    forward = float(v_old @ (M * keep)) if keep is not None else 0.0
                    if keep is not None and forward > 0.0:  # the creep goes on undamped
                        v = forward * keep
                        ke_prev = 0.5 * forward * forward
                    else:
                        v = np.zeros_like(v)
                        ke_prev = 0.0
                    restart = True
                    if not ramp:  # back to the peak, about a quarter step ago
                        x = x - 0.5 * dt * v_old
                        rel, resp, fint = self._forces(x, plastic, cracked)
                        R = F - fint
                        if creeping:
                            peak_sum += x
                            peak_count += 1
                        if (probe is not None or creeping) and cycle - probed >= probe_every:
                            probed = cycle
                            if creeping:
                                tracked.measure(peak_sum, peak_count, M, creep_cos)
                                peak_sum[:] = 0.0
                                peak_count = 0
                            if probe is not None and probe(x):
                                return Relaxed(True, "converged", x, lam, resp, cycle)
                    continue
                ke_prev = ke_new
            else:
                cdt = 0.5 * c * dt
                v = ((1.0 - cdt) * v + dt * a) / (1.0 + cdt)
            dx = dt * v
            x = x + dx
            if ramp:
                lam = min(lam + rate * dt, top)
                F = self.F_dead + lam * self.F_live
            rel, resp, fint_new = self._forces(x, plastic, cracked)
            df = fint_new - fint
            fint = fint_new
            R = F - fint
            if ramp:
                # slip memory follows the motion; tensile cracks do not: an inertial overshoot
                # of the ramp would crack mortar joints that the quasi-static path leaves
                # intact and lower lambda for good. Cracks enter at verified states only.
                plastic = self.law.plastic_part(rel, resp.actions)
            # blow-up check: Rayleigh quotient of the increment against the stability limit
            dmd = float(dx @ (M * dx))
            omega2 = float(dx @ df) / dmd if dmd > 0 else 0.0
            # a stable step never sees omega^2 dt^2 > 4 (a Rayleigh quotient is at most
            # lambda_max); count such steps over the whole relaxation, not in a row: a contact
            # that chatters above the limit separates every other step and bounds the growth
            if omega2 * dt * dt > self._courant:
                self._courant = omega2 * dt * dt
            if omega2 * dt * dt > 4.0:
                over += 1
            rabs = float(np.linalg.norm(R))
            if not math.isfinite(rabs) or over >= s.blowup_patience or rabs > 1e8 * fscale:
                return self._blown_up(start, lam, resp, cycle, dt, rabs, over)
            if s.damping == "viscous":
                dxs = x - x0
                num = float(dxs @ (fint - f0))
                den = float(dxs @ (M * dxs))
                if num > 0 and den > 0:
                    c = 2.0 * s.viscous_ratio * math.sqrt(num / den)
            umax = float(np.abs(x[self._translation] - origin).max(initial=0.0))
            if umax > self.limit:
                return self._mechanism(x, lam, resp, cycle)
        return self._no_rest(x, lam, resp, rnorm)

    def _relax_compiled(
        self,
        start: RelaxationStart,
        target: float,
        dt: float,
        from_start: bool,
        probe: Probe | None,
        probe_every: int,
        creep_cos: float,
    ) -> Relaxed:
        """:meth:`_relax` with kinetic damping at a fixed load, its time steps in
        :data:`~masonry_dem.solvers.dynamic_relaxation.kinetic.kinetic_steps` (the same
        operations in the same order, so the same bits); this side asks the probe and
        measures the creep at the peaks where they are due, and words the ending."""
        s = self.settings
        M = self.mass
        W = self._weight
        x = start.x.copy()
        plastic = start.plastic.copy()
        cracked = start.cracked.copy()
        v = np.zeros_like(x)
        lam = target
        F = self.F_dead + lam * self.F_live
        rel, resp, fint = self._forces(x, plastic, cracked)
        R = F - fint
        trans = np.flatnonzero(self._translation)
        origin = x[trans] if from_start else np.zeros(trans.size)
        self._courant = 0.0
        fscale = max(
            float(np.linalg.norm(self.F_dead + max(abs(target), 1e-12) * self.F_live)), 1e-30
        )
        Fn = max(float(np.linalg.norm(W * F)), 1e-30)
        window = self._stall_window()
        creeping = creep_cos > 0.0
        asking = probe is not None or creeping
        peak_sum = np.zeros_like(x)
        tracked = _Creep(x.copy())
        fs = np.array([0.0, 0.0, math.inf, math.inf, 0.0, math.nan])
        ints = np.zeros(8, dtype=np.int64)
        ints[kin.RESTART] = 1
        operands = self.law.kernel_operands(self.Hf, plastic, cracked, self.asm.H_free_T)
        steps = kin.kinetic_steps.for_rows(self.m)
        while True:
            code, rel, trial, ft, actions, flags = steps(
                x, v, fint, R, F, M, W,
                tracked.keep if tracked.keep is not None else peak_sum, tracked.keep is not None,
                peak_sum, creeping, asking, trans, origin, fs, ints,
                dt, Fn, fscale, s.tolerance, s.energy_tolerance, self.limit, window,
                s.max_cycles, s.max_time_steps - self.stats.time_steps, probe_every,
                s.blowup_patience,
                rel, resp.trial, resp.tensile_force, resp.actions, resp.flags,
                *operands,
            )  # fmt: skip
            self.stats.time_steps += int(ints[kin.STEPS])
            self.stats.kinetic_resets += int(ints[kin.RESETS])
            self.stats.law_evaluations += int(ints[kin.EVALUATIONS])
            ints[kin.STEPS] = ints[kin.RESETS] = ints[kin.EVALUATIONS] = 0
            self._courant = float(fs[kin.COURANT])
            resp = LawResponse(trial, ft, actions, flags, None, self.law.cohesion_at(cracked))
            cycle = int(ints[kin.CYCLE])
            check_stop()  # at each return of the kernel: a signal stops a long relaxation
            if code != kin.PEAK:
                break
            ints[kin.PROBED] = cycle
            if creeping:
                tracked.measure(peak_sum, int(ints[kin.PEAK_COUNT]), M, creep_cos)
                peak_sum[:] = 0.0
                ints[kin.PEAK_COUNT] = 0
            if probe is not None:
                here = x.copy()  # the loop goes on in x: the probe keeps its own
                if probe(here):
                    return Relaxed(True, "converged", here, lam, resp, cycle)
        if code == kin.NOT_FINITE:
            self._forces(x, plastic, cracked)  # says which action is not finite
            raise FloatingPointError("non-finite interface actions in a relaxation")
        if code == kin.CONVERGED:
            return Relaxed(True, "converged", x, lam, resp, cycle)
        if code == kin.STALLED:
            return self._stalled(x, lam, resp, cycle, float(fs[kin.BEST_NOW]), window)
        if code == kin.BUDGET:
            return self._spent(start, lam, resp, cycle)
        if code == kin.BLOWUP:
            rabs = float(np.linalg.norm(R))
            return self._blown_up(start, lam, resp, cycle, dt, rabs, int(ints[kin.OVER]))
        if code == kin.MECHANISM:
            return self._mechanism(x, lam, resp, cycle)
        return self._no_rest(x, lam, resp, float(fs[kin.RNORM]))

    # ------------------------------------------------------------------ endings (both loops)
    def _spent(self, start: RelaxationStart, lam: float, resp: LawResponse, cycle: int) -> Relaxed:
        budget = self.settings.max_time_steps
        why = f"time-step budget max_time_steps={budget} spent at lambda={lam:.6g}"
        return Relaxed(False, "budget", start.x, lam, resp, cycle, why)

    def _stalled(
        self, x: NDArray[np.float64], lam: float, resp: LawResponse, cycle: int,
        best: float, window: int,
    ) -> Relaxed:  # fmt: skip
        why = f"residual stalled at {best:.2e} over {window} time steps"
        return Relaxed(False, "stalled", x, lam, resp, cycle, why)

    def _blown_up(
        self, start: RelaxationStart, lam: float, resp: LawResponse, cycle: int, dt: float,
        rabs: float, over: int,
    ) -> Relaxed:  # fmt: skip
        what = (
            "non-finite forces"
            if not math.isfinite(rabs)
            else f"omega^2 dt^2 > 4 in {over} time steps"
            if over >= self.settings.blowup_patience
            else "the residual grew by 1e8"
        )
        why = (
            f"blow-up at lambda={lam:.6g} after {cycle} time steps with dt={dt:.4g} "
            f"({what}; estimated stable limit {self.dt_limit:.4g})"
        )
        return Relaxed(False, "blowup", start.x, lam, resp, cycle, why)

    def _mechanism(
        self, x: NDArray[np.float64], lam: float, resp: LawResponse, cycle: int
    ) -> Relaxed:
        why = f"displacements exceed the limit {self.limit:.3g} m (a mechanism has formed)"
        return Relaxed(False, "mechanism", x, lam, resp, cycle, why)

    def _no_rest(
        self, x: NDArray[np.float64], lam: float, resp: LawResponse, rnorm: float
    ) -> Relaxed:
        cycles = self.settings.max_cycles
        why = f"no rest within max_cycles={cycles} (residual {rnorm:.2e})"
        return Relaxed(False, "stalled", x, lam, resp, cycles, why)

    def _stall_window(self) -> int:
        """Time steps a relaxation may take without halving its residual: ``stall_factor``
        times the slowest converged step so far (a step slower than that is a mechanism or
        too close to one to settle)."""
        s = self.settings
        return int(max(s.min_stall_window, s.stall_factor * self._slowest))

    def _step_for(self, state: RelaxationStart) -> float:
        """The time step for a relaxation from ``state``."""
        s = self.settings
        if s.dt is not None or s.stability == "elastic":
            return self.dt
        f = np.maximum(state.factors, 1e-6)
        dt_limit, _ = self._stability_limit(self.asm.stiffness(f).tocsr())
        return s.dt_fraction * dt_limit

    def relax_with_cuts(
        self,
        start: RelaxationStart,
        target: float,
        *,
        ramp_to: float | None = None,
        on_checkpoint: Checkpoint | None = None,
        from_start: bool = False,
        probe: Probe | None = None,
        probe_every: int = 0,
        creep_cos: float = 0.0,
    ) -> Relaxed:
        """One relaxation from ``start``, its time step halved after a blow-up (``on_blowup``
        "cut"). ``from_start``, ``probe``, ``probe_every``, ``creep_cos``: see :meth:`_relax`."""
        s = self.settings
        dt = self._step_for(start)
        for _ in range(s.max_cuts + 1):
            out = self._relax(
                start,
                target,
                dt,
                ramp_to=ramp_to,
                on_checkpoint=on_checkpoint,
                from_start=from_start,
                probe=probe,
                probe_every=probe_every,
                creep_cos=creep_cos,
            )
            out.courant = self._courant
            self.stats.courant = max(self.stats.courant, self._courant)
            if not out.ok and out.kind in ("mechanism", "stalled") and out.courant > 4.0:
                # a failure met with the step above the limit is not evidence of collapse
                out = Relaxed(
                    False,
                    "blowup",
                    start.x,
                    out.load_factor,
                    out.response,
                    out.cycles,
                    f"blow-up at lambda={out.load_factor:.6g}: the step failed ({out.reason}) "
                    f"with omega^2 dt^2 = {out.courant:.3g} > 4, dt={dt:.4g} above the "
                    f"stability limit (estimated {self.dt_limit:.4g})",
                    out.courant,
                )
            if out.kind != "blowup":
                return out
            self.stats.events.append(out.reason)
            log.warning("%s: %s", self.model.name, out.reason)
            if s.on_blowup == "refuse":
                return out
            dt /= 2
            self.stats.cuts += 1
            self.stats.dt = min(self.stats.dt, dt)
            self.dt = min(self.dt, dt)
            log.info("time step cut to %.4g, step repeated from the last converged state", dt)
        out.reason += f"; still unstable after {s.max_cuts} cuts of the time step"
        return out
