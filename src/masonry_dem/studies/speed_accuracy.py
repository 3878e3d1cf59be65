"""Speed against accuracy: every setting of each method (static, dynamic relaxation, limit
analysis) on validation cases, the run time against the error in lambda, the Pareto front and
the time ratio of dynamic relaxation to the static solver at equal (1 %) accuracy.

The converged lambda of a case is the highest load level at which an equilibrium was verified
by any run of it, a static run with a 1e-4 bracket included: static states are
Newton-converged, and the collapse state of each DR run is polished by Newton to the static
tolerance (:func:`polish`) before it counts; each such lambda is a lower bound of the model's
collapse multiplier. Limit analysis answers another model (rigid blocks, rigid-plastic
joints), so its rows never set the converged lambda: they show what its one convex solve
costs and how far its multiplier lies from the pushover's (``ratio_to_static``).
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from masonry_dem.model import Model
from masonry_dem.results import History
from masonry_dem.studies import text
from masonry_dem.studies.runs import (
    Method,
    StudyCase,
    collapse_lambda,
    load_study_case,
    relative_error,
    run_method,
    settings_for,
    warm_up,
    with_changes,
)
from masonry_dem.studies.text import fmt

log = logging.getLogger(__name__)

DEFAULT_CASES = ("S15", "OL1", "14-15")
ACCURACY = 0.01  # the "equal accuracy" of the static / DR comparison
#: the residual tolerance at or below which a static run's states count as equilibria
VERIFIED_TOLERANCE = 1e-4

Grid = tuple[tuple[str, dict[str, Any]], ...]
#: settings of each method on the chart: (label, changes to the case's settings)
GRIDS: dict[Method, Grid] = {
    Method.STATIC: (
        ("default", {}),
        ("bracket 2%", {"bracket_tolerance": 0.02}),
        ("bracket 0.1%", {"bracket_tolerance": 0.001}),
        ("no refinement", {"refine": False}),
        ("coarse steps", {"initial_step": 0.05, "max_step": 0.5, "bracket_tolerance": 0.01}),
        ("fine steps", {"initial_step": 0.01, "max_step": 0.05}),
        ("tolerance 1e-5", {"tolerance": 1e-5}),
        ("load control only", {"continuation": "bracket"}),
        ("difference tangent", {"tangent": "difference"}),
    ),
    Method.DYNAMIC_RELAXATION: (
        ("default", {}),
        ("bracket 2%", {"bracket_tolerance": 0.02}),
        ("tolerance 1e-3", {"tolerance": 1e-3, "bracket_tolerance": 0.01}),
        ("dt 0.5 limit", {"dt_fraction": 0.5}),
        ("dt power 0.95", {"dt_rule": "power", "dt_fraction": 0.95}),
        ("viscous", {"damping": "viscous"}),
        ("density mass", {"mass": "density"}),
        ("ramp 2e-4", {"loading": "ramp", "ramp_rate": 2e-4}),
        ("ramp 1e-3", {"loading": "ramp", "ramp_rate": 1e-3}),
    ),
    Method.LIMIT_ANALYSIS: (
        # the entry point's default: the LP (HiGHS) on the circumscribed 8-face pyramid
        ("associative", {}),
        ("exact cone", {"backend": "clarabel"}),
        ("non-associative", {"associative": False, "backend": "clarabel"}),
    ),
}
#: settings run only with ``full=True``, the ones that take minutes on the default cases: a DR
#: time step costs ~5 ms on these walls (the law's energy-metric return); the default study keeps
#: the defaults, the fastest DR setting at 1 % and the static knobs, and stays under an hour
FULL_ONLY: dict[Method, tuple[str, ...]] = {
    Method.STATIC: ("bracket 0.1%", "fine steps", "tolerance 1e-5"),
    Method.DYNAMIC_RELAXATION: (
        "bracket 2%",
        "dt 0.5 limit",
        "dt power 0.95",
        "viscous",
        "density mass",
        "ramp 2e-4",
        "ramp 1e-3",
    ),
    # the non-associative iteration solves a cone program per step: 30-360 s on these walls
    Method.LIMIT_ANALYSIS: ("non-associative",),
}
QUICK: dict[Method, tuple[str, ...]] = {
    Method.STATIC: ("default", "bracket 2%", "no refinement", "coarse steps"),
    Method.DYNAMIC_RELAXATION: ("default", "bracket 2%", "ramp 2e-4"),
    Method.LIMIT_ANALYSIS: ("exact cone",),
}
#: the limit-analysis setting each limit-analysis row is measured against (its own answer):
#: the exact cone of the same flow rule
LA_OWN = {True: "exact cone", False: "non-associative"}


def polish(model: Model, static_settings: Any, hist: History) -> tuple[bool, str]:
    """Verify the collapse state of a run as an equilibrium of the static solver's discrete
    problem: Newton (tolerance of ``static_settings``) started from the run's state at its
    collapse multiplier, with the law state of that step (the joints cracked on its path,
    the plastic slip of that state under ``memory = "slip"``). A state that Newton brings to
    the static tolerance at the same lambda is an equilibrium of the same model, whatever
    method found it."""
    from masonry_dem.solvers.incremental import StaticSolver
    from masonry_dem.solvers.static.certificate import law_state_before

    lam = collapse_lambda(hist)
    if lam is None or not hist.steps:
        return False, "no collapse multiplier"
    at = [i for i, st in enumerate(hist.steps) if st.load_factor == lam]
    if not at:
        return False, "no recorded state at the collapse multiplier"
    solver = StaticSolver(model, static_settings)
    # the law state the step itself holds: its cracks, and the slip of its own state
    plastic, cracked = law_state_before(solver.problem, hist, at[-1] + 1)
    solver.plastic = plastic
    solver.restore(hist.steps[at[-1]].q, cracked)
    out = solver.equilibrate(lam)  # from the restored state
    if out.ok:
        return True, f"Newton polish converged in {out.iterations} iterations"
    return False, f"Newton polish failed: {out.reason}"


def converged_reference(case: StudyCase) -> tuple[float | None, str]:
    """lambda of the same model with a tight bracket: the static solver with a 1e-4 bracket
    (dynamic relaxation with a 1e-3 bracket if the static solver finds no collapse)."""
    tight = with_changes(case.static, {"bracket_tolerance": 1e-4})
    run = run_method(Method.STATIC, case.model, tight)
    if run.load_factor is not None:
        return run.load_factor, "static, bracket 1e-4"
    log.warning("%s: the static reference failed (%s); DR reference", case.name, run.reason)
    dr = with_changes(
        settings_for(Method.DYNAMIC_RELAXATION, case.static), {"bracket_tolerance": 1e-3}
    )
    run = run_method(Method.DYNAMIC_RELAXATION, case.model, dr)
    return run.load_factor, "dynamic relaxation, bracket 1e-3"


def best_equilibrium(rows: list[dict[str, Any]], tight: float | None) -> float | None:
    """The converged lambda of the chart: the highest load level at which an equilibrium was
    verified (``verified``: a static run at a residual tolerance of ``VERIFIED_TOLERANCE``
    or tighter, or a DR run whose collapse state Newton polished, :func:`polish`), the tight
    static run included. Every such lambda is a lower bound of the collapse multiplier of
    the model; the highest is the best estimate."""
    best = tight
    for r in rows:
        if r["lambda"] is not None and r["verified"]:
            best = r["lambda"] if best is None else max(best, r["lambda"])
    return best


def selected(method: Method, quick: bool, full: bool) -> list[tuple[str, dict[str, Any]]]:
    """The settings of ``method`` a study runs."""
    if quick:
        return [(label, c) for label, c in GRIDS[method] if label in QUICK[method]]
    if full:
        return list(GRIDS[method])
    return [(label, c) for label, c in GRIDS[method] if label not in FULL_ONLY[method]]


def speed_accuracy(
    case_names: Iterable[str],
    quick: bool = False,
    budget: int | None = None,
    progress: Callable[[dict[str, Any]], None] | None = None,
    full: bool = False,
    methods: Sequence[Method | str] = tuple(Method),
) -> dict[str, Any]:
    """Every setting of each of ``methods`` on each case: rows (one per run) and a summary
    per case (:func:`summarise`). ``budget``: the time-step budget of each DR run."""
    chosen = [Method.parse(str(m)) for m in methods]
    if Method.LIMIT_ANALYSIS in chosen:
        warm_up(limit=True)  # the solvers' imports are not the cost of a solve
    rows: list[dict[str, Any]] = []
    refs: dict[str, dict[str, Any]] = {}
    for name in case_names:
        case = load_study_case(name)
        lam_ref, ref_how = converged_reference(case)
        for method in chosen:
            base = settings_for(method, case.static)
            for label, changes in selected(method, quick, full):
                if method is Method.DYNAMIC_RELAXATION and budget is not None:
                    changes = {**changes, "max_time_steps": budget}
                row = _row(case, method, label, changes, with_changes(base, changes))
                rows.append(row)
                if progress is not None:
                    progress(row)
        refs[case.name] = {
            "lambda_static_tight": lam_ref,
            "reference_method": ref_how,
            "lambda_test": case.reference,
        }
    return summarise(rows, refs)


def _row(
    case: StudyCase, method: Method, label: str, changes: dict[str, Any], settings: Any
) -> dict[str, Any]:
    run = run_method(method, case.model, settings)
    lam = run.load_factor
    extra: dict[str, Any] = {}
    if method is Method.STATIC:
        verified = lam is not None and settings.tolerance <= VERIFIED_TOLERANCE
        how = "Newton-converged" if verified else "not verified"
    elif method is Method.DYNAMIC_RELAXATION:
        assert run.history is not None
        verified, how = polish(case.model, case.static, run.history)
    else:
        verified, how = False, "rigid blocks, rigid-plastic joints: another model"
        extra = {"bound": run.bound}
    return {
        "case": case.name,
        "method": method.value,
        "label": label,
        "settings": dict(changes),
        "seconds": round(run.seconds, 4),
        "lambda": lam,
        "lambda_converged": None,  # set once every run of the case is done
        "error_vs_converged": None,
        "lambda_test": case.reference,
        "error_vs_test": relative_error(lam, case.reference),
        "unit": case.unit,
        "status": run.status,
        "reason": run.reason,
        "verified": verified,
        "verification": how,
        **extra,
        **run.cost,
    }


def summarise(rows: list[dict[str, Any]], refs: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Errors, Pareto fronts and the equal-accuracy ratios of finished runs (also from a saved
    ``speed_accuracy.json``: ``refs`` is then its ``summary``).

    Two references per case: ``lambda_converged`` (the highest verified equilibrium, common to
    every method: :func:`best_equilibrium`) and each method's own converged answer
    (``error_vs_own``: static against the tight static run, DR against its highest lambda at
    the default tolerance, limit analysis against the exact cone of the same flow rule),
    which measures how fast a method settles its own answer even where the methods settle on
    different answers. ``ratio_to_static``: lambda over the tight static run's.
    """
    from masonry_dem.solvers.dynamic_relaxation import DRSettings

    dr_tolerance = DRSettings().tolerance
    summary: dict[str, dict[str, Any]] = {}
    for name, ref in refs.items():
        case_rows = [r for r in rows if r["case"] == name]
        tight = ref.get("lambda_static_tight")
        best = best_equilibrium(case_rows, tight)
        dr_own = [
            r["lambda"]
            for r in case_rows
            if r["method"] == Method.DYNAMIC_RELAXATION
            and r["lambda"] is not None
            and r["settings"].get("tolerance", dr_tolerance) <= dr_tolerance
        ]
        own = {"static": tight, "dynamic_relaxation": max(dr_own) if dr_own else None}
        la_own = {
            r["label"]: r["lambda"] for r in case_rows if r["method"] == Method.LIMIT_ANALYSIS
        }
        for r in case_rows:
            r["lambda_converged"] = best
            r["error_vs_converged"] = relative_error(r["lambda"], best)
            if r["method"] == Method.LIMIT_ANALYSIS:
                flow = r["settings"].get("associative", True)
                r["error_vs_own"] = relative_error(r["lambda"], la_own.get(LA_OWN[flow]))
                r["ratio_to_static"] = (
                    None if r["lambda"] is None or not tight else r["lambda"] / tight
                )
            else:
                r["error_vs_own"] = relative_error(r["lambda"], own[r["method"]])
        mark_pareto(case_rows)
        how = ref.get("reference_method", "")
        summary[name] = {
            "lambda_converged": best,
            "lambda_static_tight": tight,
            "lambda_dr_own": own["dynamic_relaxation"],
            "reference_method": how
            if best == tight
            else "highest equilibrium verified by any run (above the tight static run)",
            "lambda_test": ref.get("lambda_test"),
            **equal_accuracy(case_rows, ACCURACY),
            **{
                f"own_{k}": v
                for k, v in equal_accuracy(case_rows, ACCURACY, "error_vs_own").items()
            },
            "limit_analysis": limit_analysis_summary(case_rows),
        }
    return {"rows": rows, "summary": summary, "accuracy": ACCURACY}


def from_saved(path: Path) -> dict[str, Any]:
    """The study of a saved ``speed_accuracy.json`` summarised again (no runs). Rows saved by
    a version before the runs were verified (no ``verified``) are refused, naming the file."""
    saved = json.loads(Path(path).read_text())
    if not isinstance(saved, dict) or not {"rows", "summary"} <= set(saved):
        raise ValueError(f"{path}: not a speed_accuracy.json (no 'rows' and 'summary')")
    old = [r.get("label", "?") for r in saved["rows"] if "verified" not in r]
    if old:
        raise ValueError(
            f"{path}: {len(old)} rows (e.g. {old[0]!r}) were saved by an older version, "
            "without 'verified'; run the study again"
        )
    return summarise(saved["rows"], saved["summary"])


def limit_analysis_summary(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each limit-analysis run of a case beside the static default: lambda, its ratio to the
    static answer, seconds and the time ratio static default / limit analysis."""
    static = next(
        (r for r in rows if r["method"] == Method.STATIC and r["label"] == "default"), None
    )
    out = []
    for r in rows:
        if r["method"] != Method.LIMIT_ANALYSIS:
            continue
        out.append(
            {
                "label": r["label"],
                "status": r["status"],
                "lambda": r["lambda"],
                "bound": r.get("bound"),
                "ratio_to_static": r.get("ratio_to_static"),
                "seconds": r["seconds"],
                "static_seconds": None if static is None else static["seconds"],
                "time_ratio_static_over_la": None
                if static is None or not r["seconds"]
                else round(static["seconds"] / r["seconds"], 2),
            }
        )
    return out


def mark_pareto(rows: list[dict[str, Any]]) -> None:
    """Set ``pareto`` on each row: no other run of the case is both faster and more accurate
    (against the converged lambda of the case)."""
    front = {id(r) for r in pareto_front(rows, "error_vs_converged")}
    for r in rows:
        r["pareto"] = id(r) in front


def pareto_front(rows: list[dict[str, Any]], error: str) -> list[dict[str, Any]]:
    """Runs that no other run beats on both time and ``error``, fastest first."""
    front, best = [], math.inf
    ok = [r for r in rows if r.get(error) is not None]
    for r in sorted(ok, key=lambda r: (r["seconds"], r[error])):
        if r[error] < best:
            front.append(r)
            best = r[error]
    return front


def equal_accuracy(
    rows: list[dict[str, Any]], accuracy: float, error: str = "error_vs_converged"
) -> dict[str, Any]:
    """Fastest static and DR run within ``accuracy`` (by ``error``), and the time ratio."""
    out: dict[str, Any] = {}
    for method in (Method.STATIC, Method.DYNAMIC_RELAXATION):
        good = [
            r
            for r in rows
            if r["method"] == method and r.get(error) is not None and r[error] <= accuracy
        ]
        fastest = min(good, key=lambda r: r["seconds"]) if good else None
        out[f"{method.value}_seconds"] = fastest["seconds"] if fastest else None
        out[f"{method.value}_label"] = fastest["label"] if fastest else None
    s, d = out["static_seconds"], out["dynamic_relaxation_seconds"]
    out["time_ratio_dr_over_static"] = None if not s or not d else round(d / s, 2)
    return out


# ---------------------------------------------------------------------------- text
def progress_line(row: dict[str, Any]) -> str:
    return text.progress_line(f"{row['case']} {row['method']} [{row['label']}]", row)


#: the columns of :func:`table`
TABLE_COLUMNS = (
    text.Column("case", "<8"),
    text.Column("method", "<8", lambda r: Method(r["method"]).short),
    text.Column("settings", "<20", "label"),
    text.Column("status", "<9"),
    text.Column("lambda", "11.5g"),
    text.Column("err conv", "9.2%", "error_vs_converged"),
    text.Column("err own", "8.2%", lambda r: r.get("error_vs_own")),
    text.Column("err test", "9.2%", "error_vs_test"),
    text.Column("seconds", "8.2f"),
    text.Column("work", "9d", lambda r: r.get("time_steps", r.get("iterations"))),
    text.Column("pareto", ">6", lambda r: "*" if r.get("pareto") else ""),
)


def table(rows: list[dict[str, Any]]) -> str:
    lines = text.text_table(TABLE_COLUMNS, rows)
    lines.append(
        "err conv: against the converged lambda of the case; err own: against the method's own "
        "converged lambda; work: Newton iterations (static), time steps (DR) or convex solves "
        "(LA); * on the Pareto front"
    )
    return "\n".join(lines)


def summary_lines(summary: dict[str, Any], accuracy: float) -> str:
    lines = [f"static against dynamic relaxation at equal accuracy ({accuracy:.0%} in lambda):"]
    for name, s in summary.items():
        lines.append(
            f"  {name}: converged lambda {fmt(s['lambda_converged'], '.5g')} "
            f"({s['reference_method']}); tight static {fmt(s['lambda_static_tight'], '.5g')}, "
            f"DR {fmt(s['lambda_dr_own'], '.5g')}, test {fmt(s['lambda_test'], '.5g')}"
        )
        for key, what in (("", "common reference"), ("own_", "each method's own answer")):
            ratio = s[f"{key}time_ratio_dr_over_static"]
            lines.append(
                f"    within {accuracy:.0%} of {what}: fastest static "
                f"{fmt(s[f'{key}static_seconds'], '.2f')} s "
                f"[{s[f'{key}static_label'] or 'none'}], fastest DR "
                f"{fmt(s[f'{key}dynamic_relaxation_seconds'], '.2f')} s "
                f"[{s[f'{key}dynamic_relaxation_label'] or 'none'}]: DR / static = "
                f"{fmt(ratio, '.1f')}x"
            )
    la = [(name, s["limit_analysis"]) for name, s in summary.items() if s.get("limit_analysis")]
    if la:
        lines.append("limit analysis against the static answer (tight static lambda):")
    for name, runs in la:
        for r in runs:
            lines.append(
                f"  {name} {r['label']}: {r['status']} lambda {fmt(r['lambda'], '.5g')} "
                f"({r['bound'] or '-'}), {fmt(r['ratio_to_static'], '.3f')} x static, "
                f"{r['seconds']:.2f} s; static default / LA time = "
                f"{fmt(r['time_ratio_static_over_la'], '.2f')}x"
            )
    return "\n".join(lines)
