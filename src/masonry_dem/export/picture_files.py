"""Where a picture goes and how it gets there: the output path checked against the formats
a picture may take, and the write under a temporary name (same suffix, so the writer picks
the format) renamed into place, so a reader never sees a half-written picture and a failed
write leaves the previous one alone."""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any


def check_out(out: Path | str | None, default: Path, suffixes: tuple[str, ...], what: str) -> Path:
    """``out`` (or ``default``) as a Path, refused unless it ends in one of ``suffixes`` and
    is not a directory."""
    path = default if out is None else Path(out)
    if path.suffix.lower() not in suffixes:
        raise ValueError(f"{what} must be written to a {' or '.join(suffixes)} file, got {path}")
    if path.exists() and path.is_dir():
        raise ValueError(f"{what}: {path} is a directory")
    return path


def write_atomically(path: Path, write: Callable[[Path], Any]) -> None:
    """``write(tmp)`` to a temporary file beside ``path`` (same suffix), then move it onto
    ``path``."""
    from masonry_dem.export.results_folder import write_error

    tmp = path.with_name(f".{path.stem}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp{path.suffix}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write(tmp)
        tmp.replace(path)
    except OSError as exc:  # a full disk, a read-only folder: named, with the picture's path
        raise write_error(path, exc) from exc
    finally:
        tmp.unlink(missing_ok=True)
