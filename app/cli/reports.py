"""Commands for looking at results: compare (statistics across runs), plot, report."""

from __future__ import annotations

# Imports inside functions: start-up time. This module holds several commands and the
# one chosen loads only what it uses (the CLI imports the module when a command of it
# is chosen).
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from touchbench.app.cli.output import JsonOption, RescoreOption, info, print_json, table
from touchbench.app.cli.state import get_state

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from touchbench.app.services.compare import Comparison

# matplotlib, scipy and the statistics are imported by the commands that use them, so that
# `touchbench --help` starts at once.

MetricOption = Annotated[
    str | None,
    typer.Option(
        "--metric",
        help="Score to rank by (default: the leaderboard's, f1_weighted or hamming_score).",
    ),
]
AlphaOption = Annotated[
    float, typer.Option("--alpha", min=0.0, max=1.0, help="Significance level.")
]
MissingOption = Annotated[
    str,
    typer.Option(
        "--missing",
        metavar="drop-classifier|drop-block|worst",
        help=(
            "A classifier without a score on a data set (or fold): leave the classifier out, "
            "leave the data set out, or rank it last there. Missing cells are listed whatever "
            "the choice."
        ),
    ),
]
KINDS = ("cd", "folds", "confusion", "targets", "classes")


def register(app: typer.Typer) -> None:
    app.command("compare")(compare_command)
    app.command("plot")(plot_command)
    app.command("report")(report_command)


def compare_command(
    ctx: typer.Context,
    runs: Annotated[
        list[int],
        typer.Argument(metavar="RUN...", help="Run ids: one per data set (or one run: its folds)."),
    ],
    metric: MetricOption = None,
    alpha: AlphaOption = 0.05,
    missing: MissingOption = "drop-classifier",
    bayesian: Annotated[
        str | None,
        typer.Option(
            "--bayesian",
            metavar="A,B",
            help=(
                "Two classifiers for the Bayesian view: the correlated t-test on each run's "
                "folds and the Bayesian signed-rank test across runs."
            ),
        ),
    ] = None,
    rope: Annotated[
        float,
        typer.Option(
            "--rope", min=0.0, help="Region of practical equivalence, in the metric's units."
        ),
    ] = 0.01,
    plot: Annotated[
        Path | None,
        typer.Option("--plot", metavar="FILE.svg|png", help="Also draw the CD diagram here."),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Compare the classifiers that all the runs share, one score per data set (the run's
    mean): average ranks, Friedman's test (chi-square and Iman-Davenport F), the Nemenyi
    critical difference, Holm's test against the best, and the groups not significantly
    different (Demšar 2006). With one run, its folds are the blocks (descriptive only)."""
    from touchbench.app.reports.figures import cd_figure
    from touchbench.app.reports.plots import figure_format, save_figure
    from touchbench.app.services.compare import compare_runs
    from touchbench.benchmark.evaluation.score_table import missing_policy

    pair = _pair(bayesian) if bayesian else None
    if plot is not None:
        figure_format(plot)
    comparison = compare_runs(
        get_state(ctx).store,
        runs,
        metric=metric,
        alpha=alpha,
        missing=missing_policy(missing),
        pair=pair,
        rope=rope,
    )
    if plot is not None:
        save_figure(cd_figure(comparison), plot)
    if as_json:
        from touchbench.app.services.compare import comparison_schema

        print_json(comparison_schema(comparison).to_json())
    else:
        _print_comparison(comparison)
    if plot is not None:
        info(f"wrote {plot}")


def plot_command(
    ctx: typer.Context,
    run: Annotated[int, typer.Argument(metavar="RUN", help="Run id (see `touchbench runs`).")],
    output: Annotated[
        Path, typer.Option("--output", "-o", metavar="FILE.svg|png", help="Where to draw it.")
    ],
    kind: Annotated[
        str,
        typer.Option(
            "--kind",
            metavar="|".join(KINDS),
            help=(
                "cd: critical-difference diagram over the run's folds; folds: every fold's "
                "score per classifier; confusion: a classifier's confusion matrices (summed "
                "over folds, normalised per row); targets: per-target scores of a multi-target "
                "run; classes: instances per class of each target."
            ),
        ),
    ] = "cd",
    classifier: Annotated[
        str | None,
        typer.Option("--classifier", "-c", help="For --kind confusion (default: the best)."),
    ] = None,
    metric: MetricOption = None,
    alpha: AlphaOption = 0.05,
    missing: MissingOption = "drop-classifier",
    aggregate: RescoreOption = None,
) -> None:
    """Draw one plot of a run as SVG (text kept as text) or PNG."""
    from touchbench.app.reports.plots import figure_format, save_figure

    if kind not in KINDS:
        raise typer.BadParameter(f"'{kind}' is not one of {', '.join(KINDS)}", param_hint="--kind")
    if classifier is not None and kind != "confusion":
        raise typer.BadParameter(
            "--classifier goes with --kind confusion", param_hint="--classifier"
        )
    figure_format(output)
    figure = _run_figure(ctx, run, kind, classifier, metric, alpha, missing, aggregate)
    save_figure(figure, output)
    info(f"wrote {output}")


def report_command(
    ctx: typer.Context,
    runs: Annotated[list[int], typer.Argument(metavar="RUN...", help="Run ids.")],
    output: Annotated[
        Path, typer.Option("--output", "-o", metavar="FILE.html", help="The report to write.")
    ],
    metric: MetricOption = None,
    alpha: AlphaOption = 0.05,
    missing: MissingOption = "drop-classifier",
    confusions: Annotated[
        int,
        typer.Option(
            "--confusions", min=0, help="Confusion matrices for this many of each run's best."
        ),
    ] = 5,
    aggregate: RescoreOption = None,
) -> None:
    """Write one self-contained HTML file (inline SVG, no network) with each run's
    leaderboard and marks, plots, configuration and library versions, and the comparison
    across runs: ready to attach to a paper's supplementary material."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    from touchbench.app.reports.html import render_report
    from touchbench.app.reports.plots import write_atomically
    from touchbench.app.services.report import build_report
    from touchbench.benchmark.evaluation.score_table import missing_policy

    if output.suffix.lower() not in (".html", ".htm"):
        raise typer.BadParameter(f"'{output}' must end in .html", param_hint="--output")
    console = Console(stderr=True)
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        console=console,
        transient=True,
        disable=not console.is_terminal,
    ) as progress:
        gathering = progress.add_task("reading runs", total=len(runs))
        report = build_report(
            get_state(ctx).store,
            runs,
            metric=metric,
            alpha=alpha,
            missing=missing_policy(missing),
            confusions=confusions,
            aggregate=aggregate,
            on_run=lambda run: progress.advance(gathering),
        )
        drawing = progress.add_task("drawing plots", total=None)
        html = render_report(
            report,
            on_plan=lambda total: progress.update(drawing, total=total),
            on_figure=lambda: progress.advance(drawing),
        )
    write_atomically(output, html.encode("utf-8"))
    info(f"wrote {output} ({len(html) / 1024:.0f} KiB, {len(report.views)} run(s))")


def _run_figure(
    ctx: typer.Context,
    run_id: int,
    kind: str,
    classifier: str | None,
    metric: str | None,
    alpha: float,
    missing: str,
    aggregate: str | None,
) -> Figure:
    from touchbench.app.reports import figures
    from touchbench.app.services.compare import compare_runs
    from touchbench.app.services.report import run_view
    from touchbench.app.services.runs.rescore import check_aggregate
    from touchbench.benchmark.evaluation.score_table import missing_policy

    store = get_state(ctx).store
    if kind == "cd":
        comparison = compare_runs(
            store,
            [run_id],
            metric=metric,
            alpha=alpha,
            missing=missing_policy(missing),
            aggregate=check_aggregate(aggregate),
        )
        return figures.cd_figure(comparison)
    view = run_view(store, run_id, metric=metric, aggregate=aggregate)
    if kind == "folds":
        return figures.folds_figure(view)
    if kind == "confusion":
        return figures.confusion_figure(view, classifier)
    if kind == "targets":
        return figures.targets_figure(view)
    return figures.classes_figure(view)


def _pair(text: str) -> tuple[str, str]:
    names = [name.strip() for name in text.split(",") if name.strip()]
    if len(names) != 2:
        raise typer.BadParameter(
            f"give two classifiers as A,B, not '{text}'", param_hint="--bayesian"
        )
    return names[0], names[1]


def _print_comparison(comparison: Comparison) -> None:
    ranks = comparison.ranks
    holm = {h.classifier: h for h in ranks.holm}
    letters = {
        name: "".join(chr(ord("a") + g) for g, group in enumerate(ranks.groups) if name in group)
        for name in ranks.classifiers
    }
    blocks = "folds" if comparison.blocks_are == "folds" else "data sets"
    table(
        f"{len(ranks.classifiers)} classifiers over {ranks.n_blocks} {blocks}, "
        f"ranked by {comparison.metric}",
        ["#", "classifier", "avg rank", f"mean {comparison.metric}", "Holm p", "", "group"],
        [
            (
                i + 1,
                name,
                f"{rank:.3f}",
                float(mean) if math.isfinite(mean) else None,  # inf: ranked worst where missing
                "(control)" if name == ranks.control else f"{holm[name].adjusted_p_value:.4f}",
                "*" if name in holm and holm[name].significant else "",
                letters[name],
            )
            for i, (name, rank, mean) in enumerate(
                zip(ranks.classifiers, ranks.average_ranks, ranks.mean_scores, strict=True)
            )
        ],
    )
    f = ranks.friedman
    info(
        f"Friedman: chi2({f.df}) = {f.statistic:.3f}, p = {f.p_value:.4g}; Iman-Davenport "
        f"F({f.df}, {f.df_denominator}) = {f.iman_davenport:.3f}, "
        f"p = {f.iman_davenport_p_value:.4g}"
    )
    info(
        f"Nemenyi: CD = {ranks.critical_difference:.3f} (q = {ranks.q_alpha:.3f}, alpha "
        f"{ranks.alpha}); classifiers sharing a group letter are not significantly different"
    )
    info(
        f"Holm: each classifier against {ranks.control}; * significantly different at "
        f"alpha {ranks.alpha} (adjusted p shown)"
    )
    completed = comparison.completed
    if completed.missing:
        cells = ", ".join(f"{m.classifier} on {m.block}" for m in completed.missing)
        done = {
            "drop-classifier": f"left out: {', '.join(completed.dropped_classifiers)}",
            "drop-block": f"left out: {', '.join(completed.dropped_blocks)}",
            "worst": "ranked last where missing",
        }[completed.policy]
        info(f"missing scores ({completed.policy}): {cells}; {done}")
    if comparison.not_shared:
        info(f"not in every run (left out): {', '.join(comparison.not_shared)}")
    for note in comparison.notes:
        info(f"note: {note}")
    if comparison.pair is not None:
        _print_pair(comparison)


def _print_pair(comparison: Comparison) -> None:
    pair = comparison.pair
    assert pair is not None
    rows = [
        (scores.label, result.test, result.n, result.p_left, result.p_rope, result.p_right)
        for scores, result in pair.per_run
    ]
    if pair.across is not None:
        a = pair.across
        rows.append(("all runs", a.test, a.n, a.p_left, a.p_rope, a.p_right))
    rope = pair.across.rope if pair.across else (pair.per_run[0][1].rope if pair.per_run else 0)
    table(
        f"Bayesian comparison of {pair.a} and {pair.b} on {comparison.metric} (rope ±{rope})",
        ["block", "test", "n", f"P({pair.a} better)", "P(equivalent)", f"P({pair.b} better)"],
        rows,
    )
