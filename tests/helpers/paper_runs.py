"""One pushover per validation case per test session, shared by the test modules of tests/cases
(a run takes 2-40 s; the mechanism and the collapse-load tests read the same History)."""

from __future__ import annotations

from functools import cache

from masonry_dem.cases.paper import PaperCase, build_case
from masonry_dem.results import History
from masonry_dem.solvers.incremental import pushover


@cache
def run_case(name: str, **assumptions) -> tuple[PaperCase, History]:
    """``assumptions``: changes to :class:`masonry_dem.cases.paper.Assumptions`."""
    case = build_case(name, **assumptions)
    return case, pushover(case.model, case.settings, monitor=case.monitor)
