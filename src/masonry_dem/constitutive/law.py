"""The elastic-perfectly-plastic interface law used by the panel solvers (Section 2.2).

Trial actions come from the elastic stiffness and the stored plastic relative displacements;
the closed-form domain of Section 2.1 (:func:`~masonry_dem.constitutive.strength.check_strength`)
projects them back (the force correction) and gives the damage state and the stiffness factors
of Eqs. (13)-(14).

What the law remembers between converged steps (``memory``):

* ``"slip"`` (default, the paper's incremental law): the sliding (shear and torsion)
  components keep their plastic slip, as friction does; normal and bending components stay
  memory-free in both modes. A dry joint is a
  unilateral contact: one that opened carries load again only when the gap has closed, and a
  rocking joint rocks back along the same curve. Storing a plastic opening (the textbook
  return mapping applied to every component) would instead let a joint that opened take
  compression as soon as its faces start to move back towards each other.
* ``"none"``: no plastic displacement is stored, so the actions are the projection of the
  *total* elastic trial (deformation-theory, or holonomic, plasticity): the equilibrium at a
  load level does not depend on the steps taken to reach it. Without a potential (friction
  is non-associative) a damped motion under it need not settle, so the reference analysis
  and the instability rule may give no verdict (docs/solvers.md, "The interface law").

Tensile strength (``tension``): ``"brittle"`` (a joint whose normal force exceeds ft loses
its tensile strength for good, as a cracked mortar joint does) or ``"plastic"`` (it keeps ft).
A cracked joint loses its cohesion with its tensile strength: it becomes a dry Coulomb joint,
shear strength ``-mu fn``. With the paper's cohesion c = mu ft this is what losing ft does; a
cohesion given of its own (:class:`~masonry_dem.model.InterfaceMaterial`) goes the same way.

``tension``, ``memory`` and the shear-torsion ``projection`` are set on the model's
:class:`~masonry_dem.model.InterfaceMaterial`. The compiled kernels are :mod:`~masonry_dem.constitutive.law_kernels`'.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal, get_args

import numpy as np
from scipy import sparse

from masonry_dem.constitutive.law_kernels import fd_tangent_rows, forces, law_tangent
from masonry_dem.constitutive.states import FACTORS_OF_FLAGS, FLAG_DETACHED, STATE_OF_FLAGS
from masonry_dem.constitutive.strength import (
    StrengthCheck,
    StrengthDomain,
    checked_actions,
    checked_field,
    evaluate,
    projection_and_flags,
    writable_c,
)
from masonry_dem.model import Memory, Model, Tension

DETACHED_FLAG = FLAG_DETACHED
#: how :meth:`InterfaceLaw.tangent` differentiates the projection of yielded joints
TangentMethod = Literal["analytic", "difference"]
MEMORY: tuple[str, ...] = get_args(Memory)
TENSION: tuple[str, ...] = get_args(Tension)
TANGENT_METHODS: tuple[str, ...] = get_args(TangentMethod)
#: components that keep plastic slip with ``memory="slip"``: f1, f2, m3
SLIP_COMPONENTS = np.array([True, True, False, False, False, True])
#: relative size of the finite-difference steps of the tangent
_FD_STEP = 1e-7
#: trial normal forces within this fraction of the largest one count as "in contact" for the
#: tangent: a joint with a zero gap and zero force must not flip between the tangents of a
#: detached and of a closed joint on round-off (Newton's iterations would cycle)
CONTACT_BAND = 1e-8


@dataclass(frozen=True)
class LawResponse:
    trial: np.ndarray  # (m, 6) elastic trial actions
    tensile_force: np.ndarray  # (m,) ft in force at this iterate (0 once cracked)
    actions: np.ndarray  # (m, 6) corrected actions
    flags: np.ndarray  # (m,) violated-criteria bit flags
    utilisation: np.ndarray | None  # (m,); None when not asked for (InterfaceLaw.utilisation)
    #: (m,) the cohesive force beyond mu ft at this iterate (0 once cracked); None: zero
    cohesion: np.ndarray | None = None

    # derived from the flags when asked for: most residuals of a search never need them
    @cached_property
    def tangent(self) -> np.ndarray:
        """(m, 6) stiffness factors of Eqs. (13)-(14), 0 or 1."""
        return FACTORS_OF_FLAGS[self.flags]

    @cached_property
    def strength_at_zero(self) -> np.ndarray:
        """(m,) positive where a joint has a strength at zero normal force: its tensile force
        or its cohesive force beyond mu ft (both >= 0; the tensile force itself without
        one)."""
        if self.cohesion is None:
            return self.tensile_force
        return self.tensile_force + self.cohesion

    @cached_property
    def state(self) -> np.ndarray:
        """(m,) damage code."""
        return STATE_OF_FLAGS[self.flags]


@dataclass(frozen=True)
class InterfaceLaw:
    """Batched law for all interfaces of a model (arrays with one row per interface)."""

    kbar: np.ndarray  # (m, 6) elastic stiffness
    l1: np.ndarray
    l2: np.ndarray
    friction: np.ndarray
    tensile_force: np.ndarray  # (m,) ft = tensile strength x area
    alpha: np.ndarray
    tension: Tension = "brittle"
    memory: Memory = "slip"
    projection: str = "energy"  # shear-torsion return (see check_strength)
    #: (m,) c0 = (c - mu ft) x area, the cohesive force beyond the paper's mu ft; None: zero
    cohesion: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.tension not in TENSION:
            raise ValueError(f"tension must be one of {TENSION}, got {self.tension!r}")
        if self.memory not in MEMORY:
            raise ValueError(f"memory must be one of {MEMORY}, got {self.memory!r}")

    @classmethod
    def of(
        cls,
        model: Model,
        kbar: np.ndarray,
        tension: Tension | None = None,
        memory: Memory | None = None,
    ) -> InterfaceLaw:
        """The law of ``model``'s interfaces with stiffness ``kbar``; its options are the
        model's material's (``tension`` or ``memory`` given here override them: the
        deprecated settings fields of the solvers)."""
        its = model.interfaces
        beyond = model.cohesion_beyond_friction  # zero, bit for bit, where c = mu ft
        return cls(
            kbar,
            its.l1,
            its.l2,
            model.friction,
            model.tensile_strength * its.area,
            model.alpha,
            model.tension if tension is None else tension,
            model.memory if memory is None else memory,
            model.projection,
            beyond * its.area if beyond.any() else None,
        )

    @cached_property
    def _domain(self) -> StrengthDomain:
        """Validated per-interface constants of the strength check, built on the first call
        (the arrays are not meant to change afterwards)."""
        m = self.kbar.shape[0]
        checked_field("tensile_force", self.tensile_force, m, minimum=0.0, strict=False)
        return StrengthDomain.of(m, self.l1, self.l2, self.friction, self.alpha)

    @cached_property
    def _tensile_rows(self) -> np.ndarray:
        """ft of every row, (m,) and contiguous: the compiled forces read one per row (a
        scalar ``tensile_force`` was read past its end)."""
        m = self.kbar.shape[0]
        ft = checked_field("tensile_force", self.tensile_force, m, minimum=0.0, strict=False)
        return writable_c(ft)

    @cached_property
    def _cohesion_rows(self) -> np.ndarray:
        """c0 of every row, (m,) and contiguous (zeros without a cohesion of its own)."""
        m = self.kbar.shape[0]
        if self.cohesion is None:
            return np.zeros(m)
        return writable_c(checked_field("cohesion", self.cohesion, m, minimum=0.0, strict=False))

    def cohesion_at(self, cracked: np.ndarray) -> np.ndarray | None:
        """(m,) the cohesive force beyond mu ft of the joints, zero where ``cracked`` (None
        without a cohesion of its own: zero everywhere)."""
        if self.cohesion is None:
            return None
        return np.where(cracked, 0.0, self._cohesion_rows)

    def _check(self, trial: np.ndarray, ft: np.ndarray, c0: np.ndarray | None) -> StrengthCheck:
        if not np.isfinite(trial.sum()):  # one cheap test; _actions says what is wrong
            trial = checked_actions(trial)
        return evaluate(trial, ft, self._domain, projection=self.projection, c0=c0)

    def respond(
        self,
        relative: np.ndarray,
        plastic: np.ndarray,
        cracked: np.ndarray,
        utilisation: bool = True,
    ) -> LawResponse:
        """Actions for relative displacements (m, 6) given the plastic part (m, 6) and the
        joints already cracked in tension (m,) bool. ``utilisation=False`` leaves the
        utilisation out (None; :meth:`utilisation` computes it later): the same actions and
        flags bit for bit, about a quarter faster, for residuals that only need the forces."""
        trial = self.kbar * (relative - plastic)
        ft = np.where(cracked, 0.0, self.tensile_force)
        c0 = self.cohesion_at(cracked)
        if utilisation:
            chk = self._check(trial, ft, c0)
            actions, flags, util = chk.projected, chk.flags, chk.utilisation  # fresh arrays
        else:
            if not np.isfinite(trial.sum()):  # one cheap test; _actions says what is wrong
                trial = checked_actions(trial)
            actions, flags = projection_and_flags(trial, ft, self._domain, self.projection, c0=c0)
            util = None
        if self.tension == "brittle":
            actions[(flags & DETACHED_FLAG) > 0] = 0.0
        return LawResponse(trial, ft, actions, flags, util, c0)

    def forces(
        self,
        H: sparse.csr_matrix,
        x: np.ndarray,
        plastic: np.ndarray,
        cracked: np.ndarray,
        H_T: sparse.csr_matrix,
    ) -> tuple[np.ndarray, LawResponse, np.ndarray]:
        """(relative displacements ``H @ x``, ``respond(H @ x, plastic, cracked,
        utilisation=False)``, generalised forces ``H_T @ actions``), the same bits, in one
        compiled pass: a Newton residual or a time step without its intermediate arrays and
        calls."""
        kernel = forces.for_rows(self.kbar.shape[0])
        rel, trial, ft, actions, flags, internal, finite = kernel(
            writable_c(x), *self.kernel_operands(H, plastic, cracked, H_T)
        )
        if not finite:
            checked_actions(trial)  # says which action is not finite
        response = LawResponse(trial, ft, actions, flags, None, self.cohesion_at(cracked))
        return rel, response, internal

    def kernel_operands(
        self,
        H: sparse.csr_matrix,
        plastic: np.ndarray,
        cracked: np.ndarray,
        H_T: sparse.csr_matrix,
    ) -> tuple[Any, ...]:
        """The arguments of the kernel of :meth:`forces` after x, in its order: for a
        compiled caller that evaluates the law itself (a relaxation's time steps)."""
        dom = self._domain
        return (
            _unsigned(H.indptr),
            _unsigned(H.indices),
            H.data,
            np.ascontiguousarray(self.kbar, dtype=float),
            np.ascontiguousarray(plastic, dtype=float),
            np.ascontiguousarray(cracked, dtype=bool),
            self._tensile_rows,
            self._cohesion_rows,
            *dom.kernel_arrays,
            dom.row_constants,
            self.projection == "energy",
            self.tension == "brittle",
            _unsigned(H_T.indptr),
            _unsigned(H_T.indices),
            H_T.data,
            H_T.shape[0],
        )

    def utilisation(self, r: LawResponse) -> np.ndarray:
        """(m,) utilisation of the trial actions of ``r`` (see :func:`check_strength`)."""
        if r.utilisation is not None:
            return r.utilisation
        return self._check(r.trial, r.tensile_force, r.cohesion).utilisation

    def admissibility(self, r: LawResponse) -> np.ndarray:
        """(m,) demand/capacity of the corrected actions of ``r`` (at most 1 where they lie
        in the strength domain, up to the round-off of the return)."""
        return self._check(np.ascontiguousarray(r.actions), r.tensile_force, r.cohesion).utilisation

    def tangent(self, r: LawResponse, floor: float = 1e-9, method: str = "analytic") -> np.ndarray:
        """(m, 6, 6) consistent tangent d(actions)/d(relative displacements) at ``r``.

        Elastic joints: diag(kbar). Detached joints: zero. Yielded joints: the derivative of
        the projection of :func:`check_strength`. It holds every coupling of the domain:
        capacities that grow with compression (a sliding or rocking joint still stiffens in
        the normal direction), the curved shear-torsion surface of Eq. (A5) and the
        torsion-bending interaction. Joints with a zero gap and zero force are differentiated
        on the contact side. ``floor`` x kbar is added to the diagonal so that the matrix of a
        mechanism stays regular.

        ``method="analytic"`` (default) differentiates the energy return in closed form
        (implicit differentiation of the closest point) and keeps the forward difference for
        the rows it does not cover (zero capacity, alpha = 1, no shear, the radial
        projection); ``"difference"`` takes the forward difference of every yielded row, by
        one batched call (7 projections a row; on the small walls of the validation set it
        was a third of a static analysis).
        """
        if method not in TANGENT_METHODS:
            raise ValueError(f"method must be one of {TANGENT_METHODS}, got {method!r}")
        c0 = np.zeros(r.flags.shape[0]) if r.cohesion is None else writable_c(r.cohesion)
        T, rows, t, h, ft, c0_rows, k, normal_only = law_tangent.serial(
            r.trial,
            r.tensile_force,
            c0,
            r.flags,
            r.actions,
            self.kbar,
            float(floor),
            CONTACT_BAND,
            _FD_STEP,
            *self._domain.kernel_arrays,
            self.projection == "energy",
            method == "analytic",
        )
        if rows.size:  # the rows the analytic derivative does not cover
            fd = fd_tangent(t, h, ft, rows, self._domain, k, self.projection, normal_only, c0_rows)
            diagonal = np.arange(6)
            fd[:, diagonal, diagonal] += float(floor) * k
            T[rows] = fd
        return T

    def plastic_part(self, relative: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Plastic relative displacements to store at a converged state (see ``memory``)."""
        if self.memory == "none":
            return np.zeros_like(relative)
        plastic = relative - actions / self.kbar
        plastic[:, ~SLIP_COMPONENTS] = 0.0
        return plastic

    def cracked_after(self, cracked: np.ndarray, response: LawResponse) -> np.ndarray:
        if self.tension != "brittle":
            return cracked
        return cracked | ((response.flags & DETACHED_FLAG) > 0)


def _unsigned(index: np.ndarray) -> np.ndarray:
    """The unsigned view of a sparse matrix's index array (int32 or int64, never negative):
    a compiled gather through it needs no test for negative indices."""
    return index.view(np.uint32 if index.dtype.itemsize == 4 else np.uint64)


def fd_tangent(
    trial: np.ndarray,
    h: np.ndarray,
    ft: np.ndarray,
    rows: np.ndarray,
    dom: StrengthDomain,
    kbar: np.ndarray,
    projection: str = "energy",
    normal_only: np.ndarray | None = None,
    c0: np.ndarray | None = None,
) -> np.ndarray:
    """(n, 6, 6) forward-difference tangent of the projection at ``trial`` (n, 6), steps ``h``
    (n, 6), for the rows ``rows`` of ``dom`` (``ft`` and ``kbar`` already taken at those rows);
    ``normal_only`` (n,) marks rows at zero capacity, probed along fn alone; ``c0`` (n,) the
    rows' cohesive force beyond mu ft (None: zero); see
    :data:`~masonry_dem.constitutive.law_kernels.fd_tangent_rows`."""
    n = trial.shape[0]
    out = np.empty((n, 6, 6))
    fd_tangent_rows.for_rows(dom.l1.shape[0])(
        writable_c(trial),
        writable_c(h),
        writable_c(ft),
        np.zeros(n) if c0 is None else writable_c(c0),
        np.ascontiguousarray(rows, dtype=np.int64),
        *dom.kernel_arrays,
        projection == "energy",
        writable_c(kbar),
        np.zeros(n, dtype=np.bool_) if normal_only is None else np.asarray(normal_only, bool),
        out,
    )
    return out
