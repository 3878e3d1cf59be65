"""Why a Newton search of work control fails: the joints at the kinks of the law where it stops.

    python benchmarks/newton_basin.py [--u-wall S5] [--flat-wall S5] [--case S11 ...]
        [--return-blocks B] [--set NAME=VALUE] [--searches] [--json FILE]

Each wall runs the default static pushover with every Newton search of work control recorded
with the solver's state before it (as ``path_audit.py --replay`` does). Every failed search
is then run again from its state with the factorizations it takes recorded (the joints' flags
at each factorized iterate), and taken apart at the state where it stopped:

* **The direction at the stop.** The tangent of the stop state is factorized and the
  controlled Newton direction (dq, d lambda) solved as ``Corrector.equilibrate`` solves it.
  Along it the merit (residual plus the control's error) is evaluated at t = 8^-k of the
  full step, k = 0 .. 10, and for each t the joints whose law flags differ from the stop
  state's are counted. A joint whose flags change at t = 8^-10 (1e-9 of the correction)
  sits on a kink of the law along that direction (``at a kink``).
* **Which joints keep the merit from falling.** At the smallest t whose merit does not
  fall, each joint's miss, a(q + t dq) - a(q) - T t du (its actions against the tangent's
  prediction), pushed to the DOFs of its two blocks and measured in the residual's norm.
  The joints that make up 90 % of the summed miss are the culprits (``culprits``; at the
  shortest steps this takes in round-off of joints that change no flag), those with a
  quarter of it or more the top culprits (``top``).
* **The correction at the stop.** Its largest translation over the step asked for (the
  control's), the blocks that move at least a tenth of it, and its largest rotation x the
  median block size over its largest translation.
* **Cycling of the active set.** Joints whose flags at factorized iterates k and k + 2 agree
  and differ from those at k + 1 (an A -> B -> A flip).

Each joint at a kink or among the culprits is classed by the kink it sits on (the flag bits
that change over the smallest step: ``open`` the detachment bit, ``rock`` a rocking bit,
``slide`` the shear-torsion bit; ``enter`` from elastic into a yielded state, ``leave``
back, ``swap`` as many bits either way; ``none:same`` no bit), by whether its trial normal
force is zero within the law's contact band (``band``), or small (under 1e-3 of the median
compression of the bed joints), by where it is (``facade``, ``return:left``/``right``,
``corner:left``/``right`` of :func:`masonry_dem.geometry.selectors.part`, ``base:...`` for
the joints on the base slab; ``flat`` for a wall that has no such parts) and by its kind
(``bed``: normal along e2; ``head:e1``: a vertical joint with its normal along e1, the
facade's head joints; ``head:e3``: normal along e3, the returns' head joints and the joints
where the facade's end blocks meet the returns). The counts of each class over all failed
searches are printed for each wall; ``--searches`` also prints one line per failed search,
its top culprits and, where 6 blocks or fewer carry its correction, those blocks (part,
course, the flags of their joints). Used in docs/history/solvers_record.md, "Newton's basin on
walls that meet".
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import sparse

sys.path.insert(0, str(Path(__file__).resolve().parent))

from path_audit import recorded_searches, restore_state  # noqa: E402

STEPS = [8.0**-k for k in range(11)]


def joint_places(model, u_wall: bool) -> tuple[np.ndarray, np.ndarray]:
    """(m,) where each joint is and (m,) its kind (see the module docstring)."""
    from masonry_dem.geometry import selectors as sel

    blocks = model.blocks
    its = model.interfaces
    nb = blocks.count
    fixed = model.fixed.all(axis=1)
    label = np.array(["flat"] * nb, dtype=object)
    if u_wall:
        among = np.flatnonzero(~fixed)
        for name in ("facade", "return:left", "return:right", "corner:left", "corner:right"):
            try:
                label[sel.part(blocks, name, among=among)] = name
            except ValueError:
                pass
    label[fixed] = "base"
    li, lj = label[its.block_i], label[its.block_j]
    place = np.where(li == "base", lj, li)
    place = np.where((li == "base") | (lj == "base"), "base:" + place.astype(str), place)
    corner = np.char.startswith(li.astype(str), "corner") | np.char.startswith(
        lj.astype(str), "corner"
    )
    place = np.where(
        corner & ~((li == "base") | (lj == "base")),
        np.where(np.char.startswith(li.astype(str), "corner"), li, lj),
        place,
    )
    vertical = 1  # the wall's courses stack along e2
    kind = np.where(its.axis == vertical, "bed", np.where(its.axis == 0, "head:e1", "head:e3"))
    return place.astype(str), kind.astype(str), label.astype(str)


def flag_change(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """(m,) the kink each joint crossed: 'open', 'rock', 'slide' (the bits that changed, the
    first of them in that order) with 'enter' or 'leave' (more or fewer bits set)."""
    from masonry_dem.constitutive.states import (
        FLAG_DETACHED,
        FLAG_ROCKING_1,
        FLAG_ROCKING_2,
    )

    diff = before ^ after
    name = np.where(
        diff & FLAG_DETACHED,
        "open",
        np.where(diff & (FLAG_ROCKING_1 | FLAG_ROCKING_2), "rock", "slide"),
    )
    way = np.where(np.bitwise_count(after) > np.bitwise_count(before), "enter", "leave")
    same_count = np.bitwise_count(after) == np.bitwise_count(before)
    way = np.where(same_count, "swap", way)
    name = np.where(diff == 0, "none", name)
    way = np.where(diff == 0, "same", way)
    return np.char.add(np.char.add(name.astype(str), ":"), way.astype(str))


def take_apart(solver, out, control, lam0: float) -> dict:
    """The stop state of a failed controlled search: the merit along its Newton direction,
    the joints whose flags change at each fraction of it, the culprits of the smallest step
    that does not lower the merit (indices and misses)."""
    p = solver.problem
    free = p.asm.free_index
    q, lam, response = out.q, float(out.load_factor), out.response
    residual, rnorm, _ = solver.residual(q, lam)
    counted = p.factorizations
    T = p.joint_tangents(response)
    lu = p.factor(response)
    p.factorizations = counted
    c, goal, size = control

    def cerr(qq):
        return abs(float(c @ qq[free]) - goal) / max(size, 1e-300)

    merit = rnorm + cerr(q)
    dq = lu.solve(residual)
    a = lu.solve(p.F_live)
    dlam = (goal - float(c @ q[free]) - float(c @ dq)) / float(c @ a)
    dq = dq + dlam * a
    du = p.relative(dq)
    scan = []
    smallest_rise = None
    rt = response
    for t in STEPS:
        qt = q.copy()
        qt[free] += t * dq
        _, nt, rt = solver.residual(qt, lam + t * dlam)
        trial = nt + cerr(qt)
        changed = np.flatnonzero(rt.flags != response.flags)
        scan.append((t, trial / merit, int(changed.size)))
        if trial >= (1.0 - 1e-4 * t) * merit:
            smallest_rise = (t, rt, changed)
    # the full correction against the step asked for, and the blocks that carry it
    move = np.zeros_like(q)
    move[free] = dq
    per_block = np.abs(move.reshape(-1, 6)[:, :3]).max(axis=1)
    length = float(np.median(p.model.blocks.sizes))
    turned = float(np.abs(move.reshape(-1, 6)[:, 3:]).max()) * length
    out_d = {
        "merit": merit,
        "scan": scan,
        "dlam": dlam,
        "size": float(per_block.max()) / max(size, 1e-300),
        "turn": turned / max(float(per_block.max()), 1e-300),
        "movers": np.flatnonzero(per_block >= 0.1 * per_block.max()),
    }
    at_kink = np.flatnonzero(rt.flags != response.flags)  # rt: at the smallest step
    out_d["at_kink"] = at_kink
    out_d["kink_change"] = flag_change(response.flags[at_kink], rt.flags[at_kink])
    if smallest_rise is not None:
        t, rt, changed = smallest_rise
        miss = rt.actions - response.actions - t * np.einsum("ijk,ik->ij", T, du)
        # each joint's miss on the DOFs of its blocks, in the residual's weighted norm
        m = miss.shape[0]
        # the miss of each joint on the DOFs of its blocks, in the residual's weighted norm
        summing = sparse.csc_matrix(
            (np.ones(6 * m), (np.arange(6 * m), np.repeat(np.arange(m), 6))), shape=(6 * m, m)
        )
        pushed = sparse.csr_matrix(p.asm.H_free_T.multiply(miss.reshape(1, -1))) @ summing
        pushed = sparse.csr_matrix(pushed.multiply(p.weight[:, None]))
        per_joint = np.sqrt(np.asarray(pushed.multiply(pushed).sum(axis=0)).ravel())
        per_joint /= p._external(lam, 1.0)[1]
        order = np.argsort(per_joint)[::-1]
        total = per_joint.sum()
        kept = np.searchsorted(np.cumsum(per_joint[order]), 0.9 * total) + 1
        culprits = order[: min(kept, m)] if total > 0 else order[:0]
        out_d.update(
            t_rise=t,
            share=per_joint[order[:3]] / max(total, 1e-300),
            culprits=culprits,
            culprit_change=flag_change(response.flags[culprits], rt.flags[culprits]),
            culprit_changed=np.isin(culprits, changed),
        )
    return out_d


def normal_class(trial: np.ndarray, rows: np.ndarray, bed: np.ndarray) -> np.ndarray:
    """'band' (trial normal force within the law's contact band of zero), 'small' (under 1e-3
    of the median compression of the bed joints), 'tension' or 'compressed'."""
    from masonry_dem.constitutive.law import CONTACT_BAND

    fn = trial[:, 2]
    largest = np.abs(fn).max()
    comp = -fn[bed & (fn < 0)]
    median = float(np.median(comp)) if comp.size else largest
    f = fn[rows]
    return np.where(
        np.abs(f) <= CONTACT_BAND * largest,
        "band",
        np.where(np.abs(f) < 1e-3 * median, "small", np.where(f > 0, "tension", "compressed")),
    )


def diagnose(model, settings, monitor, u_wall: bool, verbose: bool) -> dict:
    from masonry_dem.solvers.static import StaticSolver

    hist, calls = recorded_searches(model, settings, monitor)
    place, kind, block_label = joint_places(model, u_wall)
    again = StaticSolver(model, settings)
    again.run(monitor=monitor)  # the scales and limits of the path
    flags_seen: list[np.ndarray] = []
    factor = again.problem.factor

    def recording_factor(response, floor=None):
        flags_seen.append(response.flags.copy())
        return factor(response, floor)

    again.problem.factor = recording_factor
    counts: dict[str, Counter] = {
        "at_kink": Counter(),
        "culprit": Counter(),
        "cycling": Counter(),
        "why": Counter(),
        "size": Counter(),
        "movers": Counter(),
        "top": Counter(),
    }
    searches = {"work": 0, "failed": 0, "mismatches": 0}
    scans = []
    for args, kwargs, state, ok in calls:
        control = kwargs.get("control")
        if control is None:
            continue
        searches["work"] += 1
        if ok:
            continue
        restore_state(again, state)
        flags_seen.clear()
        out = again.equilibrate(*args, **kwargs)
        searches["mismatches"] += int(out.ok != ok)
        searches["failed"] += 1
        counts["why"][str(out.failure.value)] += 1
        seen = np.array(flags_seen)
        cyc = np.zeros(model.interfaces.count, bool)
        if len(seen) >= 3:
            cyc = np.any((seen[2:] == seen[:-2]) & (seen[1:-1] != seen[:-2]), axis=0)
        for i in np.flatnonzero(cyc):
            counts["cycling"][(place[i], kind[i])] += 1
        d = take_apart(again, out, control, float(args[0]) if args else 0.0)
        bed = kind == "bed"
        for rows, key, change in (
            (d["at_kink"], "at_kink", d["kink_change"]),
            (d.get("culprits", np.zeros(0, int)), "culprit", d.get("culprit_change", [])),
        ):
            normal = normal_class(out.response.trial, rows, bed)
            for i, ch, nc in zip(rows, change, normal, strict=True):
                counts[key][(place[i], kind[i], ch, nc)] += 1
        scans.append(d["scan"])
        counts["size"][f"1e{int(np.floor(np.log10(max(d['size'], 1e-300))))}"] += 1
        for b in d["movers"]:
            counts["movers"][block_label[b]] += 1
        for i, ch, sh in zip(
            d.get("culprits", [])[:3],
            d.get("culprit_change", [])[:3],
            d.get("share", []),
            strict=False,
        ):
            if sh >= 0.25:
                nc = normal_class(out.response.trial, np.array([i]), bed)[0]
                counts["top"][(place[i], kind[i], ch, nc)] += 1
        if verbose and d.get("culprits") is not None and len(d["culprits"]):
            util = again.law.utilisation(out.response)
            fn = out.response.trial[:, 2]
            med = float(np.median(-fn[bed & (fn < 0)]))
            for i, ch, sh in zip(
                d["culprits"][:3], d["culprit_change"][:3], d["share"], strict=False
            ):
                print(
                    f"    joint {i} {place[i]} {kind[i]} flags {out.response.flags[i]} {ch} "
                    f"share {sh:.2f} fn/median {fn[i] / med:+.3g} utilisation {util[i]:.9f}"
                    f" trial {np.array2string(out.response.trial[i], precision=3)}"
                )
        if verbose and len(d["movers"]) <= 6:
            blocks = model.blocks
            levels = np.unique(np.round(blocks.centres[:, 1], 9))
            for b in d["movers"]:
                course = int(np.searchsorted(levels, round(blocks.centres[b, 1], 9)))
                joints = np.flatnonzero(
                    (model.interfaces.block_i == b) | (model.interfaces.block_j == b)
                )
                print(
                    f"    moving block {b} {block_label[b]} course {course} of "
                    f"{levels.size - 1} centre {np.round(blocks.centres[b], 3)}; its joints' "
                    "flags " + " ".join(f"{kind[j]}:{out.response.flags[j]}" for j in joints)
                )
        if verbose:
            first = next((t for t, r, _ in d["scan"] if r < 1.0), None)
            print(
                f"  lambda {out.load_factor:.6f} {out.failure.value}: merit {d['merit']:.2e}, "
                f"ratio at t=1 {d['scan'][0][1]:.3g}, at 8^-10 {d['scan'][-1][1]:.6f}, "
                f"first t that lowers it {first}; joints at a kink {len(d['at_kink'])}, "
                f"culprits {len(d.get('culprits', []))} (t={d.get('t_rise')}), "
                f"cycling {int(cyc.sum())}, factorizations {len(seen)}, correction over the "
                f"step {d['size']:.3g}, moving blocks {len(d['movers'])}, its largest rotation x "
                f"the median block size over its largest translation {d['turn']:.3g}",
                flush=True,
            )
    return {
        "status": str(hist.status),
        "lambda": float(hist.collapse_multiplier or hist.final_load_factor),
        "searches": searches,
        "counts": counts,
        "scans": scans,
    }


def show(label: str, r: dict) -> None:
    s = r["searches"]
    print(
        f"{label}: {r['status']} lambda={r['lambda']:.7g}; work searches {s['work']}, failed "
        f"{s['failed']} ({s['mismatches']} mismatches on replay): "
        + ", ".join(f"{k} {v}" for k, v in r["counts"]["why"].items())
    )
    lowers = Counter()
    for scan in r["scans"]:
        first = next((k for k, (_, ratio, _) in enumerate(scan) if ratio < 1.0), None)
        lowers["none" if first is None else f"8^-{first}"] += 1
    print(
        "  first step along the stop's Newton direction that lowers the merit: "
        + ", ".join(f"{k} {v}" for k, v in sorted(lowers.items()))
    )
    print(
        "  the stop's full Newton correction over the step asked for (largest translation "
        "over the control's step): "
        + ", ".join(f"{k} {v}" for k, v in sorted(r["counts"]["size"].items()))
    )
    print(
        "  blocks that carry it (translation at least 0.1 of the largest), by part: "
        + ", ".join(f"{k} {v}" for k, v in r["counts"]["movers"].most_common())
    )
    for key, title in (
        ("top", "top culprits (a share of the miss of 0.25 or more)"),
        ("at_kink", "joints at a kink (flags change at 8^-10 of the step)"),
        ("culprit", "culprits (90 % of the miss at the smallest step that does not lower it)"),
    ):
        c = r["counts"][key]
        print(f"  {title}: {sum(c.values())}")
        for dim, name in ((0, "where"), (1, "kind"), (2, "kink"), (3, "normal force")):
            by = Counter()
            for k, v in c.items():
                by[k[dim]] += v
            print(f"    by {name}: " + ", ".join(f"{k} {v}" for k, v in by.most_common()))
        for k, v in c.most_common(8):
            print(f"    {v:5d}  {' '.join(k)}")
    cyc = r["counts"]["cycling"]
    print(f"  cycling joints (A -> B -> A between factorized iterates): {sum(cyc.values())}")
    for k, v in cyc.most_common(6):
        print(f"    {v:5d}  {' '.join(k)}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--u-wall", action="append", default=[], metavar="SIZE")
    ap.add_argument("--flat-wall", action="append", default=[], metavar="SIZE")
    ap.add_argument("--case", action="append", default=[])
    ap.add_argument("--return-blocks", type=int, default=None)
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--searches", action="store_true", help="one line per failed search")
    ap.add_argument("--json", default=None)
    a = ap.parse_args()

    from bench_validation import parse_settings
    from bench_walls_that_meet import build
    from bench_walls_that_meet import walls as meeting_walls

    from masonry_dem.cases.paper import build_case
    from masonry_dem.solvers.static import StaticSettings

    changes = parse_settings(a.set)
    walls = []
    for kind, sizes in (("U", a.u_wall), ("flat", a.flat_wall)):
        for size in sizes:
            u, flat = meeting_walls(size)
            model = build(u, held=False)[0] if kind == "U" else build(flat, held=True)[0]
            walls.append((f"{kind} wall {size}", model, StaticSettings(), None, kind == "U"))
    for name in a.case:
        if a.return_blocks:
            case = build_case(name, restraint="return-walls", return_blocks=a.return_blocks)
            label = f"{name}/{a.return_blocks}"
        else:
            case = build_case(name)
            label = name
        walls.append((label, case.model, case.settings, case.monitor, bool(a.return_blocks)))
    results = {}
    for label, model, settings, monitor, u in walls:
        settings = replace(settings, **changes) if changes else settings
        if a.searches:
            print(f"{label}:")
        r = diagnose(model, settings, monitor, u, a.searches)
        show(label, r)
        sys.stdout.flush()
        results[label] = {
            "searches": r["searches"],
            "counts": {
                k: {
                    " ".join(map(str, kk)) if isinstance(kk, tuple) else kk: v
                    for kk, v in c.items()
                }
                for k, c in r["counts"].items()
            },
        }
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
