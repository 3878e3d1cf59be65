"""Radenkovic's theorem on the validation set: the associative limit-analysis multiplier
with the DEM's circular Coulomb cone and the friction enlarged by kappa(alpha), whose domain
contains every DEM joint's (solvers.limit_analysis.dem_domain), is never below the
pushover's lambda; nor, on these walls, is the classical one (kappa = 1), which is a theorem
only for alpha = 1. Walls held on both edges may arch between the held
columns: the LP is then unbounded ("no collapse", an infinite bound), which the test
accepts and docs/limit_analysis.md lists."""

from __future__ import annotations

import pytest

from helpers.paper_runs import run_case
from masonry_dem.cases.paper import case_names
from masonry_dem.solvers.limit_analysis import dem_upper_bound, limit_analysis


@pytest.mark.slow
@pytest.mark.parametrize("name", case_names())
def test_associative_multiplier_is_never_below_the_pushover(name):
    case, history = run_case(name)
    lam = history.collapse_multiplier or history.final_load_factor
    la = dem_upper_bound(case.model)  # the exact cone: the tightest bound
    assert la.status in ("collapse", "no collapse"), la.reason
    if la.status == "collapse":
        assert la.bound == "upper"
        assert la.load_factor >= lam * (1 - 1e-6), (la.load_factor, lam)
    plain = limit_analysis(case.model, backend="clarabel")
    assert plain.status == la.status, plain.reason
    if plain.status == "collapse":
        assert plain.load_factor >= lam * (1 - 1e-6), (plain.load_factor, lam)
