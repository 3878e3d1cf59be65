"""Dynamic relaxation: masses, time step, damping and loading options, closed-form collapse
loads, agreement with the static solver, results usable by the writer."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.linalg as sla

from helpers.walls import A, B, S, on_base
from masonry_dem.export.analyses import relax
from masonry_dem.geometry import builders
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    Support,
)
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation
from masonry_dem.solvers.incremental import StaticSolver

FAST = {"bracket_tolerance": 0.01}


@pytest.fixture(scope="module")
def tilting_block() -> Model:
    return on_base(builders.single_block(A, B, S, 20e3))


@pytest.fixture(scope="module")
def small_wall() -> Model:
    return on_base(builders.running_bond_wall(2, 2, 0.1, 0.2, 0.08, 20e3))


def _lambda(h) -> float:
    assert h.status == "collapse", h.reason
    assert h.collapse_multiplier is not None
    return h.collapse_multiplier


# ---------------------------------------------------------------------------- settings
@pytest.mark.parametrize(
    "field, value",
    [
        ("mass", "lumped"),
        ("damping", "none"),
        ("loading", "cyclic"),
        ("dt_fraction", 0.0),
        ("dt_fraction", math.nan),
        ("dt", -1.0),
        ("tolerance", 0.0),
        ("growth", 0.5),
        ("max_cycles", 0),
        ("on_blowup", "ignore"),
    ],
)
def test_settings_reject_bad_values_by_name(field, value):
    with pytest.raises(ValueError, match=field):
        DRSettings(**{field: value})


# ---------------------------------------------------------------------------- masses and dt
def test_stiffness_scaled_masses_bound_the_spectrum(small_wall):
    """Gershgorin-scaled masses: lambda_max(M^-1 K) <= 1, so the stable step is 2 for any wall."""
    dr = DynamicRelaxation(small_wall)
    K = dr.K_elastic.toarray()
    eig = sla.eigh(K, np.diag(dr.mass), eigvals_only=True)
    assert eig.max() <= 1.0 + 1e-9
    assert eig.min() > 0
    assert dr.dt_limit == pytest.approx(2.0 / math.sqrt(dr.lambda_max))
    assert dr.dt == pytest.approx(0.9 * dr.dt_limit)


@pytest.mark.parametrize("mass", ["stiffness", "density"])
def test_power_estimate_is_sharp_and_safe(small_wall, mass):
    """The power-iteration limit is below the true limit (5 % margin) and above Gershgorin's."""
    power = DynamicRelaxation(small_wall, DRSettings(mass=mass, dt_rule="power"))
    gersh = DynamicRelaxation(small_wall, DRSettings(mass=mass))
    K = power.K_elastic.toarray()
    true_max = sla.eigh(K, np.diag(power.mass), eigvals_only=True).max()
    assert power.lambda_max >= true_max * 0.999
    assert power.lambda_max <= 1.06 * true_max
    assert gersh.dt_limit <= power.dt_limit * 1.06


def test_density_masses_follow_the_blocks(tilting_block):
    dr = DynamicRelaxation(tilting_block, DRSettings(mass="density"))
    m = dr.mass.reshape(-1, 6)  # one free block: u1 u2 u3 w1 w2 w3
    assert np.allclose(m[0, :3], m[0, 0])  # same mass on the three translations
    # rotational inertias m (b^2 + c^2) / 12 about each axis, relative to the mass
    ratio = m[0, 3:] / m[0, 0]
    expected = np.array([A**2 + S**2, B**2 + S**2, B**2 + A**2]) / 12
    assert np.allclose(ratio, expected)


# ---------------------------------------------------------------------------- closed form
def test_single_block_tilts_at_s_over_a(tilting_block):
    lam = _lambda(DynamicRelaxation(tilting_block).run())
    assert lam == pytest.approx(S / A, rel=0.005)


def test_single_block_slides_at_mu():
    model = on_base(builders.single_block(A, B, 0.3, 20e3), friction=0.5)
    lam = _lambda(DynamicRelaxation(model, DRSettings(**FAST)).run())
    assert lam == pytest.approx(0.5, rel=0.01)


def test_free_standing_column_tilts_at_s_over_h():
    model = on_base(builders.stack_bond_column(2, A, B, S, 20e3))
    lam = _lambda(DynamicRelaxation(model, DRSettings(**FAST)).run())
    assert lam == pytest.approx(S / (2 * A), rel=0.01)


@pytest.mark.parametrize(
    "changes",
    [
        {"damping": "viscous", "bracket_tolerance": 0.02},
        {"loading": "ramp", "ramp_rate": 1e-3},
        {"mass": "density", "bracket_tolerance": 0.02},
        {"stability": "current", "bracket_tolerance": 0.02},
    ],
    ids=["viscous", "ramp", "density", "current-stiffness"],
)
def test_every_option_finds_the_rocking_limit(tilting_block, changes):
    lam = _lambda(DynamicRelaxation(tilting_block, DRSettings(**changes)).run())
    assert lam == pytest.approx(S / A, rel=0.02)


def test_agrees_with_the_static_solver_on_a_small_wall(small_wall):
    static = StaticSolver(small_wall).run()
    dr = DynamicRelaxation(small_wall, DRSettings(**FAST)).run()
    lo_s, hi_s = static.collapse_bracket
    lo_d, hi_d = dr.collapse_bracket
    assert lo_d <= hi_s * 1.001 and lo_s <= hi_d * 1.001  # the brackets overlap
    assert _lambda(dr) == pytest.approx(_lambda(static), rel=0.01)


# ---------------------------------------------------------------------------- results
def test_history_is_complete_and_finite(small_wall, tmp_path):
    hist = relax(small_wall, DRSettings(**FAST), out=tmp_path)
    lams = hist.load_factors
    assert np.all(np.diff(lams) > 0)  # one step per converged, increasing load level
    for step in hist.steps:
        for arr in (step.q, step.actions, step.utilisation):
            assert np.all(np.isfinite(arr))
    assert hist.iterations > 0  # time steps
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["method"] == "dynamic_relaxation"
    assert summary["lambda"] == pytest.approx(hist.collapse_multiplier)
    assert (tmp_path / "pushover.csv").is_file()


def test_no_live_load_is_completed():
    blocks, base = builders.add_base(builders.single_block(A, B, S, 20e3))
    model = Model.build(blocks, InterfaceMaterial(1e9, 4e8, 0.7), [Support(np.array([base]))])
    hist = DynamicRelaxation(model).run()
    assert hist.status == "completed"
    assert hist.collapse_multiplier is None
    # the dead-load state: the block presses the base with its weight
    fn = hist.last.actions[:, 2]
    assert fn.sum() == pytest.approx(-model.blocks.weights.sum(), rel=1e-3)


def test_max_load_factor_completes_below_collapse(tilting_block):
    hist = DynamicRelaxation(tilting_block, DRSettings(max_load_factor=0.3)).run()
    assert hist.status == "completed"
    assert hist.final_load_factor == pytest.approx(0.3)
    assert hist.collapse_multiplier is None


def test_time_step_budget_fails_without_lambda(small_wall):
    hist = DynamicRelaxation(small_wall, DRSettings(max_time_steps=300)).run()
    assert hist.status == "failed"
    assert "budget" in hist.reason
    assert hist.collapse_multiplier is None


def test_a_probe_ends_a_relaxation_only_where_it_says_so(small_wall):
    """``Relaxation._relax``'s probe (the stop check's Newton tries): asked at peaks of the
    kinetic energy at least ``probe_every`` time steps apart. A probe that always says no
    leaves the relaxation exactly as it was (the same time steps, the same state); one that
    says yes ends it as converged at the first peak it is asked at, long before the motion
    dies out."""
    from masonry_dem.solvers.dynamic_relaxation import RelaxationStart

    dr = DynamicRelaxation(small_wall, DRSettings(tolerance=1e-6, max_cycles=50_000))
    nf, m = dr.Hf.shape[1], dr.m
    start = RelaxationStart(
        np.zeros(nf), np.zeros((m, 6)), np.zeros(m, dtype=bool), 0.0, np.ones((m, 6))
    )
    plain = dr.relax_with_cuts(start, 0.1)
    assert plain.ok
    asked: list[int] = []

    def no(x):
        asked.append(dr.stats.time_steps)
        return False

    again = dr.relax_with_cuts(start, 0.1, probe=no, probe_every=50)
    assert again.ok and again.cycles == plain.cycles
    assert np.array_equal(again.x, plain.x)
    assert len(asked) >= 2 and np.all(np.diff(asked) >= 50)
    short = dr.relax_with_cuts(start, 0.1, probe=lambda x: True, probe_every=50)
    assert short.ok and short.kind == "converged"
    assert 50 <= short.cycles < plain.cycles
