"""Where the factorizations of a pushover go: one row per equilibrium search of the path.

    python benchmarks/path_audit.py --scale 30 [--scale 100] [--case S11 ...] [--set k=v ...]
        [--u-wall S5] [--flat-wall S5] [--rows] [--states] [--json FILE]

Each wall runs the default static pushover (``StaticSolver(model, settings).run()``); the
searches the path followers ask for (``equilibrate``, ``pseudo_transient``, ``robust``,
``dynamic_rescue``, ``implicit_relaxation``) are wrapped on the solver instance, and each call is one row: the
controller that asked (``load``: lambda prescribed; ``work``: the work-conjugate
displacement prescribed; ``transient``: a pseudo-transient step; ``rescue``/``robust``;
``corner``: the implicit corner check, ``implicit_relaxation``),
lambda it ended at, the step it was asked for (d lambda, or d w in m), Newton iterations,
factorizations, and whether it converged (and if not, why). The totals split the
factorizations by controller and by converged/failed; what no search took (the elastic
range, the certificate, the tangents the stop check asks for) is ``other``.

``--scale N`` is ``bench_scale.scale_wall(N)`` (30: 909 blocks, 100: 10 017); ``--case`` a
validation case (its own settings and monitor); ``--return-blocks B`` (repeatable) builds
those cases with their return walls as blocks, B blocks long (``--cases``: the seven
Restrepo Velez specimens that have them), named ``S11/2`` etc. ``--u-wall SIZE`` and ``--flat-wall SIZE``
are the U wall (returns as blocks, base fixed) and the flat wall of the same block count
(end columns held) of ``bench_walls_that_meet`` (``SIZE``: S5 or big), both tilted, with
the default settings, as that benchmark pushes them. ``--states`` prints, per recorded step,
the joints whose damage state changed since the step before (on a U wall, also how many
of them touch a return: a block whose centre lies behind the facade). ``--set name=value`` overrides a
``StaticSettings`` field. ``--against name=value`` runs each wall a second time with that
override too, the two in turn ``--repeat`` times (keeping each one's fastest), and prints
the ratios of seconds (wall clock and the process's CPU), factorizations and iterations
(this run over the other): a rule
against the rule before, in one run. Counts are exact whatever the machine's load; the
seconds are not, so only their ratios within one run compare.

``--replay name=value`` (session 18) records every Newton search of the path with the
solver's state before it and runs each again from that state, once as it was (the count of
outcomes that differ, ``mismatches``, should be 0) and once with the change: searches
converged, factorizations and iterations of each corrector over the same searches, so a
change of the corrector is compared without the path it would
take (a corrector that converges one search more or less takes another path, whose folds
and halvings then move the totals by tens of per cent either way).

Four probes of the path (issue 21, session 17), each on top of a default run:

* ``--events`` adds to each work search of ``--rows`` the joints whose state the tangent of
  its start state predicts to change within the step (``events``: the law's flags at the
  goal along K_t^-1 F_L, scaled to the step in w, against those at the start; ``crossed``:
  the changes summed over 16 equal sub-steps, a joint that changes twice counted twice) and
  the distance to the first change as a fraction of the step (``next``, to 1/16). The
  tangent it takes is not counted in the factorizations.
* ``--reach M [M ...]`` restarts work control from about 16 states of the path and asks
  each for M times the step the path took from there (on the secant through that state and
  the one before, as work control starts): converged or not, iterations, factorizations. How
  far Newton's basin reaches along the path, against the step the rule chose.
* ``--transients`` prints, for each pseudo-transient step, whether it came to rest, its
  time steps, the longest run of them over which its residual did not halve (what
  ``transient_window`` bounds) and its largest residual over the start's.
* ``--misses`` (session 19) prints, per wall, the work searches converged and failed and
  the quartiles of the predictor's miss over the converged ones: the distance from the
  search's start to the state it converged to, over the distance from the last state (1:
  a start at the last state).
* ``--hand-over`` stops at the state where load control hands over to work control and
  tries from it the first work step and its halvings, from the three starts a search can
  take (the secant through the last two load steps, the state itself, the state moved along
  its tangent), beside the tangent's d lambda / d w and the last load step's.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def predicted_events(solver, dw: float, pieces: int = 16) -> tuple[int, int, float]:
    """Along the tangent of the last converged state, K_t^-1 F_L scaled to a unit of the
    work-conjugate displacement w: (joints whose law flags differ at w + dw from those at w,
    changes summed over ``pieces`` equal sub-steps, the first sub-step with a change as a
    fraction of dw; inf: none). The tangent's factorization is not counted."""
    p = solver.problem
    counted = p.factorizations
    _, _, response = solver.residual(solver.q, solver.load_factor)
    rate = p.factor(response).solve(p.F_live)
    p.factorizations = counted
    c = p.F_live / float(np.linalg.norm(p.F_live))
    moved = np.zeros_like(solver.q)
    moved[p.asm.free_index] = rate / float(c @ rate)
    base = p.asm.relative_displacements(solver.q)
    per_unit = p.asm.relative_displacements(moved)
    start = p.law.respond(base, solver.plastic, solver.cracked, False).flags
    before, crossed, first = start, 0, math.inf
    for k in range(1, pieces + 1):
        flags = p.law.respond(
            base + k / pieces * dw * per_unit, solver.plastic, solver.cracked, False
        ).flags
        changed = int((flags != before).sum())
        if changed and first == math.inf:
            first = k / pieces
        crossed += changed
        before = flags
    return int((before != start).sum()), crossed, first


def halving_stretch(residuals: list[float]) -> tuple[int, float]:
    """Of the residuals a pseudo-transient step evaluated (its start first; a time step whose
    residual is ten times the last accepted one is refused and retried shorter, so it is
    left out): the longest run of accepted time steps over which the best residual so far
    did not halve (what ``transient_window`` bounds), and the largest accepted residual over
    the start's."""
    accepted = [residuals[0]]
    for r in residuals[1:]:
        if r < 10.0 * accepted[-1]:
            accepted.append(r)
    best = np.minimum.accumulate(np.asarray(accepted))
    longest, anchor = 0, 0
    for i in range(len(best)):
        while best[i] <= 0.5 * best[anchor]:
            anchor += 1
        longest = max(longest, i - anchor)
    return longest, max(accepted) / accepted[0] if accepted[0] > 0 else math.inf


def audit(
    model, settings, monitor=None, part=None, events=False, keep=False, transients=False
) -> dict:
    """Run the pushover and return its rows and totals, and per recorded step the joints whose
    damage state changed since the step before (``changed``; of them in ``part``, a boolean
    mask of the joints, ``in_part``). ``events``: each work row also gets
    :func:`predicted_events` of its step. ``keep``: the solver and its converged states
    (``snapshots[k]``: the state of step k, to resume from) are returned too.
    ``transients``: each pseudo-transient row also gets :func:`halving_stretch` of its
    residuals (``stretch``, ``rise``)."""
    from masonry_dem.solvers.static import StaticSolver

    solver = StaticSolver(model, settings)
    snapshots: list = []
    if keep:
        accept = solver.accept

        def kept(out, step, value):
            taken = accept(out, step, value)
            snapshots.append(solver.snapshot())
            return taken

        solver.accept = kept
    rows: list[dict] = []
    depth = [0]
    free = solver.problem.asm.free_index
    c = solver.problem.F_live / float(np.linalg.norm(solver.problem.F_live))
    dead: list[np.ndarray] = []  # the dead-load state, w's origin

    def wrap(name: str) -> None:
        inner = getattr(solver, name)

        def call(*args, **kwargs):
            predicted = None
            if events and depth[0] == 0 and kwargs.get("control") is not None:
                predicted = predicted_events(solver, float(kwargs["control"][2]))
            residuals: list[float] = []
            patched = transients and depth[0] == 0 and name == "pseudo_transient"
            if patched:

                def residual(q, lam, dead_factor=1.0):
                    r = type(solver).residual(solver, q, lam, dead_factor)
                    residuals.append(float(r[1]))
                    return r

                solver.residual = residual
            before = solver.q.copy() if depth[0] == 0 else None
            depth[0] += 1
            f0, i0, t0 = solver.factorizations, solver.iterations, time.perf_counter()
            try:
                out = inner(*args, **kwargs)
            finally:
                depth[0] -= 1
                if patched:
                    del solver.residual  # the class's own again
            if depth[0] == 0:
                kind = name
                asked = float(args[0]) if args else float("nan")
                if name == "equilibrate":
                    control = kwargs.get("control")
                    kind = "load" if control is None else "work"
                    asked = float(control[2]) if control is not None else asked
                elif name == "pseudo_transient":
                    kind = "transient"
                elif name == "dynamic_rescue":
                    kind = "rescue"
                elif name == "implicit_relaxation":
                    kind = "corner"
                ok = out is not None and bool(out.ok)
                if ok and not dead:
                    dead.append(out.q[free].copy())
                w = float(c @ (out.q[free] - dead[0])) if out is not None and dead else 0.0
                rows.append(
                    {
                        "kind": kind,
                        "asked": asked,
                        "lambda": float(out.load_factor) if out is not None else float("nan"),
                        "w": w,
                        "iterations": solver.iterations - i0,
                        "factorizations": solver.factorizations - f0,
                        "ok": ok,
                        "why": "" if ok or out is None else str(out.failure.value),
                        "seconds": time.perf_counter() - t0,
                    }
                )
                if kind == "work" and ok and before is not None:
                    # the predictor's miss: from the search's start to where it converged,
                    # over the step (1: a start at the last state)
                    start = kwargs.get("start")
                    taken = float(np.linalg.norm(out.q - before))
                    gap = taken if start is None else float(np.linalg.norm(out.q - start))
                    rows[-1]["miss"] = gap / taken if taken > 0 else float("nan")
                if predicted is not None:
                    rows[-1].update(zip(("events", "crossed", "next"), predicted, strict=True))
                if residuals:
                    rows[-1].update(
                        zip(("stretch", "rise"), halving_stretch(residuals), strict=True)
                    )
            return out

        setattr(solver, name, call)

    for name in (
        "equilibrate",
        "pseudo_transient",
        "robust",
        "dynamic_rescue",
        "implicit_relaxation",
    ):
        wrap(name)
    t0, c0 = time.perf_counter(), time.process_time()
    hist = solver.run(monitor=monitor)
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    lam = hist.collapse_multiplier
    states = []
    for before, st in zip(hist.steps, hist.steps[1:], strict=False):
        moved = st.state != before.state
        states.append(
            {
                "step": st.step,
                "lambda": float(st.load_factor),
                "iterations": st.iterations,
                "changed": int(moved.sum()),
                "in_part": int(moved[part].sum()) if part is not None else 0,
            }
        )
    by = Counter()
    for r in rows:
        by[(r["kind"], r["ok"], "n")] += 1
        by[(r["kind"], r["ok"], "f")] += r["factorizations"]
        by[(r["kind"], r["ok"], "i")] += r["iterations"]
    kept_states = {"solver": solver, "hist": hist, "snapshots": snapshots} if keep else {}
    misses = [r["miss"] for r in rows if "miss" in r and math.isfinite(r["miss"])]
    return kept_states | {
        "status": str(hist.status),
        "lambda": float(lam if lam is not None else hist.final_load_factor),
        "steps": len(hist.steps),
        "iterations": solver.iterations,
        "factorizations": solver.factorizations,
        "time_steps": solver.time_steps,
        "implicit_steps": solver.implicit_steps,
        "other": solver.factorizations - sum(r["factorizations"] for r in rows),
        "seconds": seconds,
        "cpu": cpu,
        "rows": rows,
        "states": states,
        "work_ok": sum(r["kind"] == "work" and r["ok"] for r in rows),
        "work_failed": sum(r["kind"] == "work" and not r["ok"] for r in rows),
        # quartiles of the predictor's miss over the converged work searches
        "miss": [float(x) for x in np.quantile(misses, (0.25, 0.5, 0.75))] if misses else [],
        "by": {f"{k[0]}/{'ok' if k[1] else 'failed'}/{k[2]}": v for k, v in by.items()},
    }


def _work_search(solver, hist, k: int, dw: float, start: str = "secant"):
    """From the state of step ``k`` (resumed by the caller), a work search of ``dw`` as work
    control asks for it, started on the secant through steps k - 1 and k (``"secant"``),
    at the state (``"state"``) or moved along its tangent (``"tangent"``). Returns the outcome
    and its iterations and factorizations."""
    from masonry_dem.solvers.static.paths import control_radius

    p = solver.problem
    free = p.asm.free_index
    c = p.F_live / float(np.linalg.norm(p.F_live))
    qa, qb = hist.steps[k - 1].q.reshape(-1), hist.steps[k].q.reshape(-1)
    la, lb = float(hist.steps[k - 1].load_factor), float(hist.steps[k].load_factor)
    wa, wb = float(c @ qa[free]), float(c @ qb[free])
    q, lam = None, lb
    if start == "secant" and wb != wa:
        f = dw / (wb - wa)
        q, lam = qb + f * (qb - qa), lb + f * (lb - la)
    elif start == "tangent":
        _, _, response = solver.residual(solver.q, solver.load_factor)
        rate = p.factor(response).solve(p.F_live)
        dlam = dw / float(c @ rate)
        q = solver.q.copy()
        q[free] += dlam * rate
        lam = lb + dlam
    f0, i0 = solver.factorizations, solver.iterations
    out = solver.equilibrate(
        lam, control=(c, wb + dw, dw), radius=control_radius(solver, c, dw), start=q
    )
    return out, solver.iterations - i0, solver.factorizations - f0


def reach(run: dict, multiples: list[float], samples: int = 16) -> None:
    """From about ``samples`` states of the path ``run`` (an :func:`audit` with ``keep``),
    work steps of each multiple of the step the path took from there."""
    solver, hist, snapshots = run["solver"], run["hist"], run["snapshots"]
    free = solver.problem.asm.free_index
    c = solver.problem.F_live / float(np.linalg.norm(solver.problem.F_live))
    w = [float(c @ st.q.reshape(-1)[free]) for st in hist.steps]
    # work steps of the path: the next state further along w, the state before it recorded
    ks = [k for k in range(1, len(hist.steps) - 1) if w[k + 1] > w[k] and w[k] != w[k - 1]]
    ks = [k for k in ks if k >= _first_work_step(run)]
    print("  from step  lambda     step [m]   " + "".join(f"x{m:<12g}" for m in multiples))
    print("                                   " + "ok it  f      " * len(multiples))
    for k in ks[:: max(1, len(ks) // samples)]:
        dw = w[k + 1] - w[k]
        cells = []
        for m in multiples:
            solver.resume(snapshots[k])
            out, its, fs = _work_search(solver, hist, k, m * dw)
            cells.append(f"{'y' if out.ok else 'n'} {its:3d} {fs:3d}     ")
        print(f"  {k:9d}  {hist.steps[k].load_factor:.5f}  {dw:.3e}  " + "".join(cells))
    sys.stdout.flush()


def _first_work_step(run: dict) -> int:
    """The recorded step the first converged work search started from (each converged row
    is one recorded step)."""
    done = 0
    for row in run["rows"]:
        if row["kind"] == "work" and row["ok"]:
            return done - 1
        done += row["ok"]
    return len(run["hist"].steps)


def hand_over(model, settings) -> None:
    """From the state at which load control hands over to work control: the tangent's
    d lambda / d w against the last load step's, and the first work step (work control's:
    the last load step's increment of w) and its halvings from three starts."""
    from masonry_dem.solvers.static import StaticSolver, paths

    solver = StaticSolver(model, settings)
    taken: list = []

    class HandOver(Exception):
        pass

    def stop(solver_, hist, record, first_failure):
        taken.extend((solver_.snapshot(), hist, first_failure))
        raise HandOver

    work_control, paths.work_control = paths.work_control, stop
    try:
        solver.run()
    except HandOver:
        pass
    finally:
        paths.work_control = work_control
    if not taken:
        print("  load control never handed over")
        return
    state, hist, why = taken
    p = solver.problem
    free = p.asm.free_index
    c = p.F_live / float(np.linalg.norm(p.F_live))
    w = [float(c @ st.q.reshape(-1)[free]) for st in hist.steps]
    lam = [float(st.load_factor) for st in hist.steps]
    solver.resume(state)
    _, _, response = solver.residual(solver.q, solver.load_factor)
    slope = 1.0 / float(c @ p.factor(response).solve(p.F_live))
    first = w[-1] - w[-2]
    print(
        f"  hand-over at lambda {lam[-1]:.6g} ({why}); d lambda / d w: tangent {slope:.4g}, "
        f"last load step {(lam[-1] - lam[-2]) / first:.4g}, first load step "
        f"{(lam[1] - lam[0]) / (w[1] - w[0]):.4g}; first work step {first:.4g} m"
    )
    print("  step [m]     " + "".join(f"{s:<28s}" for s in ("secant", "state", "tangent")))
    for halvings in range(6):
        dw = first / 2**halvings
        cells = []
        for start in ("secant", "state", "tangent"):
            solver.resume(state)
            out, its, fs = _work_search(solver, hist, len(hist.steps) - 1, dw, start)
            cells.append(
                f"{'y' if out.ok else 'n'} {its:3d} it {fs:3d} f l={out.load_factor:.5f}  "
            )
        print(f"  {dw:.3e}    " + "".join(cells))
    sys.stdout.flush()


_STATE = ("q", "plastic", "cracked", "last_increment", "_limit_allowance")


def _copy(value):
    return value.copy() if isinstance(value, np.ndarray) else value


def recorded_searches(model, settings, monitor=None) -> tuple[object, list]:
    """The pushover with ``settings`` and every Newton search (``equilibrate``) of it: (the
    history, [(args, kwargs, the solver's state before the search, converged?)])."""
    from masonry_dem.solvers.static import StaticSolver

    solver = StaticSolver(model, settings)
    plain = solver.equilibrate
    calls = []

    def recording(*args, **kwargs):
        state = {k: _copy(getattr(solver, k)) for k in _STATE}
        out = plain(*args, **kwargs)
        calls.append((args, kwargs, state, out.ok))
        return out

    solver.equilibrate = recording
    hist = solver.run(monitor=monitor)
    return hist, calls


def restore_state(solver, state: dict) -> None:
    """Put ``solver`` back in a state :func:`recorded_searches` recorded."""
    for k, v in state.items():
        setattr(solver, k, _copy(v))


def replay(model, settings, other, monitor=None) -> dict:
    """Every Newton search (``equilibrate``) of the pushover with ``settings``, recorded with
    the solver's state before it, then run again from that state with ``settings`` (the
    replay must give the same outcome: ``mismatches`` counts where it does not) and with
    ``other``. The path is the first run's for both, so the counts compare the correctors
    from the same states, searches and trust radii, whatever path each would have taken.
    Returns, for each: searches converged, factorizations and iterations (over all
    searches, and over those both converge), and the searches only one converges."""
    from masonry_dem.solvers.static import StaticSolver

    _, calls = recorded_searches(model, settings, monitor)
    runs = {}
    for label, chosen in (("this", settings), ("other", other)):
        again = StaticSolver(model, chosen)
        again.run(monitor=monitor)  # the scales and limits of the path
        outcomes = []
        for args, kwargs, state, _ in calls:
            restore_state(again, state)
            it, f = again.iterations, again.factorizations
            out = again.equilibrate(*args, **kwargs)
            stop = 0.0 if out.ok else again.residual(out.q, out.load_factor)[1]
            outcomes.append((out.ok, again.iterations - it, again.factorizations - f, stop))
        runs[label] = outcomes
    this, that = runs["this"], runs["other"]
    both = [i for i in range(len(calls)) if this[i][0] and that[i][0]]
    return {
        "searches": len(calls),
        "mismatches": sum(this[i][0] != calls[i][3] for i in range(len(calls))),
        **{
            f"{label}_{key}": value
            for label, rs in runs.items()
            for key, value in (
                ("converged", sum(r[0] for r in rs)),
                ("factorizations", sum(r[2] for r in rs)),
                ("iterations", sum(r[1] for r in rs)),
                ("factorizations_both", sum(rs[i][2] for i in both)),
                ("failed_factorizations", sum(r[2] for r in rs if not r[0])),
                # where the failed searches stop: far from an equilibrium, or at a kink
                ("failed_stop_median", float(np.median([r[3] for r in rs if not r[0]] or [0]))),
            )
        },
        "both": len(both),
        "only_this": sum(a[0] and not b[0] for a, b in zip(this, that, strict=True)),
        "only_other": sum(b[0] and not a[0] for a, b in zip(this, that, strict=True)),
    }


def _misses(r: dict) -> str:
    """The work searches of a run and how far their starts were from where they converged."""
    quart = "/".join(f"{x:.3g}" for x in r["miss"]) or "-"
    return (
        f"work searches {r['work_ok']} converged, {r['work_failed']} failed; the predictor's "
        f"miss over the step (quartiles) {quart}"
    )


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scale", type=int, action="append", default=[], help="scale_wall(N)")
    p.add_argument("--case", action="append", default=[], help="a validation case")
    p.add_argument("--cases", action="store_true", help="all 18 validation cases")
    p.add_argument(
        "--return-blocks",
        type=int,
        action="append",
        default=[],
        metavar="B",
        help="the cases with return walls of B blocks (with --cases: the 7 of Table 2)",
    )
    p.add_argument("--u-wall", action="append", default=[], metavar="SIZE", help="S5 or big")
    p.add_argument("--flat-wall", action="append", default=[], metavar="SIZE", help="S5 or big")
    p.add_argument("--brief", action="store_true", help="one line a wall, and the totals")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--against", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--repeat", type=int, default=1, help="runs of each, in turn (--against)")
    p.add_argument("--rows", action="store_true", help="print every search")
    p.add_argument("--states", action="store_true", help="joints whose state changed, step by step")
    p.add_argument("--events", action="store_true", help="with --rows: predicted joint events")
    p.add_argument("--reach", type=float, nargs="+", default=[], metavar="M")
    p.add_argument("--hand-over", action="store_true", help="the first work steps, three starts")
    p.add_argument(
        "--transients", action="store_true", help="each pseudo-transient step's residual"
    )
    p.add_argument(
        "--replay",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="each search of the path again from its state, as it was and with this change",
    )
    p.add_argument(
        "--misses",
        action="store_true",
        help="work searches converged/failed and the quartiles of the predictor's miss",
    )
    p.add_argument("--json", default=None)
    a = p.parse_args()

    from bench_scale import scale_wall
    from bench_validation import parse_settings
    from bench_walls_that_meet import SIZES, build
    from bench_walls_that_meet import walls as meeting_walls

    from masonry_dem.cases.paper import RETURN_WALL_CASES, build_case, case_names
    from masonry_dem.solvers.static import StaticSettings

    changes = parse_settings(a.set)
    other = parse_settings(a.against)
    walls = [(f"scale_wall({n})", scale_wall(n), StaticSettings(), None) for n in a.scale]
    parts: dict[str, np.ndarray] = {}  # per wall, the joints counted apart (--states)
    for kind, sizes in (("U", a.u_wall), ("flat", a.flat_wall)):
        for size in sizes:
            if size not in SIZES:
                p.error(f"--{kind.lower()}-wall {size!r}: the sizes are {', '.join(SIZES)}")
            u, flat = meeting_walls(size)
            model = build(u, held=False)[0] if kind == "U" else build(flat, held=True)[0]
            walls.append((f"{kind} wall {size}", model, StaticSettings(), None))
            if kind == "U":  # the returns: blocks whose centre is behind the facade's
                z = model.blocks.centres[:, 2]
                behind = z < 0.5 * z.max()
                parts[walls[-1][0]] = (
                    behind[model.interfaces.block_i] | behind[model.interfaces.block_j]
                )
    for blocks in a.return_blocks or [None]:
        names = (RETURN_WALL_CASES if blocks else case_names()) if a.cases else a.case
        for name in names:
            if blocks is None:
                case = build_case(name)
            else:
                case = build_case(name, restraint="return-walls", return_blocks=blocks)
            label = name if blocks is None else f"{name}/{blocks}"
            walls.append((label, case.model, case.settings, case.monitor))
    results = {}
    replayed = parse_settings(a.replay)
    totals: Counter = Counter()
    for label, model, settings, monitor in walls:
        settings = replace(settings, **changes) if changes else settings
        if replayed:
            rp = replay(model, settings, replace(settings, **replayed), monitor)
            totals.update({k: v for k, v in rp.items() if not k.endswith("_median")})
            print(
                f"{label}: {rp['searches']} searches replayed ({rp['mismatches']} mismatches); "
                f"converged {rp['this_converged']} -> {rp['other_converged']} (only this "
                f"{rp['only_this']}, only {' '.join(a.replay)} {rp['only_other']}); "
                f"factorizations {rp['this_factorizations']} -> {rp['other_factorizations']} "
                f"(failed searches {rp['this_failed_factorizations']} -> "
                f"{rp['other_failed_factorizations']}; the {rp['both']} both converge "
                f"{rp['this_factorizations_both']} -> {rp['other_factorizations_both']}); "
                f"iterations {rp['this_iterations']} -> {rp['other_iterations']}; failed "
                f"searches stop at a residual of {rp['this_failed_stop_median']:.2g} -> "
                f"{rp['other_failed_stop_median']:.2g} (median)",
                flush=True,
            )
            continue
        if a.hand_over:
            print(f"{label}:")
            hand_over(model, settings)
        r = audit(model, settings, monitor, parts.get(label), a.events, bool(a.reach), a.transients)
        if other:
            b = audit(model, replace(settings, **other), monitor)
            for _ in range(a.repeat - 1):  # in turn, so both see the same machine
                for kept, again in ((r, settings), (b, replace(settings, **other))):
                    more = audit(model, again, monitor)
                    kept["seconds"] = min(kept["seconds"], more["seconds"])
                    kept["cpu"] = min(kept["cpu"], more["cpu"])
            results[f"{label} against"] = b
        results[label] = r
        print(
            f"{label}: {r['status']} lambda={r['lambda']:.7g} steps={r['steps']} "
            f"iterations={r['iterations']} factorizations={r['factorizations']} "
            f"(other {r['other']}) time_steps={r['time_steps']} implicit={r['implicit_steps']} "
            f"{r['seconds']:.1f} s ({r['cpu']:.1f} s of CPU)"
        )
        if a.misses:
            print(f"{label}: " + _misses(r))
        if other:
            print(
                f"{label}, {' '.join(a.against)}: {b['status']} lambda={b['lambda']:.7g} "
                f"steps={b['steps']} iterations={b['iterations']} "
                f"factorizations={b['factorizations']} time_steps={b['time_steps']} "
                f"implicit={b['implicit_steps']} "
                f"{b['seconds']:.1f} s "
                f"({b['cpu']:.1f} s of CPU)"
            )
            if a.misses:
                print(f"{label}, {' '.join(a.against)}: " + _misses(b))
            print(
                f"{label}, this over that: seconds {r['seconds'] / b['seconds']:.2f}x "
                f"(CPU {r['cpu'] / b['cpu']:.2f}x), "
                f"factorizations {r['factorizations'] / b['factorizations']:.2f}x, "
                f"iterations {r['iterations'] / b['iterations']:.2f}x, "
                f"lambda {r['lambda'] / b['lambda'] - 1:+.3%}"
            )
        if a.transients:
            for row in r["rows"]:
                if "stretch" in row:
                    print(
                        f"  pseudo-transient to {row['asked']:.6g}: "
                        f"{'rest' if row['ok'] else row['why']} after "
                        f"{row['iterations']} time steps; longest run without halving the "
                        f"residual {row['stretch']}, largest residual {row['rise']:.3g}x the start's"
                    )
        if a.reach:
            reach(r, a.reach)
            for key in ("solver", "hist", "snapshots"):
                del r[key]
        if a.brief:
            continue
        kinds = sorted({k.split("/")[0] for k in r["by"]})
        print("  controller  | converged: n, iterations, factorizations | failed: n, it, f")
        for kind in kinds:
            ok = [r["by"].get(f"{kind}/ok/{x}", 0) for x in "nif"]
            bad = [r["by"].get(f"{kind}/failed/{x}", 0) for x in "nif"]
            print(
                f"  {kind:11s} | {ok[0]:5d} {ok[1]:6d} {ok[2]:6d} | {bad[0]:5d} {bad[1]:6d} {bad[2]:6d}"
            )
        if a.states:
            part = label in parts
            print("  step  lambda     it  changed" + ("  of them in the returns" if part else ""))
            for st in r["states"]:
                print(
                    f"  {st['step']:4d}  {st['lambda']:.5f} {st['iterations']:3d} "
                    f"{st['changed']:7d}" + (f"  {st['in_part']:7d}" if part else "")
                )
            if part:
                n = int(parts[label].sum())
                print(
                    f"  joints: {len(parts[label])}, {n} of them touch a return; changes: "
                    f"{sum(st['changed'] for st in r['states'])}, "
                    f"{sum(st['in_part'] for st in r['states'])} of them in the returns"
                )
        if a.rows:
            head = "    #  kind       lambda      w [m]        asked   it  f  ok"
            print(head + ("  events crossed next" if a.events else "") + "  why")
            for i, row in enumerate(r["rows"]):
                predicted = (
                    f" {row['events']:7d} {row['crossed']:7d} {row['next']:5.3f}"
                    if "events" in row
                    else " " * 21 * a.events
                )
                print(
                    f"  {i:3d}  {row['kind']:9s} {row['lambda']:.7f} {row['w']:10.4g} "
                    f"{row['asked']:11.4g} "
                    f"{row['iterations']:4d} {row['factorizations']:2d}  "
                    f"{'y' if row['ok'] else 'n'} {predicted}  {row['why']}"
                )
        sys.stdout.flush()
    if replayed and len(walls) > 1:
        print("total replayed: " + ", ".join(f"{k} {v}" for k, v in totals.items()))
    mine = [r for k, r in results.items() if not k.endswith(" against")]
    if len(mine) > 1:
        total = {k: sum(r[k] for r in mine) for k in ("steps", "iterations", "time_steps")}
        f = sum(r["factorizations"] for r in mine)
        print(
            f"total: {len(mine)} walls, steps={total['steps']} "
            f"iterations={total['iterations']} factorizations={f} "
            f"time_steps={total['time_steps']}"
        )
        theirs = [r for k, r in results.items() if k.endswith(" against")]
        if theirs:
            t = {
                k: sum(r[k] for r in theirs)
                for k in ("steps", "iterations", "factorizations", "time_steps", "cpu")
            }
            print(
                f"total, {' '.join(a.against)}: steps={t['steps']} "
                f"iterations={t['iterations']} factorizations={t['factorizations']} "
                f"time_steps={t['time_steps']}; CPU this over that "
                f"{sum(r['cpu'] for r in mine) / t['cpu']:.2f}x"
            )
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
