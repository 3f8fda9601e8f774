"""Leaderboards as people and other tools read them: table rows, CSV and Markdown (the JSON
report is :meth:`app.services.runs.RunLeaderboard.report`)."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from typing import Any

from touchbench.app.services.beside import Beside, row_runs
from touchbench.app.store.runs import RunInfo
from touchbench.benchmark.evaluation.leaderboard import Leaderboard, LeaderboardRow

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


def leaderboard_header(
    board: Leaderboard, columns: Sequence[str], besides: Sequence[Beside] = ()
) -> list[str]:
    notes = ["notes"] if _has_notes(board) else []
    run = ["run"] if besides else []
    return ["#", "classifier", *run, "", *columns, *notes]


def leaderboard_rows(
    board: Leaderboard,
    columns: Sequence[str],
    besides: Sequence[Beside] = (),
    *,
    rows: Sequence[LeaderboardRow] | None = None,
) -> list[tuple[Any, ...]]:
    """Rank, classifier, (with runs beside: the run it comes from,) mark and
    ``mean ± std`` per column, ready for a table; a notes column when a row failed or
    stopped early (``dropped after fold 3 (p ..., mean so far ...), 3 folds``).  With runs
    beside, a classifier that only compares by its mean has ``=`` (means only) where a
    mark would be.  ``rows``: these of the board's only (a page showing the first), with
    the columns of the whole board."""
    origins = row_runs(besides)
    notes = _has_notes(board)  # once: each row asking made the table quadratic
    out = []
    for row in board.rows if rows is None else rows:
        cells: list[Any] = [row.rank, row.classifier]
        if besides:
            cells.append(origins.get(row.classifier, "this"))
        cells.append(_mark(row, board, means_only=bool(besides)))
        for column in columns:
            value = row.metrics.get(column)
            cells.append(mean_std(value) if isinstance(value, tuple) else "-")
        if notes:
            cells.append(row_note(row))
        out.append(tuple(cells))
    return out


def row_note(row: LeaderboardRow) -> str:
    """How the run came by a row (``from fold predictions of ...``, ``helper of ...``), why
    it stopped early and what failed, in one line; empty when none of these."""
    parts = [row.origin.describe()] if row.origin is not None else []
    if row.dropped is not None and row.dropped.reason == "not started":
        parts.append(row.dropped.describe())
    elif row.dropped is not None:
        parts.append(f"{row.dropped.describe()}, {row.n_ok + row.n_failed} folds run")
    if row.errors:
        parts.append(f"{row.n_failed} failed: {row.errors[0]}")
    return "; ".join(parts)


def _has_notes(board: Leaderboard) -> bool:
    return any(
        row.n_failed or row.dropped is not None or row.origin is not None for row in board.rows
    )


def leaderboard_csv(
    board: Leaderboard,
    columns: Sequence[str],
    besides: Sequence[Beside] = (),
    *,
    aggregate: str = "window",
) -> str:
    """One row per classifier: its mean and deviation per column, its folds, its mark and
    a column ``aggregate`` saying what one prediction of the scores is (``window`` or
    ``recording``)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    origins = row_runs(besides)
    header = ["rank", "classifier", "mark"]
    for column in columns:
        header += [f"{column}_mean", f"{column}_std"]
    extra = ["run", "tested"] if besides else []
    writer.writerow(
        [*header, "n_ok", "n_failed", "p_value", "dropped_after_fold", "note", "aggregate", *extra]
    )
    for row in board.rows:
        cells: list[Any] = [row.rank, row.classifier, row.mark]
        for column in columns:
            value = row.metrics.get(column)
            cells += list(value) if isinstance(value, tuple) else ["", ""]
        p_value = "" if math.isnan(row.p_value) else row.p_value
        after = "" if row.dropped is None else row.dropped.after_fold
        more = [origins.get(row.classifier, ""), row.tested] if besides else []
        note = row_note(row)
        writer.writerow([*cells, row.n_ok, row.n_failed, p_value, after, note, aggregate, *more])
    return buffer.getvalue()


def beside_notes(besides: Sequence[Beside]) -> list[str]:
    """One line per run beside: what it is, and how its classifiers compare."""
    out = []
    for beside in besides:
        run = beside.run
        name = f" ({run.config.name})" if run.config.name else ""
        out.append(f"run {run.id}{name}, {run.fold_scheme}: {beside.note}")
    if any(b.test == "means" for b in besides):
        out.append("= : means only, no t-test (folds that do not pair with the baseline's)")
    return out


def leaderboard_markdown(
    run: RunInfo,
    board: Leaderboard,
    columns: Sequence[str],
    besides: Sequence[Beside] = (),
    notes: Sequence[str] = (),
) -> str:
    marks = (
        f"marks against {board.baseline} (corrected resampled t-test, alpha 0.05): "
        "v better, * worse."
        if board.baseline
        else f"no task succeeded (run {run.status})."
    )
    run_column = " run |" if besides else ""
    lines = [
        f"Run {run.id} on {run.dataset_name} ({', '.join(run.targets)}), "
        f"{run.folds_text}, ranked by {board.metric}; {marks}",
        "",
        "| rank | classifier |" + run_column + " | " + " | ".join(columns) + " |",
        "|---:|---|" + ("---:|" if besides else "") + ":-:|" + "---:|" * len(columns),
    ]
    lead = 4 if besides else 3
    for row, board_row in zip(leaderboard_rows(board, columns, besides), board.rows, strict=True):
        cells = [str(cell) for cell in row[: lead + len(columns)]]
        note = row_note(board_row)
        if note and (board_row.dropped is not None or board_row.origin is not None):
            cells[1] = f"{cells[1]} ({note})"
        lines.append("| " + " | ".join(cells) + " |")
    v, same, worse = board.summary
    lines += ["", f"(v/ /*) = ({v}/{same}/{worse})", *(f"{note}." for note in notes)]
    lines += [f"- {note}" for note in beside_notes(besides)]
    return "\n".join(lines) + "\n"


def _mark(row: LeaderboardRow, board: Leaderboard, *, means_only: bool = False) -> str:
    if row.classifier == board.baseline:
        return "(base)"
    if means_only and not row.tested and board.baseline is not None:
        return "="
    return row.mark


def mean_std(value: tuple[float, float]) -> str:
    """``"0.8440 ±0.012"``; ``-`` without a mean, the mean alone without a deviation."""
    mean, std = value
    if mean is None or (isinstance(mean, float) and math.isnan(mean)):
        return "-"
    if std is None or (isinstance(std, float) and math.isnan(std)):
        return f"{mean:.4f}"
    return f"{mean:.4f} ±{std:.3f}"
