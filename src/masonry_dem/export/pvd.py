"""The PVD index of a VTU time series (a small XML file ParaView reads as a time series)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import numpy as np


def write_pvd(path: Path, files: Sequence[str], times: Sequence[float] | np.ndarray) -> None:
    """Write ``path`` listing ``files`` (relative to the PVD's folder) at ``times``."""
    if len(files) != len(times):
        raise ValueError(f"pvd: {len(files)} files but {len(times)} times")
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for f, t in zip(files, times, strict=True):
        ET.SubElement(coll, "DataSet", timestep=repr(float(t)), group="", part="0", file=str(f))
    ET.indent(root)
    tmp = Path(path).with_suffix(".pvd.tmp")
    ET.ElementTree(root).write(tmp, xml_declaration=True, encoding="utf-8")
    tmp.replace(path)  # never leave a half-written index behind


def read_pvd(path: Path) -> list[tuple[float, str]]:
    """(time, relative file) of every data set in a PVD file."""
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep", "0")), d.get("file", "")) for d in root.iter("DataSet")]
