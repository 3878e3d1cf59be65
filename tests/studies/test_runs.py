"""The methods of a study: each named explicitly, each run through its public entry point."""

from __future__ import annotations

import pytest

from helpers.walls import A, B, S, on_base
from masonry_dem.geometry import builders
from masonry_dem.solvers.incremental import StaticSettings
from masonry_dem.studies.kn_sweep import kn_sweep
from masonry_dem.studies.runs import Method, run_method, settings_for


def test_a_method_that_is_not_one_of_the_three_is_refused():
    model = on_base(builders.single_block(A, B, S, 20e3))
    with pytest.raises(ValueError):
        run_method("newton", model, StaticSettings())  # type: ignore[arg-type]


def test_each_method_finds_the_tilting_load_of_one_block():
    """One block a x b x s on a rigid base, tilted out of plane: it overturns about its base
    edge at lambda = s / a (moment of the weight W s / 2 against lambda W a / 2), below the
    sliding load mu = 0.7. Static and DR to their bracket, limit analysis exactly."""
    model = on_base(builders.single_block(A, B, S, 20e3))
    for method, rel in ((Method.STATIC, 0.01), (Method.LIMIT_ANALYSIS, 1e-9)):
        run = run_method(method, model, settings_for(method, StaticSettings()))
        assert run.status == "collapse", run.reason
        assert run.load_factor == pytest.approx(S / A, rel=rel)
        assert run.seconds > 0 and run.cost["iterations"] >= 1
    # the plain associative multiplier: a certified upper bound of the DEM only where every
    # joint has alpha = 1 (solvers.limit_analysis.dem_domain); this block's joint has the
    # default alpha, so the study labels it an estimate
    assert run.history is None and run.bound == "estimate"


def test_the_kn_sweep_refuses_limit_analysis():
    with pytest.raises(ValueError, match="rigid blocks have no kn"):
        kn_sweep("S15", [1.0], Method.LIMIT_ANALYSIS)
