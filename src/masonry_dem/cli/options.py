"""Command-line options that several commands share: their argparse definitions and parsers,
so that a flag means the same and reads the same in every command."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any, TypeVar

#: ``--overwrite`` of the commands that write a results folder
OVERWRITE_HELP = (
    "replace the run already in --out (removes the package's own files there, and only "
    "those); without it such a folder is refused"
)


def add_case(p: argparse.ArgumentParser) -> None:
    """``CASE``: the case file to run, optional (the bundled default wall)."""
    p.add_argument("case", nargs="?", help="TOML case file (see README, 'Case files')")


def add_output(p: argparse.ArgumentParser, default: str, renders: str) -> None:
    """``--out`` (the results folder, ``default`` unless given) and ``--no-render`` (skip
    ``renders``, the PNGs the command would write)."""
    p.add_argument("--out", default=default, help="results folder (default: %(default)s)")
    p.add_argument("--no-render", action="store_true", help=f"skip {renders}")


def add_results(p: argparse.ArgumentParser) -> None:
    """``RESULTS``: the results folder a command reads."""
    p.add_argument("results", help="results folder (blocks.pvd, interfaces.pvd, steps/, ...)")


def add_overwrite(p: argparse.ArgumentParser) -> None:
    """``--overwrite``: a results folder that holds a run is refused without it."""
    p.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)


def add_max_memory(p: argparse.ArgumentParser, what: str) -> None:
    """``--max-memory``: refuse ``what`` (a run, an analysis) whose estimated memory is above
    it (the estimate is checked against the least of it and what the machine leaves)."""
    p.add_argument(
        "--max-memory",
        default=None,
        help=f"refuse {what} whose estimated memory is above this (e.g. 16G, 500M; "
        "default: what the machine and the process's limits leave)",
    )


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


def positive_seconds(option: str) -> Callable[[str], float]:
    """An argparse ``type``: a finite number of seconds > 0, else an error that names
    ``option``, the range and the text given."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not 0 < value < float("inf"):
            raise argparse.ArgumentTypeError(
                f"{option} must be a finite number of seconds > 0, got {text!r}"
            )
        return value

    return parse


def results_line(out: Path) -> str:
    """A command's last line: the folder and the files the run left in it (the PNGs among
    them), as they are on disk; ``steps/`` for the step files."""
    names = sorted(f.name for f in out.iterdir() if f.is_file() and not f.name.startswith("."))
    if (out / "steps").is_dir():
        names.append("steps/")
    return f"results in {out}/ ({', '.join(names)})"


def parameter_file(path: str | None, keys: Collection[str], what: str) -> dict[str, Any]:
    """The values of a TOML file of parameters (``--config``; None: none), each key among
    ``keys``; a file that is no TOML, or an unknown key, is a ValueError naming ``what`` (e.g.
    "assessment file") and the file."""
    if path is None:
        return {}
    from masonry_dem._toml import tomllib

    where = Path(path)
    try:
        params: dict[str, Any] = tomllib.loads(where.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{what} {where}: not TOML ({exc})") from exc
    unknown = sorted(set(params) - set(keys))
    if unknown:
        raise ValueError(
            f"{what} {where}: unknown key {unknown[0]!r}; the keys are {', '.join(keys)}"
        )
    return params


Line = TypeVar("Line", bound="EventLine")


class EventLine:
    """A progress line on stderr (tqdm) that appears at the first event a running analysis
    reports (:mod:`masonry_dem._progress`), one tick per event, and closes on exit: an
    analysis that reports nothing shows nothing, and ``quiet`` shows nothing at all."""

    def __init__(self, desc: str, unit: str, quiet: bool) -> None:
        self.desc, self.unit, self.quiet = desc, unit, quiet
        self.bar: Any = None

    def __enter__(self: Line) -> Line:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.close()

    def tick(self, postfix: str) -> None:
        """One event, described by ``postfix``."""
        if self.quiet:
            return
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(desc=self.desc, unit=self.unit)
        self.bar.set_postfix_str(postfix, refresh=False)  # shown by the update, with its count
        self.bar.update(1)
