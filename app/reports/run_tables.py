"""The tables a run's leaderboard has below its ranking, as text cells: tuned twins against
their defaults and what each fold chose (``bench --tune/--stack``), and the scores of each
target of a multi-target regression.

One builder for the three places that show them: the CLI's ``leaderboard``, the HTML
report and the web page's run view, all from the same :class:`LeaderboardSchema`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from touchbench.app.schemas.runs import FoldChoiceSchema, LeaderboardSchema, MetricValue

#: Per-target scores of a multi-target regression, in table order.
REGRESSION_TARGET_METRICS = ("mae", "rmse", "r2")


@dataclass(frozen=True)
class RunTable:
    """A titled table of text cells.

    Attributes
    ----------
    key : str
        What the table is (``tuning``, ``choices``, ``target``), for styles and tests.
    title : str
    header : tuple of str
    rows : list of tuple of str
        One tuple per row, as many cells as ``header``.
    numeric : tuple of bool
        Per column, whether it holds numbers (right-aligned).
    """

    key: str
    title: str
    header: tuple[str, ...]
    rows: list[tuple[str, ...]]
    numeric: tuple[bool, ...]


def run_tables(report: LeaderboardSchema) -> list[RunTable]:
    """Every table below a run's leaderboard: tuning, choices, then one per target."""
    return [*tuning_tables(report), *target_tables(report)]


def tuning_tables(report: LeaderboardSchema) -> list[RunTable]:
    """The tuned twins against their defaults (corrected resampled t-test) and the
    parameters each tuned twin or stack chose per outer training fold; none without."""
    tables = []
    if report.tuning:
        tables.append(
            RunTable(
                key="tuning",
                title=f"tuned against default ({report.tuning[0].metric}, corrected resampled "
                "t-test, alpha 0.05; v tuned significantly better, * worse)",
                header=(
                    "tuned",
                    "default",
                    "default mean",
                    "tuned mean",
                    "difference",
                    "p",
                    "",
                    "folds",
                ),
                rows=[
                    (
                        c.tuned,
                        c.default,
                        _number(c.default_mean),
                        _number(c.tuned_mean),
                        _number(
                            None
                            if c.tuned_mean is None or c.default_mean is None
                            else c.tuned_mean - c.default_mean,
                            signed=True,
                        ),
                        _number(c.p),
                        c.mark,
                        str(c.n_folds),
                    )
                    for c in report.tuning
                ],
                numeric=(False, False, True, True, True, True, False, True),
            )
        )
    if report.choices:
        nested = any(_per_target(c) for c in report.choices)
        rows = []
        for c in report.choices:
            where = c.params.items() if _per_target(c) else [("", c.params)]
            for target, params in where:
                cells = (c.classifier, str(c.repeat + 1), str(c.fold + 1))
                rows.append((*cells, *((target,) if nested else ()), describe(params)))
        tables.append(
            RunTable(
                key="choices",
                title="chosen in each outer training fold (inner cross-validation only)",
                header=("classifier", "repeat", "fold", *(("target",) if nested else ()), "chosen"),
                rows=rows,
                numeric=(False, True, True, *((False,) if nested else ()), False),
            )
        )
    return tables


def target_tables(report: LeaderboardSchema) -> list[RunTable]:
    """A multi-target regression's MAE, RMSE and R^2 on each target, one table per target,
    classifiers in leaderboard order (``mean ±std`` over folds); none for other runs."""
    if report.kind != "regression" or len(report.targets) < 2:
        return []
    tables = []
    for target in report.targets:
        rows = []
        for row in report.leaderboard:
            per_target = row.metrics.get("per_target")
            scores = per_target.get(target) if isinstance(per_target, dict) else None
            if not scores:
                continue
            rows.append(
                (row.classifier, *(_mean_std(scores.get(m)) for m in REGRESSION_TARGET_METRICS))
            )
        if rows:
            tables.append(
                RunTable(
                    key="target",
                    title=f"target {target} (mean ±std over folds; mae and rmse lower is "
                    "better, r2 higher)",
                    header=("classifier", *REGRESSION_TARGET_METRICS),
                    rows=rows,
                    numeric=(False, True, True, True),
                )
            )
    return tables


def describe(params: dict[str, Any]) -> str:
    """``"C=10, gamma=scale"``: chosen parameters as one line."""
    return ", ".join(f"{name}={_short(value)}" for name, value in params.items())


def _per_target(choice: FoldChoiceSchema) -> bool:
    """Whether a choice is a multi-target model's: each search's parameters by where it sits
    (``{"gesture": {...}, "position": {...}}``), not parameters themselves."""
    return bool(choice.params) and all(isinstance(v, dict) for v in choice.params.values())


def _number(value: float | None, *, signed: bool = False) -> str:
    if value is None or not math.isfinite(value):
        return ""
    return f"{value:+.4f}" if signed else f"{value:.4f}"


def _mean_std(value: MetricValue | None) -> str:
    if value is None or value.mean is None or not math.isfinite(value.mean):
        return "-"
    if value.std is None or not math.isfinite(value.std):
        return f"{value.mean:.4f}"
    return f"{value.mean:.4f} ±{value.std:.3f}"


def _short(value: object) -> str:
    if isinstance(value, list):
        return "[" + " ".join(_short(v) for v in value) + "]"
    return f"{value:g}" if isinstance(value, float) else str(value)
