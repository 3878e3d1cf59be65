"""The peer wall of issue 18: the package against LMGC90 and an associative rigid-block LP.

    python benchmarks/bench_peer_wall.py                      # package, LP, peers if present
    python benchmarks/bench_peer_wall.py --no-peers           # package and LP only
    python benchmarks/bench_peer_wall.py --dr                 # dynamic relaxation as well
    python benchmarks/bench_peer_wall.py --mechanism --no-peers   # the two collapse modes
    python benchmarks/bench_peer_wall.py --pieces --no-peers      # lambda against pieces
    python benchmarks/bench_peer_wall.py --stiffness --no-peers   # whole joints, kn and kt
    python benchmarks/bench_peer_wall.py --validation --no-peers  # Tables 1-3 in pieces
    python benchmarks/bench_peer_wall.py --peer-python /work/peer-venv/bin/python

The wall: 5 x 6 running bond of 0.4 x 0.2 x 0.2 m blocks (half blocks at both ends of every
other course), friction 0.6, 2000 kg/m3, on a fixed rigid slab, a lateral acceleration
lambda g in the plane of the wall on every block. It prints lambda and the seconds of:

* the package, one interface per joint (the paper's law: a rocking joint turns about its
  centre) and with every joint cut into pieces (``subdivide_interfaces``: it turns about its
  compressed edge, as a rigid dry joint does); the static solver, and with ``--dr`` dynamic
  relaxation;
* an associative rigid-block LP on the same geometry (forces at the four corners of every
  joint, |t| <= mu n, scipy's HiGHS): the associative collapse multiplier, an upper bound of
  the non-associative one;
* LMGC90 through compas_lmgc90 (contact dynamics, 4 corner contacts per face, Coulomb
  friction): gravity for 0.5 s, then the lateral acceleration held for 2 s; collapse when a
  block has moved a quarter of its smallest side (0.05 m); lambda bisected to 0.005. It runs
  in another Python (``--peer-python``, default /work/peer-venv/bin/python, or
  $PEER_PYTHON) as a subprocess of this script, only when compas_lmgc90 imports there;
  otherwise it says so and goes on. This script installs nothing.

compas_cra (CRA and RBE) needs an IPOPT executable for pyomo; when none is found the script
prints the figures issue 18 reports for it instead of running it. See docs/peer_wall.md.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from _machine import arguments, print_machine

N_ALONG, COURSES = 5, 6
B, A, S = 0.4, 0.2, 0.2  # block length (e1), height (e2), thickness (e3) [m]
DENSITY, G, FRICTION = 2000.0, 9.81, 0.6
LMGC90_REPORTED = (0.575, 0.580)
CRA_REPORTED = "equilibrium at 0.583, none at 0.589 (issue 18)"
DEFAULT_PEER_PYTHON = "/work/peer-venv/bin/python"


# ------------------------------------------------------------------ the package side
def package_model(pieces=(1, 1)):
    """The peer wall as a masonry_dem Model, every interface cut into ``pieces``."""
    import masonry_dem as md

    wall = md.running_bond_wall(N_ALONG, COURSES, a=A, b=B, s=S, unit_weight=DENSITY * G)
    blocks, base = md.add_base(wall)
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=FRICTION),
        [md.Support([base])],
        [md.SelfWeight(), md.WeightProportional(direction=(1.0, 0.0, 0.0))],
        interfaces=md.subdivide_interfaces(md.detect_interfaces(blocks), *pieces),
        name=f"peer wall, joints in {pieces[0]} x {pieces[1]}",
    )


def in_plane_pieces(interfaces, k: int):
    """Every joint cut into ``k`` pieces along its side in the plane of the wall (e1 for bed
    joints, e2 for head joints), none across the thickness."""
    import masonry_dem as md
    from masonry_dem.geometry.interfaces import Interfaces

    bed = md.subdivide_interfaces(interfaces.subset(np.flatnonzero(interfaces.axis == 1)), 1, k)
    head = md.subdivide_interfaces(interfaces.subset(np.flatnonzero(interfaces.axis == 0)), k, 1)
    return Interfaces(
        *(
            np.concatenate([getattr(bed, f), getattr(head, f)])
            for f in Interfaces.__dataclass_fields__
        )
    )


def print_pieces_sweep() -> None:
    """lambda against the number of pieces along the in-plane side, for two ratios kt/kn."""
    import masonry_dem as md
    from masonry_dem.solvers.incremental import pushover

    wall = md.running_bond_wall(N_ALONG, COURSES, a=A, b=B, s=S, unit_weight=DENSITY * G)
    blocks, base = md.add_base(wall)
    print(f"{'pieces':>6} {'kt/kn':>6} {'lambda':>8} {'seconds':>8}  status")
    for k in (1, 2, 3, 4, 5, 6, 8, 12):
        for ratio in (0.4, 0.1):
            model = md.Model.build(
                blocks,
                md.InterfaceMaterial(kn=1e9, kt=ratio * 1e9, friction=FRICTION),
                [md.Support([base])],
                [md.SelfWeight(), md.WeightProportional(direction=(1.0, 0.0, 0.0))],
                interfaces=in_plane_pieces(md.detect_interfaces(blocks), k),
            )
            t0 = time.perf_counter()
            history = pushover(model)
            seconds = time.perf_counter() - t0
            lam = history.collapse_multiplier
            value = "-" if lam is None else f"{lam:.4f}"
            print(f"{k:6d} {ratio:6.1f} {value:>8} {seconds:8.2f}  {history.status}")


def print_stiffness_sweep() -> None:
    """lambda with whole joints for joint stiffnesses over four decades of kt/kn."""
    import masonry_dem as md
    from masonry_dem.solvers.incremental import pushover

    wall = md.running_bond_wall(N_ALONG, COURSES, a=A, b=B, s=S, unit_weight=DENSITY * G)
    blocks, base = md.add_base(wall)
    print(f"{'kn':>8} {'kt':>8} {'lambda':>12}  status")
    for kn, kt in ((1e9, 1e7), (1e9, 1e8), (1e9, 4e8), (1e9, 1e9), (1e9, 1e10), (1e11, 1e8)):
        model = md.Model.build(
            blocks,
            md.InterfaceMaterial(kn=kn, kt=kt, friction=FRICTION),
            [md.Support([base])],
            [md.SelfWeight(), md.WeightProportional(direction=(1.0, 0.0, 0.0))],
        )
        history = pushover(model)
        lam = history.collapse_multiplier
        value = "-" if lam is None else f"{lam:.8f}"
        print(f"{kn:8.0e} {kt:8.0e} {value:>12}  {history.status}")


def print_validation_in_pieces() -> None:
    """The paper's validation cases with whole joints and with every joint in 2 x 2 pieces."""
    from dataclasses import replace

    import masonry_dem as md
    from masonry_dem.cases.paper import build_case, case_names
    from masonry_dem.solvers.incremental import pushover

    print(f"{'case':6} {'whole':>9} {'2x2':>9} {'paper DEM':>9} {'reference':>9}  status 2x2")
    for name in case_names():
        case = build_case(name)
        whole = pushover(case.model, case.settings).collapse_multiplier
        m = case.model
        cut = replace(
            m,
            interfaces=md.subdivide_interfaces(m.interfaces, 2, 2),
            **{
                f: np.repeat(getattr(m, f), 4)
                for f in ("kn", "kt", "friction", "tensile_strength", "alpha")
            },
        )
        history = pushover(cut, case.settings)
        lam = history.collapse_multiplier
        print(
            f"{name:6} {whole!s:>9.7} {lam!s:>9.7} {case.paper_dem:9.4g} {case.reference:9.4g}"
            f"  {history.status}",
            flush=True,
        )


def associative_lp(model) -> float:
    """The associative rigid-block multiplier of the same model, by the package's limit
    analysis (the LP of ``masonry_dem.solvers.limit_analysis``, HiGHS)."""
    from masonry_dem.solvers.limit_analysis import limit_analysis

    result = limit_analysis(model, associative=True)
    if result.status != "collapse":
        raise RuntimeError(f"the limit analysis did not find a collapse: {result.reason}")
    return result.load_factor


def package_rows(with_dr: bool) -> list[tuple[str, str, float, str]]:
    from masonry_dem.solvers.dynamic_relaxation import relax
    from masonry_dem.solvers.incremental import pushover
    from masonry_dem.studies.runs import warm_up

    warm_up()
    rows = []
    for pieces in ((1, 1), (1, 2), (2, 2)):
        model = package_model(pieces)
        label = "whole joints" if pieces == (1, 1) else f"joints in {pieces[0]} x {pieces[1]}"
        runs = [("static", pushover)] + ([("DR", relax)] if with_dr else [])
        for solver, run in runs:
            t0 = time.perf_counter()
            history = run(model)
            seconds = time.perf_counter() - t0
            lam = history.collapse_multiplier
            value = f"{lam:.4f}" if lam is not None else f"none ({history.status})"
            if solver == "DR" and history.collapse_bracket is not None:
                value = "[{:.4f}, {:.4f}]".format(*history.collapse_bracket)
            rows.append((f"masonry_dem {solver}, {label}", value, seconds, history.status))
    model = package_model()
    t0 = time.perf_counter()
    lam = associative_lp(model)
    rows.append(("associative LP (HiGHS)", f"{lam:.4f}", time.perf_counter() - t0, "upper bound"))
    return rows


def print_mechanisms() -> None:
    """The last increment of the static path (the collapse mode) of the blocks that move, whole
    joints against joints in pieces: u scaled to 1 at the largest, w3 times the block height."""
    from masonry_dem.solvers.incremental import pushover

    for pieces in ((1, 1), (2, 2)):
        model = package_model(pieces)
        history = pushover(model)
        dq = history.steps[-1].q - history.steps[-2].q
        dq = dq / np.abs(dq[:, :3]).max()
        moving = np.flatnonzero(np.abs(dq[:, :3]).max(axis=1) > 1e-3)
        lam = history.collapse_multiplier
        print(f"collapse mode, {model.name}, lambda {lam:.5f}:")
        print(f"  {'block':>5} {'x':>5} {'y':>5} {'u1':>7} {'u2':>7} {'w3 a':>7}")
        for b in moving:
            x, y = model.blocks.centres[b, :2]
            u1, u2, w3 = dq[b, 0], dq[b, 1], dq[b, 5] * A
            print(f"  {b:5d} {x:5.2f} {y:5.2f} {u1:+7.3f} {u2:+7.3f} {w3:+7.3f}")


# ------------------------------------------------------------------ the peer side (peer venv)
_FACES = [[3, 2, 1, 0], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]


def _peer_boxes() -> list[tuple[list[float], list[float]]]:
    """The same wall in compas axes (x along, y thickness, z up); the slab last. Even courses
    hold whole blocks, odd ones a half block at each end (as running_bond_wall)."""
    boxes = []
    for k in range(COURSES):
        if k % 2 == 0:
            cuts = np.arange(N_ALONG + 1.0)
        else:
            cuts = np.concatenate([[0.0], np.arange(N_ALONG) + 0.5, [float(N_ALONG)]])
        for left, right in zip(cuts[:-1], cuts[1:], strict=True):
            boxes.append(([left * B, 0.0, k * A], [right * B, S, (k + 1) * A]))
    boxes.append(([0.0, 0.0, -A], [N_ALONG * B, S, 0.0]))
    return boxes


def _lmgc90_run(lam: float, dt: float, t_rest: float, t_hold: float) -> tuple[float, list]:
    """Largest displacement of any block during the held lateral acceleration lambda g, and
    the centres (x along, y up) of the blocks that moved more than a fifth of it (the mode)."""
    from compas_lmgc90.solver import Solver

    boxes = _peer_boxes()
    meshes = []
    for lo, hi in boxes:
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        vertices = [
            [x0, y0, z0],
            [x1, y0, z0],
            [x1, y1, z0],
            [x0, y1, z0],
            [x0, y0, z1],
            [x1, y0, z1],
            [x1, y1, z1],
            [x0, y1, z1],
        ]
        meshes.append({"vertices": vertices, "faces": _FACES})
    solver = Solver(dt=dt, theta=0.5, density=DENSITY)
    solver.geometry_from_v_f(meshes)
    slab = len(boxes) - 1
    for component in ("Vx", "Vy", "Vz", "Rx", "Ry", "Rz"):
        solver.apply_velocity(slab, component, 0.0)
    end = t_rest + t_hold + 1.0
    for i, (lo, hi) in enumerate(boxes[:-1]):
        force = lam * DENSITY * G * float(np.prod(np.subtract(hi, lo)))
        series = np.array([[0.0, t_rest, t_rest + dt, end], [0.0, 0.0, force, force]])
        solver.apply_force(i, "Fx", series)
    solver.contact_law("IQS_CLB", FRICTION)
    solver.preprocess()
    solver.run(int(round(t_rest / dt)))
    at_rest = np.array([solver.last_result.bodies[i] for i in range(slab)])
    limit = 0.25 * min(A, B, S)
    moved = 0.0
    each = np.zeros(slab)
    steps = int(round(t_hold / dt))
    for k in range(steps):
        solver.run(1)
        if k % 50 == 49 or k == steps - 1:
            now = np.array([solver.last_result.bodies[i] for i in range(slab)])
            each = np.linalg.norm(now - at_rest, axis=1)
            moved = float(each.max())
            if moved > limit:
                break
    solver.finalize()
    mode = [
        [round(0.5 * (lo[0] + hi[0]), 3), round(0.5 * (lo[2] + hi[2]), 3)]
        for (lo, hi), d in zip(boxes[:-1], each, strict=True)
        if moved > 0 and d > 0.2 * moved
    ]
    return moved, mode


def peer_lmgc90(low: float, high: float, width: float, dt: float) -> dict:
    """Bisect the lateral acceleration between a stable ``low`` and a collapsing ``high``."""
    import contextlib
    import io

    t0 = time.perf_counter()
    limit = 0.25 * min(A, B, S)
    runs = []
    modes = {}

    def collapses(lam: float) -> bool:
        with contextlib.redirect_stdout(io.StringIO()):  # the wrapper prints progress
            moved, mode = _lmgc90_run(lam, dt, t_rest=0.5, t_hold=2.0)
        runs.append((lam, moved))
        modes[lam] = mode
        return moved > limit

    if collapses(low) or not collapses(high):
        return {"error": f"the bracket [{low}, {high}] does not hold a collapse", "runs": runs}
    while high - low > width:
        mid = 0.5 * (low + high)
        if collapses(mid):
            high = mid
        else:
            low = mid
    seconds = time.perf_counter() - t0
    return {"bracket": [low, high], "seconds": seconds, "runs": runs, "mode": modes[high]}


def peer_side(args) -> int:
    """Runs in the peer Python: prints one JSON line."""
    out: dict = {}
    try:
        import compas_lmgc90.solver  # noqa: F401
    except Exception as exc:  # any failure to import is a reason to skip, reported as is
        out["lmgc90"] = {"skipped": f"compas_lmgc90 does not import: {exc!r}"}
    else:
        out["lmgc90"] = peer_lmgc90(args.low, args.high, args.width, args.dt)
    try:
        import compas_cra.equilibrium  # noqa: F401
        import pyomo.environ as pyo
    except Exception as exc:
        out["cra"] = {"skipped": f"compas_cra does not import: {exc!r}"}
    else:
        if pyo.SolverFactory("ipopt").available(exception_flag=False):
            out["cra"] = {"skipped": "IPOPT found, but this script does not run CRA yet"}
        else:
            out["cra"] = {"skipped": "compas_cra imports, but pyomo finds no IPOPT executable"}
    print(json.dumps(out))
    return 0


# ------------------------------------------------------------------ main
def peer_rows(python: str, args) -> list[tuple[str, str, float, str]]:
    if not Path(python).exists():
        msg = f"no peer Python at {python} (--peer-python or $PEER_PYTHON)"
        return [("LMGC90 (compas_lmgc90)", "skipped", 0.0, msg)]
    cmd = [python, str(Path(__file__).resolve()), "--peer-side"]
    cmd += ["--low", str(args.low), "--high", str(args.high)]
    cmd += ["--width", str(args.width), "--dt", str(args.dt)]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - t0
    lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0 or not lines:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no output"]
        return [("peers", "skipped", seconds, f"the peer run failed: {tail[0]}")]
    result = json.loads(lines[-1])
    rows = []
    lm = result["lmgc90"]
    if "bracket" in lm:
        value = "[{:.4f}, {:.4f}]".format(*lm["bracket"])
        note = f"{len(lm['runs'])} runs; issue 18: [{LMGC90_REPORTED[0]}, {LMGC90_REPORTED[1]}]"
        rows.append(("LMGC90 (compas_lmgc90)", value, lm["seconds"], note))
    else:
        note = lm.get("skipped") or lm.get("error", "")
        rows.append(("LMGC90 (compas_lmgc90)", "skipped", 0.0, note))
    if lm.get("mode"):
        blocks = " ".join(f"({x:.2f}, {y:.2f})" for x, y in sorted(map(tuple, lm["mode"])))
        print(f"LMGC90 collapse mode at lambda {lm['bracket'][1]:.4f}, blocks (x, y): {blocks}")
    rows.append(("CRA / RBE (compas_cra)", "skipped", 0.0, f"{result['cra']['skipped']}"))
    rows.append(("CRA / RBE, reported", "[0.583, 0.589]", float("nan"), CRA_REPORTED))
    return rows


def main() -> int:
    p = arguments(__doc__)
    p.add_argument("--no-peers", action="store_true", help="skip LMGC90 and CRA")
    p.add_argument("--dr", action="store_true", help="dynamic relaxation too (about 30 s)")
    p.add_argument("--mechanism", action="store_true", help="print the two collapse modes")
    p.add_argument("--pieces", action="store_true", help="lambda against the number of pieces")
    p.add_argument("--stiffness", action="store_true", help="whole joints, kn and kt swept")
    p.add_argument(
        "--validation", action="store_true", help="the validation cases in 2 x 2 pieces (minutes)"
    )
    p.add_argument("--peer-python", default=os.environ.get("PEER_PYTHON", DEFAULT_PEER_PYTHON))
    p.add_argument("--low", type=float, default=0.55, help="LMGC90 bracket: a stable lambda")
    p.add_argument("--high", type=float, default=0.60, help="LMGC90 bracket: a collapse")
    p.add_argument("--width", type=float, default=0.005, help="LMGC90 bisection width")
    p.add_argument("--dt", type=float, default=1e-3, help="LMGC90 time step [s]")
    p.add_argument("--peer-side", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.peer_side:
        return peer_side(args)
    print_machine()
    print(f"python {platform.python_version()} on {platform.machine()}, {time.ctime()}")
    print(f"peer wall: {N_ALONG} x {COURSES} running bond, {B} x {A} x {S} m, mu {FRICTION}")
    if args.mechanism:
        print_mechanisms()
    if args.pieces:
        print_pieces_sweep()
    if args.stiffness:
        print_stiffness_sweep()
    if args.validation:
        print_validation_in_pieces()
    rows = package_rows(args.dr)
    if not args.no_peers:
        rows += peer_rows(args.peer_python, args)
    width = max(len(r[0]) for r in rows)
    print(f"{'method':{width}}  {'lambda [g]':>16}  {'seconds':>8}  note")
    for name, value, seconds, note in rows:
        time_text = "-" if np.isnan(seconds) else f"{seconds:.2f}"
        print(f"{name:{width}}  {value:>16}  {time_text:>8}  {note}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
