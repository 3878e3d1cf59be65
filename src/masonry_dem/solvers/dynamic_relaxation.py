"""Dynamic relaxation (DR): the explicit baseline the paper's static method is measured against.

The block equations of motion with fictitious masses and rotational inertias,

    M qdd + C qd = F_D + lambda F_L - H_f^T f(H_f q),

are integrated by central differences (leapfrog) until the motion dies out; the state where it
stops is the static equilibrium. The interface actions f come from the same
:class:`~masonry_dem.constitutive.law.InterfaceLaw` as the static solver, through its public
``respond`` / ``plastic_part`` / ``cracked_after`` methods, so both solvers answer the same
discrete problem and must find the same collapse multiplier.

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

Loading (``loading``): ``"steps"`` raises lambda in steps exactly as the static solver does
(same initial step, growth, bracket refinement by halving) and relaxes every step from the last
converged state with the plastic state of that state held (the same holonomic step problem as
the static solver); ``"ramp"`` raises lambda continuously at ``ramp_rate`` per unit of pseudo
time, updates the plastic state every time step (the classical explicit DEM) and records the
quasi-static states it passes through, verified afterwards by relaxing them at their own
lambda; with ``refine`` the collapse bracket is then refined in steps from the highest verified
state. Tensile cracks are held during the ramp (an inertial overshoot would crack joints that
the quasi-static path leaves intact) and enter at verified states only.

Convergence: relative residual ||F_ext - F_int|| / ||F_ext|| <= ``tolerance`` (moments
measured as forces at the median block size, as in the static solver) and kinetic
energy below ``energy_tolerance`` times its peak in the step.

Failure, never a wrong lambda:

* a mechanism: displacements beyond ``displacement_limit`` (default half the smallest size of
  the blocks that can move), or a residual that does not halve within ``stall_factor`` times the time steps of the
  slowest converged step: the load step fails and the bracket is refined as in the static
  solver; the run ends with status ``"collapse"``;
* blow-up (the time step is above the stability limit): a stable central-difference step never
  meets a Rayleigh quotient of the increment with omega^2 dt^2 > 4 (omega^2 <= lambda_max).
  Such steps are counted (``blowup_patience`` of them end the relaxation; not in a row, since a
  contact chattering above the limit separates every other step and bounds the growth), and a
  load step that failed after meeting even one is not taken as evidence of collapse. An
  exploding residual or a non-finite value is a blow-up too. ``on_blowup="cut"`` halves dt and
  repeats the step from the last converged state (at most ``max_cuts`` times); ``"refuse"``
  ends the run with status ``"failed"``, no collapse multiplier, and a reason naming the step
  and the estimated limit.
* ``max_time_steps`` bounds the whole run: when spent, status ``"failed"`` and no lambda.

The results are a :class:`~masonry_dem.results.History` (one StepResult per converged load
step), so the VTU/PVD writer works unchanged; ``History.iterations`` counts time steps.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import dataclass, field

import numpy as np
from scipy import sparse

from masonry_dem._threads import kernel_threads_for
from masonry_dem.constitutive.law import LawResponse
from masonry_dem.model import Model, deprecated_law_option
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.static.outcome import Status
from masonry_dem.solvers.static.problem import DiscreteProblem

log = logging.getLogger(__name__)

_CHOICES = {
    "mass": ("stiffness", "density"),
    "dt_rule": ("gershgorin", "power"),
    "damping": ("kinetic", "viscous"),
    "loading": ("steps", "ramp"),
    "on_blowup": ("cut", "refuse"),
    "stability": ("elastic", "current"),
}

#: outcomes of a relaxation that end the whole run (no lambda is reported)
_FATAL = ("blowup", "budget")


@dataclass(frozen=True)
class DRSettings:
    """Knobs of dynamic relaxation (defaults: see docs/solvers.md for why).

    Load steps are in units of the load scale |F_D| / |F_L| (1 for a tilt table), as in
    :class:`~masonry_dem.solvers.incremental.StaticSettings`; ``ramp_rate`` is lambda (in load
    scales) per unit of pseudo time (the stiffness-scaled stable step is 2).
    """

    mass: str = "stiffness"
    dt_rule: str = "gershgorin"
    dt_fraction: float = 0.9
    dt: float | None = None
    stability: str = "elastic"
    damping: str = "kinetic"
    viscous_ratio: float = 1.0
    loading: str = "steps"
    ramp_rate: float = 2e-4
    check_every: int = 25
    ramp_tolerance: float = 1e-2
    tolerance: float = 1e-4
    energy_tolerance: float = 1e-6
    # a relaxation that keeps halving its residual may run this long: near the peak of a
    # cracked mortar wall (Chee Liang 14-15) one load step needs 1e5 time steps, and 2e4 ended
    # the path 6 % low; relaxations that stop converging end earlier, by the stall test
    max_cycles: int = 400_000
    stall_factor: float = 5.0
    min_stall_window: int = 200
    initial_step: float = 0.02
    max_step: float = 0.2
    growth: float = 1.5
    bracket_tolerance: float = 0.005
    refine: bool = True
    max_steps: int = 1000
    max_load_factor: float = math.inf
    displacement_limit: float | None = None
    tension: str | None = None  # deprecated: InterfaceMaterial(tension=...)
    memory: str | None = None  # deprecated: InterfaceMaterial(memory=...)
    max_time_steps: int = 2_000_000
    on_blowup: str = "cut"
    max_cuts: int = 6
    blowup_patience: int = 5
    power_iterations: int = 30

    def __post_init__(self) -> None:
        deprecated_law_option("DRSettings", "tension", self.tension)
        deprecated_law_option("DRSettings", "memory", self.memory)
        for name, allowed in _CHOICES.items():
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {allowed}, got {getattr(self, name)!r}")
        for name in (
            "dt_fraction",
            "viscous_ratio",
            "ramp_rate",
            "tolerance",
            "energy_tolerance",
            "ramp_tolerance",
            "initial_step",
            "max_step",
            "bracket_tolerance",
            "stall_factor",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        if self.dt is not None and not (math.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"dt must be a positive number or None, got {self.dt!r}")
        if self.growth < 1:
            raise ValueError(f"growth must be >= 1, got {self.growth!r}")
        for name in (
            "max_cycles",
            "max_steps",
            "check_every",
            "blowup_patience",
            "min_stall_window",
        ):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be at least 1, got {getattr(self, name)!r}")
        if self.max_cuts < 0 or self.power_iterations < 1:
            raise ValueError("max_cuts must be >= 0 and power_iterations >= 1")


@dataclass
class _Relaxed:
    """Outcome of one relaxation: converged, mechanism, stalled or blown up."""

    ok: bool
    kind: str  # "converged", "mechanism", "stalled", "blowup", "limit", "budget"
    x: np.ndarray  # free DOFs
    load_factor: float
    response: LawResponse
    cycles: int
    reason: str = ""
    courant: float = 0.0  # largest omega^2 dt^2 seen (4 is the stability limit)


@dataclass
class _State:
    """A converged state to restart from: free DOFs, plastic part, cracked joints."""

    x: np.ndarray
    plastic: np.ndarray
    cracked: np.ndarray
    load_factor: float
    factors: np.ndarray


@dataclass
class DRStats:
    """What a run cost: time steps, law evaluations, cuts of the step, estimates of the limit."""

    time_steps: int = 0
    law_evaluations: int = 0
    kinetic_resets: int = 0
    cuts: int = 0
    dt: float = 0.0
    dt_limit: float = 0.0
    lambda_max: float = 0.0
    courant: float = 0.0  # largest omega^2 dt^2 met (central differences are stable below 4)
    events: list[str] = field(default_factory=list)


class DynamicRelaxation:
    """Dynamic relaxation of one model (keeps the assembly, the masses and the time step)."""

    def __init__(self, model: Model, settings: DRSettings | None = None) -> None:
        self.model = model
        self.settings = s = settings or DRSettings()
        # the discrete problem of the static solver: the same loads, law, residual norm
        # (moments as forces at the median block size) and displacement limit
        self.problem = DiscreteProblem(
            model, tension=s.tension, memory=s.memory, displacement_limit=s.displacement_limit
        )
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
    def _masses(self) -> np.ndarray:
        """(nf,) diagonal fictitious masses of the free DOFs."""
        K = self.K_elastic
        diag = K.diagonal()
        if self.settings.mass == "stiffness":
            d = np.sqrt(np.maximum(diag, 1e-300))
            absK = abs(K)
            return d * (absK @ (1.0 / d))
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

    def _rng_vector(self, n: int) -> np.ndarray:
        x = np.random.default_rng(1).standard_normal(n)
        return x / max(float(np.linalg.norm(x)), 1e-300)

    # ------------------------------------------------------------------ forces
    def _forces(self, x: np.ndarray, plastic: np.ndarray, cracked: np.ndarray):
        rel, resp, internal = self.law.forces(self.Hf, x, plastic, cracked, self.asm.H_free_T)
        self.stats.law_evaluations += 1
        return rel, resp, internal

    # ------------------------------------------------------------------ one relaxation
    def _relax(
        self,
        start: _State,
        target: float,
        dt: float,
        ramp_to: float | None = None,
        on_checkpoint: Callable[[np.ndarray, float, LawResponse, np.ndarray, np.ndarray], None]
        | None = None,
    ) -> _Relaxed:
        """Integrate from ``start`` at rest until equilibrium under lambda = ``target``.

        With ``ramp_to`` lambda grows from ``start.load_factor`` at ``ramp_rate`` (capped at
        ``ramp_to``), the plastic state is updated every time step, and ``on_checkpoint`` is
        called at each quasi-static state (residual below tolerance) passed on the way.
        """
        s = self.settings
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
        # a ramp runs until a mechanism forms or lambda reaches its top: only the budget ends it
        for cycle in range(1, (s.max_time_steps if ramp else s.max_cycles) + 1):
            self.stats.time_steps += 1
            if self.stats.time_steps > s.max_time_steps:
                return _Relaxed(
                    False,
                    "budget",
                    start.x,
                    lam,
                    resp,
                    cycle,
                    f"time-step budget max_time_steps={s.max_time_steps} spent at lambda={lam:.6g}",
                )
            Fn = max(float(np.linalg.norm(W * F)), 1e-30)
            rnorm = float(np.linalg.norm(W * R)) / Fn
            best_now = min(best_now, rnorm)
            if not ramp and cycle % window == 0:
                if best_now > 0.5 * best_before:
                    return _Relaxed(
                        False,
                        "stalled",
                        x,
                        lam,
                        resp,
                        cycle,
                        f"residual stalled at {best_now:.2e} over {window} time steps",
                    )
                best_before, best_now = best_now, math.inf
            ke = 0.5 * float(v @ (M * v))
            ke_peak = max(ke_peak, ke)
            if (
                not ramp
                and rnorm <= s.tolerance
                and ke <= s.energy_tolerance * max(ke_peak, 1e-300)
            ):
                return _Relaxed(True, "converged", x, lam, resp, cycle - 1)
            if ramp and cycle % s.check_every == 0 and rnorm <= s.ramp_tolerance and on_checkpoint:
                on_checkpoint(x, lam, resp, plastic, cracked)
            if ramp and lam >= top and rnorm <= s.tolerance:
                return _Relaxed(True, "limit", x, lam, resp, cycle - 1)
            a = R / M
            if s.damping == "kinetic":
                v_old = v
                v = v + (0.5 * dt if restart else dt) * a
                restart = False
                ke_new = 0.5 * float(v @ (M * v))
                if ke_new < ke_prev:  # a peak of the kinetic energy has passed
                    self.stats.kinetic_resets += 1
                    v[:] = 0.0
                    ke_prev = 0.0
                    restart = True
                    if not ramp:  # back to the peak, about a quarter step ago
                        x = x - 0.5 * dt * v_old
                        rel, resp, fint = self._forces(x, plastic, cracked)
                        R = F - fint
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
                why = (
                    "non-finite forces"
                    if not math.isfinite(rabs)
                    else f"omega^2 dt^2 > 4 in {over} time steps"
                    if over >= s.blowup_patience
                    else "the residual grew by 1e8"
                )
                return _Relaxed(
                    False,
                    "blowup",
                    start.x,
                    lam,
                    resp,
                    cycle,
                    f"blow-up at lambda={lam:.6g} after {cycle} time steps with dt={dt:.4g} "
                    f"({why}; estimated stable limit {self.dt_limit:.4g})",
                )
            if s.damping == "viscous":
                dxs = x - x0
                num = float(dxs @ (fint - f0))
                den = float(dxs @ (M * dxs))
                if num > 0 and den > 0:
                    c = 2.0 * s.viscous_ratio * math.sqrt(num / den)
            umax = float(np.abs(x[self._translation]).max(initial=0.0))
            if umax > self.limit:
                return _Relaxed(
                    False,
                    "mechanism",
                    x,
                    lam,
                    resp,
                    cycle,
                    f"displacements exceed the limit {self.limit:.3g} m (a mechanism has formed)",
                )
        return _Relaxed(
            False,
            "stalled",
            x,
            lam,
            resp,
            s.max_cycles,
            f"no rest within max_cycles={s.max_cycles} (residual {rnorm:.2e})",
        )

    def _stall_window(self) -> int:
        """Time steps a relaxation may take without halving its residual: ``stall_factor``
        times the slowest converged step so far (a step slower than that is a mechanism or
        too close to one to settle)."""
        s = self.settings
        return int(max(s.min_stall_window, s.stall_factor * self._slowest))

    # ------------------------------------------------------------------ bookkeeping
    def _record(
        self,
        hist: History,
        x: np.ndarray,
        lam: float,
        resp: LawResponse,
        cycles: int,
        monitor_dof: int | None,
        callback,
    ) -> None:
        q = np.zeros(self.model.n_dofs)
        q[self.asm.free_index] = x
        disp = (
            float(np.abs(q.reshape(-1, 6)[:, :3]).max(initial=0.0))
            if monitor_dof is None
            else float(q[monitor_dof])
        )
        sr = StepResult(
            step=len(hist.steps),
            load_factor=float(lam),
            q=q.reshape(-1, 6),
            actions=resp.actions.copy(),
            state=resp.state.astype(np.int32),
            utilisation=np.minimum(self.law.utilisation(resp), 1.0),
            flags=resp.flags.astype(np.int32),
            control_displacement=disp,
            iterations=int(cycles),
        )
        hist.steps.append(sr)
        if callback is not None:
            callback(sr)

    def _converged_state(
        self, x: np.ndarray, lam: float, start: _State, resp: LawResponse, ramp: bool
    ) -> _State:
        rel = (self.Hf @ x).reshape(-1, 6)
        plastic = self.law.plastic_part(rel, resp.actions)
        cracked = self.law.cracked_after(start.cracked, resp)
        return _State(x.copy(), plastic, cracked, lam, resp.tangent.copy())

    def _step_for(self, state: _State) -> float:
        """The time step for a relaxation from ``state``."""
        s = self.settings
        if s.dt is not None or s.stability == "elastic":
            return self.dt
        f = np.maximum(state.factors, 1e-6)
        dt_limit, _ = self._stability_limit(self.asm.stiffness(f).tocsr())
        return s.dt_fraction * dt_limit

    def _relax_with_cuts(
        self, start: _State, target: float, hist: History | None, **kw
    ) -> _Relaxed:
        s = self.settings
        dt = self._step_for(start)
        for _ in range(s.max_cuts + 1):
            out = self._relax(start, target, dt, **kw)
            out.courant = self._courant
            self.stats.courant = max(self.stats.courant, self._courant)
            if not out.ok and out.kind in ("mechanism", "stalled") and out.courant > 4.0:
                # a failure met with the step above the limit is not evidence of collapse
                out = _Relaxed(
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

    # ------------------------------------------------------------------ analyses
    def run(
        self,
        callback: Callable[[StepResult], None] | None = None,
        monitor: tuple[int, str] | None = None,
    ) -> History:
        """Dead load, then lambda raised in steps or ramped until a mechanism forms."""
        with kernel_threads_for(self.m):
            return self._run(callback, monitor)

    def _run(
        self,
        callback: Callable[[StepResult], None] | None,
        monitor: tuple[int, str] | None,
    ) -> History:
        t0 = time.perf_counter()
        s = self.settings
        hist = History()
        monitor_dof = self._global_dof(*monitor) if monitor is not None else None
        nf = self.asm.n_free
        zero = _State(
            np.zeros(nf),
            np.zeros((self.m, 6)),
            np.zeros(self.m, dtype=bool),
            0.0,
            np.ones((self.m, 6)),
        )
        if not np.all(np.isfinite(self.mass)) or np.any(self.mass <= 0):
            return self._fail_empty(
                hist, zero, "the fictitious masses are not positive", t0, callback
            )
        dead = self._relax_with_cuts(zero, 0.0, hist)
        if not dead.ok:
            return self._fail_empty(
                hist, zero, f"no equilibrium under the dead load: {dead.reason}", t0, callback
            )
        self._slowest = dead.cycles
        state = self._converged_state(dead.x, 0.0, zero, dead.response, False)
        self._record(hist, dead.x, 0.0, dead.response, dead.cycles, monitor_dof, callback)
        if not np.any(self.F_live):
            return self._finish(
                hist, Status.COMPLETED, "no live load: the dead-load state is the answer", t0
            )
        if s.loading == "ramp":
            state = self._ramp(hist, state, monitor_dof, callback)
            if hist.status in (Status.FAILED, Status.COMPLETED):
                return self._finish(hist, hist.status, hist.reason, t0)
            if hist.status is Status.COLLAPSE and not s.refine:
                return self._finish(hist, hist.status, hist.reason, t0)
        self._load_control(hist, state, monitor_dof, callback)
        return self._finish(hist, hist.status, hist.reason, t0)

    def _ramp(self, hist: History, state: _State, monitor_dof, callback) -> _State:
        """Raise lambda continuously, then verify the quasi-static states passed on the way.

        A state passed during the ramp has a residual below ``ramp_tolerance`` only: it is a
        candidate, not an equilibrium. After the ramp ends in a mechanism, candidates are
        relaxed at their own lambda (held) to the full tolerance, by bisection over the list;
        the highest one that settles is the verified state, and only candidates up to it enter
        the History. Returns the verified state (the dead-load state if none settles).
        """
        s = self.settings
        candidates: list[tuple[_State, LawResponse]] = []

        def checkpoint(x, lam, resp, plastic, cracked):
            if candidates and lam <= candidates[-1][0].load_factor * (1 + s.bracket_tolerance):
                return
            st = _State(x.copy(), plastic.copy(), cracked.copy(), lam, resp.tangent.copy())
            candidates.append((st, resp))

        top = s.max_load_factor if math.isfinite(s.max_load_factor) else 1e6 * self.load_scale
        out = self._relax_with_cuts(state, top, hist, ramp_to=top, on_checkpoint=checkpoint)
        if out.kind in _FATAL:
            hist.status, hist.reason = Status.FAILED, out.reason
            return state
        if out.ok:
            plastic, cracked = self._plastic_of(out, state)
            candidates.append(
                (
                    _State(out.x, plastic, cracked, out.load_factor, out.response.tangent),
                    out.response,
                )
            )
        lam_fail = math.inf if out.ok else float(out.load_factor)
        # bisection for the highest candidate that settles at its own lambda
        lo, hi = -1, len(candidates)
        verified: tuple[_State, _Relaxed] | None = None
        while hi - lo > 1:
            mid = (lo + hi) // 2
            cand, _ = candidates[mid]
            probe = self._relax_with_cuts(cand, cand.load_factor, hist)
            if probe.kind in _FATAL:
                hist.status, hist.reason = Status.FAILED, probe.reason
                return state
            if probe.ok:
                lo = mid
                verified = (cand, probe)
            else:
                hi = mid
                lam_fail = min(lam_fail, cand.load_factor)
        for cand, resp in candidates[:lo]:
            self._record(hist, cand.x, cand.load_factor, resp, 0, monitor_dof, callback)
        if verified is not None:
            cand, probe = verified
            self._slowest = max(self._slowest, probe.cycles)
            state = self._converged_state(probe.x, cand.load_factor, cand, probe.response, False)
            self._record(
                hist, probe.x, cand.load_factor, probe.response, probe.cycles, monitor_dof, callback
            )
        if out.ok and lo == len(candidates) - 1:
            hist.status, hist.reason = (
                Status.COMPLETED,
                f"reached max_load_factor {out.load_factor:.6g}",
            )
            return state
        hist.collapse_bracket = (state.load_factor, lam_fail)
        hist.status = Status.COLLAPSE
        hist.reason = (
            f"ramp: no equilibrium beyond lambda={state.load_factor:.6g} "
            f"(first failure at {lam_fail:.6g}: {out.reason or 'a passed state did not settle'})"
        )
        self._ramp_fail = lam_fail
        return state

    def _plastic_of(self, out: _Relaxed, state: _State):
        rel = (self.Hf @ out.x).reshape(-1, 6)
        return self.law.plastic_part(rel, out.response.actions), self.law.cracked_after(
            state.cracked, out.response
        )

    def _load_control(self, hist: History, state: _State, monitor_dof, callback) -> None:
        s = self.settings
        lam = state.load_factor
        dlam = s.initial_step * self.load_scale
        max_dlam = s.max_step * self.load_scale
        lam_fail = self._ramp_fail
        if math.isfinite(lam_fail):
            dlam = (lam_fail - lam) / 2
        last_reason = hist.reason if math.isfinite(lam_fail) else ""
        for _ in range(s.max_steps):
            if math.isfinite(lam_fail) and lam_fail - lam <= s.bracket_tolerance * max(
                abs(lam), 1e-12 * self.load_scale
            ):
                break
            target = min(lam + dlam, s.max_load_factor)
            out = self._relax_with_cuts(state, target, hist)
            if out.kind in _FATAL:
                hist.status, hist.reason = Status.FAILED, out.reason
                hist.collapse_bracket = None
                return
            if out.ok:
                self._slowest = max(self._slowest, out.cycles)
                state = self._converged_state(out.x, target, state, out.response, False)
                self._record(hist, out.x, target, out.response, out.cycles, monitor_dof, callback)
                lam = target
                if lam >= s.max_load_factor:
                    hist.status, hist.reason = (
                        Status.COMPLETED,
                        f"reached max_load_factor {lam:.6g}",
                    )
                    return
                if math.isfinite(lam_fail):
                    dlam = (lam_fail - lam) / 2
                else:
                    dlam = min(dlam * s.growth, max_dlam)
            else:
                last_reason = out.reason
                lam_fail = min(lam_fail, target)
                log.debug("DR step to lambda=%.6g failed: %s", target, out.reason)
                if not s.refine:
                    break
                dlam = (lam_fail - lam) / 2
        else:
            hist.status, hist.reason = (
                Status.FAILED,
                f"max_steps={s.max_steps} reached at lambda={lam:.6g}",
            )
            return
        if not math.isfinite(lam_fail):
            hist.status, hist.reason = Status.FAILED, "no load step failed and none converged"
            return
        hist.collapse_bracket = (lam, lam_fail)
        hist.status = Status.COLLAPSE
        hist.reason = f"no equilibrium beyond lambda={lam:.6g} (first failure at {lam_fail:.6g}: {last_reason})"

    def _fail_empty(self, hist: History, zero: _State, reason: str, t0: float, callback) -> History:
        resp = self.law.respond(np.zeros((self.m, 6)), zero.plastic, zero.cracked)
        self._record(hist, zero.x, 0.0, resp, 0, None, callback)
        return self._finish(hist, Status.FAILED, reason, t0)

    def _global_dof(self, block: int, dof: str) -> int:
        return self.model.dof_index(block, dof)

    def _finish(self, hist: History, status: Status, reason: str, t0: float) -> History:
        hist.status, hist.reason = status, reason
        if status is not Status.COLLAPSE:
            hist.collapse_bracket = None
        hist.seconds = time.perf_counter() - t0
        hist.iterations = self.stats.time_steps
        hist.factorizations = 0
        log.info(
            "%s: DR %s after %d steps, %d time steps (%s)",
            self.model.name,
            status,
            len(hist.steps),
            self.stats.time_steps,
            reason,
        )
        return hist


def relax(
    model: Model,
    settings: DRSettings | None = None,
    out=None,
    monitor: tuple[int, str] | None = None,
    write_every: int = 1,
) -> History:
    """Run dynamic relaxation; with ``out`` write VTU/PVD, pushover.csv and summary.json."""
    writer = None
    if out is not None:
        from masonry_dem.export.writer import ResultsWriter

        writer = ResultsWriter(out, model, every=write_every, background=True)
    solver = DynamicRelaxation(model, settings)
    with writer or nullcontext():  # the steps handed to the writer reach the disk
        history = solver.run(callback=writer, monitor=monitor)
    if writer is not None:
        writer.finish(history, method="dynamic_relaxation", time_steps=solver.stats.time_steps)
    return history


__all__ = ["DRSettings", "DRStats", "DynamicRelaxation", "relax"]
