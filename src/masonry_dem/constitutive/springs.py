"""Fibre (spring) model of one interface, Section 2.1 of Baraldi & Cecchi.

An ``l1 x l2`` interface is divided into ``n x n`` equal cells with one spring at each cell
centre: a rigid indenter on an elastic-plastic Winkler support with friction. Per unit area each
spring has a normal stiffness ``kn`` and a shear stiffness ``ks`` (N/m^3). The normal stress is
elastic with a tension cut-off, ``sigma = min(kn * un, sigma_t)`` (no tension when
``sigma_t = 0``; the cut-off has no memory, which is exact for dry contact and for monotonic
opening). The shear stress is elastic-perfectly plastic with the Mohr-Coulomb limit
``|tau| <= c - mu sigma`` with ``c = mu sigma_t`` (Appendix; zero at the cut-off) or a
cohesion ``c >= mu sigma_t`` of its own (then ``c - mu sigma_t`` at the cut-off); the plastic
slip is remembered through the stress (radial return each step).

The indenter moves by a history of relative displacements and rotations about the interface
centre, in the package's local order ``[d1, d2, dn, delta1, delta2, delta3]`` (see
:mod:`masonry_dem.constitutive.strength`). At a spring at ``(y1, y2)``::

    slip1 = d1 - delta3 * y2,   slip2 = d2 + delta3 * y1,   un = dn + delta1 * y2 - delta2 * y1

and the resultants ``[f1, f2, fn, m1, m2, m3]`` are work-conjugate to those six components.
The history starts from the unloaded state; row k of a path is the total displacement at step k.
"""

from __future__ import annotations

import logging
from dataclasses import KW_ONLY, dataclass
from functools import cached_property
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar

from masonry_dem._parameters import function_of
from masonry_dem.constitutive.strength import DIRECTIONS, radial_factor
from masonry_dem.model import check_tension_cap

__all__ = [
    "REFERENCE_INTERFACE",
    "ReferenceInterface",
    "SpringInterface",
    "SpringResponse",
    "fit_alpha",
    "shear_strength_numeric",
    "torsion_shear_domain",
    "torsion_strength_numeric",
]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class ReferenceInterface:
    """The dry interface of Section 2.1 (Orduna 2004): block 0.30 x 0.20 x 0.20 m, 20 kN/m^3."""

    l1: float = 0.30  # block width b
    l2: float = 0.20  # block thickness s
    normal_force: float = -240.0  # N, self-weight of the block above
    kn: float = 2.4e9  # N/m^3 (2.4 MPa/mm)
    ks: float = 1.0e9  # N/m^3 (1 MPa/mm)
    friction: float = 0.7
    n: int = 32  # springs per side


REFERENCE_INTERFACE: Final = ReferenceInterface()

#: Final displacement of the strength runs, in multiples of the spring yield slip measured at the
#: spring nearest to the centre of rotation: every spring is deep in the plastic range.
_PLASTIC_MULTIPLE: Final[float] = 200.0


def _positive(name: str, value: float, *, strict: bool = True) -> float:
    v = float(value)
    if not np.isfinite(v) or (v <= 0 if strict else v < 0):
        rel = ">" if strict else ">="
        raise ValueError(f"{name} must be finite and {rel} 0, got {value!r}")
    return v


@dataclass(frozen=True)
class SpringResponse:
    """Response of :meth:`SpringInterface.run`; leading batch axis ``...`` as in the path.

    Attributes:
        displacements: (..., steps, 6) the imposed path, with dn replaced by the solved value
            when a normal force was prescribed.
        actions: (..., steps, 6) resultants ``[f1, f2, fn, m1, m2, m3]`` (N, N m).
        spring_normal: (..., steps, N) normal stress of each spring (Pa, tension positive).
        spring_shear: (..., steps, N, 2) shear stress (tau1, tau2) of each spring (Pa).
        centres: (N, 2) spring coordinates (y1, y2) about the interface centre (m).
        cell_area: area of one cell (m^2).
    """

    displacements: NDArray
    actions: NDArray
    spring_normal: NDArray
    spring_shear: NDArray
    centres: NDArray
    cell_area: float

    @property
    def ultimate(self) -> NDArray:
        """(..., 6) actions at the last step."""
        return self.actions[..., -1, :]


@dataclass(frozen=True)
class SpringInterface:
    """An ``l1 x l2`` interface discretized by ``n x n`` springs (Section 2.1, Figure 3).

    Args:
        l1, l2: sides along y1 and y2 (m), > 0.
        n: springs per side (n*n springs; spring index ``i * n + j``, i along y1).
        kn, ks: normal and shear stiffness per unit area (N/m^3), > 0.
        friction: mu >= 0.
        tensile_strength: sigma_t >= 0 (Pa).
        cohesion: c (Pa), ``mu * sigma_t <= c``; None: ``mu * sigma_t``.
    """

    l1: float
    l2: float
    n: int
    kn: float
    ks: float
    friction: float
    tensile_strength: float = 0.0
    cohesion: float | None = None

    def __post_init__(self) -> None:
        for name in ("l1", "l2", "kn", "ks"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))
        for name in ("friction", "tensile_strength"):
            object.__setattr__(self, name, _positive(name, getattr(self, name), strict=False))
        if self.cohesion is not None:
            object.__setattr__(self, "cohesion", _positive("cohesion", self.cohesion, strict=False))
            check_tension_cap(self.friction, self.tensile_strength, self.cohesion)
        if isinstance(self.n, bool) or not float(self.n).is_integer() or int(self.n) < 1:
            raise ValueError(f"n must be an integer >= 1, got {self.n!r}")
        object.__setattr__(self, "n", int(self.n))

    @property
    def area(self) -> float:
        return self.l1 * self.l2

    @property
    def cell_area(self) -> float:
        return self.area / self.n**2

    @property
    def tensile_force(self) -> float:
        """ft = sigma_t * area (N)."""
        return self.tensile_strength * self.area

    @cached_property
    def centres(self) -> NDArray:
        """(n*n, 2) spring coordinates (y1, y2) about the interface centre."""
        y1 = ((np.arange(self.n) + 0.5) / self.n - 0.5) * self.l1
        y2 = ((np.arange(self.n) + 0.5) / self.n - 0.5) * self.l2
        g1, g2 = np.meshgrid(y1, y2, indexing="ij")
        out = np.column_stack([g1.ravel(), g2.ravel()])
        out.flags.writeable = False
        return out

    def yield_slip(self, normal_force: float) -> float:
        """Shear slip at which a spring yields under a uniform normal stress (m)."""
        sigma = min(normal_force / self.area, self.tensile_strength)
        if self.cohesion is None:
            return self.friction * (self.tensile_strength - sigma) / self.ks
        return (self.cohesion - self.friction * sigma) / self.ks

    # ----------------------------------------------------------------------------------------

    def _normal_opening(self, disp: NDArray, normal_force: NDArray | None) -> NDArray:
        """(..., steps) solved dn so that the normal resultant equals ``normal_force``.

        The normal resultant is a non-decreasing piecewise-linear function of dn; its
        breakpoints (where a spring reaches the cut-off) are sorted and the linear piece that
        contains the target is solved exactly, for every step at once.
        """
        if normal_force is None:
            return disp[..., 2]
        y1, y2 = self.centres.T
        ecc = disp[..., 3, None] * y2 - disp[..., 4, None] * y1  # (..., steps, N)
        st, kn, area_c = self.tensile_strength, self.kn, self.cell_area
        n_springs = ecc.shape[-1]
        t = st / kn - ecc  # dn at which each spring reaches the cut-off
        order = np.argsort(t, axis=-1)
        ts = np.take_along_axis(t, order, axis=-1)
        es = np.take_along_axis(ecc, order, axis=-1)
        # suffix sums S_k = sum_{j >= k} es_j, k = 0..N
        suffix = np.concatenate(
            [np.cumsum(es[..., ::-1], axis=-1)[..., ::-1], np.zeros(es.shape[:-1] + (1,))],
            axis=-1,
        )
        k = np.arange(n_springs)
        force_at_t = area_c * (k * st + kn * ((n_springs - k) * ts + suffix[..., :n_springs]))
        target = normal_force[..., None]
        capped = np.sum(force_at_t <= target, axis=-1)  # springs at the cut-off
        elastic = n_springs - capped
        s_k = np.take_along_axis(suffix, capped[..., None], axis=-1)[..., 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            dn = (normal_force / area_c - capped * st - kn * s_k) / (kn * elastic)
        all_capped = elastic == 0
        return np.where(all_capped, ts[..., -1], dn)

    def run(self, path: ArrayLike, normal_force: ArrayLike | None = None) -> SpringResponse:
        """Drive the indenter along ``path`` and return resultants and spring stresses.

        Args:
            path: (steps, 6) or (batch, steps, 6) total relative displacements and rotations
                ``[d1, d2, dn, delta1, delta2, delta3]`` at each step (m, rad). Several paths
                are run at once, vectorized over paths and springs (the loop is over steps).
            normal_force: None to impose dn from the path; otherwise the normal resultant to
                hold (N, compression negative), a scalar or an array broadcastable to
                ``path.shape[:-1]``; dn (column 2 of the path) is then solved at every step.

        Raises:
            ValueError: bad path shape or non-finite values; a normal force above the tensile
                capacity ``tensile_strength * area``.
        """
        disp = np.array(path, dtype=float)
        if disp.ndim not in (2, 3) or disp.shape[-1] != 6 or disp.shape[-2] < 1:
            raise ValueError(
                f"path must have shape (steps, 6) or (batch, steps, 6), got {disp.shape}"
            )
        if not np.all(np.isfinite(disp)):
            raise ValueError("path must be finite")
        nf: NDArray | None = None
        if normal_force is not None:
            nf = np.asarray(normal_force, dtype=float)
            try:
                nf = np.broadcast_to(nf, disp.shape[:-1]).copy()
            except ValueError:
                raise ValueError(
                    f"normal_force must broadcast to {disp.shape[:-1]}, got shape {nf.shape}"
                ) from None
            if not np.all(np.isfinite(nf)):
                raise ValueError(f"normal_force must be finite, got {normal_force!r}")
            ft = self.tensile_force
            if np.any(nf > ft):
                raise ValueError(
                    f"normal_force must be <= tensile capacity {ft!r} N, got {nf.max()!r}"
                )
            disp[..., 2] = self._normal_opening(disp, nf)

        y1, y2 = self.centres.T
        mu, st = self.friction, self.tensile_strength
        d1, d2, dn, r1, r2, r3 = (disp[..., i, None] for i in range(6))
        sigma = np.minimum(self.kn * (dn + r1 * y2 - r2 * y1), st)  # (..., steps, N)
        if self.cohesion is None:
            tau_lim = np.maximum(mu * (st - sigma), 0.0)
        else:  # sigma <= st <= c / mu: never below c - mu st >= 0
            tau_lim = np.maximum(self.cohesion - mu * sigma, 0.0)
        slip = np.stack([d1 - r3 * y2, d2 + r3 * y1], axis=-1)  # (..., steps, N, 2)
        dslip = np.diff(slip, axis=-3, prepend=np.zeros_like(slip[..., :1, :, :]))
        dslip *= self.ks

        tau = np.empty_like(slip)
        current = np.zeros(slip.shape[:-3] + slip.shape[-2:])
        for k in range(slip.shape[-3]):  # path-dependent: loop over steps, vectorized inside
            current += dslip[..., k, :, :]
            norm = np.hypot(current[..., 0], current[..., 1])
            lim = tau_lim[..., k, :]
            over = norm > lim
            if over.any():
                scale = np.where(over, lim / np.where(over, norm, 1.0), 1.0)
                current *= scale[..., None]
            tau[..., k, :, :] = current

        area_c = self.cell_area
        actions = np.empty(disp.shape)
        actions[..., 0] = tau[..., 0].sum(axis=-1) * area_c
        actions[..., 1] = tau[..., 1].sum(axis=-1) * area_c
        actions[..., 2] = sigma.sum(axis=-1) * area_c
        actions[..., 3] = (sigma @ y2) * area_c
        actions[..., 4] = -(sigma @ y1) * area_c
        actions[..., 5] = (tau[..., 1] @ y1 - tau[..., 0] @ y2) * area_c
        return SpringResponse(
            displacements=disp,
            actions=actions,
            spring_normal=sigma,
            spring_shear=tau,
            centres=self.centres,
            cell_area=area_c,
        )

    # ----------------------------------------------------------------------------------------

    def rotation_paths(
        self, shear_direction: ArrayLike, theta: ArrayLike, normal_force: float, steps: int = 4
    ) -> NDArray:
        """Proportional (d, delta3) paths whose centre of rotation sweeps the plane.

        Path i ends at ``d = U sin(theta_i) e`` and ``delta3 = U cos(theta_i) / R`` with ``e``
        the unit shear direction (angle from y1), ``R`` the half diagonal and ``U`` large
        enough for every spring to be deep in the plastic range: ``theta = 0`` is pure torsion
        and ``theta = pi/2`` pure shear along ``e``. Returns (len(theta), steps, 6).
        """
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        ang = np.broadcast_to(np.asarray(shear_direction, dtype=float), th.shape)
        radius = 0.5 * np.hypot(self.l1, self.l2)
        # the spring nearest to a centre of rotation on the interface is at most half a cell
        # diagonal away, but at least min(cell side)/2 from the interface centre
        h_min = 0.5 * min(self.l1, self.l2) / self.n
        u_y = max(self.yield_slip(normal_force), np.finfo(float).tiny)
        amp = _PLASTIC_MULTIPLE * u_y * max(1.0, radius / h_min)
        end = np.zeros(th.shape + (6,))
        end[:, 0] = amp * np.sin(th) * np.cos(ang)
        end[:, 1] = amp * np.sin(th) * np.sin(ang)
        end[:, 5] = amp * np.cos(th) / radius
        frac = np.arange(1, steps + 1) / steps
        return end[:, None, :] * frac[None, :, None]


# --------------------------------------------------------------------------------------------
# strength helpers


def _interface(
    l1: float,
    l2: float,
    n: int,
    kn: float | None,
    ks: float | None,
    friction: float,
    st: float,
    cohesion: float | None = None,
) -> SpringInterface:
    ref = REFERENCE_INTERFACE
    return SpringInterface(
        l1=l1,
        l2=l2,
        n=n,
        kn=ref.kn if kn is None else kn,
        ks=ref.ks if ks is None else ks,
        friction=friction,
        tensile_strength=st,
        cohesion=cohesion,
    )


@dataclass(frozen=True)
class _StrengthRun:
    """A strength run of the spring model: an ``l1`` x ``l2`` interface with ``friction`` and
    ``tensile_strength`` (and ``cohesion``, None: mu x tensile strength), under the constant
    ``normal_force``, of ``n`` x ``n`` springs of stiffness ``kn``, ``ks`` (None: the
    reference interface's), loaded in ``steps`` steps."""

    l1: float
    l2: float
    normal_force: float
    friction: float
    tensile_strength: float = 0.0
    _: KW_ONLY
    n: int = 32
    kn: float | None = None
    ks: float | None = None
    steps: int = 20
    cohesion: float | None = None

    def interface(self, l1: float, l2: float, tensile_strength: float) -> SpringInterface:
        return _interface(
            l1, l2, self.n, self.kn, self.ks, self.friction, tensile_strength, self.cohesion
        )


@dataclass(frozen=True)
class _ShearStrengthNumeric(_StrengthRun):
    """Spring-model shear strength |f| (N) for pure relative shear along each of ``angles``.

    One incremental analysis per direction (angle from y1, rad), all run at once, under the
    constant ``normal_force``; returns the shear force at the last step, shape of ``angles``.
    """

    angles: ArrayLike = 0.0

    def __call__(self) -> NDArray:
        iface = self.interface(self.l1, self.l2, self.tensile_strength)
        ang = np.asarray(self.angles, dtype=float)
        fn = self.normal_force
        paths = iface.rotation_paths(ang.ravel(), np.full(ang.size, 0.5 * np.pi), fn, self.steps)
        ult = iface.run(paths, normal_force=fn).ultimate
        return np.hypot(ult[:, 0], ult[:, 1]).reshape(ang.shape)


@dataclass(frozen=True)
class _TorsionStrengthNumeric(_StrengthRun):
    """Spring-model pure-torsion strength (N m): an incremental relative rotation delta3.

    Without bending moments the interface of ``n x n`` springs (with its tensile strength) is
    twisted about its centre under the constant ``normal_force``. With bending moments the
    paper's assumption is followed (Figure 10, after Orduna and Lourenco): the compression
    ``ft - fn`` is uniform over the reduced rectangle
    ``l1' = l1 - 2|m2|/(ft - fn)``, ``l2' = l2 - 2|m1|/(ft - fn)``, which is discretized by its
    own ``n x n`` springs and twisted about its centre (so the resultant shear is zero). With
    a ``cohesion`` above mu x tensile strength, the rest of the interface sits at the cut-off,
    where the shear strength is ``c - mu sigma_t``: the whole interface, as springs of that
    cohesion and no friction, twisted about its centre, adds its torsion.
    """

    m1: float = 0.0
    m2: float = 0.0

    def __call__(self) -> float:
        l1, l2, m1, m2 = self.l1, self.l2, self.m1, self.m2
        ft = self.tensile_strength * l1 * l2
        cap = ft - self.normal_force
        if cap <= 0:
            raise ValueError(
                f"normal_force must be below the tensile capacity {ft!r}, got {self.normal_force!r}"
            )
        if m1 == 0 and m2 == 0:
            iface = self.interface(l1, l2, self.tensile_strength)
            fn = self.normal_force
        else:
            l1r = l1 - 2.0 * abs(m2) / cap
            l2r = l2 - 2.0 * abs(m1) / cap
            if l1r <= 0 or l2r <= 0:
                raise ValueError(
                    f"bending moments m1={m1!r}, m2={m2!r} reach the rocking limit: no compressed area"
                )
            iface = _interface(l1r, l2r, self.n, self.kn, self.ks, self.friction, 0.0)
            fn = -cap
        path = iface.rotation_paths(0.0, np.zeros(1), fn, self.steps)
        m3 = float(iface.run(path, normal_force=fn).ultimate[0, 5])
        if (m1 != 0 or m2 != 0) and self.cohesion is not None:
            beyond = self.cohesion - self.friction * self.tensile_strength
            if beyond > 0:
                rest = _interface(l1, l2, self.n, self.kn, self.ks, 0.0, 0.0, beyond)
                path = rest.rotation_paths(0.0, np.zeros(1), 0.0, self.steps)
                m3 += float(rest.run(path, normal_force=0.0).ultimate[0, 5])
        return m3


shear_strength_numeric = function_of(_ShearStrengthNumeric)
torsion_strength_numeric = function_of(_TorsionStrengthNumeric)


def _direction_angle(direction: str) -> float:
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    return {"f1": 0.0, "f2": 0.5 * np.pi, "f1=f2": 0.25 * np.pi}[direction]


def torsion_shear_domain(
    aspect: float, direction: str = "f1", n: int = 32, points: int = 64, steps: int = 4
) -> tuple[NDArray, NDArray]:
    """Dimensionless torsion-shear strength domain of the spring model (Figures 8, 9, A4).

    Proportional paths of shear displacement along ``direction`` combined with a rotation
    delta3 (``"f1"``: d1 only, ``"f2"``: d2 only, ``"f1=f2"``: d1 = d2, the paper's loading for
    the third column of Table A1; only for a square are the two forces then equal). Their
    ultimate actions, normalised by the spring model's own pure-torsion and pure-shear
    strengths, give points ``(x, y) = (|m3|/m3u, |f|/fsu)`` ordered from pure torsion (1, 0) to
    pure shear (0, 1), endpoints included. The domain depends only on the aspect ratio l1/l2
    (the reference interface's l2 = 0.2 m, stiffness and friction are used).
    """
    aspect = _positive("aspect", aspect)
    if int(points) < 3:
        raise ValueError(f"points must be >= 3, got {points!r}")
    ref = REFERENCE_INTERFACE
    iface = _interface(aspect * ref.l2, ref.l2, n, None, None, ref.friction, 0.0)
    theta = np.linspace(0.0, 0.5 * np.pi, int(points))
    paths = iface.rotation_paths(_direction_angle(direction), theta, ref.normal_force, steps)
    ult = iface.run(paths, normal_force=ref.normal_force).ultimate
    f = np.hypot(ult[:, 0], ult[:, 1])
    m3 = np.abs(ult[:, 5])
    return m3 / m3[0], f / f[-1]


def fit_alpha(
    aspect: float,
    direction: str = "f1",
    n: int = 32,
    points: int = 64,
    samples: int = 45,
) -> float:
    """Exponent alpha of ``(m3/m3u)^alpha + (f/fsu)^2 = 1`` fitted to the spring-model domain.

    The domain of :func:`torsion_shear_domain` is resampled at ``samples`` polar angles spread
    uniformly over the quarter plane (so the fit weighs every part of the boundary alike,
    whatever the path sampling), and alpha minimises the sum of squared logarithmic radial
    distances between those points and the curve, alpha in [1, 4].
    """
    x, y = torsion_shear_domain(aspect, direction, n=n, points=points)
    phi = np.arctan2(y, x)
    order = np.argsort(phi)
    phis = np.linspace(0.0, 0.5 * np.pi, int(samples) + 2)[1:-1]
    r = np.interp(phis, phi[order], np.hypot(x, y)[order])
    a, c = r * np.cos(phis), r * np.sin(phis)

    def objective(alpha: float) -> float:
        s = radial_factor(a, c, np.full_like(a, alpha))
        return float(np.sum(np.log(s) ** 2))

    res = minimize_scalar(objective, bounds=(1.0, 4.0), method="bounded", options={"xatol": 1e-6})
    logger.debug("fit_alpha(%g, %s, n=%d) = %.4f", aspect, direction, n, res.x)
    return float(res.x)
