"""Settings of the static solver: every number that steers it, with why it has its value
(the measurements behind each are in docs/history/solvers_record.md, "Settings and their
evidence")."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal, get_args

from masonry_dem._docstrings import SHARED, fill
from masonry_dem._validation import (
    check_choice,
    choice,
    count,
    finite,
    is_count,
    is_number,
    positive,
)
from masonry_dem.constitutive.law import TANGENT_METHODS, TangentMethod
from masonry_dem.model import DofName
from masonry_dem.solvers.load_path import LoadPathSettings

#: what follows the first failure of load control (see ``StaticSettings.continuation``)
Continuation = Literal["work", "bracket"]
CONTINUATION: tuple[str, ...] = get_args(Continuation)


@fill(SHARED)
@dataclass(frozen=True)
class StaticSettings(LoadPathSettings):
    """The settings of the static solver: the parameters of its methods and its tolerances.

    The physical tolerances and the parameters of the methods, each with its range and source
    in docs/solvers.md, "Settings". Step sizes are in load scales ``|F_D| / |F_L|`` (1 for a tilt
    table, where the live load is the weight turned horizontal). The fields come in three
    groups: the path (load control, then work control; Batoz & Dhatt 1979), from
    ``initial_step`` to ``flat_slope``; one equilibrium (the corrector: Newton with a trust
    region and a line search), from ``tolerance`` to ``tangent``; the certificate of a
    collapse (:mod:`masonry_dem.solvers.static.certificate`), from ``certify`` on. A value out
    of range is refused at construction, by the field's name.

    Parameters
    ----------
    initial_step, max_step : float, default 0.02 and 1.0
        The first and the largest lambda increment of load control in load scales, > 0.
    growth : float, default 1.5
        An easy step makes the next one ``growth`` times longer (the same rule for the steps
        of work control), >= 1.
    bracket_tolerance : float, default 0.005
        Collapse bracket width, relative to lambda, > 0; also how far above a stop the
        instability rule looks for rest.
    refine : bool, default True
        Halve a failed load step (False: stop at the first failure, an upper bracket only,
        unchecked by the instability rule).
    max_steps : int, default 1000
        Converged steps of a run (all path followers together), >= 1.
    max_load_factor : float, default inf
        The run ends ``completed`` when lambda reaches it, > 0 (inf: no cap).
    displacement_limit : float, optional
        Largest translation [m] still in the small-displacement range, > 0 (None: half the
        smallest dimension of the blocks that can move).
    easy_iterations : int, default 6
        A step that converges in at most this many Newton iterations is easy (quadratic
        convergence from well inside the basin), >= 0.
    continuation : {"work", "bracket"}, default "work"
        What follows the first failure of load control: ``"work"``, the work-conjugate
        displacement of the live load prescribed, lambda free, past plastic plateaus;
        ``"bracket"``: the paper's method, the load-control bracket refined.
    elastic_first_step : bool, default True
        The first live step goes to just short of the end of the elastic range (the load at
        which the first joint reaches its strength domain along the tangent response of the
        dead-load state), started from that response.
    tolerance : float, default 1e-8
        Force residual ``|R| / |F_D + lambda F_L|`` (moments as forces at the median block size)
        below which a state is in equilibrium, > 0.
    control_tolerance : float, default 1e-6
        A controlled displacement is reached within this fraction of the step, > 0.
    max_iterations : int, default 40
        Newton iterations per search, >= 1.
    residual_stiffness : float, default 1e-9
        Fraction of the elastic stiffness kept on the tangent's diagonal, > 0.
    tangent : {"analytic", "difference"}, default "analytic"
        ``"analytic"`` (the closed-form derivative of the return) or ``"difference"``.
    flat_slope : float, default 1e-3
        A work step gaining less than this fraction of the elastic d lambda / d w is flat;
        three in a row end the path (a formed mechanism); near the stop a step gains at most
        ``flat_slope`` x lambda (:func:`.steps.tail_cap`). Finite.
    certify : bool, default True
        Check a collapse before reporting it, with the instability rule at every stop (False:
        the stop of the path is reported as a collapse, unchecked).
    mode_stiffness : float, default 0.05
        The tangent of the last state is singular along the live load's mode when its
        Rayleigh quotient rho (against the dead-load tangent) is at most this, > 0.
    bound_tolerance : float, default 0.01
        lambda may exceed the associative limit-analysis bound (when one is given) by this
        fraction, > 0.

    %(field_errors)s

    Notes
    -----
    Where Newton finds no equilibrium, and at every stop of the path, one rule decides: the
    damped motion of the reference analysis (:mod:`masonry_dem.solvers.quasi_static`) at a
    bracket above (``StaticSolver.rule_at``). Its own numbers and the corrector's safeguards
    are constants of their modules, each with its reason.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.StaticSettings(continuation="bracket").max_step
    1.0
    >>> md.StaticSettings(growth=0.5)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: ...growth...
    """

    easy_iterations: int = count(6, least=0)
    continuation: Continuation = choice("work", CONTINUATION)
    elastic_first_step: bool = True
    tolerance: float = positive(1e-8)
    control_tolerance: float = positive(1e-6)
    max_iterations: int = count(40, least=1)
    residual_stiffness: float = positive(1e-9)
    tangent: TangentMethod = choice("analytic", TANGENT_METHODS)
    flat_slope: float = finite(1e-3)
    certify: bool = True
    mode_stiffness: float = positive(0.05)
    bound_tolerance: float = positive(0.01)


SETTING_NAMES = tuple(f.name for f in fields(StaticSettings))


@fill(SHARED)
@dataclass(frozen=True)
class DisplacementControl:
    """Drive DOF ``dof`` (name, e.g. ``u3``) of ``block`` to ``target`` in ``steps`` steps.

    Parameters
    ----------
    block : int
        The driven block, >= 0.
    dof : {"u1", "u2", "u3", "w1", "w2", "w3"}
        The driven DOF.
    target : float
        The displacement [m] (or rotation [rad]) to reach, finite and not 0.
    steps : int, default 50
        Steps to reach it, >= 1.

    %(field_errors)s

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.DisplacementControl(block=5, dof="u3", target=0.01).steps
    50
    """

    block: int
    dof: DofName
    target: float
    steps: int = 50

    def __post_init__(self) -> None:
        if not is_count(self.block, 0):
            raise ValueError(f"block must be an integer >= 0, got {self.block!r}")
        check_choice("dof", self.dof, get_args(DofName))
        if not is_number(self.target) or not math.isfinite(self.target) or self.target == 0:
            raise ValueError(f"target must be a finite number other than 0, got {self.target!r}")
        if not is_count(self.steps, 1):
            raise ValueError(f"steps must be an integer >= 1, got {self.steps!r}")
