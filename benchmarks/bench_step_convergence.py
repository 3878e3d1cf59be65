"""Benchmark: does the collapse multiplier converge as the steps of the path shorten?

    NUMBA_NUM_THREADS=1 python benchmarks/bench_step_convergence.py [--case 2-3 ...]
        [--variants default growth=1.2 ...] [--set NAME=VALUE ...] [--json FILE] [--png FILE]
        [--from-json FILE]

``--set`` changes a setting in every variant (the default's included), e.g. ``--set
tail_resolution=1e-3``; a variant may name any setting too
(``growth=1.025,tail_resolution=1.25e-4``).

Each validation case runs the default static pushover (``StaticSolver(model,
settings).run()``, the case's own settings) once per variant of the step length:

* ``growth`` 1.5 (default), 1.2, 1.1, 1.05, 1.025: how much longer each easy step is than the last (work
  control has no cap on its step, so near the peak a step is about (growth - 1) times the
  distance w travelled from the hand-over: ``growth - 1`` is the step variable);
* ``max_step`` (and ``initial_step``) halved and quartered: the load-control steps, which
  also set work control's first step (the last load step's w);
* the two combined (``growth=1.1`` with steps quartered), the finest path.

Per run it prints lambda, converged steps, factorizations and CPU seconds, and per case the
ratios to the default: lambda's relative difference, factorizations and CPU. It then
extrapolates lambda to a zero step in x = growth - 1 (lambda = lambda_0 + C x, least squares
over growth 1.2 to 1.025 at the case's max_step; a first-order (backward-Euler) return
per step has an error linear in the step) and gives the default's error against it, and the
joints whose damage state differs at the peak between the default and the finest path
(growth 1.025).

Then, against ``--reference`` (a variant, by default the finest growth): each run's largest
difference of lambda from the reference path at the same w, and where its path stopped
(the w of its highest lambda and the stop's reason). The paths coincide to a few 1e-4 and
their stops differ (docs/history/solvers_record.md, "The step near the peak").

The chart (``--png``): factorizations over the default's against |lambda - lambda_0| /
lambda_0, one line per case through the growth variants (the default starred), the shorter
load steps as crosses. CPU seconds compare only within one run; the factorizations are exact.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from _machine import arguments, print_machine

sys.path.insert(0, str(Path(__file__).resolve().parent))

PRESSURE = ["2-3", "4-5", "8-12", "9-13", "10-11", "14-15"]
TILT = ["S5", "S15", "OL1"]
VARIANTS = [
    "default",
    "growth=1.2",
    "growth=1.1",
    "growth=1.05",
    "growth=1.025",
    "steps/2",
    "steps/4",
    "growth=1.1,steps/4",
]


FINEST = "growth=1.025"


def changes_of(variant: str, base) -> dict:
    """The ``StaticSettings`` changes a variant's name stands for (``steps/k``: both
    ``initial_step`` and ``max_step`` of the case divided by k)."""
    out: dict = {}
    if variant == "default":
        return out
    for part in variant.split(","):
        if part.startswith("steps/"):
            k = float(part.split("/")[1])
            out["initial_step"] = base.initial_step / k
            out["max_step"] = base.max_step / k
        else:
            name, value = part.split("=")
            out[name] = _value(value)
    return out


def _value(text: str) -> float | str:
    try:
        return float(text)
    except ValueError:
        return text


def one_run(case, variant: str, common: dict | None = None) -> dict:
    from masonry_dem.solvers.static import StaticSolver

    base = replace(case.settings, **(common or {}))
    settings = replace(base, **changes_of(variant, base))
    solver = StaticSolver(case.model, settings)
    c0 = time.process_time()
    hist = solver.run(monitor=case.monitor)
    cpu = time.process_time() - c0
    lam = hist.collapse_multiplier
    lam = float(lam if lam is not None else hist.final_load_factor)
    peak = max(hist.steps, key=lambda st: float(st.load_factor))
    problem = solver.problem
    c = problem.F_live / float(np.linalg.norm(problem.F_live))
    q0 = hist.steps[0].q.reshape(-1)[problem.free]
    return {
        "variant": variant,
        "status": str(hist.status),
        "stop": str(hist.stop),
        "path_w": [float(c @ (st.q.reshape(-1)[problem.free] - q0)) for st in hist.steps],
        "path_lambda": [float(st.load_factor) for st in hist.steps],
        "lambda": lam,
        "steps": len(hist.steps),
        "factorizations": int(solver.factorizations),
        "iterations": int(solver.iterations),
        "cpu": cpu,
        "peak_state": np.asarray(peak.state).tolist(),
    }


def extrapolate(runs: dict) -> tuple[float, float] | None:
    """lambda_0 and C of lambda = lambda_0 + C (growth - 1), least squares over the growth
    variants of at most 1.2 at the case's own steps (None when fewer than two ran). The
    default's 1.5 is left out: it is the point whose error is asked, and it may lie outside
    the range where the error is linear in the step."""
    pts = []
    for g in ("1.2", "1.1", "1.05", "1.025"):
        if f"growth={g}" in runs:
            pts.append((float(g) - 1.0, runs[f"growth={g}"]["lambda"]))
    if len(pts) < 2:
        return None
    x = np.array([p[0] for p in pts])
    y = np.array([p[1] for p in pts])
    slope, intercept = np.polyfit(x, y, 1)
    return float(intercept), float(slope)


def state_changes(a: list[int], b: list[int]) -> dict:
    """Joints whose damage state differs between two peaks, by (state in a -> state in b)."""
    from masonry_dem.constitutive import STATE_NAMES

    sa, sb = np.asarray(a), np.asarray(b)
    diff = sa != sb
    pairs: dict[str, int] = {}
    for i, j in zip(sa[diff], sb[diff], strict=True):
        key = f"{STATE_NAMES[int(i)]}->{STATE_NAMES[int(j)]}"
        pairs[key] = pairs.get(key, 0) + 1
    return {"joints": int(sa.size), "differ": int(diff.sum()), "pairs": pairs}


def report(results: dict) -> None:
    print()
    head = f"{'case':7s} {'variant':20s} {'lambda':>12s} {'d lambda':>9s} {'steps':>6s}"
    print(head + f" {'fact':>6s} {'f ratio':>8s} {'cpu ratio':>9s}  status")
    for name, runs in results.items():
        base = runs.get("default")
        for v, r in runs.items():
            d = (r["lambda"] / base["lambda"] - 1) if base else math.nan
            fr = r["factorizations"] / base["factorizations"] if base else math.nan
            cr = r["cpu"] / base["cpu"] if base and base["cpu"] > 0 else math.nan
            print(
                f"{name:7s} {v:20s} {r['lambda']:12.6g} {d:+9.3%} {r['steps']:6d} "
                f"{r['factorizations']:6d} {fr:7.2f}x {cr:8.2f}x  {r['status']}"
            )
    print()
    print("extrapolated to a zero step in x = growth - 1 (lambda = lambda_0 + C x):")
    for name, runs in results.items():
        fit = extrapolate(runs)
        if fit is None:
            continue
        lam0, slope = fit
        errs = ", ".join(f"{v} {r['lambda'] / lam0 - 1:+.3%}" for v, r in runs.items())
        print(
            f"  {name:7s} lambda_0 = {lam0:.6g}  C/lambda_0 = {slope / lam0:+.4f}  errors: {errs}"
        )
    print()
    print("joints whose state at the peak differs, default -> finest path:")
    for name, runs in results.items():
        fine = runs.get(FINEST)
        if "default" in runs and fine is not None:
            s = state_changes(runs["default"]["peak_state"], fine["peak_state"])
            pairs = ", ".join(f"{k} {n}" for k, n in sorted(s["pairs"].items()))
            print(f"  {name:7s} {s['differ']} of {s['joints']}: {pairs}")


def same_w(run: dict, ref: dict) -> tuple[float, int]:
    """The largest |lambda / lambda_ref - 1| of a run's states against the reference path at
    the same w (interpolated), over the states in the second half of the reference's range
    of w (its tail, where the stop is decided; the first half holds the hand-over, whose
    load steps ``growth`` also sets), and how many states were compared. Small where the
    paths coincide and only their stops differ."""
    w, lam = np.asarray(run["path_w"]), np.asarray(run["path_lambda"])
    rw, rlam = np.asarray(ref["path_w"]), np.asarray(ref["path_lambda"])
    order = np.argsort(rw)
    inside = (w >= 0.5 * rw.max()) & (w <= rw.max())
    if not inside.any():
        return math.nan, 0
    there = np.interp(w[inside], rw[order], rlam[order])
    return float(np.max(np.abs(lam[inside] / there - 1))), int(inside.sum())


def stops(results: dict, reference: str) -> None:
    """Per run: where its path stopped (w, why) and how far its states lie from the
    reference path at the same w."""
    print()
    print(f"the paths against {reference} at the same w, and where each stopped:")
    for name, runs in results.items():
        ref = runs.get(reference)
        if ref is None or "path_w" not in ref:
            continue
        for v, r in runs.items():
            dev, n = same_w(r, ref)
            stop_w = r["path_w"][int(np.argmax(r["path_lambda"]))]
            print(
                f"  {name:7s} {v:24s} lambda {r['lambda'] / ref['lambda'] - 1:+8.3%}  "
                f"at the same w {dev:8.4%} ({n:3d} states)  peak at w={stop_w:.4g}  {r['stop']}"
            )


def chart(results: dict, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["axes.formatter.useoffset"] = False  # every tick its own value
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, runs in results.items():
        fit = extrapolate(runs)
        base = runs.get("default")
        if fit is None or base is None:
            continue
        lam0 = fit[0]

        def point(r: dict, f0: float = base["factorizations"], l0: float = lam0) -> tuple:
            return r["factorizations"] / f0, 100 * abs(r["lambda"] / l0 - 1)

        growths = [v for v in runs if v == "default" or v.startswith("growth=") and "," not in v]
        xs, ys = zip(*(point(runs[v]) for v in growths), strict=True)
        style = "-o" if name in PRESSURE else "--s"
        (line,) = ax.plot(xs, ys, style, label=name, ms=4)
        others = [point(r) for v, r in runs.items() if v not in growths]
        if others:
            ox, oy = zip(*others, strict=True)
            ax.plot(ox, oy, "x", color=line.get_color(), ms=5)
        ax.plot(*point(base), "k*", ms=9)
    ax.axhline(0.1, color="grey", lw=0.8, ls=":")
    ax.set_xlabel("factorizations / the default's")
    ax.set_ylabel("|lambda - lambda_0| / lambda_0 (%)")
    ax.set_title(
        "lambda against the step: growth 1.5 (star) to 1.025 (lines); x: shorter load steps",
        fontsize=9,
    )
    ax.legend(fontsize=7, ncol=3)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=110)
    print(f"chart: {png}")


def main() -> int:
    p = arguments(__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--case", action="append", default=[], help="a validation case")
    p.add_argument("--variants", nargs="+", default=VARIANTS)
    p.add_argument("--json", default=None, help="write the runs here (after each run)")
    p.add_argument("--from-json", default=None, help="report and chart runs written before")
    p.add_argument("--png", default=None, help="the chart")
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="in every variant"
    )
    p.add_argument("--reference", default=FINEST, help="the variant the paths are compared with")
    a = p.parse_args()
    print_machine()
    common = {k: _value(v) for k, v in (kv.split("=", 1) for kv in a.set)}
    if a.from_json:
        results = json.loads(Path(a.from_json).read_text())
    else:
        from masonry_dem.cases.paper import build_case

        if a.json:
            Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        names = a.case or PRESSURE + TILT
        one_run(build_case(names[0]), "default", common)  # compiles the kernels: not timed
        results = {}
        for name in names:
            case = build_case(name)
            results[name] = {}
            for v in a.variants:
                r = one_run(case, v, common)
                results[name][v] = r
                print(
                    f"{name} {v}: lambda={r['lambda']:.6g} steps={r['steps']} "
                    f"factorizations={r['factorizations']} cpu={r['cpu']:.1f} s {r['status']}",
                    flush=True,
                )
                if a.json:
                    Path(a.json).write_text(json.dumps(results))
    report(results)
    stops(results, a.reference)
    if a.png:
        chart(results, Path(a.png))
    return 0


if __name__ == "__main__":
    sys.exit(main())
