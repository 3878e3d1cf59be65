"""The PVD index of a VTU time series (a small XML file ParaView reads as a time series)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import numpy as np


def write_pvd(
    path: Path, files: Sequence[str], times: Sequence[float] | np.ndarray, atomic: bool = True
) -> None:
    """Write ``path`` listing ``files`` (relative to the PVD's folder) at ``times``;
    ``atomic``: under a unique temporary name renamed into place (``False`` for a caller that
    renames itself, e.g. both PVDs of a folder together)."""
    if len(files) != len(times):
        raise ValueError(f"pvd: {len(files)} files but {len(times)} times")
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for f, t in zip(files, times, strict=True):
        ET.SubElement(coll, "DataSet", timestep=repr(float(t)), group="", part="0", file=str(f))
    ET.indent(root)

    def write(target: Path) -> None:
        ET.ElementTree(root).write(target, xml_declaration=True, encoding="utf-8")

    if atomic:
        from masonry_dem.export.results_folder import write_atomic

        write_atomic(Path(path), write)  # never a half-written index, never a shared tmp name
    else:
        write(Path(path))


def read_pvd(path: Path) -> list[tuple[float, str]]:
    """(time, relative file) of every data set in a PVD file."""
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep", "0")), d.get("file", "")) for d in root.iter("DataSet")]
