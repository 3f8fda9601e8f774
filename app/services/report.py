"""What the plots and the HTML report show of runs: leaderboards, per-fold scores, confusion
matrices with the schema's labels, class counts, per-target scores, and the comparison
across runs; plus the library versions behind them."""

from __future__ import annotations

import platform
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from importlib import metadata

import numpy as np

from touchbench.app.schemas.learning import LearningCurveResult
from touchbench.app.services.answers import RunAnswers, latest_learning_curve, run_answers
from touchbench.app.services.compare import Comparison, compare_runs, with_besides
from touchbench.app.services.runs import (
    PerTargetSummary,
    RankedRun,
    RunLeaderboard,
    per_target_summary,
    run_leaderboard,
)
from touchbench.app.services.runs.rescore import check_aggregate, rescored_results
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_schema
from touchbench.app.store.runs import RunInfo, get_run, load_results
from touchbench.benchmark.errors import BenchmarkError, ConfigurationError
from touchbench.benchmark.evaluation.score_table import MissingPolicy, ScoreTable, fold_score_table
from touchbench.benchmark.results import TaskResult

#: Distributions whose versions a report names.
LIBRARIES = (
    "touchbench",
    "numpy",
    "scipy",
    "scikit-learn",
    "xgboost",
    "scikit-multilearn-ng",
    "sqlalchemy",
    "matplotlib",
)


@dataclass(frozen=True)
class Confusion:
    """A classifier's confusion matrices summed over its successful folds.

    Attributes
    ----------
    classifier : str
    matrices : dict of str to ndarray of shape (n_classes, n_classes)
        One per target, rows true, columns predicted.
    n_folds : int
        Folds summed (over every repeat).
    n_failed : int
        Folds without a result to sum.
    """

    classifier: str
    matrices: dict[str, np.ndarray]
    n_folds: int
    n_failed: int

    @property
    def description(self) -> str:
        failed = f", {self.n_failed} failed" if self.n_failed else ""
        return f"{self.classifier}, summed over {self.n_folds} folds{failed}"


@dataclass(frozen=True)
class RunView(RunLeaderboard):
    """One run as the plots and the report see it: its leaderboard and what they add.

    Attributes
    ----------
    run : RunInfo
    board : Leaderboard
    results : list of TaskResult
    labels : dict of str to list of str
        Class labels of each target, from the data set's schema.
    per_target : dict or None
        Multi-target runs: classifier -> target -> metric -> (mean, std), in leaderboard
        order; ``None`` for multi-class runs.
    """

    labels: dict[str, list[str]]
    per_target: PerTargetSummary | None = None

    @property
    def metric(self) -> str:
        return self.board.metric

    @property
    def title(self) -> str:
        return f"run {self.run.id}: {self.run.dataset_name} ({', '.join(self.run.targets)})"

    def fold_scores(self) -> ScoreTable:
        """Per-fold scores on the leaderboard's metric, best classifier first."""
        own = [row.classifier for row in self.board.rows if row.classifier in self.run.classifiers]
        return fold_score_table(self.results, self.metric, classifiers=own)

    def confusion(self, classifier: str) -> Confusion:
        """``classifier``'s confusion matrices summed over its successful folds."""
        if classifier not in self.entries:
            raise ConfigurationError(
                f"run {self.run.id} has no classifier '{classifier}' "
                f"(classifiers: {', '.join(self.entries)})"
            )
        mine = [r for r in self.results if r.key.classifier == classifier]
        ok = [r for r in mine if r.ok and r.confusion is not None]
        if not ok:
            raise ConfigurationError(
                f"'{classifier}' has no successful fold in run {self.run.id}: no confusion matrix"
            )
        return Confusion(classifier, _sum_confusions(self.run, ok), len(ok), len(mine) - len(ok))

    def class_counts(self) -> dict[str, dict[str, int]] | None:
        """Instances per class of each target, as the run's first repeat tested them.

        Every instance is tested once per repeat of k-fold cross-validation, so the row
        sums of a classifier's confusion matrices over the folds of repeat 1 count the
        classes of the instances the run used.  ``None`` when no classifier completed every
        fold of repeat 1.
        """
        first = {r.key.fold for r in self.results if r.key.repeat == 0}
        by_classifier: dict[str, list[TaskResult]] = {}  # once: not a pass per classifier
        for r in self.results:
            if r.key.repeat == 0 and r.ok and r.confusion is not None:
                by_classifier.setdefault(r.key.classifier, []).append(r)
        for row in self.board.rows:
            done = by_classifier.get(row.classifier, [])
            if {r.key.fold for r in done} == first:
                matrices = _sum_confusions(self.run, done)
                return {
                    target: {
                        label: int(count)
                        for label, count in zip(
                            self.labels[target], matrix.sum(axis=1), strict=True
                        )
                    }
                    for target, matrix in matrices.items()
                }
        return None


@dataclass(frozen=True)
class Report:
    """Everything an HTML report of some runs shows.

    Attributes
    ----------
    views : list of RunView
    comparison : Comparison or None
        Across the runs (two or more), when it can be made.
    comparison_note : str or None
        Why there is no comparison across runs, if there could have been one.
    fold_ranks : dict of int to Comparison or str
        Per run id: its classifiers ranked over its folds, or why that cannot be done.
    confusions : int
        How many of each run's best classifiers get a confusion matrix.
    versions : dict of str to str
    created_at : datetime
    answers : dict of int to RunAnswers
        Per run id: its kept ablation and importance.
    learning : dict of int to LearningCurveResult
        Per run id: the newest learning curve of its data set, where one was computed.
    """

    views: list[RunView]
    comparison: Comparison | None
    comparison_note: str | None
    fold_ranks: dict[int, Comparison | str]
    confusions: int
    versions: dict[str, str]
    created_at: datetime = field(default_factory=lambda: datetime.now(UTC))
    answers: dict[int, RunAnswers] = field(default_factory=dict)
    learning: dict[int, LearningCurveResult] = field(default_factory=dict)


def run_view(
    store: Store,
    run_ref: int | str,
    *,
    metric: str | None = None,
    baseline: str | None = None,
    beside: Sequence[int | str] = (),
    aggregate: str | None = None,
) -> RunView:
    """A run with its leaderboard (marks against ``baseline``, default the best; with the
    classifiers of the runs ``beside`` it; scored per ``aggregate`` as
    :func:`~app.services.runs.run_leaderboard` says), results and class labels."""
    ranked = run_leaderboard(
        store, run_ref, metric=metric, baseline=baseline, beside=beside, aggregate=aggregate
    )
    return _view(store, ranked, ranked.results)


def page_view(store: Store, ranked: RankedRun, classifiers: Sequence[str]) -> RunView:
    """A ranked run (:func:`~app.services.runs.ranked_run`) with the fold results of
    ``classifiers`` only: what a page that draws a few of a run's classifiers needs, read
    without the thousands of others (an imported results file); scored again as the
    ranking was (:attr:`~app.services.runs.RankedRun.rescored`)."""
    results = load_results(store, ranked.run.id, classifiers=classifiers)
    if ranked.rescored is not None:
        results = rescored_results(store, ranked.run, results, ranked.rescored)
    return _view(store, ranked, results)


def _view(store: Store, ranked: RunLeaderboard | RankedRun, results: list[TaskResult]) -> RunView:
    """``ranked`` with ``results``, the class labels of its targets and, for a multi-target
    run, the per-target scores of the classifiers ``results`` has."""
    run, board = ranked.run, ranked.board
    _, schema, _ = load_schema(store, run.dataset_id)
    labels = {}
    for target in run.targets:
        attribute = schema.attributes[schema.index(target)]
        labels[target] = list(attribute.values)
    per_target = None
    if run.kind == "multitarget":
        summary = per_target_summary(results)
        per_target = {
            r.classifier: summary[r.classifier] for r in board.rows if r.classifier in summary
        }
    return RunView(
        run,
        board,
        results,
        ranked.besides,
        ranked.drops,
        labels,
        per_target,
        rescored=ranked.rescored,
    )


def build_report(
    store: Store,
    run_refs: Sequence[int | str],
    *,
    metric: str | None = None,
    alpha: float = 0.05,
    missing: MissingPolicy = "drop-classifier",
    confusions: int = 5,
    aggregate: str | None = None,
    on_run: Callable[[RunInfo], None] = lambda run: None,
) -> Report:
    """Gather what a report of ``run_refs`` shows.

    Parameters
    ----------
    store : Store
    run_refs : sequence of int or str
        The runs; an imported run (a paper's WEKA results) on the data set and targets of
        another run given is shown beside that run's leaderboard rather than on its own
        (:mod:`app.services.beside`).
    metric : str, optional
        Ranking metric; default each run's leaderboard default.
    alpha : float
        Significance level of the comparisons.
    missing : {"drop-classifier", "drop-block", "worst"}
        Missing-cell policy of the comparison across runs.
    confusions : int
        Confusion matrices for this many of each run's best classifiers (>= 0).
    aggregate : {"window", "recording"}, optional
        Score every run per window or per recording (each recording's windows as one
        prediction), from the stored test-fold predictions of a run that scored otherwise;
        default as each run scored.
    on_run : callable
        Called with each run as it is gathered (progress).
    """
    if not run_refs:
        raise ConfigurationError("give at least one run to report")
    if confusions < 0:
        raise ConfigurationError(
            f"the number of confusion matrices must be at least 0, got {confusions}"
        )
    asked = check_aggregate(aggregate)
    views = []
    fold_ranks: dict[int, Comparison | str] = {}
    hosts, joined = with_besides([get_run(store, ref) for ref in run_refs])
    for host in hosts:
        beside = [run.id for run in joined.get(host.id, [])]
        view = run_view(store, host.id, metric=metric, beside=beside, aggregate=asked)
        try:
            fold_ranks[view.run.id] = compare_runs(
                store,
                [view.run.id, *beside],
                metric=view.metric,
                alpha=alpha,
                missing=missing,
                aggregate=asked,
            )
        except BenchmarkError as error:
            fold_ranks[view.run.id] = str(error)
        on_run(view.run)
        views.append(view)
    comparison, note = None, None
    if len(views) >= 2:
        try:
            comparison = compare_runs(
                store, run_refs, metric=metric, alpha=alpha, missing=missing, aggregate=asked
            )
        except BenchmarkError as error:  # the report stands without it; it says why
            note = str(error)
    return Report(
        views,
        comparison,
        note,
        fold_ranks,
        confusions,
        library_versions(),
        answers={view.run.id: run_answers(store, view.run.id) for view in views},
        learning=_learning_curves(store, views),
    )


def _learning_curves(store: Store, views: Sequence[RunView]) -> dict[int, LearningCurveResult]:
    """The newest learning curve of each run's data set (runs without one left out)."""
    found = {}
    for view in views:
        run = view.run
        if run.dataset_id is None:  # an imported run's data set may be gone
            continue
        curve = latest_learning_curve(store, run.dataset_id, run.dataset_name or "")
        if curve is not None:
            found[run.id] = curve
    return found


def library_versions() -> dict[str, str]:
    """Python's and the main libraries' versions in this environment."""
    versions = {"python": platform.python_version()}
    for name in LIBRARIES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def _sum_confusions(run: RunInfo, results: Sequence[TaskResult]) -> dict[str, np.ndarray]:
    """Per-target sums of the results' confusion matrices."""
    sums: dict[str, np.ndarray] = {}
    for result in results:
        matrices = result.confusion if run.kind == "multitarget" else [result.confusion]
        for target, matrix in zip(run.targets, matrices or [], strict=True):
            counts = np.asarray(matrix, dtype=np.int64)
            sums[target] = sums[target] + counts if target in sums else counts
    return sums
