"""A self-contained HTML report of runs: leaderboards with WEKA's marks, plots as inline
SVG, the comparison across runs, each run's configuration and the library versions.

One file, no script, no style sheet or font fetched from anywhere: it opens offline and
can be attached to a paper's supplementary material as it is.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

from jinja2 import Environment, FileSystemLoader, StrictUndefined, select_autoescape
from markupsafe import Markup
from matplotlib.figure import Figure

from touchbench.app.reports import bounds, figures
from touchbench.app.reports.answer_tables import learning_table, run_answer_tables
from touchbench.app.reports.certainty_tables import calibration_table, class_tables
from touchbench.app.reports.leaderboard import (
    beside_notes,
    leaderboard_header,
    leaderboard_rows,
    metric_columns,
)
from touchbench.app.reports.plots import svg_text
from touchbench.app.reports.run_tables import run_tables
from touchbench.app.services.answers import RunAnswers
from touchbench.app.services.certainty import certainty_of
from touchbench.app.services.compare import Comparison
from touchbench.app.services.imported import is_imported
from touchbench.app.services.report import Report, RunView
from touchbench.benchmark.errors import BenchmarkError

TEMPLATES = Path(__file__).with_name("templates")


@dataclass
class _Plot:
    """A figure to draw: its caption and how to build it."""

    caption: str
    build: Callable[[], Figure]
    svg: Markup | None = None
    error: str | None = None


def render_report(
    report: Report,
    *,
    on_plan: Callable[[int], None] = lambda total: None,
    on_figure: Callable[[], None] = lambda: None,
) -> str:
    """The report as one HTML document.

    Parameters
    ----------
    report : Report
        From :func:`app.services.report.build_report`.
    on_plan : callable
        Told how many figures will be drawn.
    on_figure : callable
        Called after each figure (progress).
    """
    comparison = None
    plots: list[_Plot] = []
    if report.comparison is not None:
        comparison = comparison_context(report.comparison)
        comparison["plot"] = _plan(
            plots,
            "Critical-difference diagram across data sets",
            partial(figures.cd_figure, report.comparison),
        )
    runs = [_run(report, view, plots) for view in report.views]
    on_plan(len(plots))
    for plot in plots:
        try:
            figure = plot.build()
        except BenchmarkError as error:  # e.g. a run with one classifier has no CD diagram
            plot.error = str(error)
        else:
            plot.svg = Markup(svg_text(figure, inline=True))
        on_figure()
    template = template_environment().get_template("report.html.j2")
    return template.render(
        title=_title(report),
        created_at=report.created_at.strftime("%Y-%m-%d %H:%M UTC"),
        comparison=comparison,
        comparison_note=report.comparison_note,
        runs=runs,
        versions=report.versions,
    )


def template_environment(*folders: Path) -> Environment:
    """The Jinja environment of the report's templates, ``folders`` searched first (the web
    page's): autoescaped, strict about undefined names, with the ``score`` filter and those
    of :mod:`app.reports.bounds` (``names``, ``first``, ``count``, ``and_more``; its limits
    as ``bounds.PANELS``, ...)."""
    environment = Environment(
        loader=FileSystemLoader([*folders, TEMPLATES]),
        autoescape=select_autoescape(["html", "j2"]),
        undefined=StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    environment.filters["score"] = score
    # what a page shows of a long list: the first items and a count of the others
    environment.filters["names"] = bounds.names
    environment.filters["first"] = bounds.first
    environment.filters["count"] = bounds.count
    environment.filters["and_more"] = bounds.and_more
    environment.globals["bounds"] = {
        name: getattr(bounds, name) for name in ("NAMES", "PANELS", "CLASSES", "ATTRIBUTES", "ROWS")
    }
    return environment


def _plan(plots: list[_Plot], caption: str, build: Callable[[], Figure]) -> _Plot:
    plot = _Plot(caption, build)
    plots.append(plot)
    return plot


def _title(report: Report) -> str:
    names = ", ".join(dict.fromkeys(view.run.dataset_name for view in report.views))
    runs = ", ".join(str(view.run.id) for view in report.views)
    return f"Report on run{'s' if len(report.views) > 1 else ''} {runs} ({names}) · touchbench"


def comparison_context(comparison: Comparison) -> dict[str, Any]:
    """What the comparison section (``comparison.html.j2``) shows of a comparison."""
    ranks = comparison.ranks
    holm = {h.classifier: h for h in ranks.holm}
    rows = []
    for name, rank, mean in zip(
        ranks.classifiers, ranks.average_ranks, ranks.mean_scores, strict=True
    ):
        test = holm.get(name)
        rows.append(
            {
                "classifier": name,
                "average_rank": f"{rank:.3f}",
                "mean": float(mean),
                "holm": "control" if test is None else f"{test.adjusted_p_value:.4f}",
                "significant": bool(test and test.significant),
                "groups": "".join(
                    chr(ord("a") + g) for g, group in enumerate(ranks.groups) if name in group
                ),
            }
        )
    completed = comparison.completed
    return {
        "metric": comparison.metric,
        "blocks": list(ranks.blocks),
        "blocks_are": comparison.blocks_are,
        "rows": rows,
        "friedman": ranks.friedman,
        "cd": ranks.critical_difference,
        "q_alpha": ranks.q_alpha,
        "alpha": ranks.alpha,
        "control": ranks.control,
        "missing": [f"{m.classifier} on {m.block}" for m in completed.missing],
        "policy": completed.policy,
        "dropped": completed.dropped_classifiers + completed.dropped_blocks,
        "not_shared": comparison.not_shared,
        "notes": comparison.notes,
        "direction": "lower is better" if comparison.lower_is_better else "higher is better",
    }


def _run(report: Report, view: RunView, plots: list[_Plot]) -> dict[str, Any]:
    run, board = view.run, view.board
    columns = metric_columns(run, board)
    run_plots = [
        _plan(plots, f"{board.metric} of every fold", partial(figures.folds_figure, view)),
    ]
    ranked = report.fold_ranks.get(run.id)
    if isinstance(ranked, Comparison):
        run_plots.append(
            _plan(
                plots,
                "Critical-difference diagram over this run's folds (folds share training "
                "data: descriptive, not a test across data sets)",
                partial(figures.cd_figure, ranked),
            )
        )
    if view.per_target is not None:
        run_plots.append(_plan(plots, "Accuracy per target", partial(figures.targets_figure, view)))
    run_plots.append(_plan(plots, "Instances per class", partial(figures.classes_figure, view)))
    confusions = []
    for row in board.rows[: report.confusions]:
        if row.n_ok and row.classifier in run.classifiers:  # imported results have none
            confusions.append(
                _plan(
                    plots,
                    f"Confusion matrix of {row.classifier} (normalised per true class)",
                    partial(figures.confusion_figure, view, row.classifier),
                )
            )
    sure = _how_sure(view, [row.classifier for row in board.rows[: report.confusions]], plots)
    config = run.config.to_json()
    return {
        "id": run.id,
        "title": view.title,
        "kind": run.kind,
        "status": run.status,
        "created_at": run.created_at.strftime("%Y-%m-%d %H:%M"),
        "finished_at": run.finished_at.strftime("%Y-%m-%d %H:%M") if run.finished_at else "-",
        "config": {key: config[key] for key in sorted(config)},
        "n_classifiers": len(run.classifiers),
        "tasks": run.tasks_text(),
        "header": leaderboard_header(board, columns, view.besides),
        "rows": leaderboard_rows(board, columns, view.besides),
        "beside_notes": beside_notes(view.besides),
        "mark_column": 4 if view.besides else 3,
        "sure": sure,
        "answers": run_answer_tables(report.answers.get(run.id, RunAnswers())),
        "learning": _learning(report, run.id, plots),
        "metric": board.metric,
        "baseline": board.baseline,
        "alpha": board.alpha,
        "summary": board.summary,
        "plots": run_plots,
        "confusions": confusions,
        "fold_note": ranked if isinstance(ranked, str) else None,
        "tables": run_tables(view.report()),
        "notes": view.notes(),
    }


def _learning(report: Report, run_id: int, plots: list[_Plot]) -> dict[str, Any] | None:
    """The table and plot of the newest learning curve of the run's data set, or None."""
    curve = report.learning.get(run_id)
    if curve is None:
        return None
    return {
        "table": learning_table(curve),
        "plot": _plan(
            plots,
            "Score by share of each training fold",
            partial(figures.learning_figure, curve),
        ),
    }


def _how_sure(view: RunView, best: list[str], plots: list[_Plot]) -> dict[str, Any] | None:
    """Per-class tables of the best classifiers, every classifier's calibration and the
    reliability diagram; ``None`` for a run without classes or confusion matrices."""
    if view.run.kind == "regression" or is_imported(view.run):
        return None
    own_run = set(view.run.classifiers)  # not the classifiers of runs beside it
    own = [c for c in best if c in own_run and view.board.row(c).n_ok]
    everyone = [r.classifier for r in view.board.rows if r.n_ok and r.classifier in own_run]
    if not own:
        return None
    certainty = certainty_of(view, everyone)
    chosen = certainty.model_copy(
        update={"classifiers": [e for e in certainty.classifiers if e.classifier in own]}
    )
    diagram = []
    if any(e.calibration is not None for e in certainty.classifiers):
        diagram.append(
            _plan(
                plots,
                "Reliability of the best classifiers with probabilities: accuracy of the top "
                "label against its confidence, out of fold",
                partial(figures.reliability_figure, certainty, len(own)),
            )
        )
    return {
        "classes": class_tables(chosen),
        "calibration": calibration_table(certainty),
        "plots": diagram,
    }


def score(value: Any) -> str:
    """A score as the tables show it: 4 decimals, ``-`` when there is none."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if isinstance(value, float):
        return f"{value:.4f}"
    return str(value)
