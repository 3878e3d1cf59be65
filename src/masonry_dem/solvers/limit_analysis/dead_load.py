"""Can the dead load stand under the zero-dilatancy law? The check made before any multiplier.

The associative analysis lets a joint dilate: sliding along it opens it by mu times the
slip, so the statics may put any compression on a joint that no motion closes, and friction
with it. A block over an opening with nothing under it is then "held" by head joints
clamped by a self-stress, and the analysis returns a multiplier for a wall that falls under
its own weight (the pushover's joints, which do not dilate, give it none).

The check. Let ``d`` be the direction of the dead load's resultant and S a set of free
blocks. Translate S rigidly along ``d``, everything else still. Every joint between S and
the rest (or a support) then either opens (its normal velocity is positive), slides in its
own plane (zero normal velocity), or closes. If none closes:

* with zero dilatancy the sliding joints' normal gap does not change, so nothing compresses
  them: they resist with their cohesion ``c A`` only; the opening joints with their
  tensile strength ``ft A`` (times the normal share of ``d``) at most;
* the virtual work of any equilibrium on this motion is the dead load's work on S,
  ``W = sum over S of F_dead . d``, and the joints' forces can do at most
  ``R = sum over the joints of S of ft A (max(d_n, 0) + mu |d_t|)``.

So if W > R no equilibrium of the dead load exists with the zero-dilatancy joints: the blocks
of S hang. The largest S with no closing joint is the set of free blocks with no chain of
bearing contacts (a joint that the motion along ``d`` would close) down to a support (a block
whose translation along ``d`` is held); it is found by one breadth-first search from the
supports, and each of its connected groups is checked on its own (a group's joints with the
rest all lie on held blocks). With dry joints (ft = 0) every such group hangs.

What it assumes: the joints along which S falls get their compression from S's own motion,
and a fall in their plane gives them none. A thrust pressed into them by neighbours that tip
into the opening (a jack arch of corbels) is not counted. On the walls measured the pushover
agrees: the 10 x 15 wall with a 0.6 x 0.6 m window and no lintel, and a 7 x 7 wall whose one
hanging block sits between two half-bearing corbels, have no equilibrium under the dead load
in its dead-load search either.

What it does not find: a wall that fails under its dead load by a mechanism with rotation (a
corbel whose weight lies beyond its support) passes the check; the analyses then say so by
their own means (no equilibrium at lambda = 0, or a mechanism that needs lambda < 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import sparse
from scipy.sparse.csgraph import breadth_first_order, connected_components

from masonry_dem.model import Model

#: a joint whose normal has a share of ``d`` below this (cosine) slides in its own plane
#: under a translation along ``d`` (round-off of the axes of axis-aligned interfaces)
_IN_PLANE = 1e-9


@dataclass(frozen=True)
class DeadLoadCheck:
    """``hanging``: the blocks whose dead load no zero-dilatancy equilibrium carries (sorted,
    empty where the check passes); ``weight`` and ``resistance``: per hanging group, the
    dead load's work on its fall and the most its joints can resist (N); ``direction``: the
    unit direction of the dead load's resultant (zeros with no dead load)."""

    hanging: NDArray[np.intp]
    groups: tuple[NDArray[np.intp], ...]
    weight: tuple[float, ...]
    resistance: tuple[float, ...]
    direction: NDArray[np.float64]

    @property
    def stands(self) -> bool:
        return self.hanging.size == 0

    def describe(self, model: Model, shown: int = 6) -> str:
        """Why the dead load cannot stand, naming the hanging blocks (the first ``shown`` by
        index and centre)."""
        c = model.blocks.centres
        names = [
            f"block {b} at ({c[b, 0]:.4g}, {c[b, 1]:.4g}, {c[b, 2]:.4g})"
            for b in self.hanging[:shown]
        ]
        more = f" and {self.hanging.size - shown} more" if self.hanging.size > shown else ""
        word = "block hangs" if self.hanging.size == 1 else "blocks hang"
        return (
            f"{self.hanging.size} {word} ({'; '.join(names)}{more}): no chain of bearing "
            "joints carries them to a support, and the joints around them slide without "
            "dilating, so take no compression and no friction beyond their cohesion "
            f"(they resist {sum(self.resistance):.4g} N of the {sum(self.weight):.4g} N "
            "that pulls the blocks down)"
        )


def check_dead_load(model: Model) -> DeadLoadCheck:
    """The blocks that cannot be held under the dead load with zero dilatancy (module
    docstring): free blocks with no chain of bearing contacts to a support, grouped, whose
    dead load exceeds what their joints' tension and cohesion can resist."""
    n = model.blocks.count
    dead = np.asarray(model.dead, dtype=float)[:, :3]
    total = dead.sum(axis=0)
    size = float(np.linalg.norm(total))
    empty = np.zeros(0, dtype=np.intp)
    if size == 0.0 or not np.isfinite(size):
        return DeadLoadCheck(empty, (), (), (), np.zeros(3))
    d = total / size
    # a block whose translation along d is held: a fixed translation with a share of d
    moves = np.abs(d) > _IN_PLANE
    held = (np.asarray(model.fixed)[:, :3] & moves[None, :]).any(axis=1)
    its = model.interfaces
    i, j = np.asarray(its.block_i), np.asarray(its.block_j)
    axis = np.asarray(its.axis)
    side = np.sign(model.blocks.centres[j, axis] - model.blocks.centres[i, axis])
    # t: the normal velocity (from i to j) of j moving along d with i still; t < 0 closes
    t = d[axis] * side
    j_on_i, i_on_j = t < -_IN_PLANE, t > _IN_PLANE
    # edges supporter -> the block bearing on it, and a source (node n) -> every held block
    src = np.concatenate([i[j_on_i], j[i_on_j], np.full(int(held.sum()), n)])
    dst = np.concatenate([j[j_on_i], i[i_on_j], np.flatnonzero(held)])
    graph = sparse.csr_matrix((np.ones(src.size), (src, dst)), shape=(n + 1, n + 1))
    carried = np.zeros(n + 1, dtype=bool)
    carried[breadth_first_order(graph, n, directed=True, return_predecessors=False)] = True
    loose = ~carried[:n]
    if not loose.any():
        return DeadLoadCheck(empty, (), (), (), d)
    inner = loose[i] & loose[j]
    links = sparse.csr_matrix((np.ones(int(inner.sum())), (i[inner], j[inner])), shape=(n, n))
    _, label = connected_components(links, directed=False)
    # what each joint between a loose and a carried block can resist along d (zero
    # compression: its tension where the fall opens it, its cohesion where it slides)
    edge = loose[i] ^ loose[j]
    ft_area = np.asarray(model.tensile_strength)[edge] * np.asarray(its.area)[edge]
    opening = np.abs(t[edge])  # no joint between loose and carried blocks closes
    sliding = np.sqrt(np.maximum(1.0 - t[edge] ** 2, 0.0))
    resist = ft_area * (opening + np.asarray(model.friction)[edge] * sliding)
    # the cohesion beyond mu ft, where the joint has one of its own (+ 0.0 where not)
    resist = resist + model.cohesion_beyond_friction[edge] * np.asarray(its.area)[edge] * sliding
    owner = np.where(loose[i[edge]], i[edge], j[edge])
    # per group, in one pass whatever their number (a carried block's group weighs nothing):
    # the dead load's work on the fall and what the group's joints resist
    count = int(label.max(initial=-1)) + 1
    weight = np.bincount(label[loose], weights=(dead @ d)[loose], minlength=count)
    resisted = np.bincount(label[owner], weights=resist, minlength=count)
    falls = (weight > resisted * (1 + 1e-9)) & (weight > 1e-12 * size)
    hang = loose & falls[label]
    order = np.argsort(label[hang], kind="stable")
    members = np.flatnonzero(hang)[order]
    cuts = np.flatnonzero(np.diff(label[members])) + 1
    groups = np.split(members, cuts) if members.size else []
    kept = np.flatnonzero(falls)
    weights = [float(weight[g]) for g in kept]
    resistances = [float(resisted[g]) for g in kept]
    hanging = np.flatnonzero(hang)
    return DeadLoadCheck(hanging, tuple(groups), tuple(weights), tuple(resistances), d)
