"""Command line: ``masonry-dem <command>``.

Each command lives in its own module of this package and exposes ``add_parser(subparsers)``
(which registers the sub-command and sets ``func``) so commands stay independent.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

COMMANDS = ("run", "validate", "interface", "render", "paraview_state", "study", "limit")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="masonry-dem",
        description="Nonlinear 3D discrete element analysis of masonry walls.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"masonry_dem.cli.{name}")
        except ModuleNotFoundError as exc:  # a command not built yet
            if exc.name != f"masonry_dem.cli.{name}":
                raise
            continue
        module.add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileNotFoundError) as exc:
        print(f"masonry-dem: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
