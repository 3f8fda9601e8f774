"""How sure: a run's per-class precision, recall and F1 and confusion matrices per
classifier and target, and the calibration of its classifiers' probabilities.

Everything comes from what the store keeps of each fold: its confusion matrix (per target)
and, for multi-class folds of classifiers with probabilities, its reliability bins
(:mod:`benchmark.evaluation.calibration`), per target for multi-target folds (runs carried
out before the bins were kept have none, and say so).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from touchbench.app.schemas.certainty import (
    Calibration,
    ClassifierCertainty,
    ClassScores,
    ReliabilityBin,
    RunCertainty,
    TargetClasses,
)
from touchbench.app.services.imported import is_imported
from touchbench.app.services.report import RunView, run_view
from touchbench.app.store.database import Store
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.calibration import PER_TARGET, Reliability, merge
from touchbench.benchmark.results import TaskResult


def run_certainty(
    store: Store,
    run_ref: int | str,
    *,
    classifiers: Sequence[str] | None = None,
    aggregate: str | None = None,
) -> RunCertainty:
    """Per-class scores, confusion matrices and calibration of a run's classifiers.

    Parameters
    ----------
    classifiers : sequence of str, optional
        These classifiers, in this order; default every classifier of the run with a
        successful fold, best first.
    aggregate : {"window", "recording"}, optional
        Count each window, or each recording's windows pooled into one prediction, as the
        run's leaderboard scores (:func:`~app.services.runs.run_leaderboard`); default as
        the run scored.

    Raises
    ------
    ConfigurationError
        A regression run (no classes), a classifier not in the run, or one without a
        successful fold.
    NotFoundError
        No such run.
    FieldError
        For ``aggregate``: another value, or a run it cannot re-score.
    """
    return certainty_of(run_view(store, run_ref, aggregate=aggregate), classifiers)


def certainty_of(view: RunView, classifiers: Sequence[str] | None = None) -> RunCertainty:
    """:func:`run_certainty` of a run already read (the report's run views)."""
    run = view.run
    if run.kind == "regression":
        raise ConfigurationError(f"run {run.id} is a regression: its targets have no classes")
    if is_imported(run):
        raise ConfigurationError(
            f"run {run.id} was imported from a WEKA results file, which keeps no confusion "
            "matrices or probabilities"
        )
    if classifiers:
        unknown = [c for c in classifiers if c not in view.entries]
        if unknown:
            raise ConfigurationError(
                f"run {run.id} has no classifier '{unknown[0]}' "
                f"(classifiers: {', '.join(view.entries)})"
            )
        chosen = list(dict.fromkeys(classifiers))
    else:
        chosen = [row.classifier for row in view.board.rows if row.n_ok]
    return RunCertainty(
        run_id=run.id,
        dataset=run.dataset_name,
        kind=run.kind,
        targets=run.targets,
        metric=view.metric,
        classifiers=[_classifier(view, name) for name in chosen],
        aggregate=view.aggregate,
    )


def class_scores(confusion: np.ndarray, labels: Sequence[str]) -> list[ClassScores]:
    """Precision, recall and F1 of each class of a confusion matrix (rows true); ``None``
    where undefined (a class never predicted, or never present)."""
    counts = np.asarray(confusion, dtype=np.float64)
    hits = np.diag(counts)
    support = counts.sum(axis=1)
    predicted = counts.sum(axis=0)
    out = []
    for k, label in enumerate(labels):
        precision = hits[k] / predicted[k] if predicted[k] else None
        recall = hits[k] / support[k] if support[k] else None
        f1 = None
        if precision is not None and recall is not None:
            f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
        out.append(
            ClassScores(
                label=label,
                precision=None if precision is None else float(precision),
                recall=None if recall is None else float(recall),
                f1=None if f1 is None else float(f1),
                support=int(support[k]),
            )
        )
    return out


def calibration_of(results: Sequence[TaskResult], target: str | None = None) -> Calibration | None:
    """The summed reliability bins of the results that have them (``None`` if none has):
    a multi-class fold's, or of a multi-target fold the bins of ``target``."""
    bins = [
        r.calibration if target is None else r.calibration.get(PER_TARGET, {}).get(target)
        for r in results
        if r.ok and r.calibration is not None
    ]
    kept = [b for b in bins if b]
    merged = merge(Reliability.from_json(b) for b in kept)
    if merged is None:
        return None
    edges = merged.edges
    confidence, accuracy = merged.mean_confidence(), merged.accuracy()
    return Calibration(
        ece=merged.ece(),
        n_instances=int(merged.count.sum()),
        n_folds=len(kept),
        bins=[
            ReliabilityBin(
                lower=float(edges[b]),
                upper=float(edges[b + 1]),
                count=int(merged.count[b]),
                confidence=_number(confidence[b]),
                accuracy=_number(accuracy[b]),
            )
            for b in range(merged.n_bins)
        ],
    )


def _classifier(view: RunView, name: str) -> ClassifierCertainty:
    confusion = view.confusion(name)
    mine = [r for r in view.results if r.key.classifier == name and r.ok]
    multitarget = view.run.kind == "multitarget"
    calibration = None if multitarget else calibration_of(mine)
    per_target = {t: calibration_of(mine, t) for t in confusion.matrices} if multitarget else {}
    note = None
    if multitarget and not any(per_target.values()):
        note = (
            "no fold kept its targets' probability bins (a configuration without "
            "probabilities, or a run carried out before they were kept)"
        )
    elif multitarget:
        note = "per target"
    elif calibration is None:
        note = (
            "no fold kept its probabilities' bins (a classifier without probabilities, "
            "or a run carried out before they were kept)"
        )
    return ClassifierCertainty(
        classifier=name,
        n_folds=confusion.n_folds,
        targets=[
            TargetClasses(
                target=target,
                labels=view.labels[target],
                confusion=matrix.astype(int).tolist(),
                classes=class_scores(matrix, view.labels[target]),
                calibration=per_target.get(target),
            )
            for target, matrix in confusion.matrices.items()
        ],
        calibration=calibration,
        calibration_note=note,
    )


def _number(value: float) -> float | None:
    return None if np.isnan(value) else float(value)
