"""Commands that answer questions after the leaderboard: the paper's published results
imported beside ours (``import-results``); where and how sure the classifiers are
(``classes``: per-class scores, confusion matrices and calibration; ``calibration``: the
expected calibration error and the reliability diagram); which features (``importance``)
and how many touches (``learning-curve``)."""

from __future__ import annotations

# Imports inside functions: start-up time. Each command loads only what it uses (the
# store, NumPy, matplotlib), when it is chosen.
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from touchbench.app.cli.output import (
    JsonOption,
    RescoreOption,
    info,
    print_json,
    run_table,
    table,
)
from touchbench.app.cli.state import get_state
from touchbench.app.schemas.runs import DEFAULT_TIMEOUT

if TYPE_CHECKING:
    from touchbench.app.schemas.certainty import RunCertainty


def register(app: typer.Typer) -> None:
    app.command("import-results")(import_results_command)
    app.command("classes")(classes_command)
    app.command("calibration")(calibration_command)
    app.command("importance")(importance_command)
    app.command("learning-curve")(learning_curve_command)


RunArgument = Annotated[
    int, typer.Argument(metavar="RUN", help="Run id (see `touchbench runs`).", min=1)
]
ClassifiersOption = Annotated[
    str | None,
    typer.Option(
        "--classifier",
        "-c",
        metavar="ID[,ID...]",
        help="These classifiers (default: every one with a successful fold, best first).",
    ),
]


def classes_command(
    ctx: typer.Context,
    run: RunArgument,
    classifier: ClassifiersOption = None,
    aggregate: RescoreOption = None,
    as_json: JsonOption = False,
) -> None:
    """Show per-class precision, recall and F1, the confusion matrix (summed over folds)
    and the expected calibration error of a run's classifiers, per target."""
    from touchbench.app.reports.certainty_tables import calibrations, class_tables, score

    certainty = _certainty(ctx, run, classifier, aggregate)
    if as_json:
        print_json(certainty.to_json())
        return
    for shown in class_tables(certainty):
        run_table(shown)
    for entry, target, calibration in calibrations(certainty):
        name = entry.classifier if target is None else f"{entry.classifier} on {target}"
        if calibration is not None:
            info(
                f"{name}: expected calibration error {score(calibration.ece)} "
                f"over {calibration.n_instances} out-of-fold predictions"
            )
        else:
            info(f"{name}: no calibration ({entry.calibration_note})")
    info("rows: true class; the columns after support: predicted class (counts)")


def calibration_command(
    ctx: typer.Context,
    run: RunArgument,
    classifier: ClassifiersOption = None,
    output: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", metavar="FILE.svg|png", help="Draw the reliability diagram here."
        ),
    ] = None,
    top: Annotated[
        int, typer.Option("--top", min=1, help="Classifiers in the diagram (the best first).")
    ] = 5,
    aggregate: RescoreOption = None,
    as_json: JsonOption = False,
) -> None:
    """Show the expected calibration error of a run's classifiers from their out-of-fold
    probabilities, and draw their reliability diagram."""
    from touchbench.app.reports.plots import figure_format, save_figure

    if output is not None:
        figure_format(output)
    certainty = _certainty(ctx, run, classifier, aggregate)
    if output is not None:
        from touchbench.app.reports.figures import reliability_figure

        save_figure(reliability_figure(certainty, top), output)
    if as_json:
        print_json(certainty.to_json())
    else:
        from touchbench.app.reports.certainty_tables import calibration_table

        run_table(calibration_table(certainty))
    if output is not None:
        info(f"wrote {output}")


def _certainty(
    ctx: typer.Context, run: int, classifiers: str | None, aggregate: str | None
) -> RunCertainty:
    from touchbench.app.services.certainty import run_certainty

    names = [c.strip() for c in classifiers.split(",") if c.strip()] if classifiers else None
    return run_certainty(get_state(ctx).store, run, classifiers=names, aggregate=aggregate)


def import_results_command(
    ctx: typer.Context,
    file: Annotated[
        Path,
        typer.Argument(metavar="FILE", help="WEKA Experimenter results ARFF.", show_default=False),
    ],
    name: Annotated[
        str | None,
        typer.Option("--name", metavar="NAME", help="The run's name (default: WEKA FILE)."),
    ] = None,
    dataset: Annotated[
        str | None,
        typer.Option(
            "--dataset",
            metavar="DATASET",
            help=(
                "The stored data set the results are of (default: the one whose relation "
                "the file's Key_Dataset names)."
            ),
        ),
    ] = None,
    target: Annotated[
        str | None,
        typer.Option(
            "--target",
            metavar="NAME",
            help=(
                "The target the schemes predicted (default: the data set's only target, or "
                "the one WEKA's Remove filter in Key_Dataset left)."
            ),
        ),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Import a WEKA Experimenter results file (InstanceResultListener ARFF) as a finished
    run, so that leaderboards and reports rank the paper's classifiers beside ours."""
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.imported import ImportResultsRequest
    from touchbench.app.services.imported import import_results

    request = build_request(
        ImportResultsRequest,
        {"file": "FILE"},
        file=file,
        name=name,
        dataset=dataset,
        target=target,
    )
    run = import_results(get_state(ctx).store, request)
    if as_json:
        print_json(run.to_json())
        return
    config = run.config
    table(
        f"run {run.id}: {config.name} on {run.dataset_name} "
        f"({', '.join(run.targets)}), {config.folds} folds x "
        f"{config.repeats} runs, {run.n_results} results",
        ["classifier", "WEKA scheme", "options"],
        [(s.classifier, s.scheme, s.options) for s in config.schemes],
    )
    info(
        f"`touchbench leaderboard RUN --beside {run.id}` ranks these beside a run of yours "
        f"on {run.dataset_name}"
    )


def importance_command(
    ctx: typer.Context,
    run: RunArgument,
    classifier: Annotated[
        str,
        typer.Option("--classifier", "-c", metavar="ID", help="One of the run's classifiers."),
    ],
    repeats: Annotated[
        int | None,
        typer.Option("--repeats", metavar="N", help="Shuffles per feature and fold (3)."),
    ] = None,
    top: Annotated[
        int, typer.Option("--top", min=1, help="Features listed (the most important).")
    ] = 20,
    as_json: JsonOption = False,
) -> None:
    """Permutation importance of a run's classifier on each of its outer test folds, per
    feature and per group of features (channel, feature family), with the t-test of each
    group's drop. Kept as a job: the run's web page and report show it."""
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.importance import ImportanceRequest, ImportanceResult
    from touchbench.app.services.jobs import carry_out_here

    request = build_request(
        ImportanceRequest,
        {"run": "RUN", "classifier": "--classifier"},
        run=run,
        classifier=classifier,
        repeats=repeats,
    )

    def progress(partial: object) -> None:
        if not as_json and isinstance(partial, ImportanceResult):
            info(f"fold {partial.done} of {partial.total} done")

    # kept as a job, so that the run's web page and report show it
    _, kept = carry_out_here(get_state(ctx).store, request, on_progress=progress)
    found = ImportanceResult.model_validate(kept)
    if as_json:
        print_json(found.to_json())
        return
    from touchbench.app.reports.answer_tables import importance_tables

    for shown in importance_tables(found, top):
        run_table(shown)


def learning_curve_command(
    ctx: typer.Context,
    dataset: Annotated[
        str, typer.Argument(metavar="DATA", help="Data set name or id.", show_default=False)
    ],
    classifiers: Annotated[
        str,
        typer.Option(
            "--classifiers", "-c", metavar="ID,ID,...", help="Classifier ids (a curve each)."
        ),
    ],
    target: Annotated[
        str | None, typer.Option("--target", metavar="NAME", help="This one target.")
    ] = None,
    fractions: Annotated[
        str | None,
        typer.Option(
            "--fractions",
            metavar="F,F,...",
            help="Shares of each training fold (default 0.1,0.2,0.3,0.5,0.7,1).",
        ),
    ] = None,
    folds: Annotated[int | None, typer.Option("--folds", metavar="K", help="k (5).")] = None,
    seed: Annotated[int | None, typer.Option("--seed", metavar="N", help="Seed (0).")] = None,
    timeout: Annotated[
        float | None,
        typer.Option(
            "--timeout", metavar="SECONDS", help=f"Per task ({DEFAULT_TIMEOUT:g}; 0: no limit)."
        ),
    ] = None,
    metric: Annotated[
        str | None, typer.Option("--metric", metavar="NAME", help="Score (as a run's).")
    ] = None,
    jobs: Annotated[int, typer.Option("--jobs", "-j", min=1, help="Local worker processes.")] = 1,
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o", metavar="FILE.svg|png", help="Draw the curves here."),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Cross-validate classifiers on growing shares of each training fold (stratified,
    group-aware; the test folds stay whole): the share at which each comes within a point
    of its full score answers "do I need to record more?". Kept as a job with its progress."""
    from touchbench.app.cli.progress import TenthsProgress
    from touchbench.app.cli.requests import build_request
    from touchbench.app.reports.plots import figure_format, save_figure
    from touchbench.app.schemas.learning import LearningCurveRequest, LearningCurveResult
    from touchbench.app.services.jobs import carry_out_here

    if output is not None:
        figure_format(output)
    request = build_request(
        LearningCurveRequest,
        {"dataset": "DATA", "fractions": "--fractions", "classifiers": "--classifiers"},
        dataset=dataset,
        classifiers=_items(classifiers),
        target=target,
        fractions=_items(fractions),
        folds=folds,
        seed=seed,
        timeout=timeout,
        metric=metric,
    )
    progress = TenthsProgress("learning curve", quiet=as_json)
    job_id, found = carry_out_here(get_state(ctx).store, request, jobs=jobs, on_progress=progress)
    result = LearningCurveResult.model_validate(found)
    if output is not None:
        from touchbench.app.reports.figures import learning_figure

        save_figure(learning_figure(result), output)
    if as_json:
        print_json(result.to_json())
        return
    from touchbench.app.reports.answer_tables import learning_table

    run_table(learning_table(result))
    info(f"kept as job {job_id}" + (f"; wrote {output}" if output is not None else ""))


def _items(text: str | None) -> list[str] | None:
    """``a,b`` as ``["a", "b"]`` (``None`` stays ``None``, so the request's default holds)."""
    if text is None:
        return None
    return [item.strip() for item in text.split(",") if item.strip()]
