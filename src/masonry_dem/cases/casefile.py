"""Case files: a TOML description of a scene (geometry, material, supports, loads, analysis).

The schema is documented in the README ("Case files") and checked by :mod:`.schema` before
anything is built: unknown keys, values of the wrong type and values out of range are errors
(:class:`~masonry_dem.cases.schema.CaseError`, a ValueError) naming the file, the table path
and the value. A new builder is one line in ``_BUILDERS``: the schema reads its signature.
"""

from __future__ import annotations

import inspect
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import MISSING, dataclass, fields
from importlib import resources
from pathlib import Path
from typing import Any, Literal, cast, get_args

import numpy as np
from numpy.typing import NDArray

from masonry_dem._toml import tomllib
from masonry_dem._validation import plain
from masonry_dem.cases.schema import CaseError, check_case, located
from masonry_dem.geometry import builders, plans, specimens
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.model import (
    LAW_OPTIONS,
    LOAD_TYPES,
    DofName,
    InterfaceMaterial,
    Load,
    Model,
    Monitor,
    Support,
)
from masonry_dem.solvers.incremental import DisplacementControl, StaticSettings
from masonry_dem.solvers.static.stages import Stage, as_stages, plan_stages

DEFAULT_CASE = "default_wall.toml"
AnalysisMethod = Literal["pushover", "limit"]
ANALYSIS_METHODS: tuple[str, ...] = get_args(AnalysisMethod)
LIMIT_OPTIONS = ("associative", "grid", "backend", "time_limit", "start")

_BUILDERS = {
    "running_bond_wall": builders.running_bond_wall,
    "running_bond_wall_of_size": builders.running_bond_wall_of_size,
    "stack_bond_column": builders.stack_bond_column,
    "single_block": builders.single_block,
    "boxes": builders.boxes,
    "l_wall": plans.l_wall,
    "t_wall": plans.t_wall,
    "u_wall": plans.u_wall,
    "box_wall": plans.box_wall,
    "shear_wall": specimens.shear_wall,
}
_GEOMETRY_EXTRA = {"builder", "base", "openings", "lintels", "top_beam"}


@dataclass(frozen=True)
class Case:
    """A scene ready to run: the model, the solver settings and the optional control.

    Made by :func:`load_case` from a case file (docs/case_files.md).

    Parameters
    ----------
    model : Model
        The wall, its supports and loads.
    settings : StaticSettings
        The static solver's settings (``[solver]``).
    control : DisplacementControl or None
        Displacement control (None: load control).
    monitor : (int, str) or None
        (block, DOF name) whose displacement the pushover curve records (None: the largest
        block translation).
    source : str
        Where the case came from (a path, or ``bundled:<name>``).
    method : {"pushover", "limit"}, default "pushover"
        ``[analysis] method``: "pushover" (default) or "limit" (limit analysis).
    limit_options : dict, optional
        The options of the limit analysis (``associative``, ``grid``, ``backend``,
        ``time_limit``, ``start``).
    stages : tuple of Stage, optional
        The loading stages of ``[[stages]]`` (None: one stage, the model as it is), for
        ``pushover(case.model, case.settings, stages=case.stages)``.

    Examples
    --------
    >>> import masonry_dem as md
    >>> case = md.load_case()
    >>> case.source, case.method, case.model.blocks.count
    ('bundled:default_wall.toml', 'pushover', 46)
    """

    model: Model
    settings: StaticSettings
    control: DisplacementControl | None
    monitor: Monitor | None
    source: str
    #: ``[analysis] method``: "pushover" (default) or "limit" (limit analysis); the options of
    #: the limit analysis (``associative``, ``grid``, ``backend``) in ``limit_options``
    method: AnalysisMethod = "pushover"
    limit_options: dict[str, Any] | None = None
    #: ``[[stages]]``: the loading stages (None: one stage, the model as it is)
    stages: tuple[Stage, ...] | None = None


def _unknown(section: str, given: dict[str, Any], allowed: set[str]) -> None:
    extra = sorted(set(given) - allowed)
    if extra:
        shown = [k if len(k) <= 60 else f"{k[:57]}... ({len(k)} characters)" for k in extra]
        raise ValueError(
            f"case file [{section}]: unknown key(s) {shown}; allowed: {sorted(allowed)}"
        )


def _require(section: str, data: dict[str, Any], key: str) -> Any:
    if key not in data:
        raise ValueError(f"case file [{section}]: missing key {key!r}")
    return data[key]


def build_blocks(
    geometry: dict[str, Any],
) -> tuple[Blocks, int | None, NDArray[np.bool_]]:
    """Blocks of the scene, the index of the base slab (or None) and the wall-block mask."""
    builder = _require("geometry", geometry, "builder")
    if builder not in _BUILDERS:
        raise ValueError(
            f"case file [geometry] builder must be one of {sorted(_BUILDERS)}, got {builder!r}"
        )
    params = {k: v for k, v in geometry.items() if k not in _GEOMETRY_EXTRA}
    func: Any = _BUILDERS[builder]
    allowed = set(inspect.signature(func).parameters)
    _unknown("geometry", params, allowed)
    lintels = geometry.get("lintels", False)
    # walls that meet build their lintels over their facade_openings, in the facade alone
    facade = "facade_openings" in allowed
    if lintels and facade and geometry.get("openings"):
        raise ValueError(
            f"lintels = true with builder {builder!r}: give the openings as facade_openings "
            "(lintels are built in the facade alone; openings cut every wall)"
        )
    if lintels and not (geometry.get("openings") or (facade and params.get("facade_openings"))):
        raise ValueError(
            "lintels = true builds lintels over the openings, but none are given"
            + (" (facade_openings for walls that meet)" if facade else "")
        )
    if facade:
        params["lintels"] = lintels
    # a builder that cuts its own openings (the shear wall: out of the wall, not its beams)
    own_openings = "openings" in allowed
    if own_openings:
        params["openings"] = geometry.get("openings", ())
        params["lintels"] = lintels
    try:
        blocks = func(**params)
    except TypeError as exc:
        raise ValueError(f"case file [geometry] for builder {builder!r}: {exc}") from exc
    if geometry.get("openings") and not own_openings:
        blocks = builders.cut_openings(blocks, geometry["openings"], lintels=lintels)
    wall = np.ones(blocks.count, dtype=bool)
    base = None
    # a builder that builds its own slabs (the shear wall's beams) declares them, last, by
    # the selector that names each
    slabs: tuple[str, ...] = getattr(getattr(func, "parameter_class", None), "SLABS", ())
    if slabs:
        for key in ("base", "top_beam"):
            if geometry.get(key) not in (None, False):
                raise ValueError(
                    f"{key}: builder {builder!r} builds its own slabs "
                    f"({' and '.join(f'select = {name!r}' for name in slabs)}); leave it out"
                )
        wall[-len(slabs) :] = False
        if "base" in slabs:
            base = blocks.count - len(slabs) + slabs.index("base")
    if geometry.get("base", False):
        blocks, base = builders.add_base(blocks)
        wall = np.append(wall, False)
    if geometry.get("top_beam") is not None:  # the loading beam: select = "beam"
        blocks, _ = builders.add_top_beam(blocks, depth=geometry["top_beam"])
        wall = np.append(wall, False)
    return blocks, base, wall


def _split_wall_units(
    blocks: Blocks, wall: NDArray[np.bool_], base: int | None
) -> tuple[Blocks, NDArray[np.intp], NDArray[np.bool_], int | None]:
    """Every unit of the wall split at mid-length (``[unit_cracks]``): the blocks, the
    pairs of halves, the wall mask and the base's index in the new numbering (a split unit's
    halves take its place, so the blocks after it move on by the units split before them)."""
    split, pairs = specimens.split_units(blocks, np.flatnonzero(wall))
    moved = np.cumsum(1 + wall) - (1 + wall)  # each old block's first new index
    return split, pairs, np.repeat(wall, 1 + wall), None if base is None else int(moved[base])


def select_blocks(
    blocks: Blocks, spec: str | list[int], wall: np.ndarray, base: int | None
) -> np.ndarray:
    """Resolve a selector: ``base``, ``all``, ``column:left``, ``course:K``, ``edge:top``, a part
    of walls that meet (``facade``, ``return:left``, ``corner:left``, ...), or a list of block
    indices."""
    if isinstance(spec, list):
        idx = np.asarray(spec, dtype=np.int64)
        if idx.size == 0 or idx.min() < 0 or idx.max() >= blocks.count:
            raise ValueError(
                f"select: block indices must be in 0..{blocks.count - 1}, got {plain(spec)}"
            )
        return idx
    if spec == "base":
        if base is None:
            raise ValueError(
                'select = "base" but the geometry has no base (set [geometry].base = true)'
            )
        return np.array([base])
    if spec == "beam":  # the block neither of the wall nor the base: the loading beam
        beam = np.flatnonzero(~wall & (np.arange(blocks.count) != (-1 if base is None else base)))
        if beam.size != 1:
            raise ValueError(
                'select = "beam" but the geometry has no loading beam (set [geometry].top_beam '
                "= its depth in m)"
            )
        return beam
    if spec == "all":
        return np.flatnonzero(wall)
    kind, _, arg = str(spec).partition(":")
    if kind == "column":
        # the selectors check the words of a case file
        return sel.column(blocks, cast("Literal['left', 'right']", arg or "left"), among=wall)
    if kind == "course":
        try:
            k = int(arg)
        except ValueError:
            raise ValueError(f"select: course needs an integer, got {plain(spec)}") from None
        return sel.course(blocks, k, among=wall)
    if kind == "edge":
        return sel.edge(blocks, cast("sel.Edge", arg), among=wall)
    if spec in sel.PARTS:
        return sel.part(blocks, str(spec), among=wall)
    raise ValueError(
        f"select must be 'base', 'beam', 'all', 'column:left|right', 'course:K', 'edge:NAME', "
        "a part of "
        f"walls that meet ({', '.join(sel.PARTS)}) or a list of block indices, got {plain(spec)}"
    )


def _load(
    spec: dict[str, Any], blocks: Blocks, wall: NDArray[np.bool_], base: int | None, k: int
) -> Load:
    """The load of a ``[[loads]]`` table: its keys are the fields of the load of its ``type``
    (:data:`~masonry_dem.model.LOAD_TYPES`), with ``select`` for the blocks it acts on (default:
    the wall, where the load may act on all blocks); arrays become tuples."""
    section = f"loads[{k}]"
    kind = _require(section, spec, "type")
    if kind not in LOAD_TYPES:
        raise ValueError(
            f"case file [{section}] type must be one of {', '.join(LOAD_TYPES)}, got {kind!r}"
        )
    load = {f.name: f for f in fields(LOAD_TYPES[kind])}
    keys = {"type", *load} - {"blocks"} | ({"select"} if "blocks" in load else set())
    _unknown(section, spec, keys)
    args: dict[str, Any] = {}
    for name, f in load.items():
        key = "select" if name == "blocks" else name
        if f.default is MISSING:
            value = _require(section, spec, key)
        elif key in spec:
            value = spec[key]
        elif name == "blocks":
            value = "all"
        else:
            continue
        if name == "blocks":
            value = select_blocks(blocks, value, wall, base)
        args[name] = tuple(value) if isinstance(value, list) else value
    return LOAD_TYPES[kind](**args)


def check_case_data(data: dict[str, Any], source: str = "<dict>", warn: bool = True) -> None:
    """Check a parsed case file against the schema without building anything: CaseError (a
    ValueError) naming ``source``, the table path and the value; ``warn``: log the values
    allowed but unusual (friction above 2)."""
    check_case(data, source, _BUILDERS, StaticSettings, warn=warn)


def case_from_dict(data: dict[str, Any], source: str = "<dict>") -> Case:
    """The scene of a parsed case file; raises CaseError (a ValueError) naming ``source``, the
    table path and the value for anything the schema or the builders refuse."""
    check_case_data(data, source)
    with _at(source, "[geometry]"):
        blocks, base, wall = build_blocks(data["geometry"])
    with _at(source, "[material]"):
        material = InterfaceMaterial(**data["material"])
    overrides = []
    if data.get("unit_cracks") is not None:  # every unit of the wall split at mid-length
        with _at(source, "[unit_cracks]"):
            crack = InterfaceMaterial(
                **data["unit_cracks"],
                **{name: getattr(material, name) for name in LAW_OPTIONS},
            )
        blocks, pairs, wall, base = _split_wall_units(blocks, wall, base)
        overrides.append((pairs, crack))
    supports = []
    for k, spec in enumerate(data.get("supports", [])):
        with _at(source, f"[supports][{k}].select"):
            idx = select_blocks(blocks, spec["select"], wall, base)
        supports.append(Support(idx, spec.get("dofs", "all"), spec.get("settles_with_wall", False)))
    loads = []
    for k, spec in enumerate(data.get("loads", [{"type": "self_weight"}])):
        with _at(source, f"[loads][{k}]"):
            loads.append(_load(spec, blocks, wall, base, k))
            loads[-1].vector(blocks)  # what it refuses is named here, not as a support
    analysis = dict(data.get("analysis", {}))
    if analysis.get("method") == "limit":
        _refuse_pushover_keys(analysis, source)
    control_spec = analysis.pop("control", None)
    monitor_spec = analysis.pop("monitor", None)
    method = analysis.pop("method", "pushover")
    if method not in ANALYSIS_METHODS:
        raise ValueError(
            f"case file [analysis] method must be one of {ANALYSIS_METHODS}, got {method!r}"
        )
    limit_options = {k: analysis.pop(k) for k in LIMIT_OPTIONS if k in analysis}
    if limit_options and method != "limit":
        key, value = next(iter(limit_options.items()))
        raise CaseError(
            f"case file {source}: [analysis].{key} = {plain(value)}: an option of the limit "
            f'analysis; it needs method = "limit" in [analysis] (method is "{method}")'
        )
    if "start" in limit_options and limit_options.get("associative") is not False:
        raise CaseError(
            f"case file {source}: [analysis].start = {plain(limit_options['start'])}: the "
            "starting state of the non-associative analysis; it needs associative = false "
            "in [analysis]"
        )
    with _at(source, "[analysis]"):
        settings = StaticSettings(**analysis)
    with _at(source, "[geometry]"):  # blocks that overlap are the geometry's fault
        interfaces = detect_interfaces(blocks)
    with _at(source, "[supports]"):  # what Model.build refuses is a mechanism or a support
        model = Model.build(
            blocks,
            material,
            supports,
            loads,
            name=str(data.get("name", Path(source).stem)),
            interfaces=interfaces,
            interface_overrides=overrides,
        )
    stages = _stages(data, source, model, blocks, wall, base, control_spec, method)
    control = None
    if control_spec is not None:
        with _at(source, "[analysis].control.block"):
            model.dof_index(control_spec["block"], control_spec["dof"])
        with _at(source, "[analysis].control"):
            control = DisplacementControl(**control_spec)
    monitor = None
    if monitor_spec is not None:
        with _at(source, "[analysis].monitor.block"):
            model.dof_index(monitor_spec["block"], monitor_spec["dof"])
        monitor = (int(monitor_spec["block"]), cast(DofName, monitor_spec["dof"]))  # checked above
    return Case(
        model,
        settings,
        control,
        monitor,
        source,
        cast(AnalysisMethod, method),
        limit_options,
        stages,
    )


def _stages(
    data: dict[str, Any],
    source: str,
    model: Model,
    blocks: Blocks,
    wall: NDArray[np.bool_],
    base: int | None,
    control_spec: Any,
    method: str,
) -> tuple[Stage, ...] | None:
    """The loading stages of ``[[stages]]`` (None without it), each with its own
    ``[[stages.loads]]``, ``[[stages.supports]]`` and ``[stages.control]``, checked on the
    model (a control on a held DOF, every DOF held: named)."""
    specs = data.get("stages")
    if specs is None:
        return None
    if method != "pushover":
        raise CaseError(
            f"case file {source}: [[stages]] are loading stages of the pushover; method = "
            f'"{method}" in [analysis] runs none'
        )
    if control_spec is not None:
        raise CaseError(
            f"case file {source}: [analysis].control = {plain(control_spec)} with [[stages]]: "
            "each stage names its own control ([stages.control])"
        )
    stages = []
    for k, spec in enumerate(specs):
        with _at(source, f"[stages][{k}]"):
            supports = [
                Support(
                    select_blocks(blocks, sup["select"], wall, base),
                    sup.get("dofs", "all"),
                    sup.get("settles_with_wall", False),
                )
                for sup in spec.get("supports") or []
            ]
            loads = [
                _load(ld, blocks, wall, base, j) for j, ld in enumerate(spec.get("loads") or [])
            ]
            control = spec.get("control")
            stages.append(
                Stage(
                    loads=loads,
                    supports=supports,
                    control=None if control is None else DisplacementControl(**control),
                    name=spec.get("name") or "",
                )
            )
    with _at(source, "[stages]"):  # checked here; planned again, with warnings, at the run
        plan_stages(model, as_stages(stages), warn=False)
    return tuple(stages)


def _refuse_pushover_keys(analysis: dict[str, Any], source: str) -> None:
    """``method = "limit"`` uses only ``method`` and :data:`LIMIT_OPTIONS` of
    ``[analysis]``: a pushover key there (``control``, ``tolerance``, ...) would be silently
    ignored, and the user would believe it acted."""
    used = ("method", *LIMIT_OPTIONS)
    for key, value in analysis.items():
        if key not in used:
            raise CaseError(
                f"case file {source}: [analysis].{key} = {plain(value)}: not used by "
                f'method = "limit"; with it [analysis] takes only {", ".join(used)}'
            )


@contextmanager
def _at(source: str, where: str) -> Iterator[None]:
    """Name the file and the table path in what the builders refuse."""
    try:
        yield
    except CaseError:
        raise
    except (ValueError, TypeError) as exc:
        raise located(source, where)(exc) from exc


def load_case(path: str | Path | None = None) -> Case:
    """Read a case file; with no path, the bundled default wall.

    Parameters
    ----------
    path : str or pathlib.Path, optional
        The TOML case file (docs/case_files.md); None: the bundled default wall.

    Returns
    -------
    Case
        The model, settings, control, monitor and method the file describes.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    CaseError
        A ValueError naming the file: it is a folder, unreadable, not UTF-8, not TOML, or
        refused by the schema (the table path, the value and what is allowed named).

    Examples
    --------
    >>> import masonry_dem as md
    >>> case = md.load_case()  # the bundled default wall
    >>> case.model.name
    'default wall: dry running-bond panel held on the left edge'
    >>> md.load_case("no_such_case.toml")
    Traceback (most recent call last):
    ...
    FileNotFoundError: case file not found: no_such_case.toml
    """
    data, source = read_case_data(path)
    return case_from_dict(data, source=source)


def read_case_data(path: str | Path | None = None) -> tuple[dict[str, Any], str]:
    """The parsed TOML of a case file (no path: the bundled default wall) and its source
    name, not yet checked by the schema; errors as :func:`load_case`."""
    if path is None:
        text = resources.files("masonry_dem.cases").joinpath("data", DEFAULT_CASE).read_text()
        return tomllib.loads(text), f"bundled:{DEFAULT_CASE}"
    p = Path(path)
    if p.is_dir():
        raise CaseError(f"case file {p} is a folder; give the TOML file in it")
    if not p.exists():
        raise FileNotFoundError(f"case file not found: {p}")
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise CaseError(f"case file {p} cannot be read: {exc.strerror or exc}") from exc
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CaseError(
            f"case file {p} is not UTF-8 text (byte {exc.start}: {raw[exc.start : exc.start + 1]!r}); "
            "save it as UTF-8"
        ) from exc
    # a byte-order mark, which some editors write, is no TOML statement: the text after it is
    text = text.removeprefix("\ufeff")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"case file {p} is not valid TOML: {exc}") from exc
    except RecursionError as exc:  # the parser recurses once per nested array or table
        raise CaseError(
            f"case file {p} nests arrays or inline tables too deeply to be read; a case file "
            "needs two levels (a list of [x, y, z] corners)"
        ) from exc
    return data, str(p)
