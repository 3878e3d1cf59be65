"""The loads: generalised forces at the block centres, ``dead`` (applied first, held constant)
or ``live`` (scaled by lambda): self weight, a weight-proportional pattern (a tilt table),
a pressure and point forces.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from masonry_dem._arrays import BoolArray, FloatArray
from masonry_dem._docstrings import fill
from masonry_dem._validation import (
    as_finite_array,
    block_indices,
    boolean,
    finite_scalar,
    plain,
    whole_number,
)
from masonry_dem.geometry.blocks import Blocks

log = logging.getLogger(__name__)


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
