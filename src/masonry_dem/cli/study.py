"""``masonry-dem study ...``: speed against accuracy of every solver and setting, the in-plane
reduction and the dry-joint stiffness sweep.

* ``study speed-accuracy [--cases ...] [--quick] [--json] [--out DIR]``: runs each case with
  every setting of the static solver and of dynamic relaxation, measures the run time and the
  error in lambda against a converged reference of the same model and against the test; writes
  a table, ``speed_accuracy.json`` and a PNG chart of time against error with the Pareto front
  marked; prints the DR / static time ratio at equal (1 %) accuracy per case. The converged
  reference is the highest load level at which an equilibrium was verified by any run of the
  case, a static run with a 1e-4 bracket included (static states are Newton-converged; the
  collapse state of each DR run is polished by Newton to the static tolerance before it
  counts): each such lambda is a lower bound of the model's collapse multiplier.
* ``study reduction [--json]``: in-plane scenes solved with the full 6-DOF model and with the
  3-DOF in-plane model (lambda, time, DOFs), and what the fixed-block DOFs and the closed-form
  interface domain save.
* ``study kn-sweep [--case NAME] [--factors ...] [--json]``: lambda as the dry-joint normal
  stiffness grows.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import time
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

log = logging.getLogger(__name__)

DEFAULT_CASES = ("S15", "OL1", "14-15")
ACCURACY = 0.01  # the "equal accuracy" of the static / DR comparison
PRESSURE_STEPS = (1.0, 4.0)  # initial and largest step of Table 3 cases, in load scales

#: settings of each method on the chart: (label, changes to the defaults)
STATIC_GRID: tuple[tuple[str, dict], ...] = (
    ("default", {}),
    ("bracket 2%", {"bracket_tolerance": 0.02}),
    ("bracket 0.1%", {"bracket_tolerance": 0.001}),
    ("no refinement", {"refine": False}),
    ("coarse steps", {"initial_step": 0.05, "max_step": 0.5, "bracket_tolerance": 0.01}),
    ("fine steps", {"initial_step": 0.01, "max_step": 0.05}),
    ("tolerance 1e-5", {"tolerance": 1e-5}),
    ("load control only", {"continuation": "bracket"}),
    ("no pseudo-transient", {"transient_steps": 0}),
    ("DR rescue 4000", {"rescue_time_steps": 4000}),
    ("DR rescue 16000", {"rescue_time_steps": 16_000}),
    ("modified iteration", {"iteration": "modified"}),
    ("difference tangent", {"tangent": "difference"}),
)
DR_GRID: tuple[tuple[str, dict], ...] = (
    ("default", {}),
    ("bracket 2%", {"bracket_tolerance": 0.02}),
    ("tolerance 1e-3", {"tolerance": 1e-3, "bracket_tolerance": 0.01}),
    ("dt 0.5 limit", {"dt_fraction": 0.5}),
    ("dt power 0.95", {"dt_rule": "power", "dt_fraction": 0.95}),
    ("viscous", {"damping": "viscous"}),
    ("density mass", {"mass": "density"}),
    ("ramp 2e-4", {"loading": "ramp", "ramp_rate": 2e-4}),
    ("ramp 1e-3", {"loading": "ramp", "ramp_rate": 1e-3}),
)
#: settings run only with ``full=True`` (``--full``): a DR time step costs ~5 ms since the
#: energy-metric return of the law, so a DR run takes minutes; the default study keeps the
#: defaults, the fastest DR setting at 1 % and the static knobs, and stays under an hour
FULL_ONLY = {
    "static": ("bracket 0.1%", "fine steps", "tolerance 1e-5"),
    "dynamic_relaxation": (
        "bracket 2%",
        "dt 0.5 limit",
        "dt power 0.95",
        "viscous",
        "density mass",
        "ramp 2e-4",
        "ramp 1e-3",
    ),
}
QUICK = {
    "static": ("default", "bracket 2%", "no refinement", "coarse steps"),
    "dynamic_relaxation": ("default", "bracket 2%", "ramp 2e-4"),
}
#: step-size knobs copied from a case's static settings into DR (same load stepping)
_SHARED = ("initial_step", "max_step", "growth", "max_load_factor", "displacement_limit", "tension")


# ---------------------------------------------------------------------------- cases
@dataclass(frozen=True)
class StudyCase:
    name: str
    model: Any
    reference: float | None  # test value (Table 1: FEM)
    static: Any  # StaticSettings of the case
    unit: str = "lambda"


def load_study_case(name: str) -> StudyCase:
    """A validation case from :mod:`masonry_dem.cases.paper`; ``default`` is the bundled wall."""
    if name == "default":
        from masonry_dem.cases.casefile import load_case

        case = load_case()
        return StudyCase("default", case.model, None, case.settings)
    from masonry_dem.cases.paper import build_case

    pc = build_case(name)
    settings = pc.settings
    from masonry_dem.solvers.incremental import StaticSettings

    default = StaticSettings()
    if pc.unit == "Pa" and (settings.initial_step, settings.max_step) == (
        default.initial_step,
        default.max_step,
    ):
        # pressure cases collapse at ~30 load scales (|F_D| / |F_L| = weight per unit of
        # pressure): default steps would take ~150 of them; the refined bracket does not
        # depend on the steps, so both methods start with larger ones here
        settings = replace(settings, initial_step=PRESSURE_STEPS[0], max_step=PRESSURE_STEPS[1])
    return StudyCase(pc.name, pc.model, float(pc.reference), settings, pc.unit)


def _settings(cls, base, changes: dict):
    """``base`` (or the defaults of ``cls``) with the known ``changes``; None if a knob does not
    exist in this version of the solver (the run is then skipped, not silently changed)."""
    known = {f.name for f in fields(cls)}
    if any(k not in known for k in changes):
        return None
    start = base if base is not None else cls()
    return replace(start, **changes)


def _dr_base(static):
    from masonry_dem.solvers.dynamic_relaxation import DRSettings

    shared = {k: getattr(static, k) for k in _SHARED if hasattr(static, k)}
    return replace(DRSettings(), **shared)


# ---------------------------------------------------------------------------- runs
def warm_up() -> None:
    """Load the compiled interface law (numba's on-disk cache: about 0.4 s once per process)
    with both solvers on one block, so that the first timed run does not pay for it."""
    from masonry_dem.geometry import builders
    from masonry_dem.model import (
        InterfaceMaterial,
        Model,
        SelfWeight,
        Support,
        WeightProportional,
    )
    from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation
    from masonry_dem.solvers.incremental import StaticSolver

    blocks, base = builders.add_base(builders.single_block(0.2, 0.3, 0.1, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(1e9, 4e8, 0.7),
        [Support(np.array([base]))],
        [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )
    StaticSolver(model).run()
    DynamicRelaxation(model, DRSettings(bracket_tolerance=0.05)).run()


def _run(method: str, model, settings) -> tuple[Any, float, dict]:
    from masonry_dem.solvers.dynamic_relaxation import DynamicRelaxation
    from masonry_dem.solvers.incremental import StaticSolver

    t0 = time.perf_counter()
    if method == "static":
        solver = StaticSolver(model, settings)
        hist = solver.run()
        cost = {"iterations": hist.iterations, "factorizations": hist.factorizations}
    else:
        dr = DynamicRelaxation(model, settings)
        hist = dr.run()
        cost = {
            "time_steps": dr.stats.time_steps,
            "law_evaluations": dr.stats.law_evaluations,
            "dt_cuts": dr.stats.cuts,
        }
    return hist, time.perf_counter() - t0, cost


def _lambda(hist) -> float | None:
    lam = hist.collapse_multiplier
    if hist.status != "collapse" or lam is None or not math.isfinite(lam):
        return None
    return float(lam)


def _rel(value: float | None, ref: float | None) -> float | None:
    if value is None or ref is None or ref == 0:
        return None
    return abs(value - ref) / abs(ref)


def polish(model, static_settings, hist) -> tuple[bool, str]:
    """Verify the collapse state of a run as an equilibrium of the static solver's discrete
    problem: Newton (tolerance of ``static_settings``) started from the run's state at its
    collapse multiplier, with the joints cracked on its path. The law is memory-free
    (``memory="none"``), so a state that Newton brings to the static tolerance at the same
    lambda is an equilibrium of the same model, whatever method found it."""
    from masonry_dem.constitutive.law import DETACHED_FLAG
    from masonry_dem.solvers.incremental import StaticSolver

    lam = _lambda(hist)
    if lam is None or not hist.steps:
        return False, "no collapse multiplier"
    if static_settings.memory != "none":
        return False, "the law has memory: a state is not determined by q alone"
    at = [i for i, st in enumerate(hist.steps) if st.load_factor == lam]
    if not at:
        return False, "no recorded state at the collapse multiplier"
    upto = hist.steps[: at[-1] + 1]
    solver = StaticSolver(model, static_settings)
    cracked = np.zeros(model.interfaces.count, dtype=bool)
    for st in upto:
        if st.flags is not None:
            cracked |= (np.asarray(st.flags) & DETACHED_FLAG) > 0
    solver.restore(upto[-1].q, cracked)
    out = solver.equilibrate(lam, start=solver.q)
    if out.ok:
        return True, f"Newton polish converged in {out.iterations} iterations"
    return False, f"Newton polish failed: {out.reason}"


def converged_reference(case: StudyCase) -> tuple[float | None, str]:
    """lambda of the same model with a tight bracket: the static solver with a 1e-4 bracket
    (dynamic relaxation with a 1e-3 bracket if the static solver finds no collapse)."""
    from masonry_dem.solvers.dynamic_relaxation import DRSettings
    from masonry_dem.solvers.incremental import StaticSettings

    tight = _settings(StaticSettings, case.static, {"bracket_tolerance": 1e-4})
    hist, _, _ = _run("static", case.model, tight)
    lam = _lambda(hist)
    if lam is not None:
        return lam, "static, bracket 1e-4"
    log.warning("%s: the static reference failed (%s); DR reference", case.name, hist.reason)
    dr = _settings(DRSettings, _dr_base(case.static), {"bracket_tolerance": 1e-3})
    hist, _, _ = _run("dynamic_relaxation", case.model, dr)
    return _lambda(hist), "dynamic relaxation, bracket 1e-3"


def best_equilibrium(
    rows: list[dict], tight: float | None, tolerance: float = 1e-4
) -> float | None:
    """The converged lambda of the chart: the highest load level at which an equilibrium was
    verified, the tight static run included. A row counts when ``verified`` is true: a static
    run at a residual tolerance of ``tolerance`` or tighter (its states are Newton-converged),
    or a DR run whose collapse state Newton polished to the static tolerance (:func:`polish`).
    Rows without ``verified`` (saved by older versions) count when their residual tolerance is
    ``tolerance`` or tighter. Every such lambda is a lower bound of the collapse multiplier of
    the model; the highest is the best estimate."""
    from masonry_dem.solvers.dynamic_relaxation import DRSettings
    from masonry_dem.solvers.incremental import StaticSettings

    best = tight
    for r in rows:
        if r["lambda"] is None:
            continue
        if "verified" in r:  # Newton-polished (DR) or Newton-converged (static) state
            ok = bool(r["verified"])
        else:  # runs saved before verification: the residual tolerance decides
            default = (
                StaticSettings().tolerance if r["method"] == "static" else DRSettings().tolerance
            )
            ok = r["settings"].get("tolerance", default) <= max(tolerance, default)
        if ok:
            best = r["lambda"] if best is None else max(best, r["lambda"])
    return best


def speed_accuracy(
    case_names,
    quick: bool = False,
    budget: int | None = None,
    progress=None,
    full: bool = False,
) -> dict:
    """Every setting of both methods on each case; rows (one per run) and a summary per case."""
    from masonry_dem.solvers.dynamic_relaxation import DRSettings
    from masonry_dem.solvers.incremental import StaticSettings

    rows: list[dict] = []
    refs: dict[str, dict] = {}
    for name in case_names:
        case = load_study_case(name)
        lam_ref, ref_how = converged_reference(case)
        grids = (
            ("static", STATIC_GRID, StaticSettings, case.static),
            ("dynamic_relaxation", DR_GRID, DRSettings, _dr_base(case.static)),
        )
        for method, grid, cls, base in grids:
            for label, changes in grid:
                if quick and label not in QUICK[method]:
                    continue
                if not full and not quick and label in FULL_ONLY[method]:
                    continue
                if method == "dynamic_relaxation" and budget is not None:
                    changes = {**changes, "max_time_steps": budget}
                settings = _settings(cls, base, changes)
                if settings is None:
                    log.info("%s: %s %r skipped (no such knob)", name, method, label)
                    continue
                hist, seconds, cost = _run(method, case.model, settings)
                lam = _lambda(hist)
                if method == "static":
                    verified = lam is not None and settings.tolerance <= 1e-4
                    how = "Newton-converged" if verified else "not verified"
                else:
                    verified, how = polish(case.model, case.static, hist)
                row = {
                    "case": case.name,
                    "method": method,
                    "label": label,
                    "settings": {k: v for k, v in changes.items()},
                    "seconds": round(seconds, 4),
                    "lambda": lam,
                    "lambda_converged": None,  # set once every run of the case is done
                    "error_vs_converged": None,
                    "lambda_test": case.reference,
                    "error_vs_test": _rel(lam, case.reference),
                    "unit": case.unit,
                    "status": hist.status,
                    "reason": hist.reason,
                    "verified": verified,
                    "verification": how,
                    **cost,
                }
                rows.append(row)
                if progress is not None:
                    progress(row)
        refs[case.name] = {
            "lambda_static_tight": lam_ref,
            "reference_method": ref_how,
            "lambda_test": case.reference,
        }
    return summarise(rows, refs)


def summarise(rows: list[dict], refs: dict[str, dict]) -> dict:
    """Errors, Pareto fronts and the equal-accuracy ratios of finished runs (also from a saved
    ``speed_accuracy.json``: ``refs`` is then its ``summary``).

    Two references per case: ``lambda_converged`` (the highest verified equilibrium, common to
    both methods: :func:`best_equilibrium`) and each method's own converged answer
    (``error_vs_own``: static against the tight static run, DR against its highest lambda at
    the default tolerance), which measures how fast a method settles its own answer even where
    the two methods settle on different answers.
    """
    from masonry_dem.solvers.dynamic_relaxation import DRSettings

    summary: dict[str, dict] = {}
    for name, ref in refs.items():
        case_rows = [r for r in rows if r["case"] == name]
        tight = ref.get("lambda_static_tight")
        best = best_equilibrium(case_rows, tight)
        dr_own = [
            r["lambda"]
            for r in case_rows
            if r["method"] != "static"
            and r["lambda"] is not None
            and r["settings"].get("tolerance", DRSettings().tolerance) <= DRSettings().tolerance
        ]
        own = {"static": tight, "dynamic_relaxation": max(dr_own) if dr_own else None}
        for r in case_rows:
            r["lambda_converged"] = best
            r["error_vs_converged"] = _rel(r["lambda"], best)
            r["error_vs_own"] = _rel(r["lambda"], own[r["method"]])
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
        }
    return {"rows": rows, "summary": summary, "accuracy": ACCURACY}


def mark_pareto(rows: list[dict]) -> None:
    """Set ``pareto`` on each row: no other run of the case is both faster and more accurate
    (against the converged lambda of the case)."""
    front = {id(r) for r in pareto_front(rows, "error_vs_converged")}
    for r in rows:
        r["pareto"] = id(r) in front


def equal_accuracy(rows: list[dict], accuracy: float, error: str = "error_vs_converged") -> dict:
    """Fastest run of each method within ``accuracy`` (by ``error``), and the time ratio."""
    out: dict[str, Any] = {}
    for method in ("static", "dynamic_relaxation"):
        good = [
            r
            for r in rows
            if r["method"] == method and r.get(error) is not None and r[error] <= accuracy
        ]
        fastest = min(good, key=lambda r: r["seconds"]) if good else None
        out[f"{method}_seconds"] = fastest["seconds"] if fastest else None
        out[f"{method}_label"] = fastest["label"] if fastest else None
    s, d = out["static_seconds"], out["dynamic_relaxation_seconds"]
    out["time_ratio_dr_over_static"] = None if not s or not d else round(d / s, 2)
    return out


# ---------------------------------------------------------------------------- output
def _fmt(value, spec: str, missing: str = "-") -> str:
    return missing if value is None else format(value, spec)


def table(rows: list[dict]) -> str:
    head = (
        f"{'case':<8} {'method':<8} {'settings':<20} {'status':<9} {'lambda':>11} "
        f"{'err conv':>9} {'err own':>8} {'err test':>9} {'seconds':>8} {'work':>9} {'pareto':>6}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        work = r.get("time_steps", r.get("iterations"))
        lines.append(
            f"{r['case']:<8} {'DR' if r['method'] != 'static' else 'static':<8} "
            f"{r['label']:<20} {r['status']:<9} {_fmt(r['lambda'], '11.5g')} "
            f"{_fmt(r['error_vs_converged'], '9.2%')} {_fmt(r.get('error_vs_own'), '8.2%')} "
            f"{_fmt(r['error_vs_test'], '9.2%')} "
            f"{r['seconds']:8.2f} {_fmt(work, '9d')} {'*' if r.get('pareto') else '':>6}"
        )
    lines.append(
        "err conv: against the converged lambda of the case; err own: against the method's own "
        "converged lambda; work: Newton iterations (static) or time steps (DR); * on the "
        "Pareto front"
    )
    return "\n".join(lines)


def summary_lines(summary: dict, accuracy: float) -> str:
    lines = [f"static against dynamic relaxation at equal accuracy ({accuracy:.0%} in lambda):"]
    for name, s in summary.items():
        lines.append(
            f"  {name}: converged lambda {_fmt(s['lambda_converged'], '.5g')} "
            f"({s['reference_method']}); tight static {_fmt(s['lambda_static_tight'], '.5g')}, "
            f"DR {_fmt(s['lambda_dr_own'], '.5g')}, test {_fmt(s['lambda_test'], '.5g')}"
        )
        for key, what in (("", "common reference"), ("own_", "each method's own answer")):
            ratio = s[f"{key}time_ratio_dr_over_static"]
            lines.append(
                f"    within {accuracy:.0%} of {what}: fastest static "
                f"{_fmt(s[f'{key}static_seconds'], '.2f')} s "
                f"[{s[f'{key}static_label'] or 'none'}], fastest DR "
                f"{_fmt(s[f'{key}dynamic_relaxation_seconds'], '.2f')} s "
                f"[{s[f'{key}dynamic_relaxation_label'] or 'none'}]: DR / static = "
                f"{_fmt(ratio, '.1f')}x"
            )
    return "\n".join(lines)


def pareto_front(rows: list[dict], error: str) -> list[dict]:
    """Runs that no other run beats on both time and ``error``, fastest first."""
    front, best = [], math.inf
    ok = [r for r in rows if r.get(error) is not None]
    for r in sorted(ok, key=lambda r: (r["seconds"], r[error])):
        if r[error] < best:
            front.append(r)
            best = r[error]
    return front


def chart(rows: list[dict], path: Path, floor: float = 1e-5) -> Path:
    """Run time against error in lambda, one column per case; top row against the converged
    lambda of the case, bottom row against each method's own converged lambda. The Pareto
    front of each panel is joined and ringed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    cases = list(dict.fromkeys(r["case"] for r in rows))
    ncol = max(len(cases), 1)
    fig, axes = plt.subplots(2, ncol, figsize=(5.0 * ncol, 8.2), squeeze=False)
    style = {
        "static": dict(marker="o", color="tab:blue", label="static (paper's method)"),
        "dynamic_relaxation": dict(marker="^", color="tab:orange", label="dynamic relaxation"),
    }
    panels = (
        ("error_vs_converged", "error vs converged lambda of the case"),
        ("error_vs_own", "error vs the method's own converged lambda"),
    )
    for row, (error, ylabel) in enumerate(panels):
        for col, name in enumerate(cases):
            ax = axes[row, col]
            rs = [r for r in rows if r["case"] == name]
            for method, st in style.items():
                ok = [r for r in rs if r["method"] == method and r.get(error) is not None]
                bad = [r for r in rs if r["method"] == method and r.get(error) is None]
                ax.scatter(
                    [r["seconds"] for r in ok], [max(r[error], floor) for r in ok], s=36, **st
                )
                if bad:
                    ax.scatter(
                        [r["seconds"] for r in bad],
                        [1.0] * len(bad),
                        marker="x",
                        color=st["color"],
                        label=f"{method.replace('_', ' ')}: no lambda (failed)",
                    )
                for r in ok:
                    ax.annotate(
                        r["label"],
                        (r["seconds"], max(r[error], floor)),
                        fontsize=6,
                        xytext=(3, 2),
                        textcoords="offset points",
                    )
            front = pareto_front(rs, error)
            if front:
                xs = [r["seconds"] for r in front]
                ys = [max(r[error], floor) for r in front]
                ax.step(xs, ys, where="post", color="k", lw=1, label="Pareto front")
                ax.scatter(xs, ys, s=110, facecolors="none", edgecolors="k")
            ax.axhline(ACCURACY, color="grey", ls=":", lw=1)
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())  # no crowded labels
            ax.set_yscale("log")
            ax.set_ylim(floor / 2, 2.0)
            ax.set_xlabel("run time [s]")
            ax.set_title(name if row == 0 else f"{name} (own answer)")
            ax.grid(True, which="both", alpha=0.2)
        axes[row, 0].set_ylabel(f"{ylabel}\n(floor {floor:g}; dotted: 1 %)")
    axes[0, 0].legend(fontsize=7, loc="lower left")
    fig.suptitle("Speed against accuracy of every solver setting")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# ---------------------------------------------------------------------------- reduction
def in_plane_scenes() -> list[tuple[str, Any]]:
    """In-plane scenes: running-bond shear walls on a rigid base pushed along e1 by lambda x
    their weight (the Orduna-Lourenco block and a Chee Liang-sized brick wall)."""
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional

    out = []
    for name, nx, nc, dims, gamma, mat in (
        ("shear wall 6x13", 6, 13, (0.081, 0.210, 0.070), 20e3, (2.4e9, 1.0e9, 0.7, 0.0)),
        ("shear wall 12x26", 12, 26, (0.081, 0.210, 0.070), 20e3, (2.4e9, 1.0e9, 0.7, 0.0)),
        ("mortar wall 20x40", 20, 40, (0.046, 0.122, 0.053), 18e3, (25e9, 105e9, 0.57, 0.35e6)),
    ):
        wall = running_bond_wall(nx, nc, *dims, gamma)
        blocks, base = add_base(wall)
        model = Model.build(
            blocks,
            InterfaceMaterial(*mat),
            [Support(np.array([base]))],
            [SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
            name=name,
        )
        out.append((name, model))
    return out


def reduction_study(repeats: int = 3) -> dict:
    from masonry_dem.solvers import reduction

    scenes = []
    for name, model in in_plane_scenes():
        r = reduction.measure_reduction(model, repeats=repeats)
        r["scene"] = name
        scenes.append(r)
    fixed = []
    for name in ("S15", "14-15"):
        try:
            case = load_study_case(name)
        except (ImportError, ValueError) as exc:
            log.warning("case %s unavailable: %s", name, exc)
            continue
        f = reduction.measure_fixed_dofs(case.model, repeats=repeats)
        f["case"] = name
        s = reduction.measure_strength_model(case.model, repeats=repeats)
        fixed.append({**f, "strength": s})
    return {"in_plane": scenes, "fixed_dofs": fixed}


def reduction_text(res: dict) -> str:
    lines = ["in-plane scenes: full 6-DOF model against the 3-DOF (u1, u2, w3) model (static)"]
    lines.append(
        f"  {'scene':<18} {'free DOFs':>11} {'nnz K':>13} {'lambda 6-DOF':>13} "
        f"{'lambda 3-DOF':>13} {'rel diff':>9} {'t6 [s]':>7} {'t3 [s]':>7} {'t6/t3':>6}"
    )
    for r in res["in_plane"]:
        f, p = r["full"], r["in_plane"]
        lines.append(
            f"  {r['scene']:<18} {f['free_dofs']:>5}/{p['free_dofs']:<5} "
            f"{f['nnz_K']:>6}/{p['nnz_K']:<6} {_fmt(f['lambda'], '13.6g')} "
            f"{_fmt(p['lambda'], '13.6g')} {_fmt(r['lambda_relative_difference'], '9.1e')} "
            f"{f['seconds']:7.2f} {p['seconds']:7.2f} {r['time_ratio']:6.2f}"
        )
    if res["fixed_dofs"]:
        lines.append("fixed-block DOFs never assembled, and the closed-form interface domain:")
        for f in res["fixed_dofs"]:
            s = f["strength"]
            lines.append(
                f"  {f['case']:<8} DOFs {f['dofs_all']} -> {f['dofs_free']} free "
                f"(nnz K {f['nnz_K_all']} -> {f['nnz_K_free']}); factorisation "
                f"{1e3 * f['seconds_factor_all_penalty']:.2f} ms (all DOFs + penalty) -> "
                f"{1e3 * f['seconds_factor_free']:.2f} ms ({f['time_ratio']:.1f}x); "
                f"law for {s['interfaces']} interfaces: closed form "
                f"{1e3 * s['seconds_closed_form']:.2f} ms, {s['springs_per_interface']}-spring "
                f"model {1e3 * s['seconds_spring_model']:.1f} ms ({s['time_ratio']:.0f}x)"
            )
    return "\n".join(lines)


# ---------------------------------------------------------------------------- kn sweep
def kn_sweep(
    case_name: str,
    factors,
    method: str = "static",
    budget: int | None = None,
    scale_kt: bool = False,
) -> dict:
    """lambda of a dry-joint case as the dry normal stiffness is multiplied by ``factors``.

    ``scale_kt``: scale the shear stiffness too. The law is then exactly invariant (actions
    depend on kbar x relative displacement only, and displacements scale by 1/factor), so any
    drift is numerical: conditioning, tolerances, the absolute displacement limit. With kn
    alone the ratio kt/kn changes, and with it the elastic share of shear and normal forces
    from which the non-associative friction of the joints starts: a physical change too.
    """
    from masonry_dem.cases.paper import Assumptions, build_case
    from masonry_dem.solvers.dynamic_relaxation import DRSettings

    base = Assumptions()
    kn0 = base.dry_kn
    rows = []
    for f in factors:
        changes = {"dry_kn": kn0 * f}
        if scale_kt:
            changes["dry_kt"] = base.dry_kt * f
        pc = build_case(case_name, **changes)
        if method == "static":
            settings = pc.settings
        else:
            changes = {} if budget is None else {"max_time_steps": budget}
            settings = _settings(DRSettings, _dr_base(pc.settings), changes)
        hist, seconds, cost = _run(method, pc.model, settings)
        rows.append(
            {
                "case": case_name,
                "method": method,
                "kn": kn0 * f,
                "kt": base.dry_kt * (f if scale_kt else 1.0),
                "factor": f,
                "lambda": _lambda(hist),
                "status": hist.status,
                "reason": hist.reason,
                "seconds": round(seconds, 3),
                **cost,
            }
        )
    lams = [r["lambda"] for r in rows if r["lambda"] is not None]
    base = rows[0]["lambda"]
    for r in rows:
        r["drift"] = _rel(r["lambda"], base)
    spread = (max(lams) - min(lams)) / abs(base) if lams and base else None
    return {"rows": rows, "spread": spread}


# ---------------------------------------------------------------------------- CLI
def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "study",
        help="speed against accuracy of the solvers, the in-plane reduction, the kn sweep",
        description="Measurements of the solvers: see docs/solvers.md.",
    )
    sub = p.add_subparsers(dest="study", metavar="STUDY")
    sa = sub.add_parser(
        "speed-accuracy",
        help="run cases with every solver setting; table, JSON and a time-vs-error chart",
    )
    sa.add_argument(
        "--cases",
        nargs="+",
        default=list(DEFAULT_CASES),
        help="validation cases (names of masonry_dem.cases.paper, or 'default'; "
        "default: %(default)s)",
    )
    sa.add_argument("--quick", action="store_true", help="a few settings per method only")
    sa.add_argument(
        "--full",
        action="store_true",
        help="also the DR settings that only cost time (FULL_ONLY: dt 0.5, viscous, density "
        "masses, slow ramp)",
    )
    sa.add_argument(
        "--budget",
        type=int,
        default=None,
        help="time-step budget of each DR run (default: DRSettings.max_time_steps, 2 000 000: "
        "DR needs about 1e6 on the mortar wall 14-15)",
    )
    sa.add_argument("--json", action="store_true", help="print the runs as a JSON array")
    sa.add_argument(
        "--from-json",
        metavar="FILE",
        help="no runs: redo the table, errors and chart from a saved speed_accuracy.json",
    )
    sa.add_argument(
        "--out", default="results/study", help="folder for the PNG, JSON and table (%(default)s)"
    )
    sa.set_defaults(func=speed_accuracy_command)
    rd = sub.add_parser("reduction", help="3-DOF in-plane model against the 6-DOF model")
    rd.add_argument("--repeats", type=int, default=3, help="best of N timings (%(default)s)")
    rd.add_argument("--json", action="store_true")
    rd.set_defaults(func=reduction_command)
    kn = sub.add_parser("kn-sweep", help="lambda as the dry-joint normal stiffness grows")
    kn.add_argument("--case", default="S15", help="a dry-joint case (default: %(default)s)")
    kn.add_argument(
        "--factors",
        type=float,
        nargs="+",
        default=[0.1, 1.0, 10.0, 100.0, 1000.0],
        help="multipliers of the assumed dry kn (default: %(default)s)",
    )
    kn.add_argument("--method", choices=("static", "dynamic_relaxation"), default="static")
    kn.add_argument(
        "--budget",
        type=int,
        default=None,
        help="DR time-step budget (default: DRSettings.max_time_steps)",
    )
    kn.add_argument(
        "--scale-kt",
        action="store_true",
        help="scale kt with kn (a pure conditioning test: the law is then invariant)",
    )
    kn.add_argument("--json", action="store_true")
    kn.set_defaults(func=kn_sweep_command)
    p.set_defaults(func=lambda args: _help(p))


def _help(p: argparse.ArgumentParser) -> int:
    p.print_help()
    return 2


def speed_accuracy_command(args: argparse.Namespace) -> int:
    out = Path(args.out)

    def progress(row: dict) -> None:
        if not args.json:
            print(
                f"  {row['case']} {row['method']} [{row['label']}]: {row['status']} "
                f"lambda={_fmt(row['lambda'], '.5g')} in {row['seconds']:.2f} s",
                flush=True,
            )

    if args.from_json:
        saved = json.loads(Path(args.from_json).read_text())
        res = summarise(saved["rows"], saved["summary"])
    else:
        res = speed_accuracy(
            args.cases,
            quick=args.quick,
            budget=args.budget,
            progress=progress,
            full=getattr(args, "full", False),
        )
    out.mkdir(parents=True, exist_ok=True)
    (out / "speed_accuracy.json").write_text(json.dumps(res, indent=2))
    text = table(res["rows"]) + "\n\n" + summary_lines(res["summary"], res["accuracy"])
    (out / "speed_accuracy.txt").write_text(text + "\n")
    png = chart(res["rows"], out / "speed_accuracy.png")
    if args.json:
        print(json.dumps(res["rows"], indent=1))
    else:
        print(text)
        print(f"chart: {png}; data: {out / 'speed_accuracy.json'}")
    return 0 if res["rows"] else 1


def reduction_command(args: argparse.Namespace) -> int:
    res = reduction_study(repeats=args.repeats)
    print(json.dumps(res, indent=1) if args.json else reduction_text(res))
    return 0


def kn_sweep_command(args: argparse.Namespace) -> int:
    res = kn_sweep(args.case, args.factors, args.method, args.budget, args.scale_kt)
    if args.json:
        print(json.dumps(res, indent=1))
        return 0
    what = "kn and kt" if args.scale_kt else "kn (kt held)"
    print(f"{args.case}: lambda as the dry-joint {what} grow ({args.method})")
    print(
        f"  {'kn [N/m^3]':>11} {'kt [N/m^3]':>11} {'lambda':>10} {'drift':>8} {'seconds':>8}  status"
    )
    for r in res["rows"]:
        print(
            f"  {r['kn']:11.3g} {r['kt']:11.3g} {_fmt(r['lambda'], '10.5g')} "
            f"{_fmt(r['drift'], '8.2%')} {r['seconds']:8.2f}  {r['status']}"
        )
    print(f"  spread of lambda over the sweep: {_fmt(res['spread'], '.2%')}")
    return 0
