"""Static incremental analysis (Section 2.3 of the paper): the stiffness of the assembly is
updated as interfaces yield, interface actions are corrected onto the strength domain and the
residual is iterated away in every step.

Load control raises lambda in F = F_D + lambda F_L; a step that finds no equilibrium is cut in
half from the last converged state, so the collapse multiplier comes out as a bracket
[last converged, first failed] refined until it is narrower than ``bracket_tolerance``.
Displacement control drives one DOF and lets lambda follow, tracing the curve past the peak.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.sparse.linalg import splu

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive.law import InterfaceLaw, LawResponse
from masonry_dem.model import DOF_NAMES, Model
from masonry_dem.results import History, StepResult

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class StaticSettings:
    """Knobs of the static solver (defaults: see docs/solvers.md for why).

    Step sizes are in units of the load scale |F_D| / |F_L| (1 for a tilt table).
    """

    initial_step: float = 0.02
    max_step: float = 0.2
    growth: float = 1.5
    bracket_tolerance: float = 0.005
    refine: bool = True
    tolerance: float = 1e-4
    max_iterations: int = 300
    stall_iterations: int = 60
    stall_reduction: float = 0.1
    anderson: int = 5
    max_steps: int = 1000
    max_load_factor: float = math.inf
    displacement_limit: float | None = None
    tension: str = "brittle"
    residual_stiffness: float = 1e-9
    iteration: str = "elastic"

    def __post_init__(self) -> None:
        for name in ("initial_step", "max_step", "bracket_tolerance", "tolerance", "residual_stiffness"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        if self.growth < 1:
            raise ValueError(f"growth must be >= 1, got {self.growth!r}")
        if self.max_iterations < 1 or self.max_steps < 1:
            raise ValueError("max_iterations and max_steps must be at least 1")
        if self.iteration not in ("modified", "newton", "elastic"):
            raise ValueError(
                f"iteration must be 'modified', 'newton' or 'elastic', got {self.iteration!r}"
            )
        if self.tension not in ("brittle", "plastic"):
            raise ValueError(f"tension must be 'brittle' or 'plastic', got {self.tension!r}")


@dataclass(frozen=True)
class DisplacementControl:
    """Drive DOF ``dof`` (name, e.g. ``u3``) of ``block`` to ``target`` in ``steps`` steps."""

    block: int
    dof: str
    target: float
    steps: int = 50


@dataclass
class _Outcome:
    ok: bool
    q: np.ndarray
    load_factor: float
    response: LawResponse | None
    iterations: int
    reason: str = ""


class StaticSolver:
    """Incremental-iterative solver for one model (keeps the assembly and the factorizations)."""

    def __init__(self, model: Model, settings: StaticSettings | None = None) -> None:
        self.model = model
        self.settings = settings or StaticSettings()
        self.asm = Assembly.of(model)
        self.law = InterfaceLaw.of(model, self.asm.kbar, self.settings.tension)
        free = self.asm.free_index
        self.F_dead = model.dead.reshape(-1)[free]
        self.F_live = model.live.reshape(-1)[free]
        dead_norm = float(np.linalg.norm(self.F_dead))
        live_norm = float(np.linalg.norm(self.F_live))
        self.load_scale = dead_norm / live_norm if live_norm > 0 and dead_norm > 0 else 1.0
        blocks = model.blocks
        self.limit = (
            self.settings.displacement_limit
            if self.settings.displacement_limit is not None
            else 0.5 * float(blocks.sizes.min())
        )
        # translational free DOFs, for the displacement limit
        self._translation = (free % 6) < 3
        m = model.interfaces.count
        self.plastic = np.zeros((m, 6))
        self.cracked = np.zeros(m, dtype=bool)
        self.q = np.zeros(model.n_dofs)
        self.factorizations = 0
        self.iterations = 0
        self._lu = None
        self._lu_key: bytes | None = None
        self._lu_elastic = None
        self._step_factors = np.ones((m, 6))

    # ------------------------------------------------------------------ linear algebra
    def _secant_lu(self, factors: np.ndarray):
        """The paper's matrix: stiffness factors of Eqs. (13)-(14) from the last converged
        state, fixed during the step (re-used across steps while no interface changes)."""
        f = np.maximum(factors, self.settings.residual_stiffness)
        key = f.tobytes()
        if key != self._lu_key:
            self._lu = splu(self.asm.stiffness(f), permc_spec="COLAMD")
            self._lu_key = key
            self.factorizations += 1
        return self._lu

    def _factor(self, response: LawResponse):
        T = self.law.tangent(response, self.settings.residual_stiffness)
        self.factorizations += 1
        return splu(self.asm.tangent_stiffness(T), permc_spec="COLAMD")

    # ------------------------------------------------------------------ one equilibrium
    def _residual(self, q: np.ndarray, lam: float, dead_factor: float):
        rel = self.asm.relative_displacements(q)
        response = self.law.respond(rel, self.plastic, self.cracked)
        F_ext = dead_factor * self.F_dead + lam * self.F_live
        residual = F_ext - self.asm.H_free.T @ response.actions.reshape(-1)
        scale = max(float(np.linalg.norm(F_ext)), 1e-30)
        return residual, float(np.linalg.norm(residual)) / scale, response

    def _elastic_lu(self):
        if self._lu_elastic is None:
            self._lu_elastic = splu(self.asm.stiffness(), permc_spec="COLAMD")
            self.factorizations += 1
        return self._lu_elastic

    def _direction(self, lu, residual, q, lam, control):
        free = self.asm.free_index
        if control is None:
            return lu.solve(residual), 0.0
        k = control[0]
        a = lu.solve(self.F_live)
        b = lu.solve(residual)
        if abs(a[k]) < 1e-300:
            return None, 0.0
        dlam = (control[1] - q[free[k]] - b[k]) / a[k]
        return b + dlam * a, dlam

    def _equilibrate(
        self, load_factor: float, dead_factor: float = 1.0, control: tuple[int, float] | None = None
    ) -> _Outcome:
        """Iterate from the last converged state to equilibrium at ``load_factor`` (load
        control) or at the controlled DOF value ``control = (free dof, value)``.

        ``iteration="elastic"`` (default) corrects with the elastic stiffness, the
        initial-stiffness method, which contracts for any perfectly plastic law even where
        joints open, close and slide in the same step; Anderson mixing over the last few
        corrections makes it converge in tens of iterations instead of thousands.
        ``"modified"`` uses the paper's matrix (Eqs. 13-14 from the last converged step) and
        ``"newton"`` the consistent tangent of the current iterate with a line search.
        """
        s = self.settings
        q = self.q.copy()
        free = self.asm.free_index
        lam = load_factor
        best = math.inf
        since_best = 0
        residual, rnorm, response = self._residual(q, lam, dead_factor)
        xs: list[np.ndarray] = []  # Anderson history: iterates and their corrections
        gs: list[np.ndarray] = []
        for it in range(1, s.max_iterations + 1):
            constraint_ok = control is None or abs(q[free[control[0]]] - control[1]) <= 1e-9 * max(
                abs(control[1]), self.limit * 1e-6
            )
            if rnorm <= s.tolerance and constraint_ok:
                return _Outcome(True, q, lam, response, it - 1)
            if rnorm < (1 - s.stall_reduction) * best:
                best, since_best = rnorm, 0
            else:
                since_best += 1
                if since_best > s.stall_iterations:
                    return _Outcome(False, q, lam, response, it, f"residual stalled at {rnorm:.2e}")
            self.iterations += 1
            if s.iteration == "newton":
                out = self._newton_update(q, lam, residual, rnorm, response, dead_factor, control, constraint_ok)
                if out is None:
                    return _Outcome(False, q, lam, response, it, "controlled DOF does not move under the live load")
                q, lam, residual, rnorm, response = out
            else:
                lu = self._elastic_lu() if s.iteration == "elastic" else self._secant_lu(self._step_factors)
                dq, dlam = self._direction(lu, residual, q, lam, control)
                if dq is None:
                    return _Outcome(False, q, lam, response, it, "controlled DOF does not move under the live load")
                x = np.append(q[free], lam)
                g = np.append(dq, dlam)
                x_new = x + g
                if s.anderson > 0:
                    xs.append(x)
                    gs.append(g)
                    if len(xs) > s.anderson + 1:
                        xs.pop(0)
                        gs.pop(0)
                    if len(xs) > 1:
                        dX = np.diff(np.array(xs), axis=0).T
                        dG = np.diff(np.array(gs), axis=0).T
                        gamma, *_ = np.linalg.lstsq(dG, g, rcond=None)
                        x_new = x + g - (dX + dG) @ gamma
                q_try = q.copy()
                q_try[free] = x_new[:-1]
                lam_try = float(x_new[-1]) if control is not None else lam
                r_try, n_try, resp_try = self._residual(q_try, lam_try, dead_factor)
                if not np.isfinite(n_try) or n_try > 10 * rnorm:  # mixing went astray: plain step
                    xs.clear()
                    gs.clear()
                    q_try = q.copy()
                    q_try[free] += dq
                    lam_try = lam + dlam
                    r_try, n_try, resp_try = self._residual(q_try, lam_try, dead_factor)
                q, lam, residual, rnorm, response = q_try, lam_try, r_try, n_try, resp_try
            umax = float(np.abs(q[free][self._translation]).max(initial=0.0))
            if not math.isfinite(umax) or umax > self.limit:
                return _Outcome(
                    False, q, lam, response, it,
                    f"displacements exceed the limit {self.limit:.3g} m (a mechanism has formed)",
                )
        return _Outcome(False, q, lam, response, s.max_iterations, "no convergence within max_iterations")

    def _newton_update(self, q, lam, residual, rnorm, response, dead_factor, control, constraint_ok):
        free = self.asm.free_index
        for lu in (self._factor(response), self._elastic_lu()):
            dq, dlam = self._direction(lu, residual, q, lam, control)
            if dq is None:
                return None
            step = 1.0
            while step >= 1.0 / 16:
                q_try = q.copy()
                q_try[free] += step * dq
                lam_try = lam + step * dlam
                r_try, n_try, resp_try = self._residual(q_try, lam_try, dead_factor)
                if n_try < rnorm or (control is not None and not constraint_ok and step == 1.0):
                    return q_try, lam_try, r_try, n_try, resp_try
                step /= 2
        return q_try, lam_try, r_try, n_try, resp_try

    def _accept(self, out: _Outcome, step: int, control_value: float) -> StepResult:
        rel = self.asm.relative_displacements(out.q)
        resp = out.response
        assert resp is not None
        self.plastic = self.law.plastic_part(rel, resp.actions)
        self.cracked = self.law.cracked_after(self.cracked, resp)
        self._step_factors = resp.tangent
        self.q = out.q
        return StepResult(
            step=step,
            load_factor=float(out.load_factor),
            q=out.q.reshape(-1, 6).copy(),
            actions=resp.actions.copy(),
            state=resp.state.astype(np.int32),
            utilisation=np.minimum(resp.utilisation, 1.0),
            flags=resp.flags.astype(np.int32),
            control_displacement=float(control_value),
            iterations=out.iterations,
        )

    def _control_value(self, q: np.ndarray, control_dof: int | None) -> float:
        if control_dof is None:
            return float(np.abs(q.reshape(-1, 6)[:, :3]).max(initial=0.0))
        return float(q[control_dof])

    # ------------------------------------------------------------------ analyses
    def run(
        self,
        control: DisplacementControl | None = None,
        callback: Callable[[StepResult], None] | None = None,
        monitor: tuple[int, str] | None = None,
    ) -> History:
        """Dead load, then lambda raised (load control) or a DOF driven (displacement control).

        ``monitor`` = (block, dof name) picks the displacement stored on the pushover curve
        (default: the largest block translation).
        """
        t0 = time.perf_counter()
        hist = History()
        monitor_dof = None
        if monitor is not None:
            monitor_dof = self._global_dof(*monitor)
        if control is not None:
            monitor_dof = self._global_dof(control.block, control.dof)

        def record(out: _Outcome) -> None:
            sr = self._accept(out, len(hist.steps), self._control_value(out.q, monitor_dof))
            hist.steps.append(sr)
            if callback is not None:
                callback(sr)

        dead = self._equilibrate(0.0, 1.0)
        if not dead.ok:
            self._finish(hist, "failed", f"no equilibrium under the dead load: {dead.reason}", t0)
            empty = _Outcome(True, np.zeros_like(self.q), 0.0, self.law.respond(
                np.zeros_like(self.plastic), self.plastic, self.cracked), 0)
            record(empty)
            return self._finish(hist, "failed", f"no equilibrium under the dead load: {dead.reason}", t0)
        record(dead)
        if not np.any(self.F_live):
            return self._finish(hist, "completed", "no live load: the dead-load state is the answer", t0)
        if control is None:
            self._load_control(hist, record)
        else:
            self._displacement_control(hist, record, control, monitor_dof)
        return self._finish(hist, hist.status, hist.reason, t0)

    def _load_control(self, hist: History, record) -> None:
        s = self.settings
        lam = 0.0
        dlam = s.initial_step * self.load_scale
        max_dlam = s.max_step * self.load_scale
        lam_fail = math.inf
        last_reason = ""
        for _ in range(s.max_steps):
            target = min(lam + dlam, s.max_load_factor)
            out = self._equilibrate(target)
            if out.ok:
                record(out)
                lam = target
                if lam >= s.max_load_factor:
                    hist.status, hist.reason = "completed", f"reached max_load_factor {lam:.6g}"
                    return
                if math.isfinite(lam_fail):
                    dlam = (lam_fail - lam) / 2
                elif out.iterations <= 6:
                    dlam = min(dlam * s.growth, max_dlam)
            else:
                last_reason = out.reason
                lam_fail = min(lam_fail, target)
                log.debug("step to lambda=%.6g failed: %s", target, out.reason)
                if not s.refine:
                    break
                dlam = (lam_fail - lam) / 2
            if math.isfinite(lam_fail) and lam_fail - lam <= s.bracket_tolerance * max(abs(lam), 1e-12 * self.load_scale):
                break
        else:
            hist.status, hist.reason = "failed", f"max_steps={s.max_steps} reached at lambda={lam:.6g}"
            return
        hist.collapse_bracket = (lam, lam_fail)
        hist.status = "collapse"
        hist.reason = f"no equilibrium beyond lambda={lam:.6g} (first failure at {lam_fail:.6g}: {last_reason})"

    def _displacement_control(self, hist: History, record, control: DisplacementControl, dof: int) -> None:
        s = self.settings
        position = np.flatnonzero(self.asm.free_index == dof)
        if position.size == 0:
            raise ValueError(f"control dof {control.dof} of block {control.block} is fixed")
        k = int(position[0])
        if control.steps < 1:
            raise ValueError(f"control steps must be at least 1, got {control.steps!r}")
        du_nominal = control.target / control.steps
        du = du_nominal
        lam = 0.0
        u = float(self.q[dof])
        cuts = 0
        while abs(u - control.target) > 1e-12 * abs(control.target) and len(hist.steps) < s.max_steps:
            goal = u + du
            if (goal - control.target) * np.sign(du_nominal) > 0:
                goal = control.target
            out = self._equilibrate(lam, control=(k, goal))
            if out.ok:
                record(out)
                lam, u = out.load_factor, goal
                du = min(abs(du) * s.growth, abs(du_nominal)) * np.sign(du_nominal)
                cuts = 0
            else:
                du /= 2
                cuts += 1
                if cuts > 12:
                    hist.status = "failed"
                    hist.reason = f"displacement control stuck at {u:.4g}: {out.reason}"
                    break
        else:
            hist.status, hist.reason = "completed", f"control displacement reached {u:.6g}"
        lams = hist.load_factors
        peak = int(np.argmax(lams))
        hist.collapse_bracket = (float(lams[peak]), float(lams[peak]))

    def _global_dof(self, block: int, dof: str) -> int:
        if dof not in DOF_NAMES:
            raise ValueError(f"dof must be one of {DOF_NAMES}, got {dof!r}")
        if not 0 <= block < self.model.blocks.count:
            raise ValueError(f"block must be in 0..{self.model.blocks.count - 1}, got {block!r}")
        return 6 * int(block) + DOF_NAMES.index(dof)

    def _finish(self, hist: History, status: str, reason: str, t0: float) -> History:
        hist.status, hist.reason = status, reason
        hist.seconds = time.perf_counter() - t0
        hist.iterations = self.iterations
        hist.factorizations = self.factorizations
        log.info("%s: %s after %d steps (%s)", self.model.name, status, len(hist.steps), reason)
        return hist


def pushover(
    model: Model,
    settings: StaticSettings | None = None,
    control: DisplacementControl | None = None,
    out=None,
    monitor: tuple[int, str] | None = None,
    write_every: int = 1,
) -> History:
    """Run the static incremental analysis; with ``out`` write VTU/PVD, pushover.csv and
    summary.json to that folder as the steps converge."""
    writer = None
    if out is not None:
        from masonry_dem.export.writer import ResultsWriter

        writer = ResultsWriter(out, model, every=write_every)
    solver = StaticSolver(model, settings)
    history = solver.run(control=control, callback=writer, monitor=monitor)
    if writer is not None:
        writer.finish(history)
    return history


__all__ = ["StaticSettings", "DisplacementControl", "StaticSolver", "pushover", "replace"]
