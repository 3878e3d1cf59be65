"""The validation cases of Section 3 (Tables 1-3 of the paper), built from the published data.

Every number the paper gives is read from ``data/baraldi_cecchi_2016.toml`` (a verbatim copy of
``shared/reference/baraldi_cecchi_2016.toml``); nothing is retyped here. What the paper leaves
open is chosen once, in :class:`Assumptions`, with the reason next to each value; the
sensitivity of lambda to each choice is measured by ``benchmarks/bench_validation.py
--sensitivity`` and reported in ``docs/validation.md``.

Axes: e1 along the wall, e2 up, e3 out of plane; the live load pushes towards +e3.
Tables 1-2: lambda multiplies the block weights turned horizontal (a tilt table). Table 3:
lambda is the uniform pressure in Pa.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from importlib import resources
from typing import Any, Literal, get_args

import numpy as np

from masonry_dem._toml import tomllib
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.builders import (
    add_base,
    openings_with_lintels,
    running_bond_wall,
    running_bond_wall_of_size,
)
from masonry_dem.geometry.plans import l_wall, u_wall
from masonry_dem.model import (
    DofName,
    InterfaceMaterial,
    Load,
    Model,
    Monitor,
    PointLoad,
    Pressure,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.solvers.incremental import StaticSettings

DATA_FILE = "baraldi_cecchi_2016.toml"


@lru_cache(maxsize=1)
def reference_data() -> dict[str, Any]:
    """The published figures (the package copy of the shared reference TOML)."""
    text = resources.files("masonry_dem.cases").joinpath("data", DATA_FILE).read_text()
    return tomllib.loads(text)


SimpleSupport = Literal["strips", "dofs"]
Restraint = Literal["columns", "return-walls"]
SIMPLE_SUPPORTS: tuple[str, ...] = get_args(SimpleSupport)
RESTRAINTS: tuple[str, ...] = get_args(Restraint)
# the specimens of Table 2 held by return walls alone (no openings): the only ones
# ``restraint="return-walls"`` rebuilds as L (one edge) and U (both edges) walls
RETURN_WALL_CASES = ("S11", "S12", "S13", "S15", "S6", "S1-S3", "S5")


@dataclass(frozen=True)
class Assumptions:
    """Every value the paper does not give, in one place (see docs/validation.md).

    dry_kn, dry_kt [N/m^3]: stiffness of the dry joints of Tables 1-2; the paper gives none
        for the panels, so the dry interface it studies in Section 2.1 (2.4 and 1 MPa/mm).
    column_dofs_table1, column_dofs_table2: DOFs fixed on the restrained column(s). Table 1
        says "translations fixed" and Table 2 "translations and rotations", but fixing u2
        makes the dead-load step fail (no equilibrium of the dry joints is found while the
        wall settles against a column that cannot): the column settles with the wall (u2 free).
    opening_width, opening_height, sill_courses: openings of S23/S34 in blocks and courses
        (the paper shows them only in a figure): two windows of 3 blocks x 9 courses on a
        6-course sill; S23 keeps a 4-block central pier (piers 2-3-4-3-2 blocks wide),
        S34 a 2-block one (3-3-2-3-3). Over each window the blocks of the next course that
        overlap it are one lintel block of masonry weight (dry joints cannot span it).
    s32_beam_course: S32 carries its eleven beams on top of this course (1-based): the
        beams of a floor rest on the wall at the height of the hinge the paper reports
        (between courses 15 and 16), and transmit their weight vertically (dead) and, tilted
        with the table, lambda times it horizontally (live).
    s32_top_restrained: whether the wall's top is also held out of plane (False).
    s32_beams_hold: whether the beams hold the blocks they bear on out of plane (True). The
        paper calls the panel free-standing on its base yet reports a hinge between courses
        15 and 16 (Figure 17), which a panel that the beams only load cannot form: it turns
        as a whole about its base at lambda 0.0615 (hand check, and ours). Beams tied at
        their far ends, as floor joists are, hold the wall where they bear; the six courses
        above then turn about the joint between courses 15 and 16 at lambda = s / (6 a) =
        0.234. The beams then carry 156 N out of plane at collapse (8-19 N each), more than
        dry friction under their own weight could (0.7 x 16.46 = 11.5 N): the reading needs
        beams fixed to the wall or nailed, which the paper does not say.
    brick_unit_weight [N/m^3]: Chee Liang's clay bricks (not given): 18 kN/m^3, a common
        solid clay brick.
    simple_support: how the "simply supported" edges of Table 3 are held. ``"strips"``
        (default): rigid strips ``support_strip_width`` wide behind the leeward face along
        each supported edge and a slab under the bottom course, joined to the wall by dry
        contacts (the mortar's kn, kt and friction, no tension): the support acts at the
        wall's edge, and the edge turns about it and may lift off, as on a line support.
        ``"dofs"``: fix ``simple_support_dofs`` of the edge blocks at their centres (the
        bottom course also u1, u2); this holds the wall half a block inside its edges, which
        makes it stronger (the sensitivity table of docs/validation.md).
    support_strip_width [m]: width of the support strips: 0.01, the joint thickness, for a
        line support at the edge (wider strips hold the edge inside the wall).
    simple_support_dofs: the DOFs fixed by ``simple_support="dofs"``: u3 (rotations free).
    restraint: how the return walls of Table 2 are read. ``"columns"`` (default, the
        paper's): fixed DOFs of the end column(s), ``column_dofs_table2``. ``"return-walls"``:
        the specimens of ``RETURN_WALL_CASES`` rebuilt as they were built, an L wall (one
        edge) or a U wall (both edges) of :mod:`masonry_dem.geometry.plans`, the returns
        interlocked with the facade course by course, standing on the base behind it and
        tilted with it (docs/walls_that_meet.md).
    return_blocks: length of those return walls in blocks, from the facade's outer face; not
        in the stored literature. None (default): the fewest whole blocks at least half the
        wall's height long (4 for Restrepo Velez's 21 courses: 0.32 m for 0.59 m): a rigid
        return that long overturns in its own plane at lambda >= 0.5, above every lambda of
        Table 2, so by statics alone it could carry the facade's mechanism. Lambda for 2, 4
        and 6 blocks is reported side by side, not chosen against the tests.
    """

    dry_kn: float = 2.4e9
    dry_kt: float = 1.0e9
    column_dofs_table1: tuple[DofName, ...] = ("u1", "u3")
    column_dofs_table2: tuple[DofName, ...] = ("u1", "u3", "w1", "w2", "w3")
    opening_width: int = 3
    opening_height: int = 9
    sill_courses: int = 6
    s32_beam_course: int = 15
    s32_top_restrained: bool = False
    s32_beams_hold: bool = True
    brick_unit_weight: float = 18.0e3
    simple_support_dofs: tuple[DofName, ...] = ("u3",)
    simple_support: SimpleSupport = "strips"
    support_strip_width: float = 0.01
    restraint: Restraint = "columns"
    return_blocks: int | None = None

    def __post_init__(self) -> None:
        if self.restraint not in RESTRAINTS:
            raise ValueError(f"restraint must be one of {RESTRAINTS}, got {self.restraint!r}")
        m = self.return_blocks
        if m is not None and (isinstance(m, bool) or not isinstance(m, int) or m < 2):
            raise ValueError(f"return_blocks must be a whole number >= 2 or None, got {m!r}")
        if self.simple_support not in SIMPLE_SUPPORTS:
            raise ValueError(
                f"simple_support must be one of {SIMPLE_SUPPORTS}, got {self.simple_support!r}"
            )
        w = self.support_strip_width
        if not (isinstance(w, (int, float)) and np.isfinite(w) and w > 0):
            raise ValueError(f"support_strip_width must be a positive length, got {w!r}")


@dataclass(frozen=True)
class PaperCase:
    """One validation case: the model and the published values to compare with."""

    name: str
    table: str  # "1", "2" or "3"
    model: Model
    paper_dem: float
    reference: float  # Table 1: FEM; Table 2: the test; Table 3: the mean of the two tests
    unit: str  # "lambda" or "Pa"
    monitor: Monitor  # the block DOF on the pushover curve
    wall: np.ndarray  # (n_wall,) indices of the wall blocks (not supports)
    mechanism: str  # "diagonal", "vertical-axis", "hinge", "four-sided", "three-sided"
    extra: dict = field(default_factory=dict)  # other published values (LA bound, tests)
    settings: StaticSettings = field(default_factory=StaticSettings)

    def error(self, value: float, against: str = "reference") -> float:
        """Relative error of ``value`` against the reference (or ``paper_dem``)."""
        ref = self.reference if against == "reference" else self.paper_dem
        return (value - ref) / ref


def _dry(friction: float, a: Assumptions) -> InterfaceMaterial:
    return InterfaceMaterial(kn=a.dry_kn, kt=a.dry_kt, friction=friction)


def _top_centre(blocks: Blocks, wall: np.ndarray) -> int:
    top = sel.edge(blocks, "top", among=_mask(blocks, wall))
    x = blocks.centres[top, 0]
    return int(top[np.argmin(np.abs(x - np.median(blocks.centres[wall, 0])))])


def _mask(blocks: Blocks, idx: np.ndarray) -> np.ndarray:
    m = np.zeros(blocks.count, dtype=bool)
    m[idx] = True
    return m


def _nearest(blocks: Blocks, idx: np.ndarray, point) -> int:
    d = np.linalg.norm(blocks.centres[idx, :2] - np.asarray(point)[None, :], axis=1)
    return int(idx[np.argmin(d)])


def _block_size(data: dict) -> tuple[float, float, float]:
    """The unit's (a, b, s) of a test series: height, length along the wall, thickness."""
    return data["block_height_a"], data["block_width_b"], data["block_thickness_s"]


# --------------------------------------------------------------------------- Table 1
def _orduna_lourenco(spec: dict, data: dict, a: Assumptions) -> PaperCase:
    wall = running_bond_wall(
        spec["blocks_along_length"],
        spec["courses"],
        *_block_size(data),
        data["unit_weight"],
    )
    blocks, base = add_base(wall)
    widx = np.arange(wall.count)
    sides: list[Literal["left", "right"]] = (
        ["left"] if spec["blocks_along_length"] == 3 else ["left", "right"]
    )
    supports = [Support([base])] + [
        Support(sel.column(wall, side), list(a.column_dofs_table1)) for side in sides
    ]
    model = Model.build(
        blocks,
        _dry(data["friction"], a),
        supports=supports,
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name=spec["name"],
    )
    one_edge = len(sides) == 1
    corner = (wall.upper[:, 0].max(), wall.upper[:, 1].max()) if one_edge else None
    monitor = _nearest(blocks, widx, corner) if one_edge else _top_centre(blocks, widx)
    return PaperCase(
        spec["name"],
        "1",
        model,
        spec["lambda_dem_paper"],
        spec["lambda_fem_reference"],
        "lambda",
        (monitor, "u3"),
        widx,
        "diagonal" if one_edge else "vertical-axis",
        {
            "lambda_limit_analysis": spec["lambda_limit_analysis_reference"],
            "lambda_fem": spec["lambda_fem_reference"],
        },
    )


# --------------------------------------------------------------------------- Table 2
def _openings(n: int, a: Assumptions, central_pier: int, pitch: float, course: float):
    """Two windows symmetric about the wall axis, between piers of whole blocks."""
    w = a.opening_width
    side = (n - central_pier - 2 * w) / 2
    if side < 1 or side != int(side):
        raise ValueError(f"openings do not fit: {n} blocks, pier {central_pier}, width {w}")
    y0 = a.sill_courses * course
    y1 = (a.sill_courses + a.opening_height) * course
    x_left = side * pitch
    x_right = (side + w + central_pier) * pitch
    return [(x_left, y0, x_left + w * pitch, y1), (x_right, y0, x_right + w * pitch, y1)]


def default_return_blocks(data: dict) -> int:
    """The fewest whole blocks at least half the wall's height (see Assumptions)."""
    height = data["courses"] * data["block_height_a"]
    return int(np.ceil(height / (2 * data["block_width_b"]) - 1e-9))


def _restrepo_velez_as_built(spec: dict, data: dict, a: Assumptions) -> PaperCase:
    """The specimen with its return wall(s) as blocks: an L wall (return on the left, where
    the paper fixes the column) or a U wall, on a fixed base, every block tilted."""
    name = spec["name"]
    m = default_return_blocks(data) if a.return_blocks is None else a.return_blocks
    both = "both edges" in spec["setup"]
    build = u_wall if both else l_wall
    wall = build(
        spec["blocks_along_length"],
        data["courses"],
        *_block_size(data),
        data["unit_weight"],
        return_blocks=m,
    )
    blocks, base = add_base(wall)
    widx = np.arange(wall.count)
    facade = sel.part(wall, "facade")
    loads: list[Load] = [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))]
    model = Model.build(blocks, _dry(data["friction"], a), [Support([base])], loads, name=name)
    if both:
        monitor = _top_centre(blocks, facade)
    else:
        corner = (wall.upper[facade, 0].max(), wall.upper[facade, 1].max())
        monitor = _nearest(blocks, facade, corner)
    mechanism = "vertical-axis" if both else "diagonal"
    extra = {"restraint": "return-walls", "return_blocks": m, "facade": facade}
    return _table2_case(spec, model, monitor, widx, mechanism, extra)


def _restrepo_velez(spec: dict, data: dict, a: Assumptions) -> PaperCase:
    name = spec["name"]
    if a.restraint == "return-walls":
        if name not in RETURN_WALL_CASES:
            raise ValueError(
                f"restraint='return-walls' rebuilds {', '.join(RETURN_WALL_CASES)}; "
                f"{name} ({spec['setup']}) has no such reading"
            )
        return _restrepo_velez_as_built(spec, data, a)
    n = spec["blocks_along_length"]
    ha, hb, hs = _block_size(data)
    wall = running_bond_wall(n, data["courses"], ha, hb, hs, data["unit_weight"])
    setup = spec["setup"]
    loads: list = [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))]
    extra: dict = {}
    if "openings" in setup:
        pier = 4 if name == "S23" else 2
        # half-pier offsets of the running bond: cut whole blocks of the even courses
        rects = _openings(n, a, pier, hb, ha)
        wall = openings_with_lintels(wall, rects, ha)
        extra["openings"] = rects
    blocks, base = add_base(wall)
    widx = np.arange(wall.count)
    supports = [Support([base])]
    if "timber beams" in setup:
        mechanism = "hinge"
        course = sel.course(wall, a.s32_beam_course - 1)
        # eleven beams evenly along the wall, each on the block under it, at the top face
        length = wall.upper[:, 0].max()
        x_beams = (np.arange(spec["beam_count"]) + 0.5) * length / spec["beam_count"]
        xc = wall.centres[course, 0]
        half = wall.sizes[course, 0] / 2
        under = course[np.argmax((np.abs(x_beams[:, None] - xc[None, :]) <= half[None]), axis=1)]
        offsets = np.zeros((under.size, 3))
        offsets[:, 0] = x_beams - wall.centres[under, 0]
        offsets[:, 1] = wall.sizes[under, 1] / 2
        P = spec["beam_load_each"]
        for blk, off in zip(under, offsets, strict=True):
            loads.append(PointLoad([blk], (0.0, -P, 0.0), tuple(off)))
            loads.append(PointLoad([blk], (0.0, 0.0, P), tuple(off), live=True))
        if a.s32_beams_hold:
            supports.append(Support(np.unique(under), ["u3"]))
        if a.s32_top_restrained:
            supports.append(Support(sel.edge(wall, "top"), ["u3"]))
        extra["beams_on_course"] = a.s32_beam_course
        monitor = _top_centre(blocks, widx)
    elif "both edges" in setup:
        mechanism = "vertical-axis"
        for side in ("left", "right"):
            supports.append(Support(sel.column(wall, side), list(a.column_dofs_table2)))
        monitor = _top_centre(blocks, widx)
    else:
        mechanism = "diagonal"
        supports.append(Support(sel.column(wall, "left"), list(a.column_dofs_table2)))
        monitor = _nearest(blocks, widx, (wall.upper[:, 0].max(), wall.upper[:, 1].max()))
    model = Model.build(blocks, _dry(data["friction"], a), supports, loads, name=name)
    extra["restraint"] = "columns"
    return _table2_case(spec, model, monitor, widx, mechanism, extra)


def _table2_case(
    spec: dict, model: Model, monitor: int, wall: np.ndarray, mechanism: str, extra: dict
) -> PaperCase:
    """A Table 2 case: lambda against the test, the out-of-plane u3 of ``monitor`` on the curve."""
    extra = {"lambda_test": spec["lambda_test"], **extra}
    return PaperCase(
        spec["name"],
        "2",
        model,
        spec["lambda_dem_paper"],
        spec["lambda_test"],
        "lambda",
        (monitor, "u3"),
        wall,
        mechanism,
        extra,
    )


# --------------------------------------------------------------------------- Table 3
def _support_strips(wall: Blocks, edges: Sequence[str], width: float) -> tuple[Blocks, np.ndarray]:
    """Rigid strips ``width`` wide behind the leeward face (+z, where the pressure pushes the
    wall) along each supported edge, and a slab under the bottom course that carries the
    weight: the wall bears on them through dry contacts, free to turn about the support lines
    and to lift off. Returns the blocks (wall first) and the indices of the supports."""
    lo, hi = wall.lower.min(axis=0), wall.upper.max(axis=0)
    depth = float(hi[2] - lo[2])
    behind = (hi[2], hi[2] + depth)
    # horizontal strips span the length; vertical ones stop short of them (no overlap)
    y0 = lo[1] + width if "bottom" in edges else lo[1]
    y1 = hi[1] - width if "top" in edges else hi[1]
    boxes = {
        "bottom": ((lo[0], lo[1], behind[0]), (hi[0], lo[1] + width, behind[1])),
        "top": ((lo[0], hi[1] - width, behind[0]), (hi[0], hi[1], behind[1])),
        "left": ((lo[0], y0, behind[0]), (lo[0] + width, y1, behind[1])),
        "right": ((hi[0] - width, y0, behind[0]), (hi[0], y1, behind[1])),
    }
    lower = [boxes[e][0] for e in edges]
    upper = [boxes[e][1] for e in edges]
    course = float(np.median(wall.sizes[:, 1]))
    lower.append((lo[0], lo[1] - course, lo[2]))  # the slab under the bottom course
    upper.append((hi[0], lo[1], hi[2]))
    strips = Blocks.from_boxes(np.array(lower), np.array(upper), 0.0)
    return Blocks.concatenate(wall, strips), wall.count + np.arange(strips.count)


def _chee_liang(spec: dict, data: dict, a: Assumptions) -> PaperCase:
    wall = running_bond_wall_of_size(
        spec["length"],
        spec["height"],
        *_block_size(data),
        a.brick_unit_weight,
        joint=data["joint_thickness"],
    )
    widx = np.arange(wall.count)
    restraint = spec["supports"]
    edges: list[sel.Edge] = ["bottom", "left", "right", "top"]
    if "top edge free" in restraint:
        edges.remove("top")
    elif "left edge free" in restraint:
        edges.remove("left")
    material = InterfaceMaterial(
        kn=data["kn"],
        kt=data["kt"],
        friction=data["friction"],
        tensile_strength=data["tensile_strength"],
    )
    blocks, overrides = wall, []
    if a.simple_support == "strips":
        blocks, strips = _support_strips(wall, edges, a.support_strip_width)
        supports = [Support(strips)]
        contact = InterfaceMaterial(kn=data["kn"], kt=data["kt"], friction=data["friction"])
        overrides = [(strips, contact)]
    else:
        supports = [Support(sel.edge(wall, "bottom"), ["u1", "u2", *a.simple_support_dofs])]
        supports += [Support(sel.edge(wall, e), list(a.simple_support_dofs)) for e in edges[1:]]
    model = Model.build(
        blocks,
        material,
        supports,
        loads=[SelfWeight(), Pressure(1.0, axis=2, sign=1)],
        name=spec["name"],
        material_overrides=overrides,
    )
    lo, hi = wall.lower.min(axis=0), wall.upper.max(axis=0)
    if len(edges) == 4:
        point, mechanism = ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2), "four-sided"
    elif "top" not in edges:
        point, mechanism = ((lo[0] + hi[0]) / 2, hi[1]), "three-sided"
    else:
        point, mechanism = (lo[0], (lo[1] + hi[1]) / 2), "three-sided"
    tests = spec["pressure_tests"]
    return PaperCase(
        spec["name"],
        "3",
        model,
        spec["pressure_dem_paper"],
        float(np.mean(tests)),
        "Pa",
        (_nearest(wall, widx, point), "u3"),
        widx,
        mechanism,
        {"pressure_tests": list(tests), "supported_edges": edges},
    )


# --------------------------------------------------------------------------- registry
def _specs() -> dict[str, tuple[str, dict, dict]]:
    data = reference_data()
    out: dict[str, tuple[str, dict, dict]] = {}
    for spec in data["orduna_lourenco"]["case"]:
        out[spec["name"]] = ("1", spec, data["orduna_lourenco"])
    for spec in data["restrepo_velez"]["specimen"]:
        out[spec["name"]] = ("2", spec, data["restrepo_velez"])
    for spec in data["chee_liang"]["wall"]:
        out[spec["name"]] = ("3", spec, data["chee_liang"])
    return out


def case_names(table: str | None = None) -> list[str]:
    """Names of the cases in the paper's order (``OL1``, ..., ``S11``, ..., ``2-3``, ...)."""
    return [k for k, (t, _, _) in _specs().items() if table is None or t == str(table)]


def build_case(name: str, assumptions: Assumptions | None = None, **changes) -> PaperCase:
    """Build one case; ``changes`` override fields of :class:`Assumptions` (sensitivity)."""
    specs = _specs()
    if name not in specs:
        raise ValueError(f"unknown case {name!r}; the cases are {', '.join(specs)}")
    a = replace(assumptions or Assumptions(), **changes)
    table, spec, data = specs[name]
    if a.restraint != "columns" and table != "2":
        raise ValueError(
            f"restraint={a.restraint!r} rebuilds {', '.join(RETURN_WALL_CASES)}; "
            f"{name} (Table {table}) has no such reading"
        )
    builder = {"1": _orduna_lourenco, "2": _restrepo_velez, "3": _chee_liang}[table]
    return builder(spec, data, a)


def all_cases(assumptions: Assumptions | None = None) -> list[PaperCase]:
    return [build_case(n, assumptions) for n in case_names()]


__all__ = [
    "RESTRAINTS",
    "RETURN_WALL_CASES",
    "Assumptions",
    "PaperCase",
    "all_cases",
    "build_case",
    "case_names",
    "default_return_blocks",
    "reference_data",
]
