"""How a corner check's relaxation moves above a peak and above a fold (issue 18, task
`verdict`; docs/history/solvers_record.md, "Above a peak and above a fold").

    python benchmarks/relaxation_trace.py [--walls S23 U S6/2 S13/2] [--window 500]
        [--steps 30000] [--probe-every 500] [--only-last] [--keep-creep] [--line] [--probes]
        [--implicit]

With ``--implicit`` (session 18) each recorded check is run again by the implicit corner
check instead (``Relaxations.implicit_relaxation``, from the same start to the same target):
its verdict and steps beside the explicit one's, and, at the last check's start, the cost
of one factorization against one time step of dynamic relaxation.

Each wall is run by the static pushover with its default settings; every dynamic relaxation
of a corner check (``Relaxations.dynamic_rescue`` called by work control's ``rest_above``: at
a fold after the implicit check's rest, or where that check gives no verdict) is recorded: its start
state, target and whether it found rest. Then each recorded check is relaxed again with
kinetic damping as ``Relaxation._relax`` does it, every velocity zeroed at each
kinetic-energy peak (``--keep-creep``: the velocity along a converged creep kept, as
``fold_creep_cos`` does, with a cosine of 0.95), with Newton probes at the kinetic-energy
peaks as in the check (so a fold ends where a probe converges), and per window of time steps
it prints:

- ``res``: the lowest relative residual in the window; ``ke``: the highest kinetic energy
  (relative to the first window's); ``move``: the largest translation from the start (m);
- ``creep``: the mass norm of the creep, the mean of the states at the kinetic-energy peaks
  of this window less the last window's; ``ratio``: over the last window's creep; ``cos``:
  the mass-weighted cosine between the two;
- ``P_L``: the cosine between the creep and F_L (the live load's work along it);
- ``R_c``: the mean out-of-balance force at the peaks along the creep, over |F|;
- ``peaks``: kinetic-energy peaks in the window;
- with ``--line``: the out-of-balance force along the straight line from the start through
  the state, at 1, 2, 4 ... times its distance up to the displacement limit;
- with ``--probes``: each probe's Newton outcome (residual before and after, failure).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.static import StaticSettings, StaticSolver
from masonry_dem.solvers.static.relaxations import Relaxations


def wall(name: str):
    """(model, settings, monitor) of a validation case, ``NAME/m`` (return walls of m
    blocks) or ``U`` (bench_walls_that_meet's S5 U wall)."""
    if name == "U":
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from bench_walls_that_meet import build, walls

        model, _ = build(walls("S5")[0], held=False)
        return model, None, None
    if "/" in name:
        row, m = name.split("/")
        case = build_case(row, restraint="return-walls", return_blocks=int(m))
    else:
        case = build_case(name)
    return case.model, case.settings, case.monitor


def record(model, settings, monitor):
    """Run the pushover; the dynamic relaxations of the corner checks it made: (corrector,
    start state, target, budget, found, time steps, the corrector's trust increment at the
    start)."""
    checks = []
    original = Relaxations.dynamic_rescue
    settings = settings or StaticSettings()

    def spy(self, target, last, budget=None, polish=True):
        increment = self.last_increment
        start = self.relaxation_start(last)
        q_saved = self.q.copy()
        before = self.time_steps
        out = original(self, target, last, budget, polish)
        if budget is not None and polish:
            checks.append(
                (
                    self,
                    start,
                    q_saved,
                    target,
                    budget,
                    out is not None,
                    self.time_steps - before,
                    increment,
                )
            )
        return out

    Relaxations.dynamic_rescue = spy
    try:
        solver = StaticSolver(model, settings)
        history = solver.run(monitor=monitor)
    finally:
        Relaxations.dynamic_rescue = original
    return history, checks


def along_line(dr, start, x, F, plastic, cracked, limit):
    """The out-of-balance force along the line from the start through x, at distances
    |u| x 2^k up to the displacement limit: the first where it resists (turns negative)."""
    u = x - start.x
    tr = dr._translation
    umax = float(np.abs(u[tr]).max(initial=0.0))
    if umax <= 0:
        return "no motion"
    un = u / float(np.linalg.norm(u))
    Fn = float(np.linalg.norm(F))
    out = []
    s = 1.0
    while True:
        y = start.x + s * u
        _, _, fint = dr._forces(y, plastic, cracked)
        g = float((F - fint) @ un) / Fn
        out.append(f"{s:g}:{g:+.1e}")
        if g < 0:
            return f"resists at {s:g} x ({s * umax:.2e} m) " + " ".join(out)
        if s * umax > limit:
            return "driving to the limit " + " ".join(out)
        s *= 2.0


def trace(
    corrector,
    start,
    q_saved,
    target,
    budget,
    window,
    probe_every,
    steps,
    line=False,
    show_probes=False,
    keep_creep=False,
):
    dr = corrector.relaxation(budget)  # the check's own, fresh
    free = corrector.problem.asm.free_index
    # the corrector as it was at the check (the path moved it on since)
    corrector.q = q_saved.copy()
    corrector.plastic = start.plastic.copy()
    corrector.cracked = start.cracked.copy()
    dt = dr._step_for(start)
    M = dr.mass
    W = dr._weight
    x = start.x.copy()
    plastic, cracked = start.plastic, start.cracked
    v = np.zeros_like(x)
    F = dr.F_dead + target * dr.F_live
    FL = dr.F_live
    _, resp, fint = dr._forces(x, plastic, cracked)
    R = F - fint
    Fn = max(float(np.linalg.norm(W * F)), 1e-30)
    ke_prev = 0.0
    restart = True
    probed = 0
    keep = None
    rmin, kmax, peaks = math.inf, 0.0, 0
    ke_ref = None
    xsum = np.zeros_like(x)
    rsum = np.zeros_like(x)
    mean_prev = x.copy()
    creep_prev = None
    print(
        f"{'steps':>7s} {'res':>9s} {'ke':>9s} {'move':>9s} {'creep':>9s} {'ratio':>6s} "
        f"{'cos':>6s} {'P_L':>6s} {'R_c':>9s} {'peaks':>5s}"
    )

    def probe(xp):
        q = q_saved.copy()
        q[free] = xp
        before = float(corrector.residual(q, target)[1])
        out = corrector.equilibrate(target, start=q)
        after = float(corrector.residual(out.q, target)[1])
        if not out.ok and show_probes:
            print(
                f"    probe at {probed}: residual {before:.2e} -> {after:.2e} in "
                f"{out.iterations} ({out.failure.name}: {out.reason[:70]})"
            )
        return out.ok

    Fnorm = max(float(np.linalg.norm(F)), 1e-300)
    for cycle in range(1, steps + 1):
        rnorm = float(np.linalg.norm(W * R)) / Fn
        rmin = min(rmin, rnorm)
        v_old = v
        v = v + (0.5 * dt if restart else dt) * (R / M)
        restart = False
        ke_new = 0.5 * float(v @ (M * v))
        kmax = max(kmax, ke_new)
        if ke_new < ke_prev:
            x = x - 0.5 * dt * v_old
            kept = 0.0
            if keep is not None:
                kept = float(v_old @ (M * keep))
            if kept > 0:
                # the motion along the converged creep is not damped: only the rest
                v = kept * keep
                ke_prev = 0.5 * float(v @ (M * v))
            else:
                v = np.zeros_like(v)
                ke_prev = 0.0
            restart = True
            peaks += 1
            _, resp, fint = dr._forces(x, plastic, cracked)
            R = F - fint
            xsum += x
            rsum += R
            if probe_every and cycle - probed >= probe_every:
                probed = cycle
                if probe(x):
                    print(f"{cycle:7d} probe converged: FOLD")
                    return cycle
        else:
            ke_prev = ke_new
            x = x + dt * v
            _, resp, fint = dr._forces(x, plastic, cracked)
            R = F - fint
        if cycle % window == 0 and peaks:
            mean = xsum / peaks
            rmean = rsum / peaks
            c = mean - mean_prev
            cm = math.sqrt(float(c @ (M * c)))
            move = float(np.abs(x[dr._translation] - start.x[dr._translation]).max(initial=0))
            pl = float(FL @ c) / max(float(np.linalg.norm(FL)) * float(np.linalg.norm(c)), 1e-300)
            if creep_prev is not None:
                pm = math.sqrt(float(creep_prev @ (M * creep_prev)))
                cos = float(c @ (M * creep_prev)) / max(cm * pm, 1e-300)
                ratio = cm / max(pm, 1e-300)
            else:
                cos = ratio = float("nan")
            rc = float(rmean @ c) / max(float(np.linalg.norm(c)), 1e-300) / Fnorm
            ke_ref = ke_ref or max(kmax, 1e-300)
            print(
                f"{cycle:7d} {rmin:9.2e} {kmax / ke_ref:9.2e} {move:9.2e} {cm:9.2e} "
                f"{ratio:6.2f} {cos:6.3f} {pl:6.3f} {rc:9.2e} {peaks:5d}",
                flush=True,
            )
            if line:
                print(
                    "         line: "
                    + along_line(dr, start, x, F, plastic, cracked, corrector.limit)
                )
            if move > corrector.limit:
                print("  past the displacement limit")
                return cycle
            if keep_creep and cos > 0.95:
                keep = c / max(cm, 1e-300)
            else:
                keep = None
            creep_prev, mean_prev = c, mean
            xsum[:] = 0.0
            rsum[:] = 0.0
            rmin, kmax, peaks = math.inf, 0.0, 0
    return steps


def implicit(corrector, start, q_saved, target, increment) -> str:
    """The implicit corner check (``Relaxations.implicit_relaxation``) from a recorded check's
    start to its target: verdict and steps (each one factorization)."""
    corrector.q = q_saved.copy()
    corrector.plastic = start.plastic.copy()
    corrector.cracked = start.cracked.copy()
    corrector.last_increment = increment
    f0, t0 = corrector.factorizations, time.perf_counter()
    out = corrector.implicit_relaxation(target)
    verdict = "rest" if out.ok else out.failure.value
    return (
        f"{verdict} after {out.iterations} steps ({corrector.factorizations - f0} "
        f"factorizations, {time.perf_counter() - t0:.2f} s)"
    )


def costs(corrector, start, q_saved, target, budget, repeat: int = 5) -> str:
    """At a recorded check's start: one factorization and solve of the tangent, and one time
    step of the check's dynamic relaxation (a relaxation of ``budget`` time steps at most, no
    probes), in seconds, and their ratio."""
    corrector.q = q_saved.copy()
    corrector.plastic = start.plastic.copy()
    corrector.cracked = start.cracked.copy()
    _, _, response = corrector.residual(corrector.q, target)
    t0 = time.perf_counter()
    for _ in range(repeat):
        corrector.problem.factor(response).solve(corrector.problem.F_live)
    factor = (time.perf_counter() - t0) / repeat
    dr = corrector.relaxation(budget)
    t0 = time.perf_counter()
    relaxed = dr.relax_with_cuts(start, target, None, from_start=True)
    step = (time.perf_counter() - t0) / max(relaxed.cycles, 1)
    return (
        f"one factorization and solve {factor * 1e3:.2f} ms, one time step {step * 1e3:.3f} ms "
        f"(of {relaxed.cycles}): a factorization costs {factor / step:.1f} time steps"
    )


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--walls", nargs="*", default=["S23", "U", "S6/2", "S13/2"])
    p.add_argument("--window", type=int, default=500)
    p.add_argument("--steps", type=int, default=30_000)
    p.add_argument("--probe-every", type=int, default=500)
    p.add_argument("--only-last", action="store_true", help="trace only the last check")
    p.add_argument("--keep-creep", action="store_true", help="no damping along the creep")
    p.add_argument("--line", action="store_true", help="the force along the line")
    p.add_argument("--probes", action="store_true", help="each probe's Newton outcome")
    p.add_argument(
        "--implicit",
        action="store_true",
        help="instead of the trace, each check again by the implicit relaxation, and the "
        "cost of a factorization in time steps",
    )
    args = p.parse_args(argv)
    for name in args.walls:
        t0 = time.perf_counter()
        history, checks = record(*wall(name))
        print(
            f"\n== {name}: {history.status} at {history.collapse_multiplier}, "
            f"{len(checks)} corner checks ({time.perf_counter() - t0:.1f} s)"
        )
        chosen = checks[-1:] if args.only_last else checks
        if args.implicit and chosen:
            print("   " + costs(*chosen[-1][:5]))
        for corrector, start, q_saved, target, budget, found, used, increment in chosen:
            print(
                f"-- check from lambda={start.load_factor:.6g} to {target:.6g}: "
                f"{'rest (fold)' if found else 'no rest'} after {used} time steps"
            )
            if args.implicit:
                print("   implicit: " + implicit(corrector, start, q_saved, target, increment))
                continue
            trace(
                corrector,
                start,
                q_saved,
                target,
                budget,
                args.window,
                args.probe_every,
                min(args.steps, used + args.window) if found else args.steps,
                line=args.line,
                show_probes=args.probes,
                keep_creep=args.keep_creep,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
