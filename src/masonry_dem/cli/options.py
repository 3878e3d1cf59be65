"""Command-line options that several commands share: their argparse definitions and parsers,
so that a flag means the same and reads the same in every command."""

from __future__ import annotations

import argparse
from collections.abc import Callable

#: ``--overwrite`` of the commands that write a results folder
OVERWRITE_HELP = (
    "replace the run already in --out (removes the package's own files there, and only "
    "those); without it such a folder is refused"
)


def add_overwrite(p: argparse.ArgumentParser) -> None:
    """``--overwrite``: a results folder that holds a run is refused without it."""
    p.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)


def whole_number(option: str, minimum: int) -> Callable[[str], int]:
    """An argparse ``type``: a whole number of at least ``minimum``, else an error that names
    ``option``, the bound and the text given."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = minimum - 1
        if value < minimum:
            raise argparse.ArgumentTypeError(
                f"{option} must be a whole number >= {minimum}, got {text!r}"
            )
        return value

    return parse
