"""Loose blocks solved apart (nonlinear elimination).

A block whose joints have all yielded so that its own tangent keeps almost nothing of its
elastic stiffness in some direction (both bed joints sliding, or rocking, with its head
joints open) is a mechanism of the consistent tangent, held only by the tangent's floor.
Along it a Newton correction of the whole wall is orders of magnitude larger than the step,
so the trust region cuts the whole correction to nothing and the line search stops on the
kink where one of its joints stops yielding (docs/solvers.md, "Newton's basin on walls that
meet"). Nonlinear elimination (Lanzkron, Rose and Wilkes 1996; Cai and Li 2011) solves such
DOFs apart: with every other DOF and lambda held, Newton on the equilibrium of the loose
blocks alone, so that the wall's Newton iterates where they are in equilibrium. The residual
and the law are unchanged: a converged state is an equilibrium of the paper's law.

* :meth:`LooseBlocks.detect` - the loose blocks at a state: the smallest eigenvalue of each
  block's own 6 x 6 block of the tangent (its joints' contributions, the floor excluded),
  relative to that of its elastic block, below ``loose_stiffness``;
* :meth:`LooseBlocks.solve` - Newton on the loose blocks' DOFs alone, each group of blocks
  that touch one another with its own backtracking line search; a group whose residual no
  step lowers, or that moves past the displacement limit (a local mechanism: the block
  would fall), is left where it was.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.sparse.linalg import splu

if TYPE_CHECKING:
    from collections.abc import Callable

    from masonry_dem.constitutive.law import LawResponse
    from masonry_dem.solvers.static.problem import DiscreteProblem

log = logging.getLogger(__name__)

#: backtracking of a local Newton step: 1, 1/8, ... 8^-(CUTS - 1). Along a loose block's
#: mechanism its tangent is the floor's (1e-9 of the elastic stiffness), so the full step can
#: be 1e9 times the one that reaches the kink where a joint stops yielding; a local system is
#: small, so each trial costs a residual, not a factorization
CUTS = 14


@dataclass
class LocalSolve:
    """What :meth:`LooseBlocks.solve` did: the blocks solved apart, the new state and its
    residual, and the groups of those blocks it put in equilibrium, improved, or left (no
    descent, or past the limit: a local mechanism)."""

    blocks: np.ndarray
    q: np.ndarray
    residual: np.ndarray
    rnorm: float
    response: LawResponse
    solved: int
    improved: int
    left: int


class LooseBlocks:
    """The loose blocks of a :class:`DiscreteProblem` and their local solves."""

    def __init__(self, problem: DiscreteProblem, threshold: float) -> None:
        self.problem = problem
        self.threshold = threshold
        model = problem.model
        its = model.interfaces
        self.nb = model.blocks.count
        self.H_loc = problem.tangent_assembler.H_loc  # (m, 6, 12)
        self.ends = np.stack([its.block_i, its.block_j], axis=1).astype(np.int64)  # (m, 2)
        m = self.ends.shape[0]
        # incidence of each joint's two sides on the blocks: sums the (m, 36) blocks per block
        self._sum = [
            sparse.csr_matrix((np.ones(m), (self.ends[:, s], np.arange(m))), shape=(self.nb, m))
            for s in (0, 1)
        ]
        free = model.free.reshape(self.nb, 6)
        #: blocks with all six DOFs free: the only ones that can be loose
        self.candidates = free.all(axis=1)
        position = np.full(model.n_dofs, -1, dtype=np.int64)
        position[problem.free] = np.arange(problem.free.size)
        self.position = position.reshape(self.nb, 6)
        idx = np.arange(6)
        elastic = np.zeros((m, 6, 6))
        elastic[:, idx, idx] = problem.law.kbar
        Ke = self.block_stiffness(elastic)[self.candidates]
        # each candidate's elastic block is positive definite (it has joints); its Cholesky
        # factor makes the test a fraction of the block's own elastic stiffness, in every
        # direction, whatever the units of translations and rotations
        self._inverse_factor = np.linalg.inv(np.linalg.cholesky(Ke))
        self.factorizations = 0  # of the local tangents
        self.solves = 0

    def block_stiffness(self, T: np.ndarray) -> np.ndarray:
        """(nb, 6, 6) each block's own diagonal block of H^T T H for the joints' tangents T
        (m, 6, 6): the stiffness of the block with every other block held."""
        H = self.H_loc
        out = np.zeros((self.nb, 36))
        for s, cols in ((0, slice(0, 6)), (1, slice(6, 12))):
            Hs = H[:, :, cols]  # (m, 6, 6)
            B = np.einsum("mki,mkl,mlj->mij", Hs, T, Hs).reshape(-1, 36)
            out += self._sum[s] @ B
        return out.reshape(self.nb, 6, 6)

    def weakest(self, response: LawResponse) -> np.ndarray:
        """(nb,) the smallest eigenvalue of each block's tangent block (its symmetric part,
        the floor excluded) relative to its elastic block (inf for blocks with a fixed DOF):
        1 for a block whose joints are all elastic, 0 along a mechanism of its joints."""
        T = self.problem.joint_tangents(response, 0.0)
        K = self.block_stiffness(T)[self.candidates]
        K = 0.5 * (K + np.swapaxes(K, 1, 2))
        L = self._inverse_factor
        M = L @ K @ np.swapaxes(L, 1, 2)
        out = np.full(self.nb, np.inf)
        out[self.candidates] = np.linalg.eigvalsh(M)[:, 0]
        return out

    def detect(self, response: LawResponse) -> np.ndarray:
        """The loose blocks at ``response`` (indices): those whose own tangent keeps less
        than ``threshold`` of their elastic stiffness in some direction."""
        return np.flatnonzero(self.weakest(response) < self.threshold)

    def groups(self, blocks: np.ndarray) -> np.ndarray:
        """(len(blocks),) the group of each of ``blocks``: blocks that share a joint are in
        one group (their equilibria are coupled)."""
        k = blocks.size
        local = np.full(self.nb, -1, dtype=np.int64)
        local[blocks] = np.arange(k)
        a, b = local[self.ends[:, 0]], local[self.ends[:, 1]]
        both = (a >= 0) & (b >= 0)
        graph = sparse.coo_matrix((np.ones(int(both.sum())), (a[both], b[both])), shape=(k, k))
        return csgraph.connected_components(graph, directed=False)[1]

    def solve(
        self,
        q: np.ndarray,
        blocks: np.ndarray,
        residual: Callable[[np.ndarray], tuple[np.ndarray, float, LawResponse]],
        floor: float,
        tolerance: float,
        iterations: int,
        limit: float,
        origin: np.ndarray,
    ) -> LocalSolve:
        """Newton on the DOFs of ``blocks`` alone from ``q``, every other DOF held:
        ``residual(q)`` is the wall's (R on the free DOFs, its norm, the law's response), the
        local tangent the rows and columns of the consistent tangent (with ``floor``) of
        those DOFs. Each group of blocks that touch (:meth:`groups`) takes its own step
        length (1, 1/8, ...), the first that lowers its residual (in the norm of the wall's,
        relative to the load); a group is solved when that falls to ``tolerance``, and left
        where it stands when no step lowers it or a translation of its blocks passes
        ``limit`` from ``origin`` (a local mechanism). At most ``iterations`` steps."""
        problem = self.problem
        self.solves += 1
        group = self.groups(blocks)
        n_groups = int(group.max()) + 1
        dofs = self.position[blocks].reshape(-1)  # free positions (all free: candidates)
        dof_group = np.repeat(group, 6)
        k = dofs.size
        local = np.full(problem.free.size, -1, dtype=np.int64)
        local[dofs] = np.arange(k)
        joints = np.flatnonzero(np.isin(self.ends, blocks).any(axis=1))
        ends = self.ends[joints]
        jdofs = np.concatenate([self.position[ends[:, 0]], self.position[ends[:, 1]]], axis=1)
        jlocal = np.where(jdofs >= 0, local[np.maximum(jdofs, 0)], -1)  # (mj, 12)
        rows = np.broadcast_to(jlocal[:, :, None], (joints.size, 12, 12))
        cols = np.broadcast_to(jlocal[:, None, :], (joints.size, 12, 12))
        keep = (rows >= 0) & (cols >= 0)
        weight = problem.weight[dofs]
        translation = problem.translation[dofs]
        start = q.copy()

        def norms(r: np.ndarray, scale: float) -> np.ndarray:
            w = (weight * r[dofs]) ** 2
            return np.sqrt(np.bincount(dof_group, weights=w, minlength=n_groups)) * scale

        r, rnorm, response = residual(q)
        # rnorm is |W R| / |W F|: the load's norm, to put each group's norm on that scale
        total = math.sqrt(float(((problem.weight * r) ** 2).sum()))
        scale = rnorm / total if total > 0 else 0.0
        g = norms(r, scale)
        active = g > tolerance
        failed = np.zeros(n_groups, dtype=bool)
        for _ in range(iterations):
            if not active.any():
                break
            T = problem.joint_tangents(response, floor)[joints]
            Hl = self.H_loc[joints]
            B = np.einsum("mki,mkl,mlj->mij", Hl, T, Hl)
            K = sparse.csc_matrix((B[keep], (rows[keep], cols[keep])), shape=(k, k))
            self.factorizations += 1
            try:
                dy = splu(K).solve(r[dofs])
            except RuntimeError:
                break
            if not np.all(np.isfinite(dy)):
                break
            dy[~active[dof_group]] = 0.0
            t = np.where(active, 1.0, 0.0)
            base = q[problem.free[dofs]].copy()
            pending = active.copy()
            before = g
            for _ in range(CUTS):
                q_try = q.copy()
                q_try[problem.free[dofs]] = base + t[dof_group] * dy
                g_try = norms(residual(q_try)[0], scale)
                lower = pending & (g_try < (1.0 - 1e-4 * t) * before)
                pending &= ~lower
                if not pending.any():
                    break
                t[pending] *= 0.125
            # groups that found no descent keep their DOFs; the others take their step
            t[pending] = 0.0
            failed |= pending
            active &= ~pending
            q = q.copy()
            q[problem.free[dofs]] = base + t[dof_group] * dy
            r, rnorm, response = residual(q)
            g = norms(r, scale)
            moved = np.abs(q[problem.free[dofs]] - origin[problem.free[dofs]])
            past = (
                np.bincount(
                    dof_group[translation],
                    weights=(moved[translation] > limit).astype(float),
                    minlength=n_groups,
                )
                > 0
            )
            if past.any():  # a local mechanism: those groups go back to where they were
                failed |= past
                active &= ~past
                back = past[dof_group]
                q[problem.free[dofs[back]]] = start[problem.free[dofs[back]]]
                r, rnorm, response = residual(q)
                g = norms(r, scale)
            active &= g > tolerance
        solved = int((~failed & (g <= tolerance)).sum())
        left = int(failed.sum())
        log.debug(
            "%d loose blocks in %d groups: %d solved, %d left (no local equilibrium)",
            blocks.size,
            n_groups,
            solved,
            left,
        )
        return LocalSolve(blocks, q, r, rnorm, response, solved, n_groups - solved - left, left)
