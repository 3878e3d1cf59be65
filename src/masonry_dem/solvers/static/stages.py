"""Loading stages: a static analysis run as a sequence of :class:`Stage` s, each with its own
loads, supports and path follower, the state carried from one to the next
(``masonry_dem.pushover(model, stages=[...])``; docs/solvers.md, "Loading stages").

The shear-wall test is the case in point: a vertical precompression on the top beam first;
then the beam held at its current height and against rotation while it is pushed sideways
by displacement.

What a stage adds, and what it keeps:

* the loads of the earlier stages stay on at the values they reached (the dead loads, and
  each live load at the lambda its stage ended at): together they are the dead load of the
  next stage, to which its own dead loads add; its live loads are scaled by its own lambda;
* the supports of the model and of the earlier stages stay; a DOF a stage holds anew is
  held at its current displacement (not at zero). The residual needs nothing for that: the
  interface law is evaluated on H q over every DOF, free and held (``delta = H_f q_f +
  H_h q_h``), and the corrector moves the free DOFs only, so a held DOF keeps the value it
  had when it was first held;
* the wall's state: q, the joints' plastic slip and their cracks.

Each stage is a static run of the model with the stage's fixed DOFs and loads
(:class:`~masonry_dem.solvers.static.solver.StaticSolver`, started from the carried state):
its first step is its dead-load equilibrium, then load control or its displacement control.
The steps of all stages make one History, each step numbered in it and marked with its
stage (``StepResult.stage``) and the reactions at the held DOFs (``StepResult.reactions``).
A stage that ends other than ``completed`` (a collapse, a failure) ends the analysis.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.model import LOAD_TYPES, Load, Model, Monitor, Support, _warn_idle_load
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.resources import should_stream
from masonry_dem.solvers.static.certificate import Bound
from masonry_dem.solvers.static.outcome import Status
from masonry_dem.solvers.static.settings import DisplacementControl, StaticSettings
from masonry_dem.solvers.static.solver import StaticSolver
from masonry_dem.streamed_history import StreamedSteps

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Stage:
    """One loading stage of a static analysis: the loads and supports it adds.

    How its live load is followed is ``control``. The loads of the earlier stages stay on
    at the values they reached, and their supports stay; a DOF this stage holds anew is held
    where it is (its current displacement, not zero). See :func:`masonry_dem.pushover` (``stages``) and docs/solvers.md, "Loading
    stages".

    Parameters
    ----------
    loads : sequence of loads, default ()
        :class:`~masonry_dem.SelfWeight`, :class:`~masonry_dem.WeightProportional`,
        :class:`~masonry_dem.Pressure`, :class:`~masonry_dem.PointLoad` added in this stage:
        dead ones are applied first and held, live ones are scaled by the stage's lambda.
    supports : sequence of Support, default ()
        The DOFs this stage holds (besides the model's and the earlier stages'), at their
        current displacements.
    control : DisplacementControl, optional
        Drive one free DOF to its target (the DOF's value, measured from the unloaded wall)
        with the stage's lambda free; None: load control of the stage's live load.
    name : str, default ""
        A label for messages (the stage's number when empty).

    Raises
    ------
    ValueError
        If ``loads`` or ``supports`` is not a list of loads or of Supports, ``control`` is
        not a DisplacementControl or None, or ``name`` is not a string, named with the value.

    Examples
    --------
    >>> import masonry_dem as md
    >>> push = md.Stage(
    ...     loads=[md.PointLoad([2], (1.0, 0.0, 0.0), live=True)],
    ...     supports=[md.Support([2], ["u2", "w3"])],
    ...     control=md.DisplacementControl(block=2, dof="u1", target=0.002),
    ...     name="push",
    ... )
    >>> push.name, len(push.loads), push.control.dof
    ('push', 1, 'u1')
    """

    loads: Sequence[Load] = ()
    supports: Sequence[Support] = ()
    control: DisplacementControl | None = None
    name: str = ""

    def __post_init__(self) -> None:
        for field_name, kinds, hint in (
            ("loads", tuple(LOAD_TYPES.values()), "PointLoad(blocks, force)"),
            ("supports", (Support,), "Support(blocks, dofs)"),
        ):
            items = getattr(self, field_name)
            if isinstance(items, (str, bytes, Mapping)) or not isinstance(items, Sequence):
                raise ValueError(
                    f"Stage.{field_name} must be a list, got {type(items).__name__} {items!r}"
                )
            for k, item in enumerate(items):
                if not isinstance(item, kinds):
                    allowed = " or ".join(t.__name__ for t in kinds)
                    raise ValueError(
                        f"Stage.{field_name}[{k}] must be a {allowed} (e.g. {hint}), got "
                        f"{type(item).__name__} {item!r}"
                    )
            object.__setattr__(self, field_name, tuple(items))
        if self.control is not None and not isinstance(self.control, DisplacementControl):
            raise ValueError(
                f"Stage.control must be a DisplacementControl or None, got "
                f"{type(self.control).__name__} {self.control!r}"
            )
        if not isinstance(self.name, str):
            raise ValueError(f"Stage.name must be a string, got {self.name!r}")


#: the fields a stage given as a mapping may name
STAGE_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(Stage))


def as_stages(stages: object) -> list[Stage]:
    """``stages`` as a list of :class:`Stage`, each given as a Stage or a mapping of its
    fields; a ValueError naming what is wrong (an empty list, an unknown field, a wrong
    type) otherwise."""
    if isinstance(stages, (str, bytes, Mapping)) or not isinstance(stages, Sequence):
        raise ValueError(f"stages must be a list of Stage, got {type(stages).__name__} {stages!r}")
    if len(stages) == 0:
        raise ValueError("stages must hold at least one Stage, got an empty list []")
    out = []
    for k, stage in enumerate(stages):
        if isinstance(stage, Mapping):
            unknown = [key for key in stage if key not in STAGE_FIELDS]
            if unknown:
                raise ValueError(
                    f"stages[{k}]: unknown field {unknown[0]!r} = {stage[unknown[0]]!r}; "
                    f"allowed: {', '.join(STAGE_FIELDS)}"
                )
            try:
                stage = Stage(**stage)
            except ValueError as exc:
                raise ValueError(f"stages[{k}]: {exc}") from exc
        if not isinstance(stage, Stage):
            raise ValueError(
                f"stages[{k}] must be a Stage (or a mapping of its fields), got "
                f"{type(stage).__name__} {stage!r}"
            )
        out.append(stage)
    return out


@dataclass(frozen=True)
class _Plan:
    """What one stage runs: its fixed DOFs, its dead and live loads (n, 6), its control and
    its label."""

    fixed: np.ndarray
    dead_loads: np.ndarray  # this stage's own dead loads (the carried ones added at run time)
    live: np.ndarray
    control: DisplacementControl | None
    label: str


def plan_stages(model: Model, stages: Sequence[Stage], warn: bool = True) -> list[_Plan]:
    """Each stage's fixed DOFs and own loads, checked before anything runs: a stage's
    loads and supports on the model's blocks, its control on a DOF free in it, and some
    DOF left free. ``warn``: log a load that acts on held DOFs alone (False: a check whose
    stages are planned again when they run, which warns then)."""
    n = model.blocks.count
    fixed = model.fixed.copy()
    plans = []
    for k, stage in enumerate(stages):
        where = f"stages[{k}]" + (f" ({stage.name})" if stage.name else "")
        dead = np.zeros((n, 6))
        live = np.zeros((n, 6))
        if k == 0:  # the model's own loads are the first stage's
            dead += model.dead
            live += model.live
        try:
            for support in stage.supports:
                fixed = fixed | support.mask(n)
            for j, load in enumerate(stage.loads):
                vector = load.vector(model.blocks)
                (live if load.live else dead)[...] += vector
                if warn:
                    _warn_idle_load(j, load, vector, fixed)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from exc
        if fixed.all():
            raise ValueError(f"{where}.supports: every DOF of the model is held; free some")
        control = stage.control
        if control is not None:
            try:
                dof = model.dof_index(control.block, control.dof)
            except ValueError as exc:
                raise ValueError(f"{where}.control: {exc}") from exc
            if fixed.reshape(-1)[dof]:
                raise ValueError(
                    f"{where}.control: dof {control.dof!r} of block {control.block} is held in "
                    f"this stage (by the model's supports or a stage's); the controlled DOF "
                    f"must be free"
                )
        label = f"stage {k + 1} of {len(stages)}" + (f" ({stage.name})" if stage.name else "")
        plans.append(_Plan(fixed.copy(), dead, live, control, label))
    return plans


def reactions(model: Model, step: StepResult, assembly: Any) -> np.ndarray:
    """(n, 6) the generalised forces the supports of ``model`` (a stage's: its fixed DOFs and
    loads) put on the blocks at ``step``: H^T f less the applied load F_D + lambda F_L at
    the held DOFs, zero at the free ones (the equilibrium of each held DOF)."""
    internal = assembly.internal_forces(np.asarray(step.actions))
    applied = (model.dead + step.load_factor * model.live).reshape(-1)
    out = np.where(model.fixed.reshape(-1), internal - applied, 0.0)
    return out.reshape(-1, 6)


def run_stages(
    model: Model,
    stages: Sequence[Stage | Mapping[str, Any]],
    settings: StaticSettings | None = None,
    *,
    monitor: Monitor | None = None,
    callback: Callable[[StepResult], None] | None = None,
    bound: Bound = None,
    stream: bool | str | Path | None = None,
) -> History:
    """Run ``stages`` in turn on ``model``, the state carried from one to the next, into one
    History (module docstring). ``callback(step)`` is called with each step of it (numbered
    in the whole run, marked with its stage); ``monitor`` is the curve's DOF in a stage
    with no control (a stage's control DOF is its curve's). ``settings``, ``bound`` and
    ``stream`` as for :meth:`StaticSolver.run`; ``settings.max_steps`` counts per stage."""
    plans = plan_stages(model, as_stages(stages))
    return run_plans(
        model, plans, settings, monitor=monitor, callback=callback, bound=bound, stream=stream
    )


def run_plans(
    model: Model,
    plans: Sequence[_Plan],
    settings: StaticSettings | None = None,
    *,
    monitor: Monitor | None = None,
    callback: Callable[[StepResult], None] | None = None,
    bound: Bound = None,
    stream: bool | str | Path | None = None,
) -> History:
    """:func:`run_stages` of stages already planned (:func:`plan_stages`: checked, their
    loads' warnings logged once), e.g. before a results folder was claimed."""
    t0 = time.perf_counter()
    if stream is None:
        stream = should_stream(model.blocks.count, model.interfaces.count)
    hist = History()
    if stream is not False:
        hist = History(steps=StreamedSteps(None if stream is True else Path(stream)))
    m = model.interfaces.count
    q = np.zeros(model.n_dofs)
    plastic = np.zeros((m, 6))
    cracked = np.zeros(m, dtype=bool)
    carried = np.zeros((model.blocks.count, 6))  # the earlier stages' loads, as they ended
    for k, plan in enumerate(plans):
        staged = replace(model, fixed=plan.fixed, dead=carried + plan.dead_loads, live=plan.live)
        solver = StaticSolver(staged, settings, bound=bound)
        if k > 0:  # the state the stage before ended in
            solver.start_from(q, plastic, cracked)
        asm = solver.problem.asm

        def on_step(step: StepResult, k: int = k, staged: Model = staged, asm: Any = asm) -> None:
            step = replace(
                step, step=len(hist.steps), stage=k, reactions=reactions(staged, step, asm)
            )
            hist.steps.append(step)
            if callback is not None:
                callback(step)

        log.info("%s: %s", model.name, plan.label)
        part = solver.run(
            control=plan.control,
            callback=on_step,
            monitor=monitor,
            stream=False if stream is False else True,
        )
        hist.iterations += part.iterations
        hist.factorizations += part.factorizations
        hist.status, hist.stop = part.status, part.stop
        hist.reason = f"{plan.label}: {part.reason}"
        hist.certificate = part.certificate
        hist.collapse_bracket = part.collapse_bracket
        if part.status is not Status.COMPLETED:
            if k + 1 < len(plans):
                hist.reason += f"; stages {k + 2} to {len(plans)} not run"
            break
        lam = part.final_load_factor
        carried = staged.dead + lam * staged.live
        q, plastic, cracked = solver.q, solver.plastic, solver.cracked
    hist.seconds = time.perf_counter() - t0
    return hist
