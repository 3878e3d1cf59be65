"""The compiled time steps of dynamic relaxation (``DRSettings.compiled_steps``, kinetic
damping at a fixed load) against the Python loop: the same operations in the same order, so
the same bits, at every kind of ending a relaxation meets: rest, a stalled residual, a
mechanism."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.walls import on_base
from masonry_dem.geometry import builders
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation, RelaxationStart


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
