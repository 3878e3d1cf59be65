"""One run of a sweep: a parsed case file run as ``masonry-dem run`` runs it, reduced to the
result columns of its row (:data:`RESULT_COLUMNS`) and, on demand, its files."""

from __future__ import annotations

import logging
import os
import socket
import time
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from masonry_dem.model import Model
    from masonry_dem.results import History

log = logging.getLogger(__name__)

#: the result columns of a row (after ``run`` and the varied paths), with their type
RESULT_COLUMNS: dict[str, type] = {
    "status": str,  # collapse | completed | failed (the analysis) | error (an exception)
    "reason": str,
    "lambda": float,  # collapse multiplier, or the final lambda of a completed run
    "lambda_upper": float,  # upper end of the collapse bracket
    "limit_analysis_bound": float,
    "limit_analysis_status": str,
    "steps": int,
    "mechanism_blocks": int,  # blocks moving >= 5 % of the largest translation of the mode
    "mechanism_cracks": int,  # joints moving >= 50 % of the largest: the cracks
    "mechanism_sliding_share": float,  # sliding / (sliding + opening) over the cracks
    # the seismic mechanism (a weight-proportional live load c P_i d only): alpha0 = c lambda
    # and e*, the participating mass fraction of the hinged mode (Circolare 2019 [C8.7.1.5]); with
    # them a0* = alpha0 g / (e* FC) and the run's capacity as a ground acceleration
    # (masonry-dem fragility, docs/assessment.md); a completed run (no collapse) has alpha0 =
    # c lambda at its last lambda, a lower bound, and no e*
    "alpha0": float,
    "e_star": float,
    "seconds": float,  # wall-clock time of the run on its worker
    "cpu_seconds": float,  # CPU time of the worker process meanwhile: seconds / cpu_seconds
    # above 1 is time spent waiting for a core (a loaded machine), not computing
    "worker": str,
    "folder": str,
}
#: a block "moves" in the collapse mode above this share of the largest translation, the
#: threshold below which the mechanism picture draws a joint as shut
MOVING = 0.05


def run_point(
    data: dict[str, Any], source: str, keep: str = "none", folder: str | None = None
) -> dict[str, Any]:
    """Run one case (a parsed case file) as ``masonry-dem run`` does: the associative
    limit-analysis bound, then the pushover (or the limit analysis alone for ``[analysis]
    method = "limit"``). Returns the result columns of its row (:data:`RESULT_COLUMNS`);
    anything the run raises is the row's status ``error`` with the reason, never raised."""
    t0, c0 = time.perf_counter(), time.process_time()
    row: dict[str, Any] = dict.fromkeys(RESULT_COLUMNS)
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    try:
        row.update(_run(data, source, keep, None if keep == "none" else folder))
    except Exception as exc:  # a failed run is a row: the sweep goes on
        text = " ".join(str(exc).split()) or type(exc).__name__
        row.update(status="error", reason=f"{type(exc).__name__}: {text}")
        log.info("run of %s raised %s", source, row["reason"])
    row["seconds"] = time.perf_counter() - t0
    row["cpu_seconds"] = time.process_time() - c0
    return row


def _run(data: dict[str, Any], source: str, keep: str, folder: str | None) -> dict[str, Any]:
    from masonry_dem.analysis import analyze
    from masonry_dem.cases.casefile import case_from_dict
    from masonry_dem.run_case import limit_analysis_bound

    case = case_from_dict(data, source)
    if case.method == "limit":
        la = analyze(case.model, "limit", case.limit_options or {})
        if folder is not None:
            from masonry_dem.export import results_folder as rf

            Path(folder).mkdir(parents=True, exist_ok=True)
            rf.write_summary(folder, {"case": source, **la.details.summary()})
        return {
            "status": la.status,
            "reason": la.reason,
            "lambda": la.load_factor,
            "limit_analysis_bound": la.load_factor if la.bound == "upper" else None,
            "limit_analysis_status": la.status,
            "folder": folder,
        }
    # the row's bound column: the same certified bound a pushover's summary carries
    # (a run in loading stages has none: the limit analysis takes one dead and one live load)
    bound_fields = (
        limit_analysis_bound(case.model)
        if case.stages is None
        else {
            "limit_analysis_bound": None,
            "limit_analysis_status": "not computed (loading stages)",
        }
    )
    bound = bound_fields["limit_analysis_bound"]
    extra: dict[str, Any] = {
        k: bound_fields[k] for k in ("limit_analysis_bound", "limit_analysis_status")
    }
    writer = None
    if keep == "all" and folder is not None:
        from masonry_dem.export.writer import ResultsWriter

        writer = ResultsWriter(folder, case.model, overwrite=True, start={"case": source})
    with writer or nullcontext():
        run = analyze(
            case.model,
            "pushover",
            case.settings,
            control=case.control,
            stages=case.stages,
            bound=bound,
            monitor=case.monitor,
            progress=writer,
        )
    history = run.details
    if writer is not None:
        writer.finish(history, case=source, **extra)
    elif folder is not None:  # keep = "summary"
        from masonry_dem.export import pushover_file as pf
        from masonry_dem.export import results_folder as rf

        Path(folder).mkdir(parents=True, exist_ok=True)
        pf.write_history_pushover(folder, history)
        summary = history.summary(
            blocks=case.model.blocks.count, interfaces=case.model.interfaces.count
        )
        rf.write_summary(folder, {"name": case.model.name, "case": source, **summary}, extra)
    status = str(history.status)
    ended = status in ("collapse", "completed")
    bracket = history.collapse_bracket
    row: dict[str, Any] = {
        "status": status,
        "reason": history.reason,
        "lambda": history.summary()["lambda"] if ended else None,
        "lambda_upper": bracket[1] if bracket else None,
        "steps": len(history.steps),
        "folder": folder,
        **extra,
    }
    if status == "collapse":
        row.update(mechanism_summary(case.model, history))
    elif status == "completed" and row["lambda"]:
        row.update(standing_alpha0(case.model, row["lambda"]))
    return row


def standing_alpha0(model: Model, lam: float) -> dict[str, Any]:
    """alpha0 = c lambda of a run that ended still standing at ``lam`` (no collapse mode, so
    no e*): a lower bound of its alpha0, the right-censored capacity of ``masonry-dem
    fragility``; {} when the live load is not c P_i d."""
    from masonry_dem.assessment.kinematics import live_load_scale

    try:
        return {"alpha0": float(lam) * live_load_scale(model)}
    except ValueError as exc:
        log.info("%s: no seismic reading of the live load (%s)", model.name, exc)
        return {}


def mechanism_summary(model: Model, history: History) -> dict[str, Any]:
    """The collapse mode in three numbers: the blocks that move (>= 5 % of the largest
    translation), the cracks (joints whose relative motion is >= 50 % of the largest, the
    red joints of the mechanism picture) and the share of sliding in the cracks' motion
    (1: they slide, 0: they open and turn)."""
    from masonry_dem.export.render import MECHANISM_BINS
    from masonry_dem.export.vtu import joint_relative_motion
    from masonry_dem.mechanism import collapse_mode, joint_motion

    try:
        mode = collapse_mode(model, history.last)
    except (ValueError, RuntimeError, ArithmeticError) as exc:
        log.info("%s: no collapse mode (%s)", model.name, exc)
        return {}
    moved = np.linalg.norm(mode[:, :3], axis=1)
    motion = joint_relative_motion(model, mode)
    peak = float(motion.max(initial=0.0))
    cracks = motion >= MECHANISM_BINS[-1] * peak if peak > 0 else np.zeros(motion.size, bool)
    jm = joint_motion(model, mode)
    slide = float(jm.sliding[cracks].sum())
    opening = float(np.maximum(jm.opening[cracks], 0.0).sum())
    return {
        "mechanism_blocks": int((moved >= MOVING * moved.max(initial=0.0)).sum())
        if moved.max(initial=0.0) > 0
        else 0,
        "mechanism_cracks": int(cracks.sum()),
        "mechanism_sliding_share": slide / (slide + opening) if slide + opening > 0 else None,
        **seismic_mechanism(model, mode, history.collapse_multiplier),
    }


def seismic_mechanism(model: Model, mode: np.ndarray, lam: float | None) -> dict[str, Any]:
    """alpha0 = c lambda and e* of the collapse mode turned into the rigid-block mechanism
    (:func:`masonry_dem.assessment.kinematics.hinged_mode`), as ``masonry-dem assess`` reads
    it (its default share of moving blocks); {} when the live load is not c P_i d (no seismic
    reading) or there is no multiplier."""
    from masonry_dem.assessment.kinematics import Mechanism, hinged_mode

    if lam is None:
        return {}
    try:
        hinged, _ = hinged_mode(model, mode)
        mechanism = Mechanism.of(model, hinged, kinematics="independent")
        _, e_star = mechanism.participating_mass()
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        log.info("%s: no seismic mechanism (%s)", model.name, exc)
        return {}
    return {"alpha0": float(lam) * mechanism.scale, "e_star": float(e_star)}
