"""The load path of dynamic relaxation: dead load, then lambda raised in steps or ramped
until a mechanism forms (:class:`DynamicRelaxation`, :func:`relax`).

Loading (``loading``): ``"steps"`` raises lambda in steps exactly as the static solver does
(same initial step, growth, bracket refinement by halving) and relaxes every step from the last
converged state with the plastic state of that state held (the same holonomic step problem as
the static solver); ``"ramp"`` raises lambda continuously at ``ramp_rate`` per unit of pseudo
time, updates the plastic state every time step (the classical explicit DEM) and records the
quasi-static states it passes through, verified afterwards by relaxing them at their own
lambda; with ``refine`` the collapse bracket is then refined in steps from the highest verified
state. Tensile cracks are held during the ramp (an inertial overshoot would crack joints that
the quasi-static path leaves intact) and enter at verified states only.

Failure, never a wrong lambda: a load step whose relaxation finds a mechanism or stalls
fails, and the bracket is refined as in the static solver (status ``"collapse"``); a blow-up
the cuts of the time step do not cure, or the spent ``max_time_steps``, ends the run with
status ``"failed"``, no collapse multiplier, and a reason naming the step and the estimated
limit.

The results are a :class:`~masonry_dem.results.History` (one StepResult per converged load
step), so the VTU/PVD writer works unchanged; ``History.iterations`` counts time steps.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from masonry_dem._threads import kernel_threads_for
from masonry_dem.constitutive.law import LawResponse
from masonry_dem.model import DofName, Model, Monitor
from masonry_dem.results import History, Observer, StepResult, observed
from masonry_dem.solvers.dynamic_relaxation.integrator import (
    FATAL,
    Relaxation,
    RelaxationStart,
    Relaxed,
)
from masonry_dem.solvers.dynamic_relaxation.settings import DRSettings
from masonry_dem.solvers.static.outcome import Status

log = logging.getLogger(__name__)

StepCallback = Callable[[StepResult], None]


class DynamicRelaxation(Relaxation):
    """Dynamic relaxation of one model along its load path."""

    # ------------------------------------------------------------------ bookkeeping
    def _record(
        self,
        hist: History,
        x: NDArray[np.float64],
        lam: float,
        resp: LawResponse,
        cycles: int,
        monitor_dof: int | None,
        callback: StepCallback | None,
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
        self,
        x: NDArray[np.float64],
        lam: float,
        start: RelaxationStart,
        resp: LawResponse,
        ramp: bool,
    ) -> RelaxationStart:
        rel = (self.Hf @ x).reshape(-1, 6)
        plastic = self.law.plastic_part(rel, resp.actions)
        cracked = self.law.cracked_after(start.cracked, resp)
        return RelaxationStart(x.copy(), plastic, cracked, lam, resp.tangent.copy())

    # ------------------------------------------------------------------ analyses
    def run(
        self,
        callback: StepCallback | None = None,
        monitor: Monitor | None = None,
    ) -> History:
        """Dead load, then lambda raised in steps or ramped until a mechanism forms."""
        with kernel_threads_for(self.m):
            return self._run(callback, monitor)

    def _run(
        self,
        callback: StepCallback | None,
        monitor: Monitor | None,
    ) -> History:
        t0 = time.perf_counter()
        s = self.settings
        hist = History()
        monitor_dof = self._global_dof(*monitor) if monitor is not None else None
        nf = self.asm.n_free
        zero = RelaxationStart(
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
        dead = self.relax_with_cuts(zero, 0.0)
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

    def _ramp(
        self,
        hist: History,
        state: RelaxationStart,
        monitor_dof: int | None,
        callback: StepCallback | None,
    ) -> RelaxationStart:
        """Raise lambda continuously, then verify the quasi-static states passed on the way.

        A state passed during the ramp has a residual below ``ramp_tolerance`` only: it is a
        candidate, not an equilibrium. After the ramp ends in a mechanism, candidates are
        relaxed at their own lambda (held) to the full tolerance, by bisection over the list;
        the highest one that settles is the verified state, and only candidates up to it enter
        the History. Returns the verified state (the dead-load state if none settles).
        """
        s = self.settings
        candidates: list[tuple[RelaxationStart, LawResponse]] = []

        def checkpoint(
            x: NDArray[np.float64],
            lam: float,
            resp: LawResponse,
            plastic: NDArray[np.float64],
            cracked: NDArray[np.bool_],
        ) -> None:
            if candidates and lam <= candidates[-1][0].load_factor * (1 + s.bracket_tolerance):
                return
            st = RelaxationStart(x.copy(), plastic.copy(), cracked.copy(), lam, resp.tangent.copy())
            candidates.append((st, resp))

        top = s.max_load_factor if math.isfinite(s.max_load_factor) else 1e6 * self.load_scale
        out = self.relax_with_cuts(state, top, ramp_to=top, on_checkpoint=checkpoint)
        if out.kind in FATAL:
            hist.status, hist.reason = Status.FAILED, out.reason
            return state
        if out.ok:
            plastic, cracked = self._plastic_of(out, state)
            candidates.append(
                (
                    RelaxationStart(out.x, plastic, cracked, out.load_factor, out.response.tangent),
                    out.response,
                )
            )
        lam_fail = math.inf if out.ok else float(out.load_factor)
        # bisection for the highest candidate that settles at its own lambda
        lo, hi = -1, len(candidates)
        verified: tuple[RelaxationStart, Relaxed] | None = None
        while hi - lo > 1:
            mid = (lo + hi) // 2
            cand, _ = candidates[mid]
            probe = self.relax_with_cuts(cand, cand.load_factor)
            if probe.kind in FATAL:
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

    def _plastic_of(
        self, out: Relaxed, state: RelaxationStart
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        rel = (self.Hf @ out.x).reshape(-1, 6)
        return self.law.plastic_part(rel, out.response.actions), self.law.cracked_after(
            state.cracked, out.response
        )

    def _load_control(
        self,
        hist: History,
        state: RelaxationStart,
        monitor_dof: int | None,
        callback: StepCallback | None,
    ) -> None:
        s = self.settings
        lam = state.load_factor
        dlam = s.initial_step * self.load_scale
        max_dlam = s.max_step * self.load_scale
        lam_fail = self._ramp_fail
        if math.isfinite(lam_fail):
            dlam = (lam_fail - lam) / 2
        last_reason = hist.reason if math.isfinite(lam_fail) else ""
        # the stall window the failure at lam_fail was judged with (inf: not by a stall)
        fail_window = math.inf
        for _ in range(s.max_steps):
            if math.isfinite(lam_fail) and lam_fail - lam <= s.bracket_tolerance * max(
                abs(lam), 1e-12 * self.load_scale
            ):
                break
            target = min(lam + dlam, s.max_load_factor)
            window = self._stall_window()
            out = self.relax_with_cuts(state, target)
            if out.kind in FATAL:
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
                if math.isfinite(lam_fail) and self._stall_window() > fail_window:
                    # the failure was a stall judged against faster steps than this one (the
                    # first live step against the dead load's settling, a different, stiffer
                    # mode): it proves no mechanism, so the failed load is tried again
                    log.debug(
                        "DR: lambda=%.6g stalled over %d time steps, a converged step took %d: "
                        "tried again",
                        lam_fail,
                        fail_window,
                        out.cycles,
                    )
                    dlam = lam_fail - lam
                    lam_fail, fail_window, last_reason = math.inf, math.inf, ""
                elif math.isfinite(lam_fail):
                    dlam = (lam_fail - lam) / 2
                else:
                    dlam = min(dlam * s.growth, max_dlam)
            else:
                last_reason = out.reason
                if target <= lam_fail:
                    by_window = out.kind == "stalled" and out.cycles < s.max_cycles
                    fail_window = window if by_window else math.inf
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

    def _fail_empty(
        self,
        hist: History,
        zero: RelaxationStart,
        reason: str,
        t0: float,
        callback: StepCallback | None,
    ) -> History:
        resp = self.law.respond(np.zeros((self.m, 6)), zero.plastic, zero.cracked)
        self._record(hist, zero.x, 0.0, resp, 0, None, callback)
        return self._finish(hist, Status.FAILED, reason, t0)

    def _global_dof(self, block: int, dof: DofName) -> int:
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
    monitor: Monitor | None = None,
    callback: StepCallback | None = None,
    observer: Observer | None = None,
) -> History:
    """Run dynamic relaxation. ``callback(step)`` is called after each converged step (e.g.
    a progress bar); ``observer`` follows the run (:class:`~masonry_dem.results.Observer`: a
    results writer). ``masonry_dem.relax`` is this with ``out``, a results folder."""
    from masonry_dem.model import require_model

    require_model("relax", model)
    return relax_with(DynamicRelaxation(model, settings), monitor, callback, observer)


def relax_with(
    solver: DynamicRelaxation,
    monitor: Monitor | None = None,
    callback: StepCallback | None = None,
    observer: Observer | None = None,
) -> History:
    """:func:`relax` with the solver made by the caller, who keeps it for its ``stats``."""
    return observed(
        lambda on_step: solver.run(callback=on_step, monitor=monitor),
        observer,
        callback,
        lambda: {"method": "dynamic_relaxation", "time_steps": solver.stats.time_steps},
    )
