"""The frozen analysis model: blocks, interfaces, their properties, the fixed DOFs and the
dead and live loads, built from a material, supports and loads (:meth:`Model.build`) and
checked to be supported.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem._arrays import BoolArray, FloatArray
from masonry_dem._validation import (
    block_indices,
    finite_scalar,
    frozen,
    plain,
)
from masonry_dem.geometry.blocks import Blocks
from masonry_dem.geometry.interfaces import Interfaces, detect_interfaces
from masonry_dem.model.loads import LOAD_TYPES, Load, SelfWeight, _warn_idle_load
from masonry_dem.model.materials import (
    CAP_TOLERANCE,
    InterfaceMaterial,
    Memory,
    Tension,
    check_tension_cap,
)
from masonry_dem.model.supports import DOF_NAMES, DofName, Support

log = logging.getLogger(__name__)


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
