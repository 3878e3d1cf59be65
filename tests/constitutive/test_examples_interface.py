"""The interface-figures example runs (reduced) and writes its PNGs."""

from __future__ import annotations

import runpy
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "interface_figures.py"


def test_interface_figures_quick(tmp_path):
    module = runpy.run_path(str(EXAMPLE), run_name="interface_figures")
    written = module["main"](["--quick", "--out", str(tmp_path / "figs")])
    names = {p.name for p in written}
    for fig in ("5", "7", "8", "9", "10", "A1", "A4"):
        assert any(name.startswith(f"figure_{fig}_") for name in names), fig
    for path in written:
        assert path.parent == tmp_path / "figs"
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert path.stat().st_size > 2_000
