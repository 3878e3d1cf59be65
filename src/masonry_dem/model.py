"""The frozen analysis model: blocks, interfaces, interface materials, supports and loads.

Block DOFs q = (u1, u2, u3, w1, w2, w3) at the block centre. Loads are generalised forces at
block centres: ``dead`` (applied first, held constant) and ``live`` (scaled by lambda).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem._arrays import BoolArray, FloatArray
from masonry_dem._docstrings import fill
from masonry_dem._validation import (
    as_finite_array,
    block_indices,
    boolean,
    check_choice,
    finite_scalar,
    frozen,
    plain,
    positive_scalar,
    whole_number,
)
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.interfaces import Interfaces, detect_interfaces

log = logging.getLogger(__name__)

#: a block DOF: translations u1-u3 and rotations w1-w3 along / about e1, e2, e3
DofName = Literal["u1", "u2", "u3", "w1", "w2", "w3"]
#: a named group of DOFs (``in_plane``: u1, u2, w3; ``out_of_plane``: u3, w1, w2)
DofGroup = Literal["all", "translations", "rotations", "in_plane", "out_of_plane"]
DOF_NAMES: tuple[str, ...] = get_args(DofName)
#: (block, DOF): the displacement a run puts on its pushover curve
Monitor = tuple[int, DofName]
_DOF_GROUPS: dict[str, tuple[int, ...]] = {
    "all": (0, 1, 2, 3, 4, 5),
    "translations": (0, 1, 2),
    "rotations": (3, 4, 5),
    "in_plane": (0, 1, 5),
    "out_of_plane": (2, 3, 4),
}


#: the interface law's options (one definition: the law, the settings and the schema use these)
Tension = Literal["brittle", "plastic"]
Memory = Literal["none", "slip"]


@dataclass(frozen=True)
class InterfaceMaterial:
    """Joint properties: stiffness, strength and the interface law's options.

    The interface law's behaviour beyond the strength domain is one for the whole model (the
    ``material`` of :meth:`Model.build`; see :mod:`masonry_dem.constitutive.law`).

    Parameters
    ----------
    kn, kt : float
        Normal and shear stiffness per unit area [N/m^3], each > 0.
    friction : float
        mu = tan(phi), >= 0.
    tensile_strength : float, default 0.0
        ft [Pa], >= 0: the tension cap of the Mohr-Coulomb domain, at most ``cohesion /
        friction``.
    alpha : float, optional
        Torsion-shear exponent of Eq. (A5), > 0 (None: 1.5, the paper's value for
        running-bond masonry).
    tension : {"brittle", "plastic"}, default "brittle"
        ``"brittle"``: a joint that opens loses its tensile strength for good.
    memory : {"slip", "none"}, default "slip"
        ``"slip"``: the paper's incremental law, sliding keeps its plastic slip; ``"none"``:
        holonomic.
    projection : {"energy", "radial"}, default "energy"
        The shear-torsion return: ``"energy"`` (closest point) or ``"radial"``.
    cohesion : float, optional
        c [Pa], >= 0: the shear strength at zero normal stress, ``|tau| <= c - mu sigma``
        (sigma tension positive) up to the tension cap ``sigma <= ft``. None (default):
        ``c = mu * ft``, the paper's reading of Eq. (10), whose domain closes at the cap. A
        larger c leaves the joint a shear strength ``c - mu ft`` at the cap (Lourenco's
        joint: ft = 0.16 MPa, c = 0.224 MPa, mu = 0.75). It needs ``mu * ft <= c`` (``ft <=
        c / mu``; with mu = 0 any ft). A joint that cracks (``tension="brittle"``) loses
        its cohesion with its tensile strength and becomes a dry Coulomb joint.

    Raises
    ------
    ValueError
        If a stiffness is not positive, ``friction``, ``tensile_strength`` or ``cohesion`` is
        negative (or any is not finite), ``alpha`` is not positive, ``tensile_strength``
        exceeds ``cohesion / friction``, or an option is not one of its values.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.InterfaceMaterial(kn=1e9, kt=4e8, friction=0.7).alpha is None
    True
    """

    kn: float
    kt: float
    friction: float
    tensile_strength: float = 0.0
    alpha: float | None = None
    tension: Tension = "brittle"
    memory: Memory = "slip"
    projection: str = "energy"
    cohesion: float | None = None

    def __post_init__(self) -> None:
        for name in ("kn", "kt", "friction", "tensile_strength", "alpha", "cohesion"):
            value = getattr(self, name)
            if value is not None or name not in ("alpha", "cohesion"):
                strict = name in ("kn", "kt", "alpha")
                object.__setattr__(self, name, positive_scalar(name, value, strict=strict))
        if self.cohesion is not None:
            check_tension_cap(self.friction, self.tensile_strength, self.cohesion)
        for name, allowed in LAW_OPTIONS.items():
            check_choice(name, getattr(self, name), allowed)


#: the round-off allowed on ``mu * ft <= c`` (a cap given as c / mu in decimal)
CAP_TOLERANCE = 1e-12


def check_tension_cap(friction: float, tensile_strength: float, cohesion: float) -> None:
    """Refuse a tension cap above the Mohr-Coulomb vertex: ``mu * ft <= c`` (``ft <= c /
    mu``), to a relative :data:`CAP_TOLERANCE`.

    Parameters
    ----------
    friction, tensile_strength, cohesion : float
        mu, ft [Pa] and c [Pa], each finite and >= 0.

    Raises
    ------
    ValueError
        If ``friction * tensile_strength > cohesion``, naming the three and the allowed range.
    """
    if friction * tensile_strength > cohesion * (1.0 + CAP_TOLERANCE):
        raise ValueError(
            f"tensile_strength must be at most cohesion / friction = {cohesion / friction:g} Pa "
            f"(the tension cap of the Mohr-Coulomb domain, ft <= c / mu), got tensile_strength "
            f"= {tensile_strength:g} Pa with cohesion = {cohesion:g} Pa and friction = "
            f"{friction:g}; raise the cohesion to at least {friction * tensile_strength:g} Pa "
            "or lower the tensile strength"
        )


def _warn_idle_load(k: int, load: Load, vector: FloatArray, fixed: BoolArray) -> None:
    """Name a live load that pushes nothing: zero everywhere (weightless blocks, a pressure
    or force of 0) or only on held DOFs (a pressure on the base). The pushover then ends
    ``completed`` at lambda = 0 ("no live load"), which reads as an answer."""
    if not load.live:
        return
    what = f"loads[{k}] ({type(load).__name__}, live)"
    if not vector.any():
        log.warning(
            "%s is zero on every block (weightless blocks, a pressure or force of 0): "
            "nothing pushes the wall and the pushover stops at lambda = 0",
            what,
        )
    elif not vector[~fixed].any():
        held = np.flatnonzero(vector.any(axis=1))
        log.warning(
            "%s acts only on held DOFs (blocks %s): nothing pushes the wall and the "
            "pushover stops at lambda = 0",
            what,
            ", ".join(map(str, held[:5])) + (" ..." if held.size > 5 else ""),
        )


#: ways back onto the shear-torsion boundary (see ``constitutive.strength.check_strength``)
PROJECTIONS: tuple[str, ...] = ("energy", "radial")

#: the interface law's options of :class:`InterfaceMaterial` and their allowed values
LAW_OPTIONS: dict[str, tuple[str, ...]] = {
    "tension": get_args(Tension),
    "memory": get_args(Memory),
    "projection": PROJECTIONS,
}


def dof_mask(dofs: DofGroup | DofName | Sequence[DofGroup | DofName]) -> BoolArray:
    """Boolean (6,) mask from a group name (``all``, ``translations``, ``rotations``,
    ``in_plane``, ``out_of_plane``) or a list of DOF names (``u1`` ... ``w3``)."""
    mask = np.zeros(6, dtype=bool)
    names = [dofs] if isinstance(dofs, str) else list(dofs)
    for name in names:
        if name in _DOF_GROUPS:
            mask[list(_DOF_GROUPS[name])] = True
        elif name in DOF_NAMES:
            mask[DOF_NAMES.index(name)] = True
        else:
            raise ValueError(
                f"dofs must name a group {sorted(_DOF_GROUPS)} or DOFs {DOF_NAMES}, got {name!r}"
            )
    return mask


# --------------------------------------------------------------------------- supports
@dataclass(frozen=True)
class Support:
    """Fix ``dofs`` of the given blocks (indices) at zero, from the first load on.

    What a held column means (a return wall read as fixed DOFs of the end column):

    * ``u1``, ``u3``: the column cannot move horizontally; it turns and moves vertically with
      the wall (a frictionless guide that only stops it sideways);
    * rotations ``w1``-``w3`` as well: the column cannot turn either (a return wall stiff in
      its own plane and out of it);
    * ``u2`` as well (``all``, ``translations``): the column cannot move vertically at all.
      Under the dead load the rest of the wall settles on its elastic bed joints and the
      column does not, so the wall hangs on the column through the friction of its head
      joints (the column's fixed u2 carries part of the wall's weight) and those joints
      start the live load already sheared. A real return wall settles as much as the
      facade (every point of the plan carries the same height of masonry, so each course of
      an L or U wall sinks by the same amount: ``tests/cases/test_walls_that_meet.py``), so
      this reading stiffens the wall by an artefact of the model.

    ``settles_with_wall``: the column follows the wall's vertical motion: u2 of the held
    blocks stays free whatever ``dofs`` says (the other DOFs stay fixed). Under the dead load
    the column then sinks with its course (no head-joint shear, no weight on the support);
    under the live load it may also rise or sink with the wall, held only by the joints
    around it. Model the return walls as blocks (:mod:`masonry_dem.geometry.plans`) to let
    them resist uplift by their weight and interlock.

    Parameters
    ----------
    blocks : array_like of int or bool
        The held blocks (indices, or a boolean mask), e.g. from :mod:`masonry_dem.select`.
    dofs : str or sequence of str, default "all"
        A group (``all``, ``translations``, ``rotations``, ``in_plane``: u1, u2, w3;
        ``out_of_plane``: u3, w1, w2) or a list of DOF names (``u1`` ... ``w3``) and groups.
    settles_with_wall : bool, default False
        Leave u2 of the held blocks free (the column follows the wall's vertical motion).

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.Support([0, 1], "in_plane").mask(3).astype(int).tolist()
    [[1, 1, 0, 0, 0, 1], [1, 1, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0]]
    """

    blocks: ArrayLike
    dofs: DofGroup | DofName | Sequence[DofGroup | DofName] = "all"
    settles_with_wall: bool = False

    def mask(self, n_blocks: int) -> BoolArray:
        """The DOFs this support fixes.

        Parameters
        ----------
        n_blocks : int
            Blocks in the assembly.

        Returns
        -------
        numpy.ndarray of bool, shape (n_blocks, 6)
            True where a DOF is fixed.

        Raises
        ------
        ValueError
            If the selection is empty or out of range, ``settles_with_wall`` is not true or
            false, or ``dofs`` names no group or DOF.
        """
        idx = block_indices("Support.blocks", self.blocks, n_blocks)
        if idx.size == 0:
            raise ValueError("Support.blocks: the selection is empty")
        if not isinstance(self.settles_with_wall, (bool, np.bool_)):
            raise ValueError(
                f"Support.settles_with_wall must be true or false, got {self.settles_with_wall!r}"
            )
        dofs = dof_mask(self.dofs)
        if self.settles_with_wall:
            # the column follows the wall's vertical settlement: u2 is left free
            dofs[DOF_NAMES.index("u2")] = False
        out = np.zeros((n_blocks, 6), dtype=bool)
        out[np.ix_(idx, np.flatnonzero(dofs))] = True
        return out


# --------------------------------------------------------------------------- loads
#: the text the loads' docstrings share (:func:`masonry_dem._docstrings.fill`)
DOCS: dict[str, str] = {
    "vector": """
        The load's (n, 6) generalised forces at the block centres.

        Parameters
        ----------
        blocks : Blocks
            The assembly the load acts on.

        Returns
        -------
        numpy.ndarray, shape (n, 6)
            Forces [N] and moments [N m] at the block centres.
    """,
    "live_blocks": """
        live : bool, default True
            Scaled by lambda (True) or applied first and held (False).
        blocks : array_like of int or bool, optional
            The loaded blocks (None: every block).
    """,
}


@fill(DOCS)
@dataclass(frozen=True)
class SelfWeight:
    """Block weights acting along -e2 (dead, or live for a vertical-acceleration pattern).

    Parameters
    ----------
    live : bool, default False
        Scaled by lambda (True) or applied first and held (False).

    Raises
    ------
    ValueError
        If ``live`` is not true or false.

    Examples
    --------
    >>> import masonry_dem as md
    >>> block = md.single_block(0.1, 0.2, 0.1, 18e3)  # weighs 36 N
    >>> md.SelfWeight().vector(block).round(6).tolist()
    [[0.0, -36.0, 0.0, 0.0, 0.0, 0.0]]
    """

    live: bool = False

    def __post_init__(self) -> None:
        boolean("SelfWeight.live", self.live)

    def vector(self, blocks: Blocks) -> FloatArray:
        """%(vector)s"""
        out = np.zeros((blocks.count, 6))
        out[:, 1] = -blocks.weights
        return out


@fill(DOCS)
@dataclass(frozen=True)
class WeightProportional:
    """A horizontal (or any) pattern proportional to the block weights, e.g. a tilt table.

    force = weight x unit(direction). Live by default (scaled by lambda).

    Parameters
    ----------
    direction : sequence of 3 floats, default (0, 0, 1)
        The force's direction (any non-zero length; e3: out of plane).
    %(live_blocks)s

    Raises
    ------
    ValueError
        If ``live`` is not true or false; when the load is applied (:meth:`vector`), if
        ``direction`` is zero or not finite or ``blocks`` is out of range.

    Examples
    --------
    >>> import masonry_dem as md
    >>> block = md.single_block(0.1, 0.2, 0.1, 18e3)  # weighs 36 N
    >>> md.WeightProportional((1, 0, 0)).vector(block).round(6).tolist()
    [[36.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
    """

    direction: Sequence[float] = (0.0, 0.0, 1.0)
    live: bool = True
    blocks: ArrayLike | None = None

    def __post_init__(self) -> None:
        boolean("WeightProportional.live", self.live)

    def vector(self, blocks: Blocks) -> FloatArray:
        """%(vector)s"""
        d = as_finite_array("direction", self.direction, (3,))
        largest = float(np.abs(d).max())
        if largest == 0:
            raise ValueError(f"direction must be a non-zero vector, got {plain(d.tolist())}")
        norm = np.linalg.norm(d)
        if not 1e-100 < norm < 1e100:  # its squares under- or overflow: scaled first
            d = d / largest
            norm = np.linalg.norm(d)
        out = np.zeros((blocks.count, 6))
        sel = (
            slice(None)
            if self.blocks is None
            else block_indices("WeightProportional.blocks", self.blocks, blocks.count)
        )
        out[sel, :3] = blocks.weights[sel, None] * (d / norm)[None, :]
        return out


@fill(DOCS)
@dataclass(frozen=True)
class Pressure:
    """Uniform pressure [Pa] on the face of the selected blocks normal to ``axis``.

    It pushes towards ``sign`` x e[axis]; the resultant acts at the block centres (it passes
    through them).

    Parameters
    ----------
    value : float
        The pressure [Pa], finite.
    axis : {0, 1, 2}, default 2
        The normal of the loaded face (2: out of plane).
    sign : {1, -1}, default 1
        Pushes towards +e[axis] or -e[axis].
    %(live_blocks)s

    Raises
    ------
    ValueError
        If ``value`` is not finite, ``axis`` or ``sign`` is not one of its values, or
        ``live`` is not true or false.

    Examples
    --------
    >>> import masonry_dem as md
    >>> block = md.single_block(0.1, 0.2, 0.1, 18e3)  # weighs 36 N
    >>> md.Pressure(1000.0).vector(block).round(6).tolist()  # 1 kPa on 0.2 m x 0.1 m
    [[0.0, 0.0, 20.0, 0.0, 0.0, 0.0]]
    """

    value: float
    axis: int = 2
    sign: int = 1
    live: bool = True
    blocks: ArrayLike | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", finite_scalar("pressure", self.value))
        whole_number("pressure axis", self.axis, (0, 1, 2))
        whole_number("pressure sign", self.sign, (-1, 1))
        boolean("Pressure.live", self.live)

    def vector(self, blocks: Blocks) -> FloatArray:
        """%(vector)s"""
        p = self.value
        others = [k for k in range(3) if k != self.axis]
        area = blocks.sizes[:, others[0]] * blocks.sizes[:, others[1]]
        out = np.zeros((blocks.count, 6))
        sel = (
            slice(None)
            if self.blocks is None
            else block_indices("Pressure.blocks", self.blocks, blocks.count)
        )
        out[sel, self.axis] = self.sign * p * area[sel]
        return out


@fill(DOCS)
@dataclass(frozen=True)
class PointLoad:
    """Point forces on each selected block, applied at offsets from the block centres.

    Dead by default (e.g. the timber beams of S32).

    Parameters
    ----------
    blocks : array_like of int or bool
        The loaded blocks (a block named twice is loaded twice).
    force : sequence of 3 floats
        The force on each block [N].
    offset : sequence of 3 floats, default (0, 0, 0)
        Where it acts, from each block centre [m] (default: the centre).
    live : bool, default False
        Scaled by lambda (True) or applied first and held (False).

    Raises
    ------
    ValueError
        If ``live`` is not true or false; when the load is applied (:meth:`vector`), if
        ``blocks`` is out of range or ``force`` or ``offset`` is not three finite numbers.

    Examples
    --------
    >>> import masonry_dem as md
    >>> block = md.single_block(0.1, 0.2, 0.1, 18e3)  # weighs 36 N
    >>> md.PointLoad([0], (0, -100.0, 0), offset=(0.05, 0, 0)).vector(block).tolist()
    [[0.0, -100.0, 0.0, 0.0, 0.0, -5.0]]
    """

    blocks: ArrayLike
    force: Sequence[float]
    offset: Sequence[float] = (0.0, 0.0, 0.0)
    live: bool = False

    def __post_init__(self) -> None:
        boolean("PointLoad.live", self.live)

    def vector(self, blocks: Blocks) -> FloatArray:
        """%(vector)s"""
        idx = block_indices("PointLoad.blocks", self.blocks, blocks.count)
        f = as_finite_array("force", self.force, (3,))
        r = as_finite_array("offset", self.offset, (3,))
        out = np.zeros((blocks.count, 6))
        # repeated indices add up (two beams on one block)
        np.add.at(out[:, :3], idx, f)
        np.add.at(out[:, 3:], idx, np.cross(r, f))
        return out


Load = SelfWeight | WeightProportional | Pressure | PointLoad
#: the loads by the name a case file gives them (``[[loads]] type``)
LOAD_TYPES: dict[str, type[Load]] = {
    "self_weight": SelfWeight,
    "weight_proportional": WeightProportional,
    "pressure": Pressure,
    "point": PointLoad,
}


def _kind(value: object) -> str:
    return f"{type(value).__name__} {plain(value)}"


def _check_build(
    blocks: object,
    material: object,
    supports: object,
    loads: object,
    interfaces: object,
    overrides: object,
) -> None:
    """What :meth:`Model.build` is given, checked by name before anything uses it (the
    attribute or index errors it would otherwise raise name none of it)."""
    if not isinstance(blocks, Blocks):
        raise ValueError(
            f"Model.build: blocks must be a Blocks (from a builder such as running_bond_wall, "
            f"or Blocks.from_boxes), got {_kind(blocks)}"
        )
    if not isinstance(material, InterfaceMaterial):
        raise ValueError(
            f"Model.build: material must be an InterfaceMaterial (a table of kn, kt, friction "
            f"... is InterfaceMaterial(**table)), got {_kind(material)}"
        )
    if interfaces is not None and not isinstance(interfaces, Interfaces):
        raise ValueError(
            f"Model.build: interfaces must be an Interfaces (detect_interfaces(blocks)) or "
            f"None, got {_kind(interfaces)}"
        )
    for name, items, kinds, hint in (
        ("supports", supports, (Support,), "Support(select.base(blocks))"),
        ("loads", loads, tuple(LOAD_TYPES.values()), "SelfWeight(), WeightProportional()"),
    ):
        if isinstance(items, (str, bytes)) or not isinstance(items, Sequence):
            raise ValueError(f"Model.build: {name} must be a list, got {_kind(items)}")
        for k, item in enumerate(items):
            if not isinstance(item, kinds):
                allowed = " or ".join(t.__name__ for t in kinds)
                raise ValueError(
                    f"Model.build: {name}[{k}] must be a {allowed} (e.g. {hint}), got {_kind(item)}"
                )
    _check_overrides("material_overrides", overrides, "block indices")


def _check_overrides(name: str, overrides: object, what: str) -> None:
    """A list of (``what``, InterfaceMaterial) pairs, or a ValueError naming the entry."""
    if isinstance(overrides, (str, bytes)) or not isinstance(overrides, Sequence):
        raise ValueError(f"Model.build: {name} must be a list, got {_kind(overrides)}")
    for k, pair in enumerate(overrides):
        if (
            not isinstance(pair, Sequence)
            or len(pair) != 2
            or not isinstance(pair[1], InterfaceMaterial)
        ):
            raise ValueError(
                f"Model.build: {name}[{k}] must be a pair ({what}, InterfaceMaterial), "
                f"got {_kind(pair)}"
            )


def _interfaces_between(
    name: str, pairs: ArrayLike, interfaces: Interfaces, n_blocks: int
) -> BoolArray:
    """The interfaces joining the given (k, 2) pairs of blocks (either way round); a pair
    that shares no interface is named."""
    arr = np.asarray(pairs)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0:
        raise ValueError(f"{name}: pairs must have shape (k, 2) with k >= 1, got {arr.shape}")
    flat = block_indices(name, arr.reshape(-1), n_blocks).reshape(-1, 2)

    def key(i: NDArray[np.int64], j: NDArray[np.int64]) -> NDArray[np.int64]:
        return np.minimum(i, j) * n_blocks + np.maximum(i, j)

    wanted = key(flat[:, 0], flat[:, 1])
    present = key(interfaces.block_i.astype(np.int64), interfaces.block_j.astype(np.int64))
    found = np.isin(wanted, present)
    if not found.all():
        i, j = flat[np.argmin(found)]
        raise ValueError(f"{name}: blocks {i} and {j} share no interface")
    hit: BoolArray = np.isin(present, wanted)
    return hit


# --------------------------------------------------------------------------- model
@dataclass(frozen=True)
class Model:
    """Everything an analysis needs, validated and frozen.

    Build one with :meth:`build` (or :func:`~masonry_dem.load_case`); the constructor takes
    the arrays as they are.

    Parameters
    ----------
    blocks : Blocks
        The blocks (n).
    interfaces : Interfaces
        The interfaces (m).
    kn, kt, friction, tensile_strength, alpha : numpy.ndarray, shape (m,)
        Interface properties (as in :class:`InterfaceMaterial`, ``alpha`` resolved).
    fixed : numpy.ndarray of bool, shape (n, 6)
        Fixed DOFs.
    dead, live : numpy.ndarray, shape (n, 6)
        Generalised forces at block centres: ``dead`` applied first and held, ``live`` scaled
        by lambda.
    name : str, default "model"
        A label for output.
    meta : dict, optional
        Anything the caller keeps with the model (a case's source, ...).
    tension, memory, projection : str
        The interface law's options (of the ``material`` of :meth:`build`).
    cohesion : numpy.ndarray, shape (m,), optional
        c [Pa] of each interface, ``friction * tensile_strength <= cohesion`` (None:
        ``friction * tensile_strength``, the paper's reading; :meth:`build` resolves it so
        where a material gives none).

    Raises
    ------
    ValueError
        If ``cohesion`` is below ``friction * tensile_strength`` at an interface.

    Examples
    --------
    >>> import masonry_dem as md
    >>> wall = md.running_bond_wall(4, 3, 0.1, 0.2, 0.1, 18e3)
    >>> model = md.Model.build(
    ...     wall,
    ...     md.InterfaceMaterial(kn=1e9, kt=4e8, friction=0.7),
    ...     supports=[md.Support(md.select.course(wall, 0))],
    ...     loads=[md.SelfWeight(), md.WeightProportional()],
    ... )
    >>> model.interfaces.count, model.n_dofs, int(model.free.sum())
    (23, 78, 54)
    """

    blocks: Blocks
    interfaces: Interfaces
    kn: FloatArray
    kt: FloatArray
    friction: FloatArray
    tensile_strength: FloatArray
    alpha: FloatArray
    fixed: BoolArray
    dead: FloatArray
    live: FloatArray
    name: str = "model"
    meta: dict[str, Any] = field(default_factory=dict)
    #: the interface law's options (of the ``material`` of :meth:`build`)
    tension: Tension = "brittle"
    memory: Memory = "slip"
    projection: str = "energy"
    cohesion: FloatArray | None = None

    def __post_init__(self) -> None:
        for name in ("kn", "kt", "friction", "tensile_strength", "alpha", "dead", "live"):
            object.__setattr__(self, name, frozen(getattr(self, name), float))
        object.__setattr__(self, "fixed", frozen(self.fixed, bool))
        if self.cohesion is None:
            cohesion = self.friction * self.tensile_strength
        else:
            cohesion = np.broadcast_to(np.asarray(self.cohesion, dtype=float), self.friction.shape)
            low = self.friction * self.tensile_strength > cohesion * (1.0 + CAP_TOLERANCE)
            if low.any():
                k = int(np.flatnonzero(low)[0])
                check_tension_cap(
                    float(self.friction[k]), float(self.tensile_strength[k]), float(cohesion[k])
                )
        object.__setattr__(self, "cohesion", frozen(cohesion, float))

    @property
    def cohesion_beyond_friction(self) -> FloatArray:
        """(m,) ``c - mu ft`` [Pa] >= 0: the shear strength left at the tension cap.

        Zero where the cohesion is the paper's ``mu ft`` (bit for bit).
        """
        assert self.cohesion is not None  # resolved in __post_init__
        return np.maximum(self.cohesion - self.friction * self.tensile_strength, 0.0)

    @classmethod
    def build(
        cls,
        blocks: Blocks,
        material: InterfaceMaterial,
        supports: Sequence[Support] = (),
        loads: Sequence[Load] = (SelfWeight(),),
        name: str = "model",
        interfaces: Interfaces | None = None,
        material_overrides: Sequence[tuple[ArrayLike, InterfaceMaterial]] = (),
        meta: dict[str, Any] | None = None,
        interface_overrides: Sequence[tuple[ArrayLike, InterfaceMaterial]] = (),
    ) -> Model:
        """Detect contacts, apply supports and loads.

        Interfaces between two fully fixed blocks carry nothing and are dropped.

        Parameters
        ----------
        blocks : Blocks
            The assembly.
        material : InterfaceMaterial
            The joints' material (and the interface law's options, for the whole model).
        supports : sequence of Support, default ()
            The fixed DOFs.
        loads : sequence of loads, default (SelfWeight(),)
            :class:`SelfWeight`, :class:`WeightProportional`, :class:`Pressure`,
            :class:`PointLoad`; dead ones add to ``dead``, live ones to ``live``. A live load
            that pushes nothing (zero, or on held DOFs only) is named in a warning.
        name : str, default "model"
            A label for output.
        interfaces : Interfaces, optional
            The contacts (None: :func:`~masonry_dem.detect_interfaces` of ``blocks``).
        material_overrides : sequence of (blocks, InterfaceMaterial), default ()
            Other materials for the interfaces touching given blocks (e.g. the joint with a
            rigid base).
        meta : dict, optional
            Kept with the model.
        interface_overrides : sequence of (pairs, InterfaceMaterial), default ()
            Other materials for the interfaces between given pairs of blocks, ``pairs`` of
            shape (k, 2) (e.g. the potential cracks of units split by
            :func:`~masonry_dem.split_units`); applied after ``material_overrides``.

        Returns
        -------
        Model
            The model, its supports checked (:meth:`check_supported`).

        Raises
        ------
        ValueError
            If an argument has the wrong type (named, with how to make the right one), a
            block index is out of range, or the assembly is a mechanism
            (:meth:`check_supported`).
        """
        _check_build(blocks, material, supports, loads, interfaces, material_overrides)
        _check_overrides("interface_overrides", interface_overrides, "pairs of blocks (k, 2)")
        n = blocks.count
        fixed = np.zeros((n, 6), dtype=bool)
        for sup in supports:
            fixed |= sup.mask(n)
        its = detect_interfaces(blocks) if interfaces is None else interfaces
        fully = np.asarray(fixed.all(axis=1), dtype=bool)
        keep = ~(fully[its.block_i] & fully[its.block_j])
        its = its.subset(np.flatnonzero(keep))
        m = its.count

        def per_interface(mat: InterfaceMaterial) -> FloatArray:
            alpha = np.nan if mat.alpha is None else mat.alpha
            cohesion = np.nan if mat.cohesion is None else mat.cohesion
            return np.array([mat.kn, mat.kt, mat.friction, mat.tensile_strength, alpha, cohesion])

        props = np.tile(per_interface(material), (m, 1))
        for k, (blk, mat) in enumerate(material_overrides):
            blk = block_indices(f"material_overrides[{k}] blocks", blk, n)
            touch = np.isin(its.block_i, blk) | np.isin(its.block_j, blk)
            props[touch] = per_interface(mat)
        for k, (pairs, mat) in enumerate(interface_overrides):
            props[_interfaces_between(f"interface_overrides[{k}]", pairs, its, n)] = per_interface(
                mat
            )
        props[:, 4] = np.where(np.isnan(props[:, 4]), 1.5, props[:, 4])

        dead = np.zeros((n, 6))
        live = np.zeros((n, 6))
        for k, load in enumerate(loads):
            vector = load.vector(blocks)
            (live if load.live else dead)[...] += vector
            _warn_idle_load(k, load, vector, fixed)
        kn, kt, friction, tensile, alpha, cohesion = props.T.copy()
        # not given: the paper's c = mu ft, computed as Model computes it (bit for bit)
        cohesion = np.where(np.isnan(cohesion), friction * tensile, cohesion)
        model = cls(
            blocks,
            its,
            kn,
            kt,
            friction,
            tensile,
            alpha,
            fixed,
            dead,
            live,
            name=name,
            meta=dict(meta or {}),
            tension=material.tension,
            memory=material.memory,
            projection=material.projection,
            cohesion=cohesion,
        )
        model.check_supported()
        return model

    # -- DOF bookkeeping
    @property
    def n_dofs(self) -> int:
        """Number of DOFs, 6 per block."""
        return 6 * self.blocks.count

    @property
    def smallest_moving_size(self) -> float:
        """Smallest dimension [m] of the blocks that can move.

        Fully fixed supports are excluded, so a thin support strip does not shrink the
        solvers' displacement limit.
        """
        moving = ~self.fixed.all(axis=1)
        sizes = self.blocks.sizes[moving] if moving.any() else self.blocks.sizes
        return float(sizes.min())

    @property
    def free(self) -> BoolArray:
        """(6n,) bool mask of free DOFs (block-major)."""
        return ~self.fixed.reshape(-1)

    def dof_index(self, block: int, dof: DofName) -> int:
        """Global DOF number of ``dof`` (``u1`` ... ``w3``) of ``block``.

        Parameters
        ----------
        block : int
            The block index, 0 to n - 1.
        dof : {"u1", "u2", "u3", "w1", "w2", "w3"}
            The DOF.

        Returns
        -------
        int
            ``6 * block`` plus the DOF's place.

        Raises
        ------
        ValueError
            If ``dof`` is not a DOF name or ``block`` is not a block index.
        """
        if dof not in DOF_NAMES:
            raise ValueError(f"dof must be one of {DOF_NAMES}, got {dof!r}")
        if isinstance(block, (bool, np.bool_)) or not isinstance(block, (int, np.integer)):
            raise ValueError(f"block must be a whole block index, got {plain(block)}")
        if not 0 <= block < self.blocks.count:
            raise ValueError(f"block must be in 0..{self.blocks.count - 1}, got {int(block)}")
        return 6 * int(block) + DOF_NAMES.index(dof)

    def check_supported(self) -> None:
        """Refuse an assembly with a rigid-body mechanism before any solve.

        Every connected group of blocks needs fixed DOFs in it (a free-floating part is a
        mechanism) that stop its six rigid-body motions.

        Raises
        ------
        ValueError
            If no DOF is fixed, a block touches no support through any interface, or the
            fixed DOFs of a group leave a rigid-body motion free (one of them named).
        """
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        n = self.blocks.count
        if not self.fixed.any():
            raise ValueError(
                "supports: no DOF is fixed, the assembly is a free body (a mechanism); "
                "fix a base block or some DOFs"
            )
        its = self.interfaces
        graph = coo_matrix((np.ones(its.count), (its.block_i, its.block_j)), shape=(n, n))
        ncomp, label = connected_components(graph, directed=False)
        anchored = np.zeros(ncomp, dtype=bool)
        anchored[label[self.fixed.any(axis=1)]] = True
        if not anchored.all():
            loose = np.flatnonzero(~anchored[label])
            raise ValueError(
                f"supports: {loose.size} block(s) touch no support through any interface "
                f"(first: block {loose[0]} at {self.blocks.centres[loose[0]].tolist()}); "
                "the assembly is a mechanism"
            )
        self._check_rigid_modes_restrained(label, ncomp)

    def _check_rigid_modes_restrained(self, label: NDArray[np.int32], ncomp: int) -> None:
        """Each connected group must have its six rigid-body motions stopped by its fixed DOFs.

        Anchoring a group by *some* fixed DOF is not enough (e.g. only the translations of
        one base block, or no DOF along e3 anywhere): K_ff is then singular, though splu
        often factors it in floating point and returns a meaningless displacement. Elastic
        interfaces of positive area make each connected group rigid under zero energy, so
        K_ff is regular iff, per group, the fixed-DOF rows of the rigid-motion map
        q_b = [u0 + w x r_b, w] have rank 6. The rank is found exactly (integer arithmetic
        on the arms r_b counted in :data:`ARM_QUANTUM` of the smallest block), so it does
        not depend on the size of the group: a tolerance on a Gram matrix took a column of
        800 cubes on a fixed base, its arms 400 block sizes long, for a mechanism.
        """
        b, d = np.nonzero(self.fixed)  # fixed (block, dof) pairs, block-major
        span = float(np.ptp(self.blocks.centres, axis=0).max())
        # the arms stay well inside int64 whatever the wall's extent
        quantum = max(ARM_QUANTUM * float(self.blocks.sizes.min()), span * 2.0**-50)
        order = np.argsort(label[b], kind="stable")
        groups = np.split(order, np.flatnonzero(np.diff(label[b][order])) + 1)
        for rows in groups:
            group = int(label[b[rows[0]]])
            origin = self.blocks.centres[b[rows[0]]]
            arms = np.rint((self.blocks.centres[b[rows]] - origin) / quantum).astype(np.int64)
            basis = _exact_rank(_motion_rows(d[rows], arms))
            if len(basis) < 6:
                self._refuse_free_motion(label, group, basis, origin, quantum)

    def _refuse_free_motion(
        self,
        label: NDArray[np.int32],
        group: int,
        basis: list[tuple[int, list[Fraction]]],
        origin: FloatArray,
        quantum: float,
    ) -> None:
        """The ValueError of a group whose fixed DOFs leave rigid motions free, with one of
        them about the group's centroid, its translation in block sizes."""
        members = np.flatnonzero(label == group)
        pivots = {col: row for col, row in basis}
        free = next(c for c in range(6) if c not in pivots)
        mode = np.zeros(6)
        mode[free] = 1.0
        for col, row in pivots.items():
            mode[col] = -float(row[free])
        u0, w = mode[:3], mode[3:] / quantum  # rotations per quantum of arm -> per metre
        centroid = self.blocks.centres[members].mean(axis=0)
        length = float(np.median(self.blocks.sizes))
        motion = np.concatenate([(u0 + np.cross(w, centroid - origin)) / length, w])
        motion = np.round(motion / np.abs(motion).max(), 3) + 0.0  # +0.0: no "-0.0"
        raise ValueError(
            f"supports: the fixed DOFs leave {6 - len(basis)} rigid-body motion(s) of the group "
            f"of {members.size} block(s) containing block {int(members[0])} free (e.g. "
            f"(u1, u2, u3, w1, w2, w3) ~ {motion.tolist()}, u in block sizes, about its "
            f"centroid); "
            "the assembly is a mechanism: fix more DOFs"
        )


#: the unit the arms of the free-body check are counted in, a share of the smallest block:
#: far below any gap a builder leaves, far above the round-off of a centre
ARM_QUANTUM = 1e-6


def _motion_rows(dofs: NDArray[np.intp], arms: NDArray[np.int64]) -> list[tuple[int, ...]]:
    """The distinct rows (u1, u2, u3, w1, w2, w3) of the rigid motion seen by fixed DOFs:
    rotation DOF k sees w_k; translation DOF a at arm r sees u_a + w_p r_q - w_q r_p
    ((p, q) the axes after a), in whole quanta. Rotations first: one pins a column at once."""
    rows = np.zeros((dofs.size, 6), dtype=np.int64)
    turn = dofs >= 3
    rows[np.flatnonzero(turn), dofs[turn]] = 1
    k = np.flatnonzero(~turn)
    a = dofs[k]
    p, q = (a + 1) % 3, (a + 2) % 3
    rows[k, a] = 1
    rows[k, 3 + p] = arms[k, q]
    rows[k, 3 + q] = -arms[k, p]
    unique = np.unique(rows, axis=0)
    unique = unique[np.argsort(unique[:, :3].any(axis=1), kind="stable")]
    return [tuple(r) for r in unique.tolist()]


def _exact_rank(rows: list[tuple[int, ...]]) -> list[tuple[int, list[Fraction]]]:
    """A reduced row-echelon basis of ``rows`` (pivot column, row), in exact arithmetic; it
    stops at rank 6."""
    basis: list[tuple[int, list[Fraction]]] = []
    for raw in rows:
        row = [Fraction(x) for x in raw]
        for pivot, b in basis:
            if row[pivot]:
                f = row[pivot]
                row = [x - f * y for x, y in zip(row, b, strict=True)]
        lead = next((c for c, x in enumerate(row) if x), None)
        if lead is None:
            continue
        row = [x / row[lead] for x in row]
        basis = [
            (c, [x - b[lead] * y for x, y in zip(b, row, strict=True)] if b[lead] else b)
            for c, b in basis
        ]
        basis.append((lead, row))
        if len(basis) == 6:
            break
    return basis


def require_model(who: str, value: object) -> Model:
    """``value`` if it is a built :class:`Model`, else a ValueError saying how to make one
    (``who``: the function that was given it)."""
    if not isinstance(value, Model):
        raise ValueError(
            f"{who}: model must be a Model (Model.build(blocks, material, supports, loads) or "
            f"load_case(path).model), got {_kind(value)}"
        )
    return value


def check_bound(bound: object) -> None:
    """An upper bound of the collapse multiplier is a finite number, a function of the model
    or None."""
    if bound is None or callable(bound):
        return
    if isinstance(bound, (bool, np.bool_, str, bytes)) or not isinstance(
        bound, (int, float, np.integer, np.floating)
    ):
        raise ValueError(
            "bound must be a number (an upper bound of lambda), a function of the model or "
            f"None, got {_kind(bound)}"
        )
    finite_scalar("bound", bound)
