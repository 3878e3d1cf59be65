"""Results of an analysis: one StepResult per converged step, the History of a run, and how a
run ended (Status) and why its path stopped (StopReason)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import nullcontext
from dataclasses import dataclass, field
from enum import Enum
from functools import cached_property
from typing import Any, Protocol, overload

import numpy as np
from numpy.typing import NDArray

from masonry_dem._arrays import FloatArray
from masonry_dem._docstrings import SHARED, fill
from masonry_dem._validation import read_only

# re-exported: the names of the codes of StepResult.state (docs/rendering.md)
from masonry_dem.constitutive.states import STATE_NAMES as STATE_NAMES


class _Text(str, Enum):
    """A str enum that prints and formats as its value (``enum.StrEnum`` is 3.11+)."""

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)


class Status(_Text):
    """How a run ended.

    ``COLLAPSE`` only with a certificate that holds (see
    :mod:`masonry_dem.solvers.static.certificate`); a path that stops without one is
    ``FAILED``, with every step it converged kept. A ``str`` enum: ``status == "collapse"``
    holds and ``json.dumps`` writes the plain value.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.Status("collapse") is md.Status.COLLAPSE, md.Status.COLLAPSE == "collapse"
    (True, True)
    >>> f"{md.Status.FAILED}"
    'failed'
    """

    RUNNING = "running"
    COMPLETED = "completed"
    COLLAPSE = "collapse"
    FAILED = "failed"


class StopReason(_Text):
    """Why the path of a run stopped (whatever the status that follows from it).

    Callers branch on these members, never on words of the reason texts (which are for
    people). A ``str`` enum, its value the words.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.StopReason.CURVE_FLAT.value
    'pushover curve flat'
    >>> md.StopReason("no live load") is md.StopReason.NO_LIVE_LOAD
    True
    """

    NONE = "none"  # still running
    DEAD_LOAD = "no equilibrium under the dead load"
    NO_LIVE_LOAD = "no live load"
    MAX_LOAD_FACTOR = "max_load_factor reached"
    MAX_STEPS = "max_steps reached"
    LOAD_BRACKET = "load control: bracket refined"  # no equilibrium beyond the bracket
    CURVE_FLAT = "pushover curve flat"  # lambda stopped rising while w doubled
    STIFFNESS_LOST = "stiffness lost"  # three steps at < flat_slope of the elastic slope
    CREEPING = "work control creeps"  # three steps with no displacement to speak of
    DISPLACEMENT_LIMIT = "displacement limit"  # past the small-displacement range
    PATH_STUCK = "path stuck"  # no equilibrium for any step size (work control)
    LIMIT_POINT = "limit point"  # the pushover curve falls (work control)
    UNSTABLE = "unstable equilibrium"  # det K_t < 0 at a state of the path, the rule no rest
    CONTROL_REACHED = "control displacement reached"
    CONTROL_STUCK = "displacement control stuck"
    CONTROL_BUDGET = "displacement control: max_steps spent short of the target"
    SINGULAR_TANGENT = "singular tangent"  # no factorization, even with a stiffened floor
    NO_REST = "no rest"  # the reference analysis: the damped wall found no rest above lambda


#: the arrays of a :class:`StepResult` (frozen when it is made; on disk in a streamed History)
STEP_ARRAYS = (
    "q",
    "actions",
    "state",
    "utilisation",
    "flags",
    "found_plastic",
    "found_cracked",
    "reactions",
)


@fill(SHARED)
@dataclass(frozen=True)
class StepResult:
    """One converged equilibrium state.

    The arrays are made read-only at construction.

    Parameters
    ----------
    step : int
        The step's number in its run (0: the dead-load state).
    load_factor : float
        lambda of the state.
    q : numpy.ndarray, shape (n, 6)
        Block displacements/rotations (u1, u2, u3, w1, w2, w3) [m, rad].
    actions : numpy.ndarray, shape (m, 6)
        Local interface actions [f1, f2, fn, m1, m2, m3] [N, N m].
    state : numpy.ndarray of int32, shape (m,)
        Damage code (a :class:`~masonry_dem.constitutive.states.JointState`, named by
        ``STATE_NAMES``).
    utilisation : numpy.ndarray, shape (m,)
        Demand/capacity.
    flags : numpy.ndarray of int32, shape (m,), optional
        The violated criteria of each joint's strength check (bit flags,
        :class:`~masonry_dem.constitutive.states.JointFlag`).
    control_displacement : float, default 0.0
        The monitored (or largest) displacement [m].
    iterations : int, default 0
        Iterations the state took.
    found_plastic : numpy.ndarray, shape (m, 6), optional
        The law state's plastic part the state was found with, where the steps before it
        cannot rebuild it: a rest of the damped motion, whose slip and cracks moved with the
        wall (None: the one the steps before it give).
    found_cracked : numpy.ndarray of bool, shape (m,), optional
        The cracked joints the state was found with, likewise.
    stage : int, default 0
        The loading stage the state belongs to (0: the first, and the only one of an
        analysis with no stages; :class:`~masonry_dem.solvers.static.stages.Stage`).
    reactions : numpy.ndarray, shape (n, 6), optional
        The generalised forces the supports put on the blocks at their held DOFs (zero at
        the free ones): what the joints put on them less the applied load there. Set by a
        staged analysis (None otherwise).

    Examples
    --------
    %(sliding_block)s
    >>> history = md.pushover(model)
    >>> step = history.last
    >>> step.q.shape, step.actions.shape, round(step.load_factor, 6)
    ((2, 6), (1, 6), 0.6)
    >>> from masonry_dem.results import STATE_NAMES
    >>> STATE_NAMES[step.state[0]]
    'sliding'
    """

    step: int
    load_factor: float
    q: FloatArray
    actions: FloatArray
    state: NDArray[np.int32]
    utilisation: FloatArray
    flags: NDArray[np.int32] | None = None
    control_displacement: float = 0.0
    iterations: int = 0
    #: the law state (m, 6) plastic part and (m,) cracked joints the state was found with,
    #: where the steps before it cannot rebuild it: a rest of the damped motion, whose slip
    #: and cracks moved with the wall (None: the one the steps before it give)
    found_plastic: FloatArray | None = None
    found_cracked: NDArray[np.bool_] | None = None
    #: the loading stage of the state (0: the first, or the only one)
    stage: int = 0
    #: (n, 6) the supports' forces on the blocks at their held DOFs (a staged analysis)
    reactions: FloatArray | None = None

    def __post_init__(self) -> None:
        for name in STEP_ARRAYS:
            value = getattr(self, name)
            if isinstance(value, np.ndarray):
                object.__setattr__(self, name, read_only(value))


class Steps(Protocol):
    """The steps of a History: a list, or :class:`masonry_dem.streamed_history.StreamedSteps`
    (on disk)."""

    def append(self, step: StepResult, /) -> None: ...

    def __len__(self) -> int: ...

    @overload
    def __getitem__(self, index: int, /) -> StepResult: ...

    @overload
    def __getitem__(self, index: slice, /) -> list[StepResult]: ...

    def __iter__(self) -> Iterator[StepResult]: ...


class CollapseCertificate(Protocol):
    """What a History keeps of the certificate of its collapse:
    :class:`masonry_dem.solvers.static.certificate.Certificate` is one (named here by what it
    does, so that the results import nothing of the solvers, not even for annotations)."""

    @property
    def holds(self) -> bool:
        """Whether the stop is a collapse."""
        ...

    @property
    def reason(self) -> str:
        """Why, for people."""
        ...

    def as_dict(self) -> dict[str, Any]:
        """The fields, JSON-ready (no arrays)."""
        ...


@fill(SHARED)
@dataclass
class History:
    """All steps of a run, and how it ended.

    Parameters
    ----------
    steps : list of StepResult or StreamedSteps, optional
        The converged steps (a list, or
        :class:`masonry_dem.streamed_history.StreamedSteps` on disk).
    status : Status, default Status.RUNNING
        How the run ended (collapse only when certified).
    reason : str, default ""
        Why the path stopped, for people.
    stop : StopReason, default StopReason.NONE
        Why the path stopped, for code.
    certificate : Certificate, optional
        For a stop the solver took for a collapse, the certificate that confirmed or refused
        it (:class:`~masonry_dem.solvers.static.certificate.Certificate`).
    collapse_bracket : (float, float), optional
        The refined bracket of lambda at collapse: the last converged value and the first
        failed one.
    seconds : float, default 0.0
        Wall-clock time of the run.
    iterations, factorizations : int, default 0
        Solver iterations and factorizations of the run.

    Examples
    --------
    %(sliding_block)s
    >>> history = md.pushover(model)
    >>> history.status, history.stop
    (<Status.COLLAPSE: 'collapse'>, <StopReason.STIFFNESS_LOST: 'stiffness lost'>)
    >>> round(history.collapse_multiplier, 6), len(history.steps)
    (0.6, 7)
    """

    steps: Steps = field(default_factory=lambda: list[StepResult]())
    status: Status = Status.RUNNING
    reason: str = ""
    stop: StopReason = StopReason.NONE
    certificate: CollapseCertificate | None = None
    collapse_bracket: tuple[float, float] | None = None
    seconds: float = 0.0
    iterations: int = 0
    factorizations: int = 0

    def end(self, status: Status, stop: StopReason, reason: str) -> None:
        """Record how the path ended (a collapse is still to be certified by the solver).

        Parameters
        ----------
        status : Status
            How the run ended; ``COMPLETED`` clears the collapse bracket (the path went on
            past every bracket load control had set: no collapse).
        stop : StopReason
            Why the path stopped.
        reason : str
            The same for people.
        """
        self.status, self.stop, self.reason = Status(status), stop, reason
        if self.status == Status.COMPLETED:
            # the path went on past every bracket load control had set: no collapse
            self.collapse_bracket = None

    @property
    def load_factors(self) -> FloatArray:
        """(steps,) lambda of every converged step."""
        kept = getattr(self.steps, "load_factors", None)  # streamed steps keep their scalars
        if kept is not None:
            return np.array(kept, dtype=float)
        return np.array([s.load_factor for s in self.steps])

    @property
    def control_displacements(self) -> FloatArray:
        """(steps,) the monitored (or largest) displacement of every step [m]."""
        kept = getattr(self.steps, "control_displacements", None)
        if kept is not None:
            return np.array(kept, dtype=float)
        return np.array([s.control_displacement for s in self.steps])

    @property
    def stages(self) -> NDArray[np.int64]:
        """(steps,) the loading stage of every converged step (all 0 without stages)."""
        kept = getattr(self.steps, "stages", None)
        if kept is not None:
            return np.array(kept, dtype=np.int64)
        return np.array([s.stage for s in self.steps], dtype=np.int64)

    @property
    def last(self) -> StepResult:
        """The last converged step."""
        return self.steps[-1]

    @property
    def collapse_multiplier(self) -> float | None:
        """Lambda at collapse: the last converged value of the refined bracket."""
        return None if self.collapse_bracket is None else self.collapse_bracket[0]

    @property
    def final_load_factor(self) -> float:
        """lambda of the last converged step (0 without one)."""
        return float(self.steps[-1].load_factor) if self.steps else 0.0

    def summary(self, **extra: Any) -> dict[str, Any]:
        """What summary.json holds of the run.

        Parameters
        ----------
        **extra
            More fields, e.g. the method.

        Returns
        -------
        dict
            status, reason, stop, steps, lambda (the collapse multiplier, else the final
            load factor), lambda_bracket, iterations, factorizations, seconds, certificate,
            then ``extra``.
        """
        out = {
            "status": str(self.status),
            "reason": self.reason,
            "stop": str(self.stop),
            "steps": len(self.steps),
            "lambda": self.collapse_multiplier
            if self.collapse_multiplier is not None
            else self.final_load_factor,
            "lambda_bracket": list(self.collapse_bracket) if self.collapse_bracket else None,
            "iterations": self.iterations,
            "factorizations": self.factorizations,
            "seconds": round(self.seconds, 4),
            "certificate": None if self.certificate is None else self.certificate.as_dict(),
        }
        out.update(extra)
        return out


@fill(SHARED)
@dataclass(frozen=True)
class AnalysisResult:
    """What every analysis returns through :func:`masonry_dem.analyze`.

    The same core fields for the pushover, dynamic relaxation and limit analysis, and the
    method's own result.

    Parameters
    ----------
    method : {"pushover", "relaxation", "limit"}
        The method that ran.
    status : {"collapse", "completed", "no collapse", "failed"}
        ``"collapse"`` (a mechanism at ``load_factor``), ``"completed"`` (the run ended with
        no collapse to report: its target or ``max_load_factor`` reached, or no live load),
        ``"no collapse"`` (limit analysis: no mechanism exists) or ``"failed"`` (with every
        step it converged kept; ``reason`` says why).
    reason : str
        Why the analysis ended, in one line a user can read.
    load_factor : float or None
        lambda, the collapse multiplier of the live load; None without a collapse.
    bracket : (float, float) or None
        (lower, upper) of lambda where the method brackets it: the pushover's last converged
        load and the first without equilibrium; the limit analysis's certified static and
        kinematic bounds (the normal-equation method); else None.
    stop : str or None
        Why the path stopped (a :class:`~masonry_dem.solvers.static.outcome.StopReason`
        value); None for limit analysis.
    certificate : dict or None
        The pushover's certificate of its collapse (``Certificate.as_dict()``), None where
        there is none (relaxation and limit analysis have none).
    bound : str or None
        Limit analysis: what its multiplier is to the pushover's, ``"upper"``,
        ``"estimate"`` or ``"none"``, with ``bound_reason``; None for the others.
    bound_reason : str or None
        Why ``bound`` is what it is.
    history : History or None
        Every converged state (pushover, relaxation); None for limit analysis.
    seconds : float
        Wall-clock seconds of the analysis.
    cost : dict
        What it cost: Newton iterations and factorizations (pushover), time steps and law
        evaluations (relaxation), iterations (limit analysis).
    details : History or LimitAnalysisResult
        The method's own result (a :class:`History` or a
        :class:`~masonry_dem.solvers.limit_analysis.LimitAnalysisResult`).
    mechanism_of : callable, optional
        Computes the mechanism on first use (one sparse solve for the pushover's collapse
        mode: not counted in ``seconds``, nor paid by a caller who never reads it); the
        property ``mechanism`` is (n_blocks, 6) the collapse mechanism at a collapse, else
        None.

    Examples
    --------
    %(sliding_block)s
    >>> result = md.analyze(model, "relaxation")
    >>> result.summary()["status"], result.mechanism[0, :3].round(3).tolist()
    ('collapse', [1.0, 0.0, 0.0])
    """

    method: str
    status: str
    reason: str
    load_factor: float | None
    bracket: tuple[float, float] | None
    stop: str | None
    certificate: dict[str, Any] | None
    bound: str | None
    bound_reason: str | None
    history: History | None
    seconds: float
    cost: dict[str, int]
    details: Any = field(repr=False, compare=False)
    #: computes the mechanism on first use (one sparse solve for the pushover's collapse mode:
    #: not counted in ``seconds``, nor paid by a caller who never reads it)
    mechanism_of: Any = field(default=None, repr=False, compare=False)

    @cached_property
    def mechanism(self) -> NDArray[np.float64] | None:
        """(n_blocks, 6) the collapse mechanism at a collapse, else None.

        The translations of the block centres and the rotations, largest translation 1.
        """
        return None if self.mechanism_of is None else self.mechanism_of()

    def summary(self) -> dict[str, Any]:
        """The core fields as JSON-ready values (no NaN: a missing value is None).

        Returns
        -------
        dict
            method, status, reason, lambda, lambda_bracket, stop, certificate, bound,
            bound_reason, steps (None without a history), seconds, cost.
        """
        return {
            "method": self.method,
            "status": self.status,
            "reason": self.reason,
            "lambda": self.load_factor,
            "lambda_bracket": None if self.bracket is None else [float(x) for x in self.bracket],
            "stop": self.stop,
            "certificate": self.certificate,
            "bound": self.bound,
            "bound_reason": self.bound_reason,
            "steps": None if self.history is None else len(self.history.steps),
            "seconds": round(self.seconds, 4),
            "cost": dict(self.cost),
        }


@fill(SHARED)
class Observer(Protocol):
    """What follows a run as it goes, handed to a solver (``observer=``).

    The solver enters it (``with observer:``) before the first step, calls
    ``observer(step)`` after each converged step, and ``observer.finish(history)`` once the
    run is over, with what the solver knows of the run beyond the History (dynamic
    relaxation: its ``method`` and ``time_steps``); an exception raised by the run leaves the
    ``with`` block through it. :class:`masonry_dem.export.writer.ResultsWriter` is one: it
    writes the results folder. The solvers import no writer: whoever wants files passes one.

    Examples
    --------
    %(sliding_block)s
    >>> class Count:
    ...     def __enter__(self):
    ...         self.steps = 0
    ...         return self
    ...     def __exit__(self, *exc):
    ...         return None
    ...     def __call__(self, step):
    ...         self.steps += 1
    ...     def finish(self, history, **run):
    ...         self.status = str(history.status)
    >>> count = Count()
    >>> history = md.pushover(model, observer=count)
    >>> count.steps == len(history.steps), count.status
    (True, 'collapse')
    """

    def __enter__(self) -> Any: ...

    def __exit__(self, exc_type: Any, exc: Any, tb: Any, /) -> Any: ...

    def __call__(self, step: StepResult, /) -> None: ...

    def finish(self, history: History, /, *, method: str = ..., time_steps: int = ...) -> Any:
        """Called once the run is over.

        Parameters
        ----------
        history : History
            The run's steps and how it ended.
        method : str, optional
            The method, where the solver says it (dynamic relaxation).
        time_steps : int, optional
            Time steps of the run (dynamic relaxation).

        Returns
        -------
        object
            Anything; the solver ignores it.
        """
        ...


def observed(
    run: Callable[[Callable[[StepResult], None]], History],
    observer: Observer | None = None,
    callback: Callable[[StepResult], None] | None = None,
    finish: Callable[[], dict[str, Any]] | None = None,
) -> History:
    """``run(on_step)``, a solver's loop, followed as the :class:`Observer` protocol says:
    the observer entered around it, each step handed to the observer and then to
    ``callback``, and ``observer.finish(history, **finish())`` once it is over (``finish``:
    what the solver adds, known only then)."""

    def on_step(step: StepResult) -> None:
        if observer is not None:
            observer(step)
        if callback is not None:
            callback(step)

    with observer or nullcontext():  # the steps handed to a writer reach the disk
        history = run(on_step)
    if observer is not None:
        observer.finish(history, **(finish() if finish is not None else {}))
    return history
