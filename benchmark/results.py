"""The result records of a benchmark run: which task (classifier, repeat, fold) and what
came of it.

This module is deliberately light (no scikit-learn, no engine): the store, the CLI's
listings and the service read and write results through it, and must start fast.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:  # a type only: numpy stays out of the records' import
    from touchbench.benchmark.predictions import FoldPredictions

__all__ = ["Drop", "DropReason", "Origin", "OriginKind", "Status", "TaskKey", "TaskResult"]

Status = Literal["ok", "error", "timeout"]
#: Why an entry stopped before its last fold: the race found it significantly worse than
#: the leader, or the run's total budget left no time for its next task.
DropReason = Literal["race", "budget", "not started"]
#: Where an entry's folds come from, when not from fitting it as the run asked: computed
#: from its members' fold predictions, or fitted as a member no one asked for.
OriginKind = Literal["from fold predictions", "helper"]


@dataclass(frozen=True, order=True)
class TaskKey:
    """Which classifier on which fold (0-based repeat and fold)."""

    classifier: str
    repeat: int
    fold: int

    def __str__(self) -> str:
        return f"{self.classifier} (repeat {self.repeat + 1}, fold {self.fold + 1})"


@dataclass
class TaskResult:
    """The outcome of one task.

    Parameters
    ----------
    key : TaskKey
    status : {"ok", "error", "timeout"}
    error : str or None
        ``"ExceptionType: message"`` (or what stopped the worker) unless ``ok``.
    metrics : dict of str to float
        Scores (:data:`benchmark.evaluation.metrics.MULTICLASS_METRICS`, or the multi-target scores)
        and costs: ``fit_time`` and ``predict_time`` (wall seconds), ``fit_cpu_time`` and
        ``predict_cpu_time`` (CPU seconds of the worker process), ``model_size`` (bytes of
        the pickled fitted model).  Empty unless ``ok``.
    confusion : list or None
        Multi-class: the (n_classes, n_classes) matrix, rows true.  Multi-target: one such
        matrix per target.
    n_train, n_test : int
        Fold sizes.
    warnings : list of str
        Distinct warnings the classifier emitted (convergence...), at most five.
    per_target : dict or None
        Multi-target: scores per target name.
    params : dict or None
        What the classifier chose on its training fold (a tuned twin's parameters, a
        stack's members), JSON-ready; ``None`` for a classifier that chooses nothing.
    calibration : dict or None
        Multi-class with probabilities: the fold's reliability bins of the top-label
        confidence (``count``, ``confidence``, ``correct``, lists of equal length; see
        :mod:`benchmark.evaluation.calibration`); multi-target with probabilities:
        ``{"targets": {name: bins}}``, the same per target; ``None`` otherwise.
    predictions : FoldPredictions or None
        What the model predicted for the test fold's rows (:mod:`benchmark.predictions`):
        :func:`benchmark.evaluation.fold_scores.score_fold` re-scores them to ``metrics``
        exactly, and the run's ensembles are computed from them.  ``None`` unless ``ok``,
        and for results read back without them (:meth:`to_json` leaves them out: they are
        stored as :func:`benchmark.predictions.encode` blobs).
    inner_predictions : FoldPredictions or None
        Out-of-fold predictions of the training fold's rows, from the run's inner folds
        (:mod:`benchmark.catalogue.inner`), for a run whose stacks or ensemble selection
        choose among its entries; ``None`` otherwise.
    """

    key: TaskKey
    status: Status
    error: str | None
    metrics: dict[str, float]
    confusion: list[Any] | None
    n_train: int
    n_test: int
    warnings: list[str] = field(default_factory=list)
    per_target: dict[str, dict[str, float]] | None = None
    params: dict[str, Any] | None = None
    calibration: dict[str, Any] | None = None
    predictions: FoldPredictions | None = field(default=None, repr=False, compare=False)
    inner_predictions: FoldPredictions | None = field(default=None, repr=False, compare=False)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def to_json(self) -> dict[str, Any]:
        """JSON-ready data (NaN as ``null``); :meth:`from_json` restores it."""
        return {
            "classifier": self.key.classifier,
            "repeat": self.key.repeat,
            "fold": self.key.fold,
            "status": self.status,
            "error": self.error,
            "metrics": {name: _json_number(v) for name, v in self.metrics.items()},
            "confusion": self.confusion,
            "n_train": self.n_train,
            "n_test": self.n_test,
            "warnings": list(self.warnings),
            "per_target": None
            if self.per_target is None
            else {
                target: {name: _json_number(v) for name, v in scores.items()}
                for target, scores in self.per_target.items()
            },
            "params": self.params,
            "calibration": self.calibration,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> TaskResult:
        per_target = data.get("per_target")
        return cls(
            key=TaskKey(data["classifier"], int(data["repeat"]), int(data["fold"])),
            status=data["status"],
            error=data.get("error"),
            metrics={name: _from_json_number(v) for name, v in data["metrics"].items()},
            confusion=data.get("confusion"),
            n_train=int(data["n_train"]),
            n_test=int(data["n_test"]),
            warnings=list(data.get("warnings", ())),
            per_target=None
            if per_target is None
            else {
                target: {name: _from_json_number(v) for name, v in scores.items()}
                for target, scores in per_target.items()
            },
            params=data.get("params"),  # absent from results stored before tuning existed
            calibration=data.get("calibration"),
        )


@dataclass(frozen=True)
class Drop:
    """An entry that stopped before its last fold, and why.

    Parameters
    ----------
    classifier : str
    reason : {"race", "budget", "not started"}
        ``not started``: a run that stopped (cancelled, interrupted) before any of the
        entry's tasks began.
    after_fold : int
        Folds it ran (1-based count of rounds, repeat-major), the round of the decision.
    p_value : float or None
        The race: the corrected resampled t-test's p-value against ``leader``.
    leader : str or None
        The race: the entry it was compared with (the best live entry then).
    mean : float or None
        The race: its mean of the race's metric over the folds it ran.
    """

    classifier: str
    reason: DropReason
    after_fold: int
    p_value: float | None = None
    leader: str | None = None
    mean: float | None = None

    def describe(self) -> str:
        """``dropped after fold 3 (p 0.0012 against rf, mean so far 0.4120)``, ``cut by
        the budget after fold 2`` or ``never started``: the words every view uses."""
        if self.reason == "budget":
            return f"cut by the budget after fold {self.after_fold}"
        if self.reason == "not started":
            return "never started"
        details = []
        if self.p_value is not None:
            details.append(f"p {self.p_value:.2g} against {self.leader}")
        if self.mean is not None:
            details.append(f"mean so far {self.mean:.4f}")
        shown = f" ({', '.join(details)})" if details else ""
        return f"dropped after fold {self.after_fold}{shown}"

    def to_json(self) -> dict[str, Any]:
        return {
            "reason": self.reason,
            "after_fold": self.after_fold,
            "p_value": self.p_value,
            "leader": self.leader,
            "mean": self.mean,
            "note": self.describe(),
        }


@dataclass(frozen=True)
class Origin:
    """How a run came by an entry's folds, when not by fitting an entry it asked for.

    Parameters
    ----------
    kind : {"from fold predictions", "helper"}
        ``from fold predictions``: an ensemble, stack or selection computed from its
        members' predictions (it fits nothing itself); ``helper``: a member of such an
        entry that the run did not ask for, fitted once per fold for them.
    entries : tuple of str
        Its members (``from fold predictions``) or the entries it serves (``helper``).
    """

    kind: OriginKind
    entries: tuple[str, ...]

    def describe(self) -> str:
        """``from fold predictions of xgb, hgb`` or ``helper of voting``: what views say."""
        joined = ", ".join(self.entries)
        return (
            f"from fold predictions of {joined}" if self.kind != "helper" else f"helper of {joined}"
        )

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "entries": list(self.entries), "note": self.describe()}


def _json_number(value: float) -> float | None:
    return None if value is None or math.isnan(value) else value


def _from_json_number(value: float | None) -> float:
    return math.nan if value is None else float(value)
