"""Comparing classifiers across runs: Demšar's ranks, Friedman, Nemenyi and Holm, and the
Bayesian view of two classifiers.

Each run is one block (a data set with its targets) and each classifier's score on it is
its mean over the run's successful folds.  A single run has no data sets to rank over, so
its folds become the blocks, as autorank does for repeated measures; folds share training
data, so that reading is descriptive and the result says so (``blocks_are == "folds"``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from touchbench.app.schemas.base import finite
from touchbench.app.schemas.compare import (
    BayesianOut,
    ClassifierRank,
    ComparisonOut,
    FriedmanOut,
    HolmOut,
    HolmRow,
    MissingCellOut,
    MissingOut,
    NemenyiOut,
    PairOut,
)
from touchbench.app.schemas.runs import Aggregate
from touchbench.app.schemas.status import Status
from touchbench.app.services.beside import besides, merged_results
from touchbench.app.services.imported import is_imported
from touchbench.app.services.runs.rescore import results_as_asked
from touchbench.app.store.database import Store
from touchbench.app.store.runs import RunInfo, get_run
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.bayesian import (
    DEFAULT_ROPE,
    BayesianComparison,
    correlated_ttest,
    signed_rank_test,
)
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER
from touchbench.benchmark.evaluation.score_table import (
    CompletedTable,
    MissingPolicy,
    ScoreTable,
    fold_score_table,
)
from touchbench.benchmark.evaluation.statistics import RankComparison, compare_classifiers
from touchbench.benchmark.results import Origin, TaskResult

BlockKind = Literal["datasets", "folds"]


@dataclass(frozen=True)
class RunScores:
    """One run's scores on one metric.

    Attributes
    ----------
    run : RunInfo
    label : str
        The run as a block: ``"dataset (target, ...)"``.
    folds : ScoreTable
        Per-fold scores, shape (n_folds, n_classifiers), NaN for failed folds.
    test_train_ratio : float
        Mean ``n_test / n_train`` of the run's folds.
    """

    run: RunInfo
    label: str
    folds: ScoreTable
    test_train_ratio: float

    def mean(self, classifier: str) -> float:
        """Mean over the successful folds; NaN when there is none."""
        column = self.folds.column(classifier)
        finite = column[~np.isnan(column)]
        return float(finite.mean()) if finite.size else math.nan


@dataclass(frozen=True)
class PairComparison:
    """The Bayesian view of classifiers ``a`` and ``b``.

    Attributes
    ----------
    a, b : str
    per_run : list of (RunScores, BayesianComparison)
        The correlated t-test on each run's paired folds.
    across : BayesianComparison or None
        The Bayesian signed-rank test over the runs' means (at least 2 runs).
    """

    a: str
    b: str
    per_run: list[tuple[RunScores, BayesianComparison]]
    across: BayesianComparison | None


@dataclass(frozen=True)
class Comparison:
    """Classifiers compared over the blocks of one or more runs.

    Attributes
    ----------
    runs : list of RunScores
    metric : str
    lower_is_better : bool
    blocks_are : {"datasets", "folds"}
    table : ScoreTable
        Scores per block and shared classifier, missing cells as NaN.
    completed : CompletedTable
        The table the statistics ran on, and what the missing-cell policy did.
    ranks : RankComparison
    not_shared : list of str
        Classifiers that some of the runs lack (left out).
    pair : PairComparison or None
    notes : list of str
        What a reader should know (unfinished runs, folds as blocks...).
    origins : dict of str to str
        Classifiers some run computed from fold predictions (or fitted as helpers), and
        how (:func:`entry_origins`).
    """

    runs: list[RunScores]
    metric: str
    lower_is_better: bool
    blocks_are: BlockKind
    table: ScoreTable
    completed: CompletedTable
    ranks: RankComparison
    not_shared: list[str] = field(default_factory=list)
    pair: PairComparison | None = None
    notes: list[str] = field(default_factory=list)
    origins: dict[str, str] = field(default_factory=dict)


def default_metric(kinds: Sequence[str]) -> str:
    """The leaderboards' ranking metric for runs of these kinds."""
    distinct = set(kinds)
    if distinct == {"multiclass"}:
        return "f1_weighted"
    if distinct == {"multitarget"}:
        return "hamming_score"
    if distinct == {"regression"}:
        return "mae"
    raise ConfigurationError(
        "the runs mix multi-class and multi-target problems, or classification and regression: "
        "name a metric every run has"
    )


def run_scores(run: RunInfo, metric: str, results: Sequence[TaskResult]) -> RunScores:
    """One run's per-fold scores on ``metric``."""
    if not results:
        raise ConfigurationError(f"run {run.id} has no results yet")
    if not any(r.ok and metric in r.metrics for r in results):
        available = sorted({name for r in results if r.ok for name in r.metrics})
        raise ConfigurationError(
            f"run {run.id} has no '{metric}' scores (metrics: {', '.join(available) or 'none'})"
        )
    ratios = [r.n_test / r.n_train for r in results if r.n_train > 0]
    return RunScores(
        run=run,
        label=f"{run.dataset_name} ({', '.join(run.targets)})",
        folds=fold_score_table(results, metric, classifiers=run.classifiers),
        test_train_ratio=float(np.mean(ratios)) if ratios else 0.0,
    )


def compare_runs(
    store: Store,
    run_refs: Sequence[int | str],
    *,
    metric: str | None = None,
    alpha: float = 0.05,
    missing: MissingPolicy = "drop-classifier",
    pair: tuple[str, str] | None = None,
    rope: float = DEFAULT_ROPE,
    aggregate: Aggregate | None = None,
) -> Comparison:
    """Rank the classifiers that all the runs share, and test their differences.

    Parameters
    ----------
    store : Store
    run_refs : sequence of int or str
        Run ids: several runs (one per data set), or one run (its folds as blocks).
    metric : str, optional
        Default: the leaderboards' (weighted F1, or Hamming score for multi-target runs).
    alpha : float
        Significance level of the Nemenyi CD and Holm's procedure.
    missing : {"drop-classifier", "drop-block", "worst"}
        What to do with a classifier without a score on a block (see
        :meth:`ScoreTable.complete`); the cells are reported whatever the choice.
    pair : (str, str), optional
        Two classifiers for the Bayesian view.
    rope : float
        Region of practical equivalence of the Bayesian tests, in the metric's units.
    aggregate : {"window", "recording"}, optional
        Score each run per window or per recording, from its stored test-fold predictions
        where it scored otherwise (:func:`~app.services.runs.rescore.results_as_asked`);
        default as each run scored.

    Raises
    ------
    NotFoundError
        An unknown run.
    ConfigurationError
        No runs, a run given twice, two runs of the same data set and targets, a metric
        some run lacks, fewer than 2 shared classifiers, an unknown pair.
    FieldError
        For ``aggregate``: a run it cannot re-score.
    """
    if not run_refs:
        raise ConfigurationError("give at least one run to compare")
    runs, besides_of = with_besides([get_run(store, ref) for ref in run_refs])
    _check_distinct(runs)
    metric = metric or default_metric([run.kind for run in runs])
    scores = []
    beside_notes: list[str] = []
    for run in runs:
        others = besides(run, besides_of.get(run.id, []))
        results, _ = merged_results(
            results_as_asked(store, run, aggregate),
            [(b, results_as_asked(store, b.run, aggregate)) for b in others],
        )
        names = [name for b in others for name in b.names.values()]
        scores.append(
            run_scores(replace(run, classifiers=[*run.classifiers, *names]), metric, results)
        )
        beside_notes += [
            f"run {b.run.id} ({b.run.config.name or b.run.fold_scheme}) joins "
            f"run {run.id} (same data set and target); as for their folds: {b.note}"
            for b in others
        ]
    return _compared(
        scores, metric, alpha=alpha, missing=missing, pair=pair, rope=rope, notes=beside_notes
    )


def compare_folds(
    run: RunInfo,
    results: Sequence[TaskResult],
    *,
    metric: str,
    alpha: float = 0.05,
    missing: MissingPolicy = "drop-classifier",
) -> Comparison:
    """One run's classifiers ranked over its folds, as :func:`compare_runs` ranks a run
    given alone, from ``results`` already read (and scored as asked: a leaderboard's).

    Raises
    ------
    ConfigurationError
        As :func:`compare_runs`.
    """
    return _compared(
        [run_scores(run, metric, results)], metric, alpha=alpha, missing=missing, notes=[]
    )


def _compared(
    scores: list[RunScores],
    metric: str,
    *,
    alpha: float,
    missing: MissingPolicy,
    notes: list[str],
    pair: tuple[str, str] | None = None,
    rope: float = DEFAULT_ROPE,
) -> Comparison:
    """The classifiers every run of ``scores`` has, ranked and tested over the runs (one
    run: over its folds); ``notes`` are said first."""
    lower = metric in LOWER_IS_BETTER
    runs = [s.run for s in scores]
    shared = [c for c in runs[0].classifiers if all(c in run.classifiers for run in runs[1:])]
    not_shared = sorted({c for run in runs for c in run.classifiers} - set(shared))
    if len(shared) < 2:
        raise ConfigurationError(
            f"the runs share {len(shared)} classifier(s) ({', '.join(shared) or 'none'}): "
            "a comparison needs at least 2"
        )
    notes = notes + [
        f"run {run.id} is {run.status}: {run.n_results} of {run.n_tasks} tasks have results"
        for run in runs
        if run.status != Status.DONE
    ]
    if len(runs) == 1:
        blocks_are: BlockKind = "folds"
        only = scores[0]
        table = ScoreTable(
            np.column_stack([only.folds.column(c) for c in shared]),
            only.folds.blocks,
            tuple(shared),
        )
        notes.append(
            f"one run: its {len(table.blocks)} folds are the blocks; folds share training "
            "data, so read the ranks as descriptive (Demšar's tests assume independent data sets)"
        )
    else:
        blocks_are = "datasets"
        table = ScoreTable(
            np.array([[s.mean(c) for c in shared] for s in scores]),
            tuple(s.label for s in scores),
            tuple(shared),
        )
    completed = table.complete(missing, lower_is_better=lower)
    _check_enough(completed, missing)
    ranks = compare_classifiers(completed.table, lower_is_better=lower, alpha=alpha)
    if ranks.friedman.iman_davenport_p_value > alpha:
        notes.append(
            f"Friedman's test (Iman-Davenport F) does not reject equal ranks at alpha {alpha} "
            f"(p = {ranks.friedman.iman_davenport_p_value:.3g}): Demšar advises against reading "
            "the post-hoc tests (Nemenyi, Holm) as significant"
        )
    bayes = _pair(scores, shared, pair, rope, lower, notes) if pair else None
    origins = entry_origins(runs, shared)
    notes += [f"{name}: {note}" for name, note in origins.items()]
    return Comparison(
        runs=scores,
        metric=metric,
        lower_is_better=lower,
        blocks_are=blocks_are,
        table=table,
        completed=completed,
        ranks=ranks,
        not_shared=not_shared,
        pair=bayes,
        notes=notes,
        origins=origins,
    )


def entry_origins(runs: Sequence[RunInfo], classifiers: Sequence[str]) -> dict[str, str]:
    """How the runs came by the folds of those of ``classifiers`` that some run computed
    from fold predictions or fitted as a helper: ``from fold predictions of xgb, hgb (run
    3)``, by classifier."""
    found: dict[str, dict[str, list[int]]] = {}
    for run in runs:
        for name, origin in run.config.origins.items():
            if name in classifiers:
                note = Origin(origin.kind, tuple(origin.entries)).describe()
                found.setdefault(name, {}).setdefault(note, []).append(run.id)
    return {
        name: "; ".join(
            f"{note} (run{'s' if len(ids) > 1 else ''} {', '.join(map(str, ids))})"
            for note, ids in notes.items()
        )
        for name, notes in found.items()
    }


def with_besides(runs: Sequence[RunInfo]) -> tuple[list[RunInfo], dict[int, list[RunInfo]]]:
    """The runs that are blocks, and the imported runs that join a block of the same data
    set and targets (a paper's results beside ours) by the block's run id."""
    primary: list[RunInfo] = []
    joined: dict[int, list[RunInfo]] = {}
    for run in sorted(runs, key=is_imported):  # ours first: an imported run joins ours
        host = next(
            (
                p
                for p in primary
                if is_imported(run) and (p.dataset_id, p.targets) == (run.dataset_id, run.targets)
            ),
            None,
        )
        if host is None or host.id == run.id:
            primary.append(run)
        else:
            joined.setdefault(host.id, []).append(run)
    order = {run.id: i for i, run in enumerate(runs)}
    return sorted(primary, key=lambda run: order[run.id]), joined


def _check_distinct(runs: Sequence[RunInfo]) -> None:
    seen: dict[tuple[int, tuple[str, ...]], RunInfo] = {}
    for run in runs:
        key = (run.dataset_id, tuple(run.targets))
        earlier = seen.get(key)
        if earlier is not None:
            if earlier.id == run.id:
                raise ConfigurationError(f"run {run.id} is given twice")
            raise ConfigurationError(
                f"runs {earlier.id} and {run.id} both benchmark {run.dataset_name} "
                f"({', '.join(run.targets)}): each data set must count once"
            )
        seen[key] = run


def _check_enough(completed: CompletedTable, policy: str) -> None:
    table = completed.table
    if table.shape[1] >= 2 and table.shape[0] >= 2:
        return
    cells = ", ".join(f"{m.classifier} on {m.block}" for m in completed.missing[:4])
    more = f" and {len(completed.missing) - 4} more" if len(completed.missing) > 4 else ""
    raise ConfigurationError(
        f"with the missing-score policy {policy}, {table.shape[1]} classifier(s) on "
        f"{table.shape[0]} block(s) remain (missing scores: {cells}{more}); try another policy"
    )


def _pair(
    scores: Sequence[RunScores],
    shared: Sequence[str],
    pair: tuple[str, str],
    rope: float,
    lower: bool,
    notes: list[str],
) -> PairComparison:
    a, b = pair
    for name in pair:
        if name not in shared:
            raise ConfigurationError(
                f"'{name}' is not a classifier every run has (shared: {', '.join(shared)})"
            )
    if a == b:
        raise ConfigurationError(f"compare two different classifiers, not '{a}' with itself")
    per_run = []
    for run in scores:
        x, y = run.folds.column(a), run.folds.column(b)
        both = ~np.isnan(x) & ~np.isnan(y)
        if both.sum() < 2:
            notes.append(f"run {run.run.id}: fewer than 2 folds where both {a} and {b} succeeded")
            continue
        per_run.append(
            (
                run,
                correlated_ttest(
                    x[both],
                    y[both],
                    test_train_ratio=run.test_train_ratio,
                    rope=rope,
                    lower_is_better=lower,
                ),
            )
        )
    across = None
    if len(scores) >= 2:
        means = np.array([[s.mean(a), s.mean(b)] for s in scores])
        usable = ~np.isnan(means).any(axis=1)
        if usable.sum() < len(scores):
            notes.append(
                f"signed-rank test: {len(scores) - int(usable.sum())} run(s) left out where "
                f"{a} or {b} has no score"
            )
        if usable.sum() >= 2:
            across = signed_rank_test(
                means[usable, 0], means[usable, 1], rope=rope, lower_is_better=lower
            )
    return PairComparison(a, b, per_run, across)


def comparison_schema(comparison: Comparison) -> ComparisonOut:
    """The JSON of a comparison (``touchbench compare --json``)."""
    ranks = comparison.ranks
    table = comparison.table
    names = list(ranks.classifiers)
    completed = comparison.completed
    return ComparisonOut(
        runs=[scores.run.id for scores in comparison.runs],
        metric=comparison.metric,
        lower_is_better=comparison.lower_is_better,
        alpha=ranks.alpha,
        blocks_are=comparison.blocks_are,
        blocks=list(ranks.blocks),
        classifiers=[
            ClassifierRank(
                classifier=name,
                average_rank=float(rank),
                mean_score=finite(float(mean)),
                origin=comparison.origins.get(name),
                scores={
                    block: finite(float(value))
                    for block, value in zip(table.blocks, table.column(name), strict=True)
                },
            )
            for name, rank, mean in zip(names, ranks.average_ranks, ranks.mean_scores, strict=True)
        ],
        friedman=FriedmanOut(
            chi_square=ranks.friedman.statistic,
            p_value=ranks.friedman.p_value,
            iman_davenport_f=finite(ranks.friedman.iman_davenport),
            iman_davenport_p_value=ranks.friedman.iman_davenport_p_value,
            df=ranks.friedman.df,
            df_denominator=ranks.friedman.df_denominator,
            tie_corrected=ranks.friedman.tie_corrected,
        ),
        nemenyi=NemenyiOut(
            q_alpha=ranks.q_alpha,
            critical_difference=ranks.critical_difference,
            groups=[list(group) for group in ranks.groups],
            p_values={
                a: {b: float(ranks.nemenyi_p_values[i, j]) for j, b in enumerate(names)}
                for i, a in enumerate(names)
            },
        ),
        holm=HolmOut(
            control=ranks.control,
            comparisons=[
                HolmRow(
                    classifier=h.classifier,
                    z=h.z,
                    p_value=h.p_value,
                    adjusted_p_value=h.adjusted_p_value,
                    significant=h.significant,
                )
                for h in ranks.holm
            ],
        ),
        missing=MissingOut(
            policy=completed.policy,
            cells=[
                MissingCellOut(block=m.block, classifier=m.classifier) for m in completed.missing
            ],
            dropped_classifiers=completed.dropped_classifiers,
            dropped_blocks=completed.dropped_blocks,
        ),
        not_shared=comparison.not_shared,
        bayesian=pair_schema(comparison.pair) if comparison.pair else None,
        notes=comparison.notes,
    )


def pair_schema(pair: PairComparison) -> PairOut:
    """The JSON of a Bayesian comparison of two classifiers."""
    return PairOut(
        first=pair.a,
        second=pair.b,
        per_run=[
            BayesianOut.of(result, block=scores.label, run_id=scores.run.id)
            for scores, result in pair.per_run
        ],
        across_runs=BayesianOut.of(pair.across) if pair.across else None,
    )
