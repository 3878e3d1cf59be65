"""Write a limit analysis to a results folder: ``summary.json`` (the keys of a pushover's,
plus ``method`` and ``bound``) and, at collapse, the mechanism as ``mechanism_blocks.vtu`` /
``mechanism_interfaces.vtu``, as a pushover that ends in collapse writes them."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.model import Model
from masonry_dem.results import StepResult
from masonry_dem.solvers.limit_analysis import LimitAnalysisResult

log = logging.getLogger(__name__)


def collapse_step(model: Model, result: LimitAnalysisResult) -> StepResult:
    """The collapse state as a step: no displacement (rigid blocks), the interface actions at
    collapse, their damage state and utilisation under the DEM's strength check."""
    from masonry_dem.constitutive import check_strength

    its = model.interfaces
    actions = np.asarray(result.interface_actions, dtype=float)
    if its.count:
        chk = check_strength(
            actions, its.l1, its.l2, model.friction, model.tensile_strength * its.area, model.alpha
        )
        state, util, flags = chk.state, chk.utilisation, chk.flags
    else:
        state, util, flags = (np.zeros(0, dtype=np.int8), np.zeros(0), np.zeros(0, np.uint8))
    lam = result.load_factor if np.isfinite(result.load_factor) else 0.0
    return StepResult(0, lam, np.zeros((model.blocks.count, 6)), actions, state, util, flags)


def write_limit_results(
    folder: Path | str, model: Model, result: LimitAnalysisResult, **summary_extra: Any
) -> dict[str, Any]:
    """Write ``summary.json`` and, at collapse, the mechanism VTUs; returns the summary."""
    from masonry_dem.export.results_folder import write_summary
    from masonry_dem.export.vtu import write_mechanism_vtu

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    la = result.summary()
    summary: dict[str, Any] = {
        "status": la.pop("status"),
        "reason": la.pop("reason"),
        "steps": 1 if result.status == "collapse" else 0,
        "lambda": la.pop("lambda"),
        "lambda_bracket": None,
        "iterations": la.pop("iterations"),
        "factorizations": 0,
        "seconds": la.pop("seconds"),
        "blocks": model.blocks.count,
        "interfaces": model.interfaces.count,
        "name": model.name,
        "steps_written": 0,
        "analysis": "limit",
        "method": result.method,
        "bound": la.pop("bound"),
        "limit_analysis": la,
    }
    summary.update(summary_extra)
    if result.status == "collapse":
        step = collapse_step(model, result)
        write_mechanism_vtu(folder, model, step, result.block_velocities, None)
    summary = write_summary(folder, summary)
    log.info("limit analysis written to %s", folder)
    return summary
