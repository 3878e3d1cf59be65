"""The compiled time steps of dynamic relaxation (``DRSettings.compiled_steps``, kinetic
damping at a fixed load) against the Python loop: the same operations in the same order, so
the same bits, at every kind of ending the static solver's corner check meets.

S6 with 2-block return walls passes three folds (the check's relaxations, with Newton
probes and the creep kept undamped, come to rest above each) and stops at a certified
peak, 0.1080; the relaxation from there to 1 % above it (tests/cases/test_peaks_not_folds.py)
finds no rest. Both loops must give every relaxation the same kind
of ending, time steps and state, bit for bit, and the path the same collapse multiplier."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from helpers.walls import on_base
from masonry_dem.cases.paper import build_case
from masonry_dem.geometry import builders
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation, RelaxationStart
from masonry_dem.solvers.dynamic_relaxation.integrator import Relaxation
from masonry_dem.solvers.static import StaticSolver


def _record(monkeypatch, compiled: bool) -> list[tuple]:
    """Every relaxation of the run from now on, with ``compiled_steps`` set to ``compiled``."""
    init, relax = Relaxation.__init__, Relaxation._relax
    log: list[tuple] = []

    def set_loop(self, model, settings=None):
        init(self, model, settings)
        self.settings = dataclasses.replace(self.settings, compiled_steps=compiled)

    def recorded(self, *args, **kw):
        out = relax(self, *args, **kw)
        s = self.stats
        log.append(
            (out.kind, out.cycles, out.x.tobytes(), out.response.actions.tobytes(),
             out.reason, s.time_steps, s.law_evaluations, s.kinetic_resets, self._courant)
        )  # fmt: skip
        return out

    monkeypatch.setattr(Relaxation, "__init__", set_loop)
    monkeypatch.setattr(Relaxation, "_relax", recorded)
    return log


@pytest.mark.slow
def test_compiled_steps_give_the_bits_of_the_python_loop_at_folds_and_a_peak(monkeypatch):
    case = build_case("S6", restraint="return-walls", return_blocks=2)
    runs = {}
    for compiled in (False, True):
        with monkeypatch.context() as m:
            log = _record(m, compiled)
            solver = StaticSolver(case.model, case.settings)
            hist = solver.run(monitor=case.monitor)
            assert hist.status == "collapse", hist.reason
            peak = hist.collapse_multiplier
            solver.dynamic_rescue(1.01 * peak, solver.load_factor, budget=5_000)
        runs[compiled] = (log, hist.collapse_multiplier, [s.q.tobytes() for s in hist.steps])
    log = runs[False][0]
    kinds = {entry[0] for entry in log}
    assert "converged" in kinds  # the folds: a rest found above them
    assert log[-1][0] != "converged"  # the peak: none found above it
    assert runs[True][0] == log
    assert runs[True][1] == runs[False][1]
    assert runs[True][2] == runs[False][2]


@pytest.mark.parametrize(
    "target, kind", [(0.3, "converged"), (0.5, "stalled"), (10.0, "mechanism")]
)
def test_compiled_steps_end_where_the_python_loop_does_on_a_small_wall(target, kind):
    """A 2 x 2 wall (its collapse at 0.400) relaxed from rest to lambda = 0.3 (it comes to
    rest), 0.5 (above the peak: the residual stalls) and 10 (a mechanism forms at once),
    with a probe that says no and the creep kept: the same ending, time steps, states
    the probe is asked at, kinetic-energy resets and state."""
    model = on_base(builders.running_bond_wall(2, 2, 0.1, 0.2, 0.08, 20e3))
    out = {}
    for compiled in (False, True):
        dr = DynamicRelaxation(
            model, DRSettings(tolerance=1e-6, max_cycles=50_000, compiled_steps=compiled)
        )
        nf, m = dr.Hf.shape[1], dr.m
        start = RelaxationStart(
            np.zeros(nf), np.zeros((m, 6)), np.zeros(m, dtype=bool), 0.0, np.ones((m, 6))
        )
        asked: list[bytes] = []

        def no(x, asked=asked):
            asked.append(x.tobytes())
            return False

        r = dr.relax_with_cuts(start, target, probe=no, probe_every=40, creep_cos=0.5)
        out[compiled] = (r.kind, r.cycles, r.x.tobytes(), r.reason, asked, dr.stats.time_steps,
                         dr.stats.kinetic_resets, dr.stats.law_evaluations)  # fmt: skip
    assert out[False][0] == kind
    assert len(out[False][4]) >= (2 if target < 1.0 else 0)  # the probe was asked
    assert out[True] == out[False]
