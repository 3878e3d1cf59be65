"""The schema of a case file, checked with pydantic in strict mode before anything is built.

Strict: a boolean is ``true`` or ``false`` (never the text "no"), an integer a whole number (never
15.7 or "3"), a number a number (never "1e9"); unknown keys are errors. Every physical value has
a range with its unit and the reason for its bounds (:data:`RANGES`); a value outside it is an
error naming the file, the table path (``[loads][1].live``), the value as written, the range and
the unit.

The tables whose keys depend on a choice read registries, so that a new builder, load type or
analysis key is one line elsewhere: the geometry keys are the parameters of the builder function
named by ``builder`` (``casefile._BUILDERS``, passed in), typed by :data:`RANGES` or else by the
function's annotations; ``[analysis]`` holds the fields of ``StaticSettings`` plus
:data:`ANALYSIS_EXTRA`; ``[[loads]]`` tables are :data:`LOAD_TABLES` by ``type``.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import MISSING, fields
from typing import Annotated, Any

from pydantic import AfterValidator, BaseModel, ConfigDict, ValidationError, create_model
from pydantic_core import PydanticCustomError

from masonry_dem._validation import plain
from masonry_dem.cases.ranges import COORDINATE, RANGES, Range
from masonry_dem.model import LAW_OPTIONS, InterfaceMaterial, check_tension_cap

log = logging.getLogger(__name__)

__all__ = [
    "ANALYSIS_EXTRA",
    "CaseError",
    "LOAD_TABLES",
    "RANGES",
    "Range",
    "check_case",
]


class CaseError(ValueError):
    """A case file that cannot be read as written; the message names the file, the table
    path, the value, and what is allowed."""


DOF_NAMES = ("u1", "u2", "u3", "w1", "w2", "w3")
DOF_GROUPS = ("all", "translations", "rotations", "in_plane", "out_of_plane")


# ------------------------------------------------------------------------- field types
def _number(key: str) -> Any:
    rng = RANGES[key]
    base = int if rng.integer else float
    return Annotated[base, AfterValidator(rng.check)]


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise PydanticCustomError("range", "must be a finite number")
    return value


def _vector(key: str, rng: Range | None = None, nonzero: bool = False) -> Any:
    def check(v: list[float]) -> list[float]:
        if len(v) != 3:
            raise PydanticCustomError("shape", "must hold 3 numbers [x, y, z]")
        for x in v:
            if rng is not None:
                rng.check(x)
            else:
                _finite(x)
        if nonzero and not any(v):
            raise PydanticCustomError("range", "must not be the zero vector")
        return v

    return Annotated[list[float], AfterValidator(check)]


def _selector(value: Any) -> Any:
    """``base``, ``all``, ``column:left``... or a list of block indices (whole numbers >= 0)."""
    if isinstance(value, str):
        return value
    if isinstance(value, list) and value:
        for x in value:
            if isinstance(x, bool) or not isinstance(x, int) or x < 0:
                raise PydanticCustomError(
                    "selector",
                    "must list block indices as whole numbers >= 0, got {item}",
                    {"item": plain(x)},
                )
        return value
    raise PydanticCustomError(
        "selector",
        "must be a selector in quotes (base | all | column:left | column:right | course:K | "
        "edge:NAME) or a non-empty array of block indices",
    )


def _dofs(value: Any) -> Any:
    names = [value] if isinstance(value, str) else value
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise PydanticCustomError(
            "dofs", "must be a DOF group in quotes or an array of DOF names in quotes"
        )
    for n in names:
        if n not in DOF_GROUPS and n not in DOF_NAMES:
            raise PydanticCustomError(
                "dofs",
                "names no DOF: {name} is none of the groups {groups} or DOFs {dofs}",
                {"name": plain(n), "groups": ", ".join(DOF_GROUPS), "dofs": ", ".join(DOF_NAMES)},
            )
    return value


def _choice(options: tuple[str, ...]) -> Any:
    def check(v: str) -> str:
        if v not in options:
            raise PydanticCustomError(
                "choice", "must be one of {options}", {"options": ", ".join(options)}
            )
        return v

    return Annotated[str, AfterValidator(check)]


def _not_zero(v: float) -> float:
    if v == 0:
        raise PydanticCustomError("range", "must not be 0 (a displacement to reach)")
    return v


def _sign(v: int) -> int:
    if v not in (-1, 1):
        raise PydanticCustomError("range", "must be 1 or -1 (towards +e[axis] or -e[axis])")
    return v


_STRICT = ConfigDict(strict=True, extra="forbid")
_SELECT = Annotated[Any, AfterValidator(_selector)]
_OPENING = Annotated[list[float], AfterValidator(lambda v: _opening(v))]


def _depth(v: float) -> float:
    """A loading beam's depth [m]: a finite number > 0."""
    if not math.isfinite(v) or v <= 0:
        raise PydanticCustomError("depth", "must be a depth > 0 [m] (the loading beam's)")
    return v


def _opening(v: list[float]) -> list[float]:
    if len(v) != 4:
        raise PydanticCustomError("shape", "must hold 4 numbers [x_min, y_min, x_max, y_max]")
    for x in v:
        COORDINATE.check(x)
    return v


def _table(name: str, spec: Mapping[str, Any]) -> type[BaseModel]:
    """A strict pydantic model; ``spec``: key -> type, or (type, default)."""
    defs: dict[str, Any] = {k: (v if isinstance(v, tuple) else (v, ...)) for k, v in spec.items()}
    return create_model(name, __config__=_STRICT, **defs)  # type: ignore[call-overload]


def _by_annotation(key: str, annotation: Any) -> Any:
    """The type of a key known only by its annotation (a new builder's parameter)."""
    if key in RANGES:
        return _number(key)
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__", "")
    text = text.replace(" ", "")
    optional = text.endswith("|None") or text.startswith("None|")
    core = text.replace("|None", "").replace("None|", "")
    kind: Any = {
        "int": Annotated[int, AfterValidator(_finite)],
        "float": Annotated[float, AfterValidator(_finite)],
        "bool": bool,
        "str": str,
    }.get(core, Any)
    return kind | None if optional and kind is not Any else kind


TOP = _table(
    "CaseFile",
    {
        "name": (str, None),
        "description": (str, None),
        "geometry": dict,
        "material": dict,
        "supports": (list[dict], None),
        "loads": (list[dict], None),
        "analysis": (dict, None),
        "stages": (list[dict], None),
        "unit_cracks": (dict, None),
    },
)
_LAW = {name: (allowed, getattr(InterfaceMaterial, name)) for name, allowed in LAW_OPTIONS.items()}
MATERIAL = _table(
    "Material",
    {
        "kn": _number("kn"),
        "kt": _number("kt"),
        "friction": _number("friction"),
        "tensile_strength": (_number("tensile_strength"), 0.0),
        "cohesion": (_number("cohesion") | None, None),
        "alpha": (_number("alpha") | None, None),
        # the interface law's options
        **{name: (_choice(allowed), default) for name, (allowed, default) in _LAW.items()},
    },
)
SUPPORT = _table(
    "Support",
    {
        "select": _SELECT,
        "dofs": (Annotated[Any, AfterValidator(_dofs)], "all"),
        "settles_with_wall": (bool, False),
    },
)
_LIVE = (bool, None)
#: ``[[loads]]`` tables by ``type`` (the builders of the loads are in casefile)
LOAD_TABLES: dict[str, type[BaseModel]] = {
    "self_weight": _table("SelfWeightLoad", {"type": str, "live": _LIVE}),
    "weight_proportional": _table(
        "WeightProportionalLoad",
        {
            "type": str,
            "direction": (_vector("direction", nonzero=True), None),
            "live": _LIVE,
            "select": (_SELECT, None),
        },
    ),
    "pressure": _table(
        "PressureLoad",
        {
            "type": str,
            "value": _number("value"),
            "axis": (_number("axis"), 2),
            "sign": (Annotated[int, AfterValidator(_sign)], 1),
            "live": _LIVE,
            "select": (_SELECT, None),
        },
    ),
    "point": _table(
        "PointLoad",
        {
            "type": str,
            "select": _SELECT,
            "force": _vector("force", Range(-1e12, 1e12, "N", "a force on one block")),
            "offset": (_vector("offset", COORDINATE), None),
            "live": _LIVE,
        },
    ),
}
CONTROL = _table(
    "Control",
    {
        "block": _number("block"),
        "dof": _choice(DOF_NAMES),
        "target": Annotated[
            float, AfterValidator(RANGES["target"].check), AfterValidator(_not_zero)
        ],
        "steps": (_number("steps"), 50),
    },
)
MONITOR = _table("Monitor", {"block": _number("block"), "dof": _choice(DOF_NAMES)})
#: ``[[stages]]``: a loading stage, its loads and supports tables as the file's own
STAGE = _table(
    "Stage",
    {
        "name": (str, None),
        "loads": (list[dict], None),
        "supports": (list[dict], None),
        "control": (dict | None, None),
    },
)
#: ``[analysis] start`` of the non-associative limit analysis: the joints' elastic state
#: under the dead load, or the associative collapse (Gilbert et al. 2006); the solver's own
#: ``STARTS`` (a test keeps them equal; the schema does not import the solvers)
LIMIT_STARTS = ("elastic", "associative")
#: ``[analysis]`` keys that are not fields of StaticSettings: key -> (type, default)
ANALYSIS_EXTRA: dict[str, tuple[Any, Any]] = {
    "control": (dict | None, None),
    "monitor": (dict | None, None),
    # limit analysis instead of a pushover (``masonry-dem limit``): the method and its options
    "method": (_choice(("pushover", "limit")), "pushover"),
    "associative": (bool | None, None),
    "grid": (_number("grid") | None, None),
    "backend": (_choice(("highs", "clarabel")) | None, None),
    "time_limit": (_number("time_limit") | None, None),
    # the non-associative iteration's starting state (``limit_analysis.settings.STARTS``)
    "start": (_choice(LIMIT_STARTS) | None, None),
}


@functools.cache  # a pydantic model takes milliseconds to make: once per settings type
def _analysis_table(settings_type: type) -> type[BaseModel]:
    """The ``[analysis]`` table: every field of ``settings_type`` (StaticSettings), typed by
    :data:`RANGES` or its annotation, string options by the solver's own constants."""
    from masonry_dem.constitutive.law import TANGENT_METHODS

    choices: dict[str, Any] = {**LAW_OPTIONS, "tangent": TANGENT_METHODS}
    try:  # the solver's continuation options, wherever the solver package keeps them
        from masonry_dem.solvers import incremental

        choices["continuation"] = tuple(incremental.CONTINUATION)
    except (ImportError, AttributeError):  # pragma: no cover - a renamed constant
        pass
    spec: dict[str, Any] = {}
    for f in fields(settings_type):
        if f.name in choices:
            kind = _choice(choices[f.name])
        elif f.name not in RANGES and "most" in f.metadata:  # a count() field: its own range
            rng = Range(f.metadata["least"], f.metadata["most"], "", "a count", integer=True)
            kind = Annotated[int, AfterValidator(rng.check)]
        else:
            kind = _by_annotation(f.name, f.type)
        default = None if f.default is MISSING else f.default
        spec[f.name] = (kind | None if default is None and kind is not Any else kind, default)
    spec.update(ANALYSIS_EXTRA)
    return _table("Analysis", spec)


@functools.cache  # once per builder: a sweep checks a case per point
def _geometry_table(builder: str, func: Callable) -> type[BaseModel]:
    spec: dict[str, Any] = {
        "builder": str,
        "base": (bool, False),
        "openings": (list[_OPENING] | None, None),
        "lintels": (bool, False),
        "top_beam": (Annotated[float, AfterValidator(_depth)] | None, None),
    }
    for name, p in inspect.signature(func).parameters.items():
        kind = _by_annotation(name, p.annotation)
        if name in ("origin",):
            kind = _vector(name, COORDINATE)
        elif name in ("lower", "upper"):
            kind = list.__class_getitem__(_vector(name, COORDINATE))
        has_default = p.default is not inspect.Parameter.empty
        spec[name] = (kind, p.default) if has_default else kind
    return _table(f"Geometry_{builder}", spec)


# --------------------------------------------------------------------------- messages
_KIND = {
    bool: "a boolean",
    int: "a whole number",
    float: "a number",
    str: "text",
    list: "an array",
    dict: "a table",
}
_EXPECT = {
    "bool_type": "must be true or false (a boolean, without quotes)",
    "int_type": "must be a whole number (no decimal point, no quotes)",
    "float_type": "must be a number (without quotes)",
    "string_type": "must be text in quotes",
    "list_type": "must be an array [ ... ]",
    "dict_type": "must be a table",
    "model_type": "must be a table",
    "model_attributes_type": "must be a table",
}


def _path(loc: tuple) -> str:
    """``('loads', 1, 'live')`` -> ``[loads][1].live``: tables in brackets, then keys."""
    out = ""
    dotted = False
    for item in loc:
        if isinstance(item, int):
            out += f"[{item}]"
        elif not dotted and item in (
            "geometry",
            "material",
            "supports",
            "loads",
            "analysis",
            "stages",
        ):
            out += f"[{item}]"
            dotted = True
        else:
            key = _short(str(item))
            out += f".{key}" if out else key
            dotted = True
    return out


def _short(key: str, most: int = 60) -> str:
    """A key as it is shown in a message: a long one cut, with its length (a key of 10^5
    characters was echoed whole)."""
    return key if len(key) <= most else f"{key[: most - 3]}... ({len(key)} characters)"


def _message(err: Mapping[str, Any], table: tuple, allowed: list[str]) -> str:
    loc = table + tuple(err["loc"])
    where = _path(loc)
    kind = err["type"]
    value = err.get("input")
    if kind == "extra_forbidden":
        key = str(loc[-1])
        close = [a for a in allowed if a.lower() == key.lower()]
        if len(key) <= 100:  # difflib is quadratic in the key's length
            close = close or difflib.get_close_matches(key.lower(), allowed, n=1)
        top_table = not table and isinstance(value, (dict, list))  # a [table] of the file
        hint = f" (did you mean {f'[{close[0]}]' if top_table else close[0]}?)" if close else ""
        if table == ("analysis",) and key in LAW_OPTIONS:
            hint = f" ({key} is a property of the interface law: [material] {key})"
        if top_table:
            where = f"[{_short(key)}]"
        return f"{where}: unknown key{hint}; allowed: {', '.join(sorted(allowed))}"
    if kind == "missing":
        return f"{where} is missing"
    got = _KIND.get(type(value), type(value).__name__)
    if kind in _EXPECT:
        return f"{where} = {plain(value)}: {_EXPECT[kind]}, not {got}"
    if kind in ("too_short", "too_long"):
        return f"{where} = {plain(value)}: {err['msg'].lower()}"
    return f"{where} = {plain(value)}: {err['msg']}"


def _validate(
    model: type[BaseModel], data: Any, table: tuple, source: str, errors: list[str]
) -> BaseModel | None:
    if not isinstance(data, dict):
        got = _KIND.get(type(data), type(data).__name__)
        errors.append(f"{_path(table)} = {plain(data)}: must be a table, not {got}")
        return None
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        allowed = list(model.model_fields)
        # a misspelled key first: it explains the "missing" one
        found = sorted(exc.errors(), key=lambda e: e["type"] != "extra_forbidden")
        errors.extend(_message(e, table, allowed) for e in found)
        return None


def check_case(
    data: Any,
    source: str,
    builders: Mapping[str, Any],
    settings_type: type,
    warn: bool = True,
) -> None:
    """Raise :class:`CaseError` for the first fault of ``data`` (a parsed case file) against
    the schema, naming ``source`` and the table path; log a warning for values allowed but
    unusual (friction above 2) when ``warn`` (a check ahead of the load that repeats it
    passes False, so the warning is logged once)."""
    errors: list[str] = []
    top = _validate(TOP, data, (), source, errors)
    if top is not None:
        builder = data["geometry"].get("builder")
        if not isinstance(builder, str) or builder not in builders:
            errors.append(
                f"[geometry].builder = {plain(builder)}: must be one of "
                f"{', '.join(sorted(builders))}"
            )
        else:
            _validate(
                _geometry_table(builder, builders[builder]),
                data["geometry"],
                ("geometry",),
                source,
                errors,
            )
        material = _validate(MATERIAL, data["material"], ("material",), source, errors)
        if material is not None:
            _check_tension_cap(data["material"], errors)
        if data.get("unit_cracks") is not None:
            cracks = data["unit_cracks"]
            law = sorted(set(cracks) & set(LAW_OPTIONS))
            if law:
                errors.append(
                    f"[unit_cracks].{law[0]}: the interface law's options are the model's, "
                    "given in [material] only"
                )
            elif _validate(MATERIAL, cracks, ("unit_cracks",), source, errors) is not None:
                _check_tension_cap(cracks, errors, "[unit_cracks]")
        _check_supports_and_loads(data, (), source, errors)
        for k, stage in enumerate(data.get("stages") or []):
            if _validate(STAGE, stage, ("stages", k), source, errors) is not None:
                _check_supports_and_loads(stage, ("stages", k), source, errors)
                if stage.get("control") is not None:
                    where = ("stages", k, "control")
                    _validate(CONTROL, stage["control"], where, source, errors)
        if "analysis" in data:
            analysis = _validate(
                _analysis_table(settings_type), data["analysis"], ("analysis",), source, errors
            )
            if analysis is not None:
                for key, table in (("control", CONTROL), ("monitor", MONITOR)):
                    if data["analysis"].get(key) is not None:
                        _validate(table, data["analysis"][key], ("analysis", key), source, errors)
        if material is not None and warn:
            _warn_above(data["material"], "[material]", source)
    if errors:
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise CaseError(f"case file {source}: {errors[0]}{more}")


def _check_supports_and_loads(
    data: Mapping[str, Any], table: tuple, source: str, errors: list[str]
) -> None:
    """The ``[[supports]]`` and ``[[loads]]`` tables of ``data`` (the file, or a stage of it
    at ``table``) against their schemas."""
    for k, spec in enumerate(data.get("supports") or []):
        _validate(SUPPORT, spec, (*table, "supports", k), source, errors)
    for k, spec in enumerate(data.get("loads") or []):
        kind = spec.get("type") if isinstance(spec, dict) else None
        if not isinstance(kind, str) or kind not in LOAD_TABLES:
            where = _path((*table, "loads", k, "type"))
            errors.append(f"{where} = {plain(kind)}: must be one of {', '.join(LOAD_TABLES)}")
            continue
        _validate(LOAD_TABLES[kind], spec, (*table, "loads", k), source, errors)


def _check_tension_cap(
    material: Mapping[str, Any], errors: list[str], table: str = "[material]"
) -> None:
    """The cross-field rule of ``[material]``: a cohesion given caps the tensile strength,
    ``friction * tensile_strength <= cohesion``."""
    if material.get("cohesion") is None:
        return
    try:
        check_tension_cap(
            float(material["friction"]),
            float(material.get("tensile_strength", 0.0)),
            float(material["cohesion"]),
        )
    except ValueError as exc:
        errors.append(f"{table}: {exc}")


def _warn_above(table: Mapping[str, Any], where: str, source: str) -> None:
    for key, value in table.items():
        rng = RANGES.get(key)
        if rng is not None and rng.warn_above is not None and value > rng.warn_above:
            log.warning("case file %s: %s.%s = %s: %s", source, where, key, plain(value), rng.warn)


def located(source: str, where: str) -> Callable[[Exception], CaseError]:
    """A CaseError naming the file and the table path for an error raised while building."""

    def wrap(exc: Exception) -> CaseError:
        return CaseError(f"case file {source}: {where}: {exc}")

    return wrap
