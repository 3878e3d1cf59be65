"""Rigid-block limit analysis of a :class:`~masonry_dem.model.Model`: the collapse multiplier
and mechanism in one convex solve (associative), or by a sequence of them (non-associative).

Statics. Each interface carries point forces at a grid of ``n x n`` contact points (the
Gauss-Lobatto points of the rectangle, corners included). Point k carries
``(t1, t2, n) = (0, 0, ft_k) + compression`` where ``ft_k`` is its share of the interface's
tensile force (tensile strength x area, Lobatto weights) and the compression lies in the
friction cone ``|t| <= mu c``, ``n = ft_k - c``, ``c >= 0``: no tension beyond ``ft``, Coulomb
friction with the cohesion ``mu ft`` of the paper's law (``fsu = mu (ft - fn)``), and rocking
and torsion that follow the interface's real area. A cohesion of its own ``c > mu ft``
(:class:`~masonry_dem.model.InterfaceMaterial`) grows each point's cone by the shear the joint
keeps at its tension cap, ``|t| <= mu c + (c - mu ft) A_k`` (``formulation.cohesive_offsets``;
docs/limit_analysis.md, "The formulation"). The point forces reduce to the interface
actions ``[f1, f2, fn, m1, m2, m3]`` about its centre (``m = y x p``), which are work-conjugate
to the rows of the compatibility matrix H of Eqs. (A1)-(A3); equilibrium of the free DOFs is
``H^T a = F_dead + lambda F_live``.

Cones. ``backend="highs"``: a pyramid of ``friction_sides`` faces, in generator form (the
compression is a non-negative combination of the pyramid's edges, ``(mu rho e_d, -1)``), so
the LP has only equality rows and sign bounds; ``"circumscribed"`` (default) contains the
circular cone of the DEM; ``"inscribed"`` lies inside it. ``backend="clarabel"``: the exact
circular cone, an SOCP solved in its kinematic form (``kinematic``).

The bound. The DEM's domain lies inside the LA's, and Radenkovic's theorem makes the
associative multiplier an upper bound of the pushover's, once the friction is enlarged by
kappa(alpha) (``dem_domain``: 1 for alpha = 1, 1.0655 for the default 1.5):
:func:`dem_upper_bound`.

The package, by role: ``interface`` (grid, pyramid, actions of point forces),
``formulation`` (equilibrium rows, units, lambda cap), ``backends`` (HiGHS; static Clarabel),
``kinematic`` (the kinematic SOCP, Clarabel), ``normal_ipm`` (the same SOCP by an interior
point method on the normal equations, PARDISO, stopped at a certified bracket of lambda; the
exact cone's solver from ``NORMAL_EQUATIONS_FROM`` velocities), ``cones`` (its second-order
cone kernels), ``mirror`` (a mirror plane's antisymmetric DOFs: a wall loaded in its plane is
solved on 3 velocities a block), ``dem_domain`` (kappa), ``non_associative``, ``columns``
(its frozen-capacity LPs by column generation), ``selection`` (the optimum of a degenerate
frozen LP nearest the frozen actions, ``nearest_optimum``),
``result`` (the result and the mechanism check), ``dead_load`` (the check made before any
solve: blocks that hang under the dead load with joints that do not dilate), ``budget`` (the
time and iteration limits of every solve), ``analysis`` (the entry points; with no backend
given, HiGHS on small walls and Clarabel from ``EXACT_CONE_FROM`` free DOFs).

Why the associative answer needs only the corners is argued in ``interface``: any grid that
holds the corners gives the same associative multiplier, so the default ``grid`` of the
associative problem is 2, and a finer grid only costs time
(``tests/solvers/test_limit_analysis.py`` checks 2 against 4). The same argument shows why
four corner contacts carry a torsion of ``mu N R`` (R the half diagonal), 1.7 to 1.9 times
the ``cT mu N`` of uniform pressure: the rigid-plastic interface may put its compression in
the corners.

Non-associative (zero dilatancy). The scheme of Gilbert, Casapulla & Ahmed (2006), "Limit
analysis of masonry block structures with non-associative frictional joints using linear
programming", Computers & Structures 84, 873-887: the friction capacity of each interface is
frozen at a set of normal actions (a cohesive, Tresca-like capacity, which sliding does not
dilate), the LP is solved again, and the capacities are updated (under-relaxed) until lambda
settles. Which actions: by default (``start="elastic"``) those of least complementary
energy, the dead load's first, then each frozen LP's optimum elastic joints would take
(``selection.elastic_state``, ``least_energy_frozen``), not the solver's vertex nor the
associative collapse, which may hold a self-stress no load path makes. The frozen capacity
is spread as the DEM spreads it (Figure 10): a uniform compression ``ft - fn`` on the
reduced rectangle ``l1 - 2|m2|/(ft - fn)`` x ``l2 - 2|m1|/(ft - fn)`` centred on the
resultant, integrated at its ``n x n`` Lobatto points, so the frozen torsion capacity is the
DEM's ``cT mu (ft - fn)`` to within the quadrature error (the default n is the smallest even
n for which it is within 1 % of the closed form on rectangles up to 4:1,
``benchmarks/bench_limit_analysis.py --grid-study``). The normal forces stay at the four
corners (no tension beyond ft, free rocking). Convergence: none is proved (the
non-associative problem is not convex and its solution need not be unique, and its LPs are
degenerate, so the actions may jump between equivalent vertices); the associative multiplier
bounds it from above (Radenkovic). The iteration stops when its last three lambdas lie
within ``tolerance`` (relative) of each other. Where lambda turns back (it oscillates
between degenerate LP vertices), the relaxation is halved, down to 1/64, a damping that lets
the frozen actions settle, and doubled back after three steps the same way, so that it does
not creep; the iteration reports ``failed`` with the last lambdas when ``max_iterations``
pass without it.
"""

from .analysis import dem_upper_bound, limit_analysis
from .dem_domain import dem_friction_scale, model_friction_scale
from .formulation import LAMBDA_CAP
from .interface import (
    ASSOCIATIVE_GRID,
    NON_ASSOCIATIVE_GRID,
    PYRAMIDS,
    grid_points,
    lobatto_rule,
    torsion_quadrature,
)
from .progress import LimitProgress
from .result import STATUSES, LimitAnalysisResult, mechanism_violation
from .settings import BACKENDS, LimitSettings

__all__ = [
    "ASSOCIATIVE_GRID",
    "BACKENDS",
    "LAMBDA_CAP",
    "NON_ASSOCIATIVE_GRID",
    "PYRAMIDS",
    "STATUSES",
    "LimitAnalysisResult",
    "LimitProgress",
    "LimitSettings",
    "dem_friction_scale",
    "dem_upper_bound",
    "grid_points",
    "limit_analysis",
    "lobatto_rule",
    "mechanism_violation",
    "model_friction_scale",
    "torsion_quadrature",
]
