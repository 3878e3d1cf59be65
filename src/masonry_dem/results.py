"""Results of an analysis: one StepResult per converged step, and the History of a run."""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, overload

import numpy as np
from numpy.typing import NDArray

# re-exported: the names of the codes of StepResult.state (docs/rendering.md)
from masonry_dem._arrays import FloatArray
from masonry_dem._validation import read_only
from masonry_dem.constitutive.states import STATE_NAMES as STATE_NAMES
from masonry_dem.export.pushover_file import recorded_dof_of, save_pushover_rows
from masonry_dem.solvers.static.outcome import Status, StopReason

if TYPE_CHECKING:
    from masonry_dem.solvers.static.certificate import Certificate


@dataclass(frozen=True)
class StepResult:
    """One converged equilibrium state.

    q: (n, 6) block displacements/rotations; actions: (m, 6) local interface actions
    [f1, f2, fn, m1, m2, m3]; state: (m,) damage code (a
    :class:`~masonry_dem.constitutive.states.JointState`, named by ``STATE_NAMES``); utilisation: (m,) demand/capacity.
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

    def __post_init__(self) -> None:
        for name in (
            "q",
            "actions",
            "state",
            "utilisation",
            "flags",
            "found_plastic",
            "found_cracked",
        ):
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


@dataclass
class History:
    """All steps of a run, and how it ended: ``status`` (collapse only when certified),
    ``stop`` (why the path stopped), ``reason`` (the same for people) and, for a stop the
    solver took for a collapse, the ``certificate`` that confirmed or refused it."""

    steps: Steps = field(default_factory=lambda: list[StepResult]())
    status: Status = Status.RUNNING
    reason: str = ""
    stop: StopReason = StopReason.NONE
    certificate: Certificate | None = None
    collapse_bracket: tuple[float, float] | None = None
    seconds: float = 0.0
    iterations: int = 0
    factorizations: int = 0

    def end(self, status: Status, stop: StopReason, reason: str) -> None:
        """How the path ended (a collapse is still to be certified by the solver)."""
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
    def last(self) -> StepResult:
        return self.steps[-1]

    @property
    def collapse_multiplier(self) -> float | None:
        """Lambda at collapse: the last converged value of the refined bracket."""
        return None if self.collapse_bracket is None else self.collapse_bracket[0]

    @property
    def final_load_factor(self) -> float:
        return float(self.steps[-1].load_factor) if self.steps else 0.0

    def summary(self, **extra: Any) -> dict[str, Any]:
        """What summary.json holds of the run (``extra``: more fields, e.g. the method)."""
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


def write_pushover_csv(path: Path, history: History) -> None:
    """pushover.csv: step, lambda and the control displacement of every step."""
    displacements = history.control_displacements
    rows = np.column_stack([np.arange(len(history.steps)), history.load_factors, displacements])
    save_pushover_rows(path, rows, recorded_dof_of(history.steps, displacements))


def read_summary(folder: Path) -> dict[str, Any]:
    """The summary.json of a results folder."""
    summary: dict[str, Any] = json.loads((Path(folder) / "summary.json").read_text())
    return summary


@dataclass(frozen=True)
class AnalysisResult:
    """What every analysis returns through :func:`masonry_dem.analyze`: the same core fields
    for the pushover, dynamic relaxation and limit analysis, and the method's own result.

    Attributes:
        method: ``"pushover"``, ``"relaxation"`` or ``"limit"``.
        status: ``"collapse"`` (a mechanism at ``load_factor``), ``"completed"`` (the run
            ended with no collapse to report: its target or ``max_load_factor`` reached, or
            no live load), ``"no collapse"`` (limit analysis: no mechanism exists) or
            ``"failed"`` (with every step it converged kept; ``reason`` says why).
        reason: why the analysis ended, in one line a user can read.
        load_factor: lambda, the collapse multiplier of the live load; None without a
            collapse.
        bracket: (lower, upper) of lambda where the method brackets it: the pushover's last
            converged load and the first without equilibrium; the limit analysis's certified
            static and kinematic bounds (the normal-equation method); else None.
        stop: why the path stopped (a :class:`~masonry_dem.solvers.static.outcome.StopReason`
            value); None for limit analysis.
        certificate: the pushover's certificate of its collapse (``Certificate.as_dict()``),
            None where there is none (relaxation and limit analysis have none).
        bound: limit analysis: what its multiplier is to the pushover's, ``"upper"``,
            ``"estimate"`` or ``"none"``, with ``bound_reason``; None for the others.
        mechanism: (n_blocks, 6) the collapse mechanism at a collapse, else None (computed
            on first use).
        history: every converged state (pushover, relaxation); None for limit analysis.
        seconds: wall-clock seconds of the analysis.
        cost: what it cost: Newton iterations and factorizations (pushover), time steps
            and law evaluations (relaxation), iterations (limit analysis).
        details: the method's own result (a :class:`History` or a
            :class:`~masonry_dem.solvers.limit_analysis.LimitAnalysisResult`).
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
        """(n_blocks, 6) the collapse mechanism (the translations of the block centres and the
        rotations, largest translation 1) at a collapse, else None."""
        return None if self.mechanism_of is None else self.mechanism_of()

    def summary(self) -> dict[str, Any]:
        """The core fields as JSON-ready values (no NaN: a missing value is None)."""
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
