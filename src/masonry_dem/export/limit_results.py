"""Write a limit analysis to a results folder: ``summary.json`` (the keys of a pushover's,
plus ``method``, ``bound`` and ``bound_reason``) and, at collapse, the mechanism as
``mechanism_blocks.vtu`` / ``mechanism_interfaces.vtu``, as a pushover that ends in collapse
writes them.

Every number written is finite. JSON has no NaN or infinity: a value the analysis does not
have (lambda without a collapse, the lambda of a solve that found none) is ``null``. The
interfaces' ``utilisation`` (the DEM's strength check of the actions at collapse) is capped
at :data:`UTILISATION_CAP`, and ``utilisation_capped`` says where and why: the limit
analysis may put a joint's whole compression at one corner (a point force carries shear and
torsion there), where the DEM's reduced contact area, and so its capacity, is zero.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.model import Model
from masonry_dem.results import StepResult
from masonry_dem.solvers.limit_analysis import LimitAnalysisResult, model_friction_scale

log = logging.getLogger(__name__)

#: the largest utilisation written to ``mechanism_interfaces.vtu``: a ratio above it says only
#: that the action lies far outside the DEM's strength domain, and a cap keeps a viewer's
#: colour range on the joints that matter (an infinite ratio would swallow it)
UTILISATION_CAP = 100.0
#: ``utilisation_capped`` values: the ratio is written as it is; it was above the cap; it was
#: infinite (a non-zero demand on a zero capacity)
NOT_CAPPED, ABOVE_CAP, ZERO_CAPACITY = 0, 1, 2


def capped_utilisation(utilisation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The utilisation capped at :data:`UTILISATION_CAP` and, per interface, why it was
    (``NOT_CAPPED``, ``ABOVE_CAP``, ``ZERO_CAPACITY``). A NaN, which the strength check
    never gives, counts as a zero capacity rather than reaching a file."""
    util = np.asarray(utilisation, dtype=float)
    why = np.full(util.shape, NOT_CAPPED, dtype=np.int32)
    why[util > UTILISATION_CAP] = ABOVE_CAP
    why[np.isinf(util) | np.isnan(util)] = ZERO_CAPACITY
    return np.where(why == NOT_CAPPED, util, UTILISATION_CAP), why


def collapse_step(model: Model, result: LimitAnalysisResult) -> tuple[StepResult, np.ndarray]:
    """The collapse state as a step: no displacement (rigid blocks), the interface actions at
    collapse, their damage state and utilisation under the DEM's strength check, capped at
    :data:`UTILISATION_CAP`; and, per interface, why it was capped
    (:func:`capped_utilisation`)."""
    from masonry_dem.constitutive import check_strength

    its = model.interfaces
    actions = np.asarray(result.interface_actions, dtype=float)
    if its.count:
        beyond = model.cohesion_beyond_friction
        ft = model.tensile_strength * its.area
        cohesive = model.friction * ft + beyond * its.area if beyond.any() else None
        chk = check_strength(
            actions, its.l1, its.l2, model.friction, ft, model.alpha, cohesive_force=cohesive
        )
        state, flags = chk.state, chk.flags
        util, why = capped_utilisation(chk.utilisation)
    else:
        state, flags = np.zeros(0, dtype=np.int8), np.zeros(0, np.uint8)
        util, why = np.zeros(0), np.zeros(0, dtype=np.int32)
    lam = result.load_factor if np.isfinite(result.load_factor) else 0.0
    step = StepResult(0, lam, np.zeros((model.blocks.count, 6)), actions, state, util, flags)
    return step, why


def finite_json(value: Any) -> Any:
    """``value`` with every non-finite float (in dicts, lists, tuples, numpy scalars and
    arrays) replaced by None, which JSON writes as ``null``: JSON has no NaN or infinity, and
    a reader's parser may refuse them."""
    if isinstance(value, dict):
        return {k: finite_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return finite_json(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def bound_of(model: Model, result: LimitAnalysisResult) -> tuple[str, str]:
    """What the multiplier is to the pushover's: ``"upper"``, ``"estimate"`` or ``"none"``
    (no multiplier), and one line saying why, for the user who reads ``summary.json``."""
    if result.status == "no collapse":
        return "none", "no multiplier: the analysis found no mechanism ('no collapse'; see reason)"
    if result.status != "collapse":
        return "none", f"no multiplier: the analysis ended '{result.status}' (see reason)"
    if result.method != "associative":
        return "estimate", non_associative_reason(result)
    if result.cone == "inscribed":
        sides = max(int(result.friction_sides), 3)
        return "estimate", (
            f"an estimate, not a bound: the inscribed {sides}-face friction pyramid lies inside "
            "the joints' Coulomb cone, so this is at most the exact cone's associative "
            "multiplier and may lie below the pushover's; the circumscribed pyramid (friction "
            f"x {1 / math.cos(math.pi / sides):.4g}) bounds the cone's from above"
        )
    if result.bound == "upper":
        return "upper", (
            f"an upper bound of the pushover's multiplier: associative flow with the friction "
            f"x {result.friction_scale:.4g}, whose strength domain contains the DEM joints' "
            "(Radenkovic's theorem)"
        )
    from masonry_dem.constitutive import DEFAULT_ALPHA

    # nan in the model: the joint takes the package's alpha, as the strength check does
    alpha = np.where(np.isnan(model.alpha), DEFAULT_ALPHA, model.alpha)
    largest = float(alpha.max(initial=DEFAULT_ALPHA))
    twisting = int(np.count_nonzero(alpha > 1)) if alpha.ndim else int(largest > 1)
    joints = model.interfaces.count
    kappa = model_friction_scale(model)
    return "estimate", (
        f"an estimate, not a bound: on {twisting} of {joints} joints the DEM's torsion-shear "
        f"interaction (alpha = {largest:g} > 1) carries some actions this associative "
        f"analysis (friction x {result.friction_scale:.4g}) does not, so the pushover's "
        "multiplier may lie above it; proven: it is at most the associative multiplier with "
        f"the friction x {kappa:.4g} (--dem-bound)"
    )


def non_associative_reason(result: LimitAnalysisResult) -> str:
    """The one line of a non-associative multiplier: what is proven of it, the associative
    multiplier of the same cone above it (Radenkovic's first theorem) and the gap."""
    upper = result.info.get("associative") if result.info else None
    lam = float(result.load_factor)
    start = (result.info or {}).get("start", "elastic")
    head = (
        f"an estimate, not a bound: the zero-dilatancy (non-associative) iteration of Gilbert "
        f"et al. 2006 (from the {start} state) is not convex and no theorem bounds it from below"
    )
    if upper is None or not math.isfinite(float(upper)) or not lam > 0:
        return f"{head}, so the pushover's multiplier may lie on either side"
    upper = float(upper)
    if lam >= upper * (1 - 1e-9):
        return (
            f"{head}; it settled at the associative multiplier {upper:.6g} of the same cone, "
            "which bounds every zero-dilatancy one from above (Radenkovic): the proven gap "
            "above is 0, below none"
        )
    return (
        f"{head}; proven: the zero-dilatancy multiplier is at most the associative "
        f"{upper:.6g} of the same cone (Radenkovic), {upper / lam - 1:+.1%} above this "
        "estimate; below, no bound"
    )


def supports_text(model: Model) -> str:
    """The supports of the model in a few words: the held blocks grouped by the DOFs held,
    e.g. ``1 block held in all DOFs (45); 9 blocks held in u1, u3 (0, 5, 10, ...)``."""
    names = ("u1", "u2", "u3", "w1", "w2", "w3")
    fixed = np.asarray(model.fixed, dtype=bool)
    groups: dict[tuple[bool, ...], list[int]] = {}
    for b in np.flatnonzero(fixed.any(axis=1)):
        groups.setdefault(tuple(bool(x) for x in fixed[b]), []).append(int(b))
    if not groups:
        return "no block is held"
    parts = []
    for pattern, blocks in sorted(groups.items(), key=lambda kv: kv[1][0]):
        dofs = (
            "all DOFs"
            if all(pattern)
            else ", ".join(n for n, f in zip(names, pattern, strict=True) if f)
        )
        shown = ", ".join(str(b) for b in blocks[:6]) + (", ..." if len(blocks) > 6 else "")
        word = "block" if len(blocks) == 1 else "blocks"
        parts.append(f"{len(blocks)} {word} held in {dofs} ({shown})")
    return "; ".join(parts)


def reason_of(model: Model, result: LimitAnalysisResult) -> str:
    """The result's reason; for a mechanism the solver rules out, with the supports that
    hold the wall (the result knows no finer cause: which of them lock it is not computed)."""
    if result.status == "no collapse" and result.reason.startswith("no mechanism"):
        return f"{result.reason}; the wall is held by its supports: {supports_text(model)}"
    return result.reason


def write_limit_results(
    folder: Path | str, model: Model, result: LimitAnalysisResult, **summary_extra: Any
) -> dict[str, Any]:
    """Write ``summary.json`` and, at collapse, the mechanism VTUs; returns the summary."""
    from masonry_dem.export.results_folder import write_summary
    from masonry_dem.export.vtu import write_mechanism_vtu

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    la = result.summary()
    la.pop("bound")
    la.pop("reason")
    bound, bound_reason = bound_of(model, result)
    summary: dict[str, Any] = {
        "status": la.pop("status"),
        "reason": reason_of(model, result),
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
        "bound": bound,
        "bound_reason": bound_reason,
        "limit_analysis": la,
    }
    summary.update(summary_extra)
    if result.status == "collapse":
        step, why = collapse_step(model, result)
        extra = {"utilisation_capped": why}
        write_mechanism_vtu(folder, model, step, result.block_velocities, None, extra)
    summary = write_summary(folder, finite_json(summary))
    log.info("limit analysis written to %s", folder)
    return summary
