"""Case files for the command-line tests: one block on a base (``SINGLE_BLOCK``, tilting out
of plane at s / a = 0.5) and :func:`write_case`, which writes a case dict as TOML."""

from __future__ import annotations

import json
from pathlib import Path

SINGLE_BLOCK = {
    "name": "block",
    "geometry": {
        "builder": "single_block",
        "a": 0.4,
        "b": 0.3,
        "s": 0.2,
        "unit_weight": 20e3,
        "base": True,
    },
    "material": {"kn": 2.4e9, "kt": 1e9, "friction": 0.7},
    "supports": [{"select": "base"}],
    "loads": [{"type": "self_weight"}, {"type": "weight_proportional", "direction": [0, 0, 1]}],
}


def write_case(tmp_path: Path, data: dict) -> Path:
    """``data`` (a case as a dict) written as ``tmp_path/case.toml``: values first, then
    each table (``[a.b]``) and array of tables (``[[a.b]]``, e.g. ``[[stages]]`` with their
    ``[[stages.loads]]`` and ``[stages.control]``), nested as deep as the dict."""
    lines: list[str] = []

    def is_tables(value: object) -> bool:
        return isinstance(value, list) and bool(value) and isinstance(value[0], dict)

    def emit(table: dict, prefix: str) -> None:
        for k, v in table.items():
            if not isinstance(v, dict) and not is_tables(v):
                lines.append(f"{k} = {json.dumps(v)}")
        for k, v in table.items():
            name = f"{prefix}.{k}" if prefix else k
            if isinstance(v, dict):
                lines.append(f"[{name}]")
                emit(v, name)
            elif is_tables(v):
                for item in v:
                    lines.append(f"[[{name}]]")
                    emit(item, name)

    emit(data, "")
    path = tmp_path / "case.toml"
    path.write_text("\n".join(lines))
    return path
