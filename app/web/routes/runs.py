"""Fragments of runs: the list, a run's progress, its leaderboard (ranked by any metric,
marked against any baseline), its plots, one classifier's confusion matrix and folds, and
the form that starts a run.

A run may have thousands of classifiers (an imported results file): its fragments show the
first of them and a count, as data set pages do (:mod:`app.reports.bounds`), and its
plots draw the best of them with a note; the JSON API and the CLI give every one.  The work
is bounded too: the ranking is computed once per version of the run's results
(:func:`~app.services.runs.ranked_run`), and a plot reads the fold results of the
classifiers it draws only.
"""

from __future__ import annotations

# Imports inside functions: start-up time: matplotlib, the catalogue and the reports load
# when a fragment that draws or lists them is first asked for, not when the service starts.
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from typing import TYPE_CHECKING, Annotated, Any

from fastapi import APIRouter, Query
from fastapi.responses import HTMLResponse

from touchbench.app.errors import FieldError, NotFoundError
from touchbench.app.reports import bounds
from touchbench.app.reports.answer_tables import run_answer_tables
from touchbench.app.reports.run_tables import RunTable, run_tables
from touchbench.app.schemas.runs import Aggregate, BenchRequest
from touchbench.app.schemas.status import FINAL, RESUMABLE, Status
from touchbench.app.services.answers import run_answers
from touchbench.app.services.lifecycle import count_runs, get_run, list_runs, run_progress
from touchbench.app.services.listing import count_datasets, list_datasets
from touchbench.app.services.runs import NoResultsError, kept, ranked_run
from touchbench.app.store.database import Store
from touchbench.app.web.deps import StoreDep
from touchbench.app.web.listing import newest
from touchbench.app.web.rendering import Plot, draw, render, rendered
from touchbench.app.web.request_form import form_fields, grouped
from touchbench.app.web.routes.pages import Ref

# The plots and the statistics (matplotlib, scipy) load with the first fragment that needs
# them, so that the service starts at once.
if TYPE_CHECKING:
    from markupsafe import Markup

    from touchbench.app.services.report import RunView
    from touchbench.app.services.runs import RankedRun

router = APIRouter(prefix="/fragments/runs", include_in_schema=False)

#: Classifiers drawn in a run's reliability diagram (the table lists every one).
RELIABILITY_CURVES = 5

#: The run form's groups of :class:`BenchRequest`'s fields (a field not named here shows
#: in a last group of its own).
RUN_GROUPS = (
    (
        "basic",
        (
            "dataset", "target", "classifiers", "suite", "folds", "repeats", "seed", "metric",
            "baseline", "aggregate", "independent", "position", "weka",
        ),
    ),
    ("racing and budget", ("race", "race_alpha", "budget_total")),
    ("tuning, stacking and ensembles", ("tune", "budget", "stack", "ensemble")),
    ("limits", ("timeout", "max_memory_mb")),
)  # fmt: skip

Metric = Annotated[str | None, Query(max_length=100)]
Baseline = Annotated[str | None, Query(max_length=200)]
#: Score the leaderboard per window or per recording (``leaderboard --aggregate``).
AggregateQuery = Annotated[Aggregate | None, Query()]


@router.get("", response_class=HTMLResponse)
def runs(store: StoreDep) -> HTMLResponse:
    """Every run with its progress; polled while one is queued or running."""
    listed = newest(count_runs(store), partial(list_runs, store))
    return render(
        "fragments/runs.html.j2",
        runs=listed,
        active=any(run.status not in FINAL for run in listed.items),
    )


@router.get("/form", response_class=HTMLResponse)
def run_form(
    store: StoreDep, dataset: Annotated[str | None, Query(max_length=200)] = None
) -> HTMLResponse:
    """The form that starts a run: every field of :class:`BenchRequest` in its groups, with
    the data sets and their targets, and the classifier ids and metrics to pick from."""
    from touchbench.benchmark.catalogue import CATALOGUE
    from touchbench.benchmark.evaluation.metrics import MULTICLASS_METRICS, REGRESSION_METRICS
    from touchbench.benchmark.multitarget import multitarget_configurations

    return render(
        "fragments/run_form.html.j2",
        datasets=newest(count_datasets(store), partial(list_datasets, store)),
        chosen=dataset,
        groups=grouped(form_fields(BenchRequest), RUN_GROUPS),
        catalogue=[(spec.id, spec.description) for spec in CATALOGUE.values()],
        multitarget=multitarget_configurations(),
        metrics=[*MULTICLASS_METRICS, *REGRESSION_METRICS],
    )


@router.get("/{run_id}/progress", response_class=HTMLResponse)
def progress(
    run_id: int,
    store: StoreDep,
    metric: Metric = None,
    baseline: Baseline = None,
    aggregate: AggregateQuery = None,
) -> HTMLResponse:
    """Status and tasks done; polled every second until the run is over.  ``metric``,
    ``baseline`` and ``aggregate``: the leaderboard's CSV ranked and scored so, as the
    page's leaderboard is."""
    run = run_progress(store, run_id)
    return render(
        "fragments/progress.html.j2",
        run=run,
        final=run.status in FINAL,
        resumable=run.status in RESUMABLE,
        done=run.status == Status.DONE,
        download={"format": "csv", "metric": metric, "baseline": baseline, "aggregate": aggregate},
    )


@router.get("/{run_id}/leaderboard", response_class=HTMLResponse)
def leaderboard(
    run_id: int,
    store: StoreDep,
    metric: Metric = None,
    baseline: Baseline = None,
    beside: Annotated[list[int] | None, Query(max_length=20)] = None,
    aggregate: AggregateQuery = None,
) -> HTMLResponse:
    """The run's classifiers ranked by ``metric`` with WEKA's marks against ``baseline``;
    ``beside``: other runs' classifiers too (a paper's imported results), t-tested where
    the folds pair and by their means where they do not; ``aggregate``: scored per window
    or per recording from the run's stored test-fold predictions."""
    metric, baseline, besides = metric or None, baseline or None, tuple(beside or ())

    def made() -> tuple[Markup, bool]:
        ranked, refused = _ranked(
            store, run_id, metric=metric, baseline=baseline, beside=besides, aggregate=aggregate
        )
        table = _table(
            ranked, chosen_baseline=baseline, chosen_aggregate=None if refused else aggregate
        )
        ranking = rendered(
            "fragments/ranking.html.j2",
            run=ranked.run,
            board=ranked.board,
            table=table,
            tables=[_first_rows(part) for part in run_tables(ranked.report)],
            notes=ranked.notes(),
            refused=refused,
        )
        return ranking, ranked.board.baseline is not None

    # rendered once per version of the results, as the ranking is: a client asking for the
    # page back to back costs a light query a run, not the table again
    asked = ("leaderboard", metric, baseline, besides, aggregate)
    try:
        ranking, succeeded = kept(store, [run_id, *besides], asked, made)
    except NoResultsError as missing:
        ranking = rendered("fragments/ranking.html.j2", run=missing.run, board=None)
        succeeded = False
    # the answers (ablation, importance) change apart from the results
    answers = run_answer_tables(run_answers(store, run_id)) if succeeded else []
    return render("fragments/leaderboard.html.j2", ranking=ranking, answers=answers)


def _ranked(
    store: Store, run_id: int, *, aggregate: Aggregate | None, **asked: Any
) -> tuple[RankedRun, str | None]:
    """The run ranked as asked (:func:`~app.services.runs.ranked_run`) and ``None``; or,
    when it cannot be scored per ``aggregate`` (a recording of several labels, a run that
    kept no predictions), ranked as the run scored and why not."""
    try:
        return ranked_run(store, run_id, aggregate=aggregate, **asked), None
    except FieldError as error:
        if aggregate is None:
            raise
        return ranked_run(store, run_id, **asked), f"not scored per {aggregate}: {error.message}"


@router.get("/{run_id}/plots", response_class=HTMLResponse)
def plots(
    run_id: int, store: StoreDep, metric: Metric = None, aggregate: AggregateQuery = None
) -> HTMLResponse:
    """Every fold's score, per-target scores and class counts, scored as the leaderboard."""
    from touchbench.app.reports import figures

    def drawn() -> list[Plot]:
        view = _drawn_view(store, run_id, metric=metric or None, aggregate=aggregate)
        plots = [draw(f"{view.metric} of every fold", partial(figures.folds_figure, view))]
        if view.per_target is not None:
            plots.append(draw("Accuracy per target", partial(figures.targets_figure, view)))
        plots.append(draw("Instances per class", partial(figures.classes_figure, view)))
        return plots

    # drawn once per version of the run's results, as its ranking is
    try:
        plots = kept(store, [run_id], ("plots", metric or None, aggregate), drawn)
    except NoResultsError:
        plots = []
    return render("fragments/plots.html.j2", plots=plots)


@router.get("/{run_id}/calibration", response_class=HTMLResponse)
def calibration(run_id: int, store: StoreDep, aggregate: AggregateQuery = None) -> HTMLResponse:
    """The calibration of the classifiers the plots draw (a table) and their reliability
    diagram, per window or per recording as the leaderboard; why there is none for a
    regression or an imported run (no predictions kept)."""

    def made() -> dict[str, Any]:
        return _calibration(_drawn_view(store, run_id, metric=None, aggregate=aggregate))

    # computed once per version of the run's results, as its ranking is
    try:
        sure = kept(store, [run_id], ("calibration", aggregate), made)
    except NoResultsError:
        sure = None
    return render("fragments/calibration.html.j2", sure=sure)


def _drawn_view(
    store: Store, run_id: int, *, metric: str | None, aggregate: Aggregate | None
) -> RunView:
    """The run ranked as the leaderboard (:func:`_ranked`) with the fold results of the
    best classifiers a figure draws (:data:`~app.reports.bounds.DRAWN`), scored as ranked."""
    from touchbench.app.services.report import page_view

    ranked, _ = _ranked(store, run_id, metric=metric, aggregate=aggregate)
    own = set(ranked.run.classifiers)
    best = [row.classifier for row in ranked.board.rows if row.classifier in own]
    return page_view(store, ranked, best[: bounds.DRAWN])


def _calibration(view: RunView) -> dict[str, Any]:
    """The calibration table and diagram of a run read, or why it has none."""
    from touchbench.app.reports import figures
    from touchbench.app.reports.certainty_tables import calibration_table
    from touchbench.app.services.certainty import certainty_of
    from touchbench.benchmark.errors import BenchmarkError

    try:
        certainty = certainty_of(view)
    except BenchmarkError as why:
        return {"table": None, "diagram": None, "why": str(why)}
    return {
        "table": _first_rows(calibration_table(certainty)),
        "diagram": draw(
            "Reliability: accuracy of the top label against its confidence, out of fold",
            partial(figures.reliability_figure, certainty, RELIABILITY_CURVES),
        ),
        "why": None,
    }


@router.get("/{run_id}/answers", response_class=HTMLResponse)
def answers(run_id: int, store: StoreDep) -> HTMLResponse:
    """The forms that start a run's answers as jobs (an ablation, a classifier's permutation
    importance, learning curves on its data set), each field from its request type."""
    from touchbench.app.schemas.ablation import AblationRequest
    from touchbench.app.schemas.importance import ImportanceRequest
    from touchbench.app.schemas.learning import LearningCurveRequest

    run = get_run(store, run_id).schema()
    fixed = {"run", "dataset"}
    forms = {
        kind: [f for name, f in form_fields(request).items() if name not in fixed]
        for kind, request in (
            ("ablation", AblationRequest),
            ("importance", ImportanceRequest),
            ("learning-curve", LearningCurveRequest),
        )
    }
    return render(
        "fragments/answers.html.j2",
        run=run,
        done=run.status == Status.DONE,
        forms=forms,
    )


@router.get("/{run_id}/classifiers/{classifier}", response_class=HTMLResponse)
def classifier(
    run_id: int,
    classifier: Ref,
    store: StoreDep,
    metric: Metric = None,
    baseline: Baseline = None,
    aggregate: AggregateQuery = None,
) -> HTMLResponse:
    """A classifier's confusion matrix, its scores and its folds beside the baseline's,
    scored as the leaderboard."""
    from touchbench.app.reports import figures
    from touchbench.app.reports.leaderboard import mean_std
    from touchbench.app.services.report import page_view

    ranked, _ = _ranked(
        store, run_id, metric=metric or None, baseline=baseline or None, aggregate=aggregate
    )
    if classifier not in ranked.run.classifiers:
        raise NotFoundError(
            f"run {ranked.run.id} has no classifier '{classifier}' "
            f"(classifiers: {bounds.names(ranked.run.classifiers)})"
        )
    reference = ranked.board.baseline or classifier
    shown = list(dict.fromkeys([classifier, reference]))
    view = page_view(store, ranked, shown)
    row = view.board.row(classifier)
    return render(
        "fragments/classifier.html.j2",
        view=view,
        row=row,
        scores=[(name, mean_std(value)) for name, value in sorted(row.metrics.items())],
        confusion=draw(
            f"Confusion matrix of {classifier} (normalised per true class)",
            partial(figures.confusion_figure, view, classifier),
        ),
        folds=_folds(view, shown),
        reference=reference,
        sure=_how_sure(view, classifier),
    )


def _how_sure(view: RunView, classifier: str) -> dict[str, Any] | None:
    """The classifier's per-class tables and its calibration (none for a regression or an
    imported run)."""
    from touchbench.app.reports import figures
    from touchbench.app.reports.certainty_tables import calibrations, class_tables
    from touchbench.app.services.certainty import certainty_of
    from touchbench.app.services.imported import is_imported

    # an imported results file keeps no confusion matrices or probabilities
    if view.run.kind == "regression" or is_imported(view.run):
        return None
    if not view.board.row(classifier).n_ok:
        return None
    certainty = certainty_of(view, [classifier])
    [entry] = certainty.classifiers
    # (target or None, calibration) of each target that has one: one for a multi-class run
    kept = [(target, found) for _, target, found in calibrations(certainty) if found]
    diagram = None
    if kept:
        diagram = draw(
            f"Reliability of {classifier}: accuracy of the top label against its "
            "confidence, out of fold",
            partial(figures.reliability_figure, certainty),
        )
    return {
        "tables": class_tables(certainty),
        "entry": entry,
        "calibrations": kept,
        "diagram": diagram,
    }


def _folds(view: RunView, shown: list[str]) -> dict[str, Any]:
    """Per-fold scores of ``shown`` as a table and a strip plot."""
    from touchbench.app.reports import figures

    table = view.fold_scores()
    return {
        "names": shown,
        "rows": [
            (block, [table.column(name)[i] for name in shown])
            for i, block in enumerate(table.blocks)
        ],
        "plot": draw(f"{view.metric} of every fold", partial(figures.folds_figure, view, shown)),
    }


def _table(
    ranked: RankedRun, *, chosen_baseline: str | None, chosen_aggregate: str | None
) -> dict[str, Any]:
    """The leaderboard's header (metric columns sortable), rows, and the pickers' options;
    with runs beside it, where each row comes from and how it is compared."""
    from touchbench.app.reports.leaderboard import (
        beside_notes,
        leaderboard_header,
        leaderboard_rows,
        metric_columns,
    )
    from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER

    run, board, besides = ranked.run, ranked.board, ranked.besides
    columns = metric_columns(run, board)
    metrics = sorted({name for row in board.rows for name in row.metrics})
    # the rows shown only are formatted (a run may have thousands)
    shown = _first_and_baseline(board.rows, board.baseline, at="classifier")
    rows = bounds.Shown(leaderboard_rows(board, columns, besides, rows=shown.items), shown.more)
    baselines = [row.classifier for row in board.rows if row.n_ok]
    return {
        "header": leaderboard_header(board, columns, besides),
        "columns": columns,
        "rows": rows.items,
        "more": rows.more,
        "mark_column": 4 if besides else 3,
        "beside_notes": beside_notes(besides),
        "beside": [b.run.id for b in besides],
        "metrics": metrics,
        # the picker offers the classifiers shown (and the one chosen, wherever it ranks)
        "baselines": _first_and_baseline(baselines, chosen_baseline, at=None).items,
        "dropped": [row.classifier for row in board.rows if row.dropped is not None],
        "chosen_baseline": chosen_baseline,
        # per window or per recording: offered where the run can be scored either way
        "aggregates": ranked.aggregates,
        "aggregate": ranked.report.aggregate,
        "chosen_aggregate": chosen_aggregate,
        "direction": "lower is better" if board.metric in LOWER_IS_BETTER else "higher is better",
    }


def _first_and_baseline(
    rows: list[Any], baseline: str | None, *, at: int | str | None = 1
) -> bounds.Shown[Any]:
    """The first :data:`~app.reports.bounds.CLASSIFIERS` of ``rows`` (classifiers, table
    rows naming one in cell ``at``, or leaderboard rows naming one in attribute ``at``),
    and the baseline's after them when it ranks lower: the row every mark is against
    stays on the page."""
    shown = bounds.first(rows, bounds.CLASSIFIERS)
    named: Callable[[Any], Any]
    if at is None:
        named = lambda row: row  # noqa: E731
    elif isinstance(at, str):
        named = lambda row: getattr(row, at)  # noqa: E731
    else:
        named = lambda row: row[at]  # noqa: E731
    if baseline is not None and shown.more and all(named(r) != baseline for r in shown.items):
        extra = [row for row in rows[bounds.CLASSIFIERS :] if named(row) == baseline]
        return bounds.Shown(shown.items + extra, shown.more - len(extra))
    return shown


def _first_rows(table: RunTable) -> RunTable:
    """``table`` with its first :data:`~app.reports.bounds.CLASSIFIERS` rows, its title
    saying how many there are."""
    shown = bounds.first(table.rows, bounds.CLASSIFIERS)
    if not shown.more:
        return table
    title = f"{table.title}; {bounds.of_all(shown, 'rows')}"
    return replace(table, title=title, rows=shown.items)
