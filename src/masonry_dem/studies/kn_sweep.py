"""lambda of a dry-joint validation case as the dry-joint normal stiffness grows."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from masonry_dem.studies.runs import (
    Method,
    relative_error,
    run_method,
    settings_for,
    with_changes,
)
from masonry_dem.studies.text import fmt


def kn_sweep(
    case_name: str,
    factors: Iterable[float],
    method: Method | str = Method.STATIC,
    budget: int | None = None,
    scale_kt: bool = False,
) -> dict[str, Any]:
    """lambda of a dry-joint case as the dry normal stiffness is multiplied by ``factors``
    (``budget``: the time-step budget of dynamic relaxation).

    ``scale_kt``: scale the shear stiffness too. The law is then exactly invariant (actions
    depend on kbar x relative displacement only, and displacements scale by 1/factor), so any
    drift is numerical: conditioning, tolerances, the absolute displacement limit. With kn
    alone the ratio kt/kn changes, and with it the elastic share of shear and normal forces
    from which the non-associative friction of the joints starts: a physical change too.
    """
    from masonry_dem.cases.paper import Assumptions, build_case

    method = Method.parse(str(method))
    if method is Method.LIMIT_ANALYSIS:
        raise ValueError("method must be static or dynamic_relaxation: rigid blocks have no kn")
    base = Assumptions()
    kn0 = base.dry_kn
    rows = []
    for f in factors:
        changes: dict[str, Any] = {"dry_kn": kn0 * f}
        if scale_kt:
            changes["dry_kt"] = base.dry_kt * f
        pc = build_case(case_name, **changes)
        settings = settings_for(method, pc.settings)
        if method is Method.DYNAMIC_RELAXATION and budget is not None:
            settings = with_changes(settings, {"max_time_steps": budget})
        run = run_method(method, pc.model, settings)
        rows.append(
            {
                "case": case_name,
                "method": method.value,
                "kn": kn0 * f,
                "kt": base.dry_kt * (f if scale_kt else 1.0),
                "factor": f,
                "lambda": run.load_factor,
                "status": run.status,
                "reason": run.reason,
                "seconds": round(run.seconds, 3),
                **run.cost,
            }
        )
    lams = [r["lambda"] for r in rows if r["lambda"] is not None]
    first = rows[0]["lambda"]
    for r in rows:
        r["drift"] = relative_error(r["lambda"], first)
    spread = (max(lams) - min(lams)) / abs(first) if lams and first else None
    return {"rows": rows, "spread": spread}


def kn_sweep_text(res: dict[str, Any], case_name: str, method: str, scale_kt: bool) -> str:
    what = "kn and kt" if scale_kt else "kn (kt held)"
    lines = [
        f"{case_name}: lambda as the dry-joint {what} grow ({method})",
        f"  {'kn [N/m^3]':>11} {'kt [N/m^3]':>11} {'lambda':>10} {'drift':>8} {'seconds':>8}"
        "  status",
    ]
    for r in res["rows"]:
        lines.append(
            f"  {r['kn']:11.3g} {r['kt']:11.3g} {fmt(r['lambda'], '10.5g')} "
            f"{fmt(r['drift'], '8.2%')} {r['seconds']:8.2f}  {r['status']}"
        )
    lines.append(f"  spread of lambda over the sweep: {fmt(res['spread'], '.2%')}")
    return "\n".join(lines)
