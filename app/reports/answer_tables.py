"""The tables of the answers after a leaderboard: which group of features can go (an
ablation) and how many touches a classifier needs (a learning curve), as text cells for the
CLI, the HTML report and the web page alike."""

from __future__ import annotations

from app.reports.run_tables import RunTable
from app.schemas.ablation import AblationResult
from app.schemas.learning import LearningCurveResult


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
