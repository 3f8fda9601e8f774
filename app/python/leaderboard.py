"""A run's leaderboard in Python: a DataFrame, the winner, plots and a rich display in Jupyter.

:class:`Leaderboard` wraps the service's :class:`~app.schemas.runs.LeaderboardSchema` (the
rows of ``touchbench leaderboard --json`` and ``GET /api/runs/{id}/leaderboard``).  What
its plots need beyond the rows (every fold's score, the ranks over the folds, confusion
matrices) it asks a :class:`ResultSource` for when a plot is drawn: the in-process API reads
them from the store through the services (:class:`app.python.sources.StoreSource`), the
client fetches them over HTTP (:class:`app.python.client.Client`).  Both hand back the same
response models, so a plot reads the same whichever way the leaderboard came.
"""

from __future__ import annotations

# Imports inside functions: start-up time: pandas, numpy, matplotlib and the report tables
# load when a table or a plot is first asked for, not when the leaderboard arrives.
import html
import math
from collections.abc import Sequence
from functools import cached_property
from typing import TYPE_CHECKING, Any, Literal, Protocol, get_args

from touchbench.app.errors import AppError
from touchbench.app.schemas.certainty import RunCertainty
from touchbench.app.schemas.folds import FoldScoresSchema
from touchbench.app.schemas.runs import (
    Aggregate,
    LeaderboardRowSchema,
    LeaderboardSchema,
    MetricValue,
)

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

#: The plots of a leaderboard (the CLI's ``plot --kind`` names).
PlotKind = Literal["cd", "folds", "confusion"]
PLOT_KINDS: tuple[str, ...] = get_args(PlotKind)


class ResultSource(Protocol):
    """Where a leaderboard reads what its plots draw beyond its rows, scored per
    ``aggregate`` as the leaderboard was (a window, or a recording's windows pooled)."""

    def fold_scores(self, run_id: int, *, metric: str, aggregate: Aggregate) -> FoldScoresSchema:
        """Every fold's score of the run's classifiers on ``metric``, and their ranks."""
        ...

    def classes(self, run_id: int, *, classifier: str, aggregate: Aggregate) -> RunCertainty:
        """``classifier``'s confusion matrices (summed over folds) and per-class scores."""
        ...


class Leaderboard:
    """A run's classifiers ranked by its metric, with WEKA's marks against the baseline.

    Parameters
    ----------
    schema : LeaderboardSchema
        The rows, as the service answers them.
    source : ResultSource, optional
        Where the plots read per-fold scores and confusion matrices; without one,
        :meth:`plot` is refused (the table is all there is).
    """

    def __init__(self, schema: LeaderboardSchema, source: ResultSource | None = None) -> None:
        self.schema = schema
        self._source = source

    @classmethod
    def from_json(cls, data: dict[str, Any], source: ResultSource | None = None) -> Leaderboard:
        """A leaderboard from the JSON of ``leaderboard --json`` or the API."""
        return cls(LeaderboardSchema.model_validate(data), source)

    # --- what it holds -------------------------------------------------------------

    @property
    def run_id(self) -> int:
        return self.schema.run_id

    @property
    def metric(self) -> str:
        """The metric the rows are ranked by."""
        return self.schema.metric

    @property
    def baseline(self) -> str | None:
        """The classifier the marks compare against (``None``: no task succeeded)."""
        return self.schema.baseline

    @property
    def rows(self) -> list[LeaderboardRowSchema]:
        """The rows, best first."""
        return self.schema.leaderboard

    @property
    def best_row(self) -> LeaderboardRowSchema | None:
        """The winning row: ranked first with a score on the metric; ``None`` when no
        classifier has one (every task failed, or none has run yet)."""
        if not self.rows:
            return None
        first = self.rows[0]
        value = first.metrics.get(self.metric)
        if not isinstance(value, MetricValue) or value.mean is None:
            return None
        return first

    @property
    def best(self) -> str | None:
        """The winning classifier's id (``None`` as for :attr:`best_row`)."""
        row = self.best_row
        return None if row is None else row.classifier

    def row(self, classifier: str) -> LeaderboardRowSchema:
        """The row of ``classifier``."""
        for row in self.rows:
            if row.classifier == classifier:
                return row
        raise AppError(
            f"run {self.run_id} has no classifier '{classifier}' "
            f"(classifiers: {', '.join(r.classifier for r in self.rows)})"
        )

    def mark(self, row: LeaderboardRowSchema) -> str:
        """The row's mark as the CLI shows it: ``v`` better than the baseline, ``*``
        worse, empty when no different, ``(base)`` the baseline itself, ``=`` a row from a
        run beside whose folds do not pair with the baseline's (means only)."""
        if row.classifier == self.baseline:
            return "(base)"
        if self.schema.beside and not row.tested and self.baseline is not None:
            return "="
        return row.mark

    def note(self, row: LeaderboardRowSchema) -> str:
        """Why the row stopped early and what failed, in one line (the CLI's notes)."""
        parts = []
        if row.dropped is not None:
            folds = "" if row.dropped.reason == "not started" else f", {row.n_ok + row.n_failed}"
            parts.append(row.dropped.note + (f"{folds} folds run" if folds else ""))
        if row.errors:
            parts.append(f"{row.n_failed} failed: {row.errors[0]}")
        return "; ".join(parts)

    def metrics(self) -> list[str]:
        """The metrics of the rows: the ranking one first, then the tables' usual ones of
        the run's kind, then the others by name (per-target scores left out)."""
        from touchbench.app.reports.leaderboard import TABLE_METRICS

        present = {
            name
            for row in self.rows
            for name, value in row.metrics.items()
            if isinstance(value, MetricValue)
        }
        usual = [self.metric, *TABLE_METRICS.get(self.schema.kind, [])]
        ordered = [m for m in dict.fromkeys(usual) if m in present or m == self.metric]
        return ordered + sorted(present - set(ordered))

    def table_metrics(self) -> list[str]:
        """The columns the CLI's table shows (the ranking metric and the kind's usual ones)."""
        from touchbench.app.reports.leaderboard import TABLE_METRICS

        usual = [self.metric, *TABLE_METRICS.get(self.schema.kind, [])]
        present = set(self.metrics())
        return [m for m in dict.fromkeys(usual) if m in present]

    # --- tables ---------------------------------------------------------------------

    def to_pandas(self) -> pd.DataFrame:
        """One row per classifier, best first, indexed by classifier id.

        Returns
        -------
        pandas.DataFrame of shape (n_classifiers, 5 + 2 * n_metrics + 3)
            ``rank``, ``mark`` (as :meth:`mark`), ``<metric>_mean`` and ``<metric>_std``
            for each of :meth:`metrics` (NaN without a value), ``p_value`` (the t-test
            against the baseline), ``folds`` (folds run: ``n_ok + n_failed``), ``n_ok``,
            ``n_failed`` and ``note``.
        """
        import pandas as pd

        metrics = self.metrics()
        records = []
        for row in self.rows:
            record: dict[str, Any] = {"rank": row.rank, "mark": self.mark(row)}
            for name in metrics:
                value = row.metrics.get(name)
                scored = isinstance(value, MetricValue)
                record[f"{name}_mean"] = _number(value.mean if scored else None)  # type: ignore[union-attr]
                record[f"{name}_std"] = _number(value.std if scored else None)  # type: ignore[union-attr]
            record["p_value"] = _number(row.p_value)
            record["folds"] = row.n_ok + row.n_failed
            record["n_ok"] = row.n_ok
            record["n_failed"] = row.n_failed
            record["note"] = self.note(row)
            records.append(record)
        columns = [
            "rank",
            "mark",
            *(f"{name}_{part}" for name in metrics for part in ("mean", "std")),
            "p_value",
            "folds",
            "n_ok",
            "n_failed",
            "note",
        ]
        index = pd.Index([row.classifier for row in self.rows], name="classifier")
        return pd.DataFrame.from_records(records, index=index, columns=columns)

    def _cells(self) -> tuple[list[str], list[list[str]]]:
        """The CLI's table: header and rows of text."""
        from touchbench.app.reports.leaderboard import mean_std

        columns = self.table_metrics()
        notes = any(self.note(row) for row in self.rows)
        header = ["#", "classifier", "", *columns, *(["notes"] if notes else [])]
        body = []
        for row in self.rows:
            cells = [str(row.rank), row.classifier, self.mark(row)]
            for name in columns:
                value = row.metrics.get(name)
                cells.append(
                    mean_std((value.mean, value.std))  # type: ignore[arg-type]
                    if isinstance(value, MetricValue)
                    else "-"
                )
            if notes:
                cells.append(self.note(row))
            body.append(cells)
        return header, body

    def _caption(self) -> str:
        s = self.schema
        direction = " (lower is better)" if s.lower_is_better else ""
        folds = f", {s.folds}" if s.folds else ""
        return (
            f"run {s.run_id}: {s.dataset} ({', '.join(s.targets)}){folds}, "
            f"ranked by {s.metric}{direction}; {s.status}"
        )

    def _footer(self) -> list[str]:
        s = self.schema
        if s.baseline is None:
            lines = [f"no task of run {s.run_id} succeeded; the notes say why"]
        else:
            m = s.summary
            lines = [
                f"marks against {s.baseline}: v significantly better, * significantly worse "
                f"(corrected resampled t-test, alpha 0.05); (v/ /*) = "
                f"({m.better}/{m.same}/{m.worse})"
            ]
        return lines + list(s.notes)

    def _numeric_columns(self) -> set[int]:
        """The table's columns aligned right: the rank and the metrics."""
        return {0, *range(3, 3 + len(self.table_metrics()))}

    def __repr__(self) -> str:
        header, body = self._cells()
        widths = [max(len(line[i]) for line in [header, *body]) for i in range(len(header))]
        numeric = self._numeric_columns()

        def line(cells: Sequence[str]) -> str:
            return "  ".join(
                cell.rjust(width) if i in numeric else cell.ljust(width)
                for i, (cell, width) in enumerate(zip(cells, widths, strict=True))
            ).rstrip()

        return "\n".join(
            [f"<Leaderboard {self._caption()}>", line(header), *map(line, body), *self._footer()]
        )

    def _repr_html_(self) -> str:
        """The table as Jupyter shows it: the CLI's columns and marks, every name escaped."""
        header, body = self._cells()
        e = html.escape
        head = "".join(f"<th>{e(cell)}</th>" for cell in header)
        rows = []
        best = self.best
        numeric = self._numeric_columns()
        for cells, row in zip(body, self.rows, strict=True):
            style = ' style="font-weight:bold"' if row.classifier == best else ""
            tds = "".join(
                f'<td style="text-align:{"right" if i in numeric else "left"}">{e(cell)}</td>'
                for i, cell in enumerate(cells)
            )
            rows.append(f"<tr{style}>{tds}</tr>")
        footer = "".join(f"<li>{e(text)}</li>" for text in self._footer())
        return (
            '<div class="touchbench-leaderboard">'
            f"<table><caption>{e(self._caption())}</caption>"
            f"<thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
            f"<ul>{footer}</ul></div>"
        )

    # --- plots ----------------------------------------------------------------------

    @cached_property
    def _fold_scores(self) -> FoldScoresSchema:
        return self._needs_source().fold_scores(
            self.run_id, metric=self.metric, aggregate=self.schema.aggregate
        )

    def fold_scores(self) -> pd.DataFrame:
        """Every fold's score on the ranking metric, scored as the rows (per window or per
        recording: ``schema.aggregate``).

        Returns
        -------
        pandas.DataFrame of shape (n_folds, n_classifiers)
            Indexed by fold label, one column per classifier (best first), NaN for a
            failed fold.
        """
        import pandas as pd

        scores = self._fold_scores
        return pd.DataFrame(
            {name: [_number(v) for v in values] for name, values in scores.scores.items()},
            index=pd.Index(scores.folds, name="fold"),
        )

    def plot(self, kind: PlotKind = "cd", *, classifier: str | None = None) -> Figure:
        """One plot of the run, as ``touchbench plot --kind KIND`` draws it, scored as the
        rows (per window or per recording: ``schema.aggregate``).

        Parameters
        ----------
        kind : {"cd", "folds", "confusion"}
            ``cd``: critical-difference diagram of the classifiers' ranks over the run's
            folds; ``folds``: every fold's score per classifier; ``confusion``: a
            classifier's confusion matrices (summed over folds, normalised per row).
        classifier : str, optional
            For ``confusion``: default the best.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from touchbench.app.reports import plots

        if kind not in PLOT_KINDS:
            raise AppError(f"kind: '{kind}' is not one of {', '.join(PLOT_KINDS)}")
        if classifier is not None and kind != "confusion":
            raise AppError("classifier: goes with kind 'confusion'")
        title = f"run {self.run_id}: {self.schema.dataset} ({', '.join(self.schema.targets)})"
        if kind == "confusion":
            return self._confusion(classifier, title)
        scores = self._fold_scores
        if kind == "folds":
            return plots.fold_strip_plot(
                {name: [_number(v) for v in values] for name, values in scores.scores.items()},
                metric=scores.metric,
                lower_is_better=scores.lower_is_better,
                title=title,
            )
        ranks = scores.ranks
        if ranks is None:
            raise AppError(
                f"run {self.run_id}: no critical-difference diagram: {scores.ranks_note}"
            )
        blocks = f"run {self.run_id} ({self.schema.dataset}), {len(ranks.blocks)} folds as blocks"
        return plots.cd_diagram(
            {c.classifier: c.average_rank for c in ranks.classifiers},
            ranks.nemenyi.critical_difference,
            ranks.nemenyi.groups,
            title=f"{ranks.metric}: average ranks over {blocks} (Nemenyi, alpha {ranks.alpha})",
        )

    def _confusion(self, classifier: str | None, title: str) -> Figure:
        import numpy as np

        from touchbench.app.reports import plots

        if classifier is None:
            classifier = self.best
            if classifier is None:
                raise AppError(f"run {self.run_id} has no classifier with a successful fold")
        row = self.row(classifier)
        found = self._needs_source().classes(
            self.run_id, classifier=classifier, aggregate=self.schema.aggregate
        )
        entry = next(c for c in found.classifiers if c.classifier == classifier)
        failed = f", {row.n_failed} failed" if row.n_failed else ""
        return plots.confusion_figure(
            {t.target: np.asarray(t.confusion, dtype=np.int64) for t in entry.targets},
            {t.target: t.labels for t in entry.targets},
            title=f"{title}: {classifier}, summed over {entry.n_folds} folds{failed}",
        )

    def _needs_source(self) -> ResultSource:
        if self._source is None:
            raise AppError(
                f"this leaderboard of run {self.run_id} was made from its rows alone: its "
                "plots need the store or the service it came from"
            )
        return self._source


def _number(value: float | None) -> float:
    return math.nan if value is None else float(value)
