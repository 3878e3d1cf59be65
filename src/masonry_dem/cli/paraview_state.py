"""``masonry-dem paraview-state NAME RESULTS``: copy a ParaView state next to a results folder
with its paths filled in, so a double-click (or ``paraview --state=...``) opens it.

The data file paths, the camera and the warp scale are filled in. States: damage_map
(interfaces coloured by state), deformed_shape (Warp By Vector on displacement), force_view
(normal force and utilisation), mechanism (the collapse mode, joints by relative motion; needs
mechanism_blocks.vtu and mechanism_interfaces.vtu, written when a run ends in collapse). 'all'
writes every state the folder has the data for.
"""

from __future__ import annotations

import argparse
import sys

from masonry_dem.cli.options import add_results
from masonry_dem.export.paraview_state import STATES


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "paraview-state",
        help="write a ParaView state (damage map, deformed shape, forces, mechanism)",
        description=__doc__,
    )
    p.add_argument("name", choices=STATES + ("all",), help="state to copy")
    add_results(p)
    p.add_argument(
        "--scale", type=float, default=None, help="Warp By Vector scale factor (default: automatic)"
    )
    p.add_argument("--force", action="store_true", help="replace an existing copy")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from masonry_dem.export.paraview_state import copy_state, has_data
    from masonry_dem.export.results_folder import warn_if_unfinished

    warn_if_unfinished(args.results)  # a killed or running run: named, its steps still used
    names: tuple[str, ...] = (args.name,)
    if args.name == "all":  # the mechanism state only for a run that ended in collapse
        names = tuple(n for n in STATES if n != "mechanism" or has_data(n, args.results))
    try:
        paths = [copy_state(n, args.results, scale=args.scale, overwrite=args.force) for n in names]
    except FileExistsError as exc:
        print(f"masonry-dem: error: {exc}", file=sys.stderr)
        return 2
    for path in paths:
        print(path)
    if args.name == "all" and "mechanism" not in names:
        print(
            "mechanism state skipped: no collapse mechanism in this folder "
            "(mechanism_*.vtu are written when a run ends in collapse)",
            file=sys.stderr,
        )
    if paths:
        print(f"open with: paraview --state={paths[0]}")
    return 0
