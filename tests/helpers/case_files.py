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
    """``data`` (a case as a dict) written as ``tmp_path/case.toml``."""
    lines = []

    def emit(table: dict) -> None:
        simple = {
            k: v
            for k, v in table.items()
            if not isinstance(v, (dict, list))
            or (isinstance(v, list) and not (v and isinstance(v[0], dict)))
        }
        for k, v in simple.items():
            lines.append(f"{k} = {json.dumps(v)}")

    emit(data)
    for key in ("geometry", "material", "analysis"):
        if key in data:
            lines.append(f"[{key}]")
            emit(data[key])
    for key in ("supports", "loads"):
        for item in data.get(key, []):
            lines.append(f"[[{key}]]")
            emit(item)
    path = tmp_path / "case.toml"
    path.write_text("\n".join(lines))
    return path
