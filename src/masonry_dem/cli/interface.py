"""``masonry-dem interface``: closed-form interface strength against the spring model
(:mod:`masonry_dem.studies.interface`).

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

from masonry_dem.constitutive import REFERENCE_INTERFACE


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    ref = REFERENCE_INTERFACE
    p: argparse.ArgumentParser = subparsers.add_parser(
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
    p.add_argument("--tensile-strength", type=float, default=0.0, help="tensile strength (Pa)")
    p.add_argument(
        "--cohesion",
        type=float,
        default=None,
        help="cohesion c (Pa), at least friction x tensile strength (default: mu ft, the paper's)",
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
    from masonry_dem.studies.interface import Interface, interface_study

    it = Interface(
        args.l1,
        args.l2,
        args.fn,
        args.friction,
        args.tensile_strength,
        args.kn,
        args.ks,
        args.n,
        args.cohesion,
    )
    return interface_study(it, args.directions, args.alpha_n, not args.no_alpha_table)


def run(args: argparse.Namespace) -> int:
    from masonry_dem.studies.interface import interface_text

    res = compute(args)
    print(json.dumps(res, indent=2) if args.json else interface_text(res))
    return 0
