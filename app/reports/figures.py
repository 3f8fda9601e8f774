"""The plots of runs and comparisons: what :mod:`app.reports.plots` draws, fed from the
services' objects.  The CLI's ``plot`` and ``compare --plot``, the HTML report and a web
page all draw through these, so a plot reads the same wherever it appears."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from touchbench.app.reports import plots
from touchbench.app.reports.certainty_tables import calibrations
from touchbench.app.schemas.ablation import AblationResult
from touchbench.app.schemas.certainty import RunCertainty
from touchbench.app.schemas.datasets import DatasetDescription
from touchbench.app.schemas.importance import ImportanceResult
from touchbench.app.schemas.learning import LearningCurveResult
from touchbench.app.services.compare import Comparison
from touchbench.app.services.report import RunView
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER

#: The per-target score that ``targets`` plots show.
PER_TARGET_METRIC = "accuracy"


def cd_figure(comparison: Comparison) -> Figure:
    """The critical-difference diagram of a comparison; its title says what the blocks are
    (data sets, or one run's folds)."""
    ranks = comparison.ranks
    if comparison.blocks_are == "folds":
        run = comparison.runs[0].run
        blocks = f"run {run.id} ({run.dataset_name}), {ranks.n_blocks} folds as blocks"
    else:
        blocks = f"{ranks.n_blocks} data sets"
    return plots.cd_diagram(
        dict(zip(ranks.classifiers, ranks.average_ranks.tolist(), strict=True)),
        ranks.critical_difference,
        ranks.groups,
        title=f"{comparison.metric}: average ranks over {blocks} (Nemenyi, alpha {ranks.alpha})",
    )


def folds_figure(view: RunView, classifiers: Sequence[str] | None = None) -> Figure:
    """Every fold's score of every classifier of a run (or of ``classifiers`` only)."""
    scores = view.fold_scores()
    names = scores.classifiers if classifiers is None else dict.fromkeys(classifiers)
    return plots.fold_strip_plot(
        {name: scores.column(name) for name in names},
        metric=view.metric,
        lower_is_better=view.metric in LOWER_IS_BETTER,
        title=view.title,
    )


def confusion_figure(view: RunView, classifier: str | None = None) -> Figure:
    """A classifier's confusion matrices (default: the run's best), one panel per target."""
    confusion = view.confusion(classifier or view.board.rows[0].classifier)
    return plots.confusion_figure(
        confusion.matrices, view.labels, title=f"{view.title}: {confusion.description}"
    )


def targets_figure(view: RunView) -> Figure:
    """A multi-target run's accuracy on each target, per classifier."""
    if view.per_target is None:
        raise ConfigurationError(
            f"run {view.run.id} is multi-class (one target): per-target plots need a "
            "multi-target run"
        )
    return plots.per_target_figure(
        {
            classifier: {
                target: scores[PER_TARGET_METRIC]
                for target, scores in by_target.items()
                if PER_TARGET_METRIC in scores
            }
            for classifier, by_target in view.per_target.items()
        },
        metric=PER_TARGET_METRIC,
        title=f"{view.title}: {PER_TARGET_METRIC} per target",
    )


def classes_figure(view: RunView) -> Figure:
    """Instances per class of each target of a run's data set."""
    counts = view.class_counts()
    if counts is None:
        raise ConfigurationError(
            f"run {view.run.id}: no classifier completed every fold of the first repeat, so "
            "the class counts are unknown"
        )
    return plots.class_distribution_figure(
        counts, title=f"{view.run.dataset_name}: instances per class in run {view.run.id}"
    )


def reliability_figure(certainty: RunCertainty, classifiers: int | None = None) -> Figure:
    """The reliability diagram of a run's classifiers that kept calibration bins (the
    first ``classifiers`` of them, best first)."""

    curves = {}
    for entry, target, calibration in calibrations(certainty):
        if calibration is None or calibration.ece is None:
            continue
        bins = calibration.bins
        name = entry.classifier if target is None else f"{entry.classifier} on {target}"
        curves[name] = (
            np.array([np.nan if b.confidence is None else b.confidence for b in bins]),
            np.array([np.nan if b.accuracy is None else b.accuracy for b in bins]),
            np.array([b.count for b in bins], dtype=np.float64),
            calibration.ece,
        )
        if classifiers is not None and len(curves) == classifiers:
            break
    if not curves:
        raise ConfigurationError(
            f"no classifier of run {certainty.run_id} kept calibration bins (classifiers "
            "without probabilities, or a run carried out before the bins were kept)"
        )
    return plots.reliability_diagram(
        curves,
        title=f"run {certainty.run_id} ({certainty.dataset}, {', '.join(certainty.targets)}): "
        "out-of-fold reliability",
    )


def learning_figure(result: LearningCurveResult) -> Figure:
    """The learning curves of a learning-curve answer (those scored so far)."""
    curves = {
        curve.classifier: (
            np.array([p.fraction for p in curve.points]),
            np.array([np.nan if p.mean is None else p.mean for p in curve.points]),
            np.array([np.nan if p.std is None else p.std for p in curve.points]),
            curve.enough,
        )
        for curve in result.curves
    }
    return plots.learning_curve_figure(
        curves,
        metric=result.metric,
        lower_is_better=result.lower_is_better,
        title=f"{result.dataset} ({', '.join(result.targets)}): learning curves over "
        f"{result.n_folds} folds",
    )


def ablation_figure(result: AblationResult) -> Figure:
    """Each classifier's score without each group less its score with every feature (those
    scored so far)."""
    changes = {f"{e.classifier}: {e.group}": e.change for e in result.entries}
    marked = [f"{e.classifier}: {e.group}" for e in result.entries if e.significant]
    direction = "lower is better" if result.lower_is_better else "higher is better"
    return plots.change_bars(
        changes,
        marked=marked,
        xlabel=f"change of {result.metric} without the {result.grouping} ({direction})",
        title=f"run {result.run_id} ({result.dataset}): each {result.grouping} removed",
    )


def importance_figure(result: ImportanceResult) -> Figure:
    """The drop of a classifier's score when each group of features (or, without groups,
    each feature) is shuffled on the test folds."""
    found = next((items for items in result.groups.values() if items), result.features)
    return plots.change_bars(
        {item.name: item.mean for item in found},
        marked=[item.name for item in found if item.significant],
        xlabel=f"drop of {result.metric} when shuffled",
        title=f"run {result.run_id}: permutation importance of {result.classifier}",
    )


def dataset_classes_figure(description: DatasetDescription) -> Figure:
    """Instances per class of each nominal target of a stored data set."""
    return plots.class_distribution_figure(
        description.class_distribution,
        title=f"{description.name}: instances per class ({description.n_instances} in all)",
    )
