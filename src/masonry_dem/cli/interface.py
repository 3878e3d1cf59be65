"""``masonry-dem interface``: closed-form interface strength against the spring model.

Prints, for the reference dry interface of Section 2.1 (0.30 x 0.20 m, fn = -240 N, mu = 0.7,
32 x 32 springs) or one given on the command line, the shear and torsion strengths from the
closed form and from the spring model, the convergence of the spring-model torsion strength
for n = 4 ... 64 springs per side, and Table A1 (alpha fitted to spring-model domains) side by
side with the published values. The alpha fits use ``--alpha-n`` springs per side
(default 32: the 21 fits take about a second).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from masonry_dem.constitutive.springs import (
    REFERENCE_INTERFACE,
    fit_alpha,
    shear_strength_numeric,
    torsion_strength_numeric,
)
from masonry_dem.constitutive.strength import (
    ALPHA_TABLE_A1,
    DIRECTIONS,
    shear_strength,
    torsion_constant,
    torsion_strength,
)

#: springs per side of the torsion-convergence table (n = 64 is 4096 springs, a few ms)
CONVERGENCE_N = (4, 8, 16, 32, 64)


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    ref = REFERENCE_INTERFACE
    p = subparsers.add_parser(
        "interface",
        help="interface strength: closed form vs spring model, Table A1",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--l1", type=float, default=ref.l1, help="side along y1 (m)")
    p.add_argument("--l2", type=float, default=ref.l2, help="side along y2 (m)")
    p.add_argument("--fn", type=float, default=ref.normal_force, help="normal force (N, <0)")
    p.add_argument("--friction", type=float, default=ref.friction, help="friction coefficient")
    p.add_argument(
        "--tensile-strength", type=float, default=0.0, help="tensile strength (Pa), c = mu*ft"
    )
    p.add_argument("--kn", type=float, default=ref.kn, help="normal stiffness (N/m^3)")
    p.add_argument("--ks", type=float, default=ref.ks, help="shear stiffness (N/m^3)")
    p.add_argument("--n", type=int, default=ref.n, help="springs per side")
    p.add_argument(
        "--directions", type=int, default=16, help="shear directions checked in the plane"
    )
    p.add_argument("--alpha-n", type=int, default=32, help="springs per side for the alpha fits")
    p.add_argument("--no-alpha-table", action="store_true", help="skip the Table A1 fits")
    p.set_defaults(func=run)
    return p


def compute(args: argparse.Namespace) -> dict[str, Any]:
    """All figures of the command as a JSON-ready dict."""
    if args.directions < 1:
        raise ValueError(f"directions must be >= 1, got {args.directions}")
    ft = args.tensile_strength * args.l1 * args.l2
    fsu = float(shear_strength(args.fn, args.friction, ft))
    m3u = float(torsion_strength(args.fn, args.l1, args.l2, args.friction, ft))
    common = dict(n=args.n, kn=args.kn, ks=args.ks)
    angles = np.linspace(0.0, 2.0 * np.pi, args.directions, endpoint=False)
    fs = shear_strength_numeric(
        args.l1, args.l2, args.fn, args.friction, args.tensile_strength, angles=angles, **common
    )
    m3s = torsion_strength_numeric(
        args.l1, args.l2, args.fn, args.friction, args.tensile_strength, **common
    )
    out: dict[str, Any] = {
        "interface": {
            "l1": args.l1,
            "l2": args.l2,
            "normal_force": args.fn,
            "friction": args.friction,
            "tensile_strength": args.tensile_strength,
            "kn": args.kn,
            "ks": args.ks,
            "springs_per_side": args.n,
        },
        "torsion_constant": float(torsion_constant(args.l1, args.l2)),
        "shear_strength": fsu,
        "torsion_strength": m3u,
        "spring_shear_strength": float(fs.min()),
        "spring_shear_strength_max": float(fs.max()),
        "spring_shear_directions": len(angles),
        "spring_torsion_strength": m3s,
        "torsion_convergence": [],
        "alpha_table": [],
    }
    for n in CONVERGENCE_N:
        value = torsion_strength_numeric(
            args.l1, args.l2, args.fn, args.friction, args.tensile_strength, n=n,
            kn=args.kn, ks=args.ks,
        )  # fmt: skip
        out["torsion_convergence"].append(
            {"n": n, "spring_torsion_strength": value, "relative_error": value / m3u - 1.0}
        )
    if not args.no_alpha_table:
        out["alpha_springs_per_side"] = args.alpha_n
        for direction in DIRECTIONS:
            for aspect, paper in zip(
                ALPHA_TABLE_A1["aspect"], ALPHA_TABLE_A1[direction], strict=True
            ):
                out["alpha_table"].append(
                    {
                        "aspect": aspect,
                        "direction": direction,
                        "alpha_fitted": round(fit_alpha(aspect, direction, n=args.alpha_n), 4),
                        "alpha_paper": paper,
                    }
                )
    return out


def _pct(value: float, ref: float) -> str:
    if not ref:
        return "n/a"
    pct = 100.0 * (value / ref - 1.0)
    return f"{0.0 if abs(pct) < 5e-4 else pct:+.3f} %"  # no "-0.000 %"


def run(args: argparse.Namespace) -> int:
    res = compute(args)
    if args.json:
        print(json.dumps(res, indent=2))
        return 0
    i = res["interface"]
    print(
        f"Interface {i['l1']:.3f} x {i['l2']:.3f} m, fn = {i['normal_force']:g} N, "
        f"mu = {i['friction']:g}, tensile strength = {i['tensile_strength']:g} Pa, "
        f"{i['springs_per_side']} x {i['springs_per_side']} springs"
    )
    print(f"torsion constant cT = {res['torsion_constant']:.5f} m")
    print(f"{'':24s}{'closed form':>14s}{'spring model':>14s}{'difference':>14s}")
    fsu, fmin, fmax = (
        res["shear_strength"],
        res["spring_shear_strength"],
        res["spring_shear_strength_max"],
    )
    print(f"{'shear strength [N]':24s}{fsu:14.3f}{fmin:14.3f}{_pct(fmin, fsu):>14s}")
    print(
        f"{'':24s}{'':14s}{fmax:14.3f}{_pct(fmax, fsu):>14s}"
        f"  (min, max over {res['spring_shear_directions']} directions)"
    )
    m3u, m3s = res["torsion_strength"], res["spring_torsion_strength"]
    print(f"{'torsion strength [N m]':24s}{m3u:14.3f}{m3s:14.3f}{_pct(m3s, m3u):>14s}")
    print("\nspring-model torsion strength against the closed form, n x n springs")
    print(f"{'n':>5s}{'m3u spring [N m]':>18s}{'error':>12s}")
    for row in res["torsion_convergence"]:
        err = 100.0 * row["relative_error"]
        print(f"{row['n']:5d}{row['spring_torsion_strength']:18.4f}{err:+11.3f}%")
    if res["alpha_table"]:
        n = res["alpha_springs_per_side"]
        print(f"\nTable A1: alpha fitted to the spring-model domain ({n} x {n} springs)")
        print(f"{'l1/l2':>7s}  {'direction':9s}{'fitted':>8s}{'paper':>8s}{'diff':>8s}")
        for row in res["alpha_table"]:
            diff = row["alpha_fitted"] - row["alpha_paper"]
            print(
                f"{row['aspect']:7.1f}  {row['direction']:9s}{row['alpha_fitted']:8.3f}"
                f"{row['alpha_paper']:8.2f}{diff:+8.3f}"
            )
        print("('f1=f2': the paper's loading with equal relative displacements d1 = d2)")
    return 0
