"""Leaderboards as people and other tools read them: table rows, CSV and Markdown (the JSON
report is :meth:`app.services.runs.RunLeaderboard.report`)."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from typing import Any

from app.store.runs import RunInfo
from benchmark.evaluation.leaderboard import Leaderboard, LeaderboardRow

#: Columns shown in tables, by kind of problem (the ranking metric always comes first).
TABLE_METRICS = {
    "multiclass": ["f1_weighted", "accuracy", "kappa", "roc_auc", "fit_time"],
    "multitarget": ["hamming_score", "exact_match", "hamming_loss", "fit_time"],
    "regression": ["mae", "rmse", "r2", "euclidean_error", "fit_time"],
}


def metric_columns(run: RunInfo, board: Leaderboard) -> list[str]:
    columns = [board.metric] + [m for m in TABLE_METRICS.get(run.kind, []) if m != board.metric]
    available = {name for row in board.rows for name in row.metrics}
    return [c for c in columns if c in available or c == board.metric]


def leaderboard_header(board: Leaderboard, columns: Sequence[str]) -> list[str]:
    notes = ["notes"] if _has_notes(board) else []
    return ["#", "classifier", "", *columns, *notes]


def leaderboard_rows(board: Leaderboard, columns: Sequence[str]) -> list[tuple[Any, ...]]:
    """Rank, classifier, mark and ``mean ± std`` per column, ready for a table; a notes
    column when a row failed or stopped early (``dropped after fold 3 (p ..., mean so far
    ...), 3 folds``)."""
    out = []
    for row in board.rows:
        cells: list[Any] = [row.rank, row.classifier, _mark(row, board)]
        for column in columns:
            value = row.metrics.get(column)
            cells.append(mean_std(value) if isinstance(value, tuple) else "-")
        if _has_notes(board):
            cells.append(row_note(row))
        out.append(tuple(cells))
    return out


def row_note(row: LeaderboardRow) -> str:
    """Why a row stopped early and what failed, in one line; empty when neither."""
    parts = []
    if row.dropped is not None:
        parts.append(f"{row.dropped.describe()}, {row.n_ok + row.n_failed} folds run")
    if row.errors:
        parts.append(f"{row.n_failed} failed: {row.errors[0]}")
    return "; ".join(parts)


def _has_notes(board: Leaderboard) -> bool:
    return any(row.n_failed or row.dropped is not None for row in board.rows)


def leaderboard_csv(board: Leaderboard, columns: Sequence[str]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    header = ["rank", "classifier", "mark"]
    for column in columns:
        header += [f"{column}_mean", f"{column}_std"]
    writer.writerow([*header, "n_ok", "n_failed", "p_value", "dropped_after_fold", "note"])
    for row in board.rows:
        cells: list[Any] = [row.rank, row.classifier, row.mark]
        for column in columns:
            value = row.metrics.get(column)
            cells += list(value) if isinstance(value, tuple) else ["", ""]
        p_value = "" if math.isnan(row.p_value) else row.p_value
        after = "" if row.dropped is None else row.dropped.after_fold
        writer.writerow([*cells, row.n_ok, row.n_failed, p_value, after, row_note(row)])
    return buffer.getvalue()


def leaderboard_markdown(
    run: RunInfo, board: Leaderboard, columns: Sequence[str], notes: Sequence[str] = ()
) -> str:
    marks = (
        f"marks against {board.baseline} (corrected resampled t-test, alpha 0.05): "
        "v better, * worse."
        if board.baseline
        else f"no task succeeded (run {run.status})."
    )
    lines = [
        f"Run {run.id} on {run.dataset_name} ({', '.join(run.targets)}), "
        f"{run.fold_scheme}, ranked by {board.metric}; {marks}",
        "",
        "| rank | classifier | | " + " | ".join(columns) + " |",
        "|---:|---|:-:|" + "---:|" * len(columns),
    ]
    for row, board_row in zip(leaderboard_rows(board, columns), board.rows, strict=True):
        rank, classifier, mark, *values = row[: 3 + len(columns)]
        note = row_note(board_row)
        shown = f"{classifier} ({note})" if note and board_row.dropped is not None else classifier
        lines.append(f"| {rank} | {shown} | {mark} | " + " | ".join(values) + " |")
    v, same, worse = board.summary
    lines += ["", f"(v/ /*) = ({v}/{same}/{worse})", *(f"{note}." for note in notes)]
    return "\n".join(lines) + "\n"


def _mark(row: LeaderboardRow, board: Leaderboard) -> str:
    return "(base)" if row.classifier == board.baseline else row.mark


def mean_std(value: tuple[float, float]) -> str:
    """``"0.8440 ±0.012"``; ``-`` without a mean, the mean alone without a deviation."""
    mean, std = value
    if mean is None or (isinstance(mean, float) and math.isnan(mean)):
        return "-"
    if std is None or (isinstance(std, float) and math.isnan(std)):
        return f"{mean:.4f}"
    return f"{mean:.4f} ±{std:.3f}"
