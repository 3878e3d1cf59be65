"""Generated walls of issue 18's class: how each run ends, its certificate and its time.

Generated walls over the whole class of issue 18, each run by the static solver: how each
ends, the certificate of every collapse, and its time.

    python benchmarks/certificate_sweep.py [--walls 30] [--seed 18] [--kn-sweep]

Walls: running bond of 1-15 blocks by 1-20 courses (Orduna blocks a = 0.081, b = 0.210,
s = 0.070) on a rigid base, tilted in or out of their plane, with or without the left column
held in u1 and u3, friction 0.3-100 (log-uniform), kn 1e8-1e13 (log-uniform, kt = 0.4 kn).
Prints one row a wall (status, stop, lambda, the certificate's mode and rho, seconds) and a
count by status; a ``collapse`` without a certificate that holds, or at lambda below 1e-3,
is flagged ``!!``. ``--kn-sweep`` also reruns every collapsed wall with kn and kt x 1e-2 and
x 1e3 and prints the largest relative move of a certified lambda, and counts the reruns
that failed: "too soft" (the wall left the small-displacement range before its peak, the
physical reason) or "other".
"""

from __future__ import annotations

import time

import numpy as np
from _machine import arguments, print_machine

from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.selectors import column
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import pushover


def wall(spec: dict, kn_factor: float = 1.0) -> Model:
    blocks_wall = running_bond_wall(spec["blocks"], spec["courses"], 0.081, 0.21, 0.07, 20e3)
    blocks, base = add_base(blocks_wall)
    supports = [Support([base])]
    if spec["held"]:
        supports.append(Support(column(blocks_wall, "left"), ["u1", "u3"]))
    kn = spec["kn"] * kn_factor
    direction = (1.0, 0.0, 0.0) if spec["in_plane"] else (0.0, 0.0, 1.0)
    return Model.build(
        blocks,
        InterfaceMaterial(kn=kn, kt=0.4 * kn, friction=spec["friction"]),
        supports=supports,
        loads=[SelfWeight(), WeightProportional(direction)],
        name="sweep",
    )


def random_spec(rng: np.random.Generator) -> dict:
    """One wall of the class of issue 18, drawn from ``rng`` (the fields ``wall`` reads)."""
    return {
        "blocks": int(rng.integers(1, 16)),
        "courses": int(rng.integers(1, 21)),
        "in_plane": bool(rng.integers(0, 2)),
        "held": bool(rng.integers(0, 2)),
        "friction": float(10 ** rng.uniform(np.log10(0.3), 2.0)),
        "kn": float(10 ** rng.uniform(8.0, 13.0)),
    }


def describe(spec: dict) -> str:
    """A wall's spec in one short line."""
    return (
        f"{spec['blocks']}x{spec['courses']} {'in' if spec['in_plane'] else 'out'}"
        f"{' held' if spec['held'] else ''} mu={spec['friction']:.3g} kn={spec['kn']:.1e}"
    )


def main(argv: list[str] | None = None) -> None:
    parser = arguments(__doc__)
    parser.add_argument("--walls", type=int, default=30)
    parser.add_argument("--seed", type=int, default=18)
    parser.add_argument("--kn-sweep", action="store_true")
    args = parser.parse_args(argv)
    print_machine()
    rng = np.random.default_rng(args.seed)
    counts: dict[str, int] = {}
    flagged = 0
    worst_move = 0.0
    failures: dict[str, int] = {}
    print(
        f"{'wall':34s} {'status':9s} {'stop':30s} {'lambda':>10s} {'mode':12s} {'rho':>9s} {'s':>6s}"
    )
    for _ in range(args.walls):
        spec = random_spec(rng)
        t0 = time.perf_counter()
        hist = pushover(wall(spec))
        seconds = time.perf_counter() - t0
        status = str(hist.status)
        counts[status] = counts.get(status, 0) + 1
        cert = hist.certificate
        lam = hist.collapse_multiplier
        bad = status == "collapse" and (cert is None or not cert.holds or lam is None or lam < 1e-3)
        flagged += bad
        name = describe(spec)
        mode = cert.mode.replace("singular tangent", "tangent") if cert else "-"
        rho = f"{cert.mode_rayleigh:.2e}" if cert else "-"
        shown = f"{lam:.5g}" if lam is not None else f"({hist.final_load_factor:.3g})"
        print(
            f"{name:34s} {status:9s} {str(hist.stop):30.30s} {shown:>10s} {mode[:12]:12s} "
            f"{rho:>9s} {seconds:6.2f}{'  !!' if bad else ''}",
            flush=True,
        )
        if args.kn_sweep and status == "collapse" and lam is not None:
            for factor in (1e-2, 1e3):
                rerun = pushover(wall(spec, factor))
                other = rerun.collapse_multiplier
                if other is None:
                    # the one physical reason a stiffness may change the answer: the wall
                    # leaves the small-displacement range before its peak (soft joints)
                    physical = "left the small-displacement range" in rerun.reason
                    kind = "too soft" if physical else "other"
                    failures[kind] = failures.get(kind, 0) + 1
                    print(f"    kn x {factor:g}: {rerun.status} ({kind}: {rerun.stop})", flush=True)
                    continue
                move = abs(other - lam) / lam
                worst_move = max(worst_move, move)
                print(f"    kn x {factor:g}: {other:.6f} (move {move:.2%})", flush=True)
    print("by status:", counts, f"flagged: {flagged}")
    if args.kn_sweep:
        print(
            f"largest move of a certified lambda with kn, kt x 1e-2..1e3: {worst_move:.2%}; "
            f"reruns that failed: {failures or 'none'}"
        )


if __name__ == "__main__":
    main()
