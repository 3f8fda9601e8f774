"""The tables of the answers after a leaderboard: which group of features can go (an
ablation) and how many touches a classifier needs (a learning curve), as text cells for the
CLI, the HTML report and the web page alike."""

from __future__ import annotations

from touchbench.app.reports.run_tables import RunTable
from touchbench.app.schemas.ablation import AblationResult
from touchbench.app.schemas.importance import FeatureImportance, ImportanceResult
from touchbench.app.schemas.learning import LearningCurveResult
from touchbench.app.services.answers import RunAnswers

#: Features listed per classifier where a run is shown (the CLI's --top lists more).
TOP_FEATURES = 10

_IMPORTANCE_HEADER = ("feature", "features", "drop", "std", "p", "")
_IMPORTANCE_NUMERIC = (False, True, True, True, True, False)


def run_answer_tables(answers: RunAnswers) -> list[RunTable]:
    """The tables of a run's kept answers: its ablation, then each classifier's importance."""
    tables = [] if answers.ablation is None else [ablation_table(answers.ablation)]
    for found in answers.importance:
        tables.extend(importance_tables(found, TOP_FEATURES))
    return tables


def ablation_table(result: AblationResult) -> RunTable:
    """One row per classifier and group: the full set's score, the score without the group,
    the change, p and the verdict."""
    unit = "group" if result.grouping == "family" else "channel"
    return RunTable(
        key="ablation",
        title=(
            f"run {result.run_id}, {result.dataset}: each {unit} removed and the classifier "
            f"refitted ({result.metric} over {result.n_folds} folds, {result.test})"
            + ("" if result.complete else f"; {result.done} of {result.total} tasks so far")
        ),
        header=("classifier", result.grouping, "features", "full", "without", "change", "p", ""),
        rows=[
            (
                entry.classifier,
                entry.group,
                str(_size(result, entry.group)),
                _score(entry.full),
                _score(entry.without),
                _score(entry.change, signed=True),
                "-" if entry.p is None else f"{entry.p:.3g}",
                entry.verdict,
            )
            for entry in result.entries
        ],
        numeric=(False, False, True, True, True, True, True, False),
    )


def importance_tables(result: ImportanceResult, top: int | None = None) -> list[RunTable]:
    """One table per grouping (each group shuffled together), then the ``top`` most
    important features (all without ``top``)."""
    so_far = "" if result.complete else f"; {result.done} of {result.total} folds so far"
    tables = [
        RunTable(
            key="importance",
            title=f"run {result.run_id}, {result.classifier} on {result.target}: each "
            f"{grouping} shuffled ({result.metric} drop over {result.n_folds} folds, baseline "
            f"{result.baseline:.4f}{so_far}; p: corrected resampled t-test of the drop "
            "against none, * significant at 0.05)",
            header=(grouping, *_IMPORTANCE_HEADER[1:]),
            rows=[_importance_row(item) for item in items],
            numeric=_IMPORTANCE_NUMERIC,
        )
        for grouping, items in result.groups.items()
    ]
    shown = result.features if top is None else result.features[:top]
    tables.append(
        RunTable(
            key="importance",
            title=f"{result.classifier}: the {len(shown)} most important of "
            f"{len(result.features)} features",
            header=_IMPORTANCE_HEADER,
            rows=[_importance_row(item) for item in shown],
            numeric=_IMPORTANCE_NUMERIC,
        )
    )
    return tables


def _importance_row(item: FeatureImportance) -> tuple[str, ...]:
    return (
        item.name,
        str(item.n_features),
        f"{item.mean:+.4f}",
        f"{item.std:.4f}",
        "-" if item.p is None else f"{item.p:.3g}",
        "*" if item.significant else "",
    )


def learning_table(result: LearningCurveResult) -> RunTable:
    """One row per classifier: its mean score at each fraction and the fraction within the
    tolerance of its full score."""
    return RunTable(
        key="learning",
        title=(
            f"{result.dataset} ({', '.join(result.targets)}): {result.metric} by share of each "
            f"training fold ({result.n_folds} folds, {result.fold_scheme}); enough: within "
            f"{result.tolerance * 100:g} point(s) of the full score"
            + ("" if result.complete else f"; {result.done} of {result.total} tasks so far")
        ),
        header=(
            "classifier",
            *(f"{fraction:g}" for fraction in result.fractions),
            "enough",
        ),
        rows=[
            (
                curve.classifier,
                *(_score(point.mean) for point in curve.points),
                "-" if curve.enough is None else f"{curve.enough:g}",
            )
            for curve in result.curves
        ],
        numeric=(False, *(True for _ in result.fractions), True),
    )


def _size(result: AblationResult, group: str) -> int:
    return next((g.n_features for g in result.groups if g.name == group), 0)


def _score(value: float | None, *, signed: bool = False) -> str:
    if value is None:
        return "-"
    return f"{value:+.4f}" if signed else f"{value:.4f}"
