"""Commands for benchmarking: classifiers, bench, runs, leaderboard."""

from __future__ import annotations

# Imports inside functions: start-up time. This module holds several commands and the
# one chosen loads only what it uses (the CLI imports the module when a command of it
# is chosen).
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Annotated, Any

import typer
from typer.models import ArgumentInfo, OptionInfo
from typer.utils import get_params_from_function

from touchbench.app.cli.output import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    ExitWith,
    JsonOption,
    RescoreOption,
    info,
    print_json,
    run_table,
    table,
)
from touchbench.app.cli.state import get_state
from touchbench.app.schemas.runs import BenchHereRequest, BenchRequest
from touchbench.app.schemas.status import Status

if TYPE_CHECKING:
    from touchbench.app.schemas.ablation import AblationResult
    from touchbench.app.schemas.runs import LeaderboardSchema
    from touchbench.app.services.runs import IndependentResult, RunLeaderboard
    from touchbench.app.store.database import Store

# scikit-learn, the engine and Dask are imported by the commands that use them, so that
# this module's other commands (runs, leaderboard, cancel) start without them.

FORMATS = ("table", "json", "csv", "markdown", "arff")


def _default(field: str) -> Any:
    """A run option's default, as the request type says it (shown in ``--help``)."""
    return BenchRequest.model_fields[field].default


def _memory_default() -> str:
    """The default memory cap of a task on this machine, for ``--help``."""
    from touchbench.benchmark.run.memory import MB, default_task_memory

    caps = [default_task_memory(jobs) for jobs in (1, 2)]
    if caps[0] is None or caps[1] is None:
        return "none where the machine's memory cannot be read"
    return f"here {caps[0].bytes / MB:,.0f} MB at --jobs 1, {caps[1].bytes / MB:,.0f} MB at 2"


def register(app: typer.Typer) -> None:
    app.command("classifiers")(classifiers_command)
    app.command("bench")(bench_command)
    app.command("runs")(runs_command)
    app.command("leaderboard")(leaderboard_command)
    app.command("cancel")(cancel_command)


def classifiers_command(
    ctx: typer.Context,
    as_json: JsonOption = False,
    suite_name: Annotated[
        str | None, typer.Option("--suite", help="Only this suite: fast, default or all.")
    ] = None,
    multi_target: Annotated[
        bool,
        typer.Option(
            "--multi-target", help="List the multi-target configurations (META:BASE) instead."
        ),
    ] = False,
    regressors: Annotated[
        bool,
        typer.Option(
            "--regressors",
            help="List what the ids mean on numeric targets (regression) instead.",
        ),
    ] = False,
    dataset: Annotated[
        str | None,
        typer.Option(
            "--dataset",
            metavar="NAME",
            help="Say each entry's cost on this stored data set's shape (instances, "
            "features, classes) rather than the catalogue's hint at its reference shape.",
        ),
    ] = None,
) -> None:
    """List the classifier catalogue (id, WEKA name, family, capabilities).

    Classifiers marked 'sequence' read a sequence data set's windows (extract with -e
    sequence, or -e mfcc -O frames=N) and refuse flat data sets. On numeric targets the
    same ids name regressors (--regressors lists them).
    """
    from rich.markup import escape

    from touchbench.benchmark.catalogue import CATALOGUE, get_spec, suite
    from touchbench.benchmark.export.onnx import exports_onnx
    from touchbench.benchmark.extras import extras_of

    if multi_target and regressors:
        raise typer.BadParameter("give --multi-target or --regressors, not both")
    if multi_target:
        _print_multitarget(suite_name, as_json)
        return
    if regressors:
        from touchbench.benchmark.catalogue.regressors import REGRESSORS, regression_suite

        ids = (
            regression_suite(suite_name, n_targets=1, n_instances=0, sequences=True)
            if suite_name
            else list(REGRESSORS)
        )
        specs = [REGRESSORS[i] for i in ids]
    else:
        ids = suite(suite_name) if suite_name else list(CATALOGUE)
        specs = [get_spec(i) for i in ids]
    costs, cost_note = _costs(ctx, specs, dataset)
    if as_json:
        print_json(
            {
                "classifiers": [
                    {
                        "id": s.id,
                        "weka_name": s.weka_name,
                        "family": s.family,
                        "description": s.description,
                        "probabilities": s.probabilities,
                        "needs_scaling": s.needs_scaling,
                        "handles_missing": s.handles_missing,
                        "handles_nominal": s.handles_nominal,
                        "sequence": s.needs_sequence,
                        "cost": costs[s.id],
                        "suites": sorted(s.suites),
                        "limits": s.limits,
                        "search_space": s.to_json()["search_space"],
                        "onnx": exports_onnx(s),
                        "extras": [extra.name for extra in extras_of(s.requires)],
                        "installed": s.installed,
                        "members": [member.id for member in s.members],
                    }
                    for s in specs
                ],
                "cost": cost_note,
            }
        )
        return
    yes = "✓"
    table(
        f"{len(specs)} {'regressors' if regressors else 'classifiers'} (cost: {cost_note})",
        [
            "id",
            "WEKA",
            "family",
            "proba",
            "scaled",
            "missing",
            "nominal",
            "sequence",
            "onnx",
            "cost",
            "suites",
            "extra",
        ],
        [
            (
                s.id,
                s.weka_name or "",
                s.family,
                yes if s.probabilities else "",
                yes if s.needs_scaling else "",
                yes if s.handles_missing else "",
                yes if s.handles_nominal else "",
                yes if s.needs_sequence else "",
                yes if exports_onnx(s) else "",
                costs[s.id],
                ",".join(sorted(s.suites)),
                ("" if s.installed else "✗") + ",".join(e.name for e in extras_of(s.requires)),
            )
            for s in specs
        ],
        whole=("extra",),
    )
    for s in specs:
        if s.members:  # an ensemble: what it is made of, and how a run comes by its folds
            how = "in a multi-class run: from its members' fold predictions"
            info(escape(f"{s.id}: {s.description} ({how})"))
    absent = list(dict.fromkeys(e for s in specs if not s.installed for e in extras_of(s.requires)))
    for extra in absent:
        info(escape(f"entries whose extra is marked ✗ are not installed: {extra.install}"))


def _costs(
    ctx: typer.Context, specs: Sequence[Any], dataset: str | None
) -> tuple[dict[str, str], str]:
    """Each entry's cost label and what the labels mean: the catalogue's hint at its
    reference shape, or (with a data set) the shape-aware estimate the engine orders a
    race and predicts a budget by."""
    from touchbench.benchmark.catalogue.costs import (
        REFERENCE_CLASSES,
        REFERENCE_FEATURES,
        REFERENCE_INSTANCES,
        Shape,
        cost_label,
    )

    if dataset is None:
        return {s.id: s.cost for s in specs}, (
            f"the catalogue's hint at {REFERENCE_INSTANCES:,} instances x "
            f"{REFERENCE_FEATURES} features x {REFERENCE_CLASSES} classes; --dataset "
            "NAME scales it to a data set"
        )
    from touchbench.app.services.datasets import dataset_schema

    info, schema = dataset_schema(get_state(ctx).store, dataset)
    classes = max((len(t.values) for t in schema.targets), default=1)
    shape = Shape(info.n_instances, info.n_features, max(classes, 1))
    note = (
        f"estimated for {info.name}: {info.n_instances:,} instances x "
        f"{info.n_features:,} features x {classes} classes"
    )
    return {s.id: cost_label(s, shape) for s in specs}, note


def _print_multitarget(suite_name: str | None, as_json: bool) -> None:
    from touchbench.benchmark.catalogue import get_spec
    from touchbench.benchmark.export.multitarget import exports_multitarget
    from touchbench.benchmark.export.onnx import exports_onnx
    from touchbench.benchmark.multitarget import (
        META_METHODS,
        multitarget_configurations,
        parse_config,
    )
    from touchbench.benchmark.multitarget.suites import multitarget_suite

    ids = (
        multitarget_suite(suite_name)
        if suite_name
        else multitarget_configurations(include_multilabel=True)
    )
    entries = []
    for config in ids:
        meta, base = parse_config(config)
        spec = META_METHODS[meta]
        entries.append(
            {
                "id": config,
                "meta": meta,
                "base": base or None,
                "method": spec.name,
                "follows": spec.follows,
                "binary_only": spec.binary_only,
                "onnx": exports_multitarget(meta, bool(base) and exports_onnx(get_spec(base))),
            }
        )
    if as_json:
        print_json({"classifiers": entries})
        return
    table(
        f"{len(entries)} multi-target configurations",
        ["id", "method", "base", "follows", "targets", "onnx"],
        [
            (
                e["id"],
                e["method"],
                e["base"] or "",
                e["follows"],
                "binary only" if e["binary_only"] else "any",
                "✓" if e["onnx"] else "",
            )
            for e in entries
        ],
    )


def bench_command(
    ctx: typer.Context,
    dataset: Annotated[
        str | None,
        typer.Argument(metavar="DATASET", help="Data set name or id.", show_default=False),
    ] = None,
    target: Annotated[
        str | None,
        typer.Option(
            "--target",
            metavar="NAME",
            help="Benchmark this one target (multi-class catalogue; regressors if numeric).",
        ),
    ] = None,
    classifiers: Annotated[
        str | None,
        typer.Option("--classifiers", "-c", metavar="ID,ID,...", help="Classifier ids to run."),
    ] = None,
    suite: Annotated[
        str | None,
        typer.Option("--suite", metavar="NAME", help="fast, default or all (default: default)."),
    ] = None,
    folds: Annotated[
        str | None,
        typer.Option(
            "--folds",
            "-k",
            metavar="K|logo",
            help=f"Folds per repeat (2-100; default {_default('folds')}), or logo "
            "(alias leave-one-group-out): one fold per group of the data set (its import's "
            "--groups column, or its recordings), with --repeats 1.",
            show_default=False,
        ),
    ] = None,
    repeats: Annotated[
        int | None,
        typer.Option(
            "--repeats",
            "-r",
            metavar="R",
            help=f"Repeats of k-fold (1-100; default {_default('repeats')}).",
            show_default=False,
        ),
    ] = None,
    seed: Annotated[
        int | None,
        typer.Option(
            "--seed",
            metavar="S",
            help=f"Seed of folds and classifiers (default {_default('seed')}).",
            show_default=False,
        ),
    ] = None,
    jobs: Annotated[
        int,
        typer.Option(
            "--jobs",
            "-j",
            min=1,
            metavar="N",
            help="Parallel local worker processes (at most one per core unless --oversubscribe).",
        ),
    ] = 1,
    oversubscribe: Annotated[
        bool,
        typer.Option("--oversubscribe", help="Allow more --jobs than this machine has cores."),
    ] = False,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", metavar="tcp://HOST:PORT", help="Run on a Dask cluster."),
    ] = None,
    timeout: Annotated[
        float | None,
        typer.Option(
            "--timeout",
            metavar="SECONDS",
            help=(
                "Seconds per task before it is stopped (0: no limit; default "
                f"{_default('timeout'):g})."
            ),
            show_default=False,
        ),
    ] = None,
    max_memory_mb: Annotated[
        str | None,
        typer.Option(
            "--max-memory",
            metavar="MB|none",
            help=(
                "Megabytes one task may allocate (beyond its copy of the data) before it fails, "
                "marked, while the run goes on; none (or 0): no limit. Default: the memory "
                "available when the run starts, less a tenth of the RAM, shared by the --jobs "
                f"workers ({_memory_default()}); stored with the run as task_memory_mb."
            ),
            show_default=False,
        ),
    ] = None,
    metric: Annotated[
        str | None, typer.Option("--metric", metavar="NAME", help="Rank by this metric.")
    ] = None,
    baseline: Annotated[
        str | None,
        typer.Option("--baseline", metavar="ID", help="Classifier the t-test compares against."),
    ] = None,
    resume: Annotated[
        int | None,
        typer.Option("--resume", metavar="RUN", help="Finish an interrupted run.", min=1),
    ] = None,
    weka: Annotated[
        list[str] | None,
        typer.Option(
            "--weka",
            metavar="COMMAND",
            help=(
                'A WEKA command line to run as well, e.g. "weka.classifiers.trees.J48 -C 0.1 '
                '-M 5" (J48, PART, NaiveBayes, IBk, ZeroR; repeat for several).'
            ),
            show_default=False,
        ),
    ] = None,
    position: Annotated[
        str | None,
        typer.Option(
            "--position",
            metavar="X,Y[,Z]",
            help=(
                "Numeric targets that are a position's coordinates: also score the mean "
                "Euclidean error."
            ),
            show_default=False,
        ),
    ] = None,
    tune: Annotated[
        bool,
        typer.Option(
            "--tune",
            help=(
                "Add a tuned twin (ID+tuned) of every classifier that declares a search space: "
                "successive halving with a 3-fold inner CV of each outer training fold only "
                "(nested CV); the leaderboard compares each twin with its default."
            ),
        ),
    ] = False,
    budget: Annotated[
        float | None,
        typer.Option(
            "--budget",
            metavar="MINUTES",
            help=(
                "With --tune: wall minutes each tuned twin's search may plan for in one outer "
                "fold (0 < MINUTES <= 1440). Its cost is estimated from two timed fits of "
                "the default setting and the search's own overhead, and the first halving "
                "round gets as many candidates (3, 9, 27, ...) as fit. Default: about 6 fits "
                "of the default setting on the whole training fold."
            ),
            show_default=False,
        ),
    ] = None,
    stack: Annotated[
        int | None,
        typer.Option(
            "--stack",
            metavar="TOP_N",
            help=(
                "Add stack-topN (1 <= N <= 20, one target): in each outer training fold the N "
                "classifiers of the run best by a 3-fold inner CV, stacked by logistic "
                "regression. Costs about 2 fits of every classifier of the run (each at its "
                "own cost, a tuned twin with its search) plus N refits, per outer fold."
            ),
            show_default=False,
        ),
    ] = None,
    ensemble: Annotated[
        int | None,
        typer.Option(
            "--ensemble",
            metavar="N",
            help=(
                "Add ensemble-N (1 <= N <= 100, one target): in each outer training fold, N "
                "rounds of Caruana's greedy ensemble selection with replacement over the "
                "run's entries, chosen on their out-of-fold predictions of 3 inner folds of "
                "that training fold (never its test fold); the weights are shown. Computed "
                "from fold predictions: costs about 3 more fits of every entry per outer "
                "fold, shared with --stack."
            ),
            show_default=False,
        ),
    ] = None,
    independent: Annotated[
        bool,
        typer.Option(
            "--independent",
            help=(
                "Multi-target data: benchmark each target separately with multi-class "
                "classifiers and report the product of the best scores (the paper's comparison)."
            ),
        ),
    ] = False,
    race: Annotated[
        bool,
        typer.Option(
            "--race",
            help=(
                "Race: every classifier on fold 1, then fold 2, ... (dear first); after each "
                "fold from the third, those significantly worse than the leader (corrected "
                "resampled t-test, its variances moderated across the fold's entries, at "
                "--race-alpha) stop, marked `dropped after fold k`. The leader and the "
                "baseline never stop. Needs 3 folds or more."
            ),
        ),
    ] = False,
    race_alpha: Annotated[
        float | None,
        typer.Option(
            "--race-alpha",
            metavar="ALPHA",
            help=f"With --race: the t-test's level, 0 < ALPHA < 0.5 (default "
            f"{_default('race_alpha'):g}).",
            show_default=False,
        ),
    ] = None,
    budget_total: Annotated[
        float | None,
        typer.Option(
            "--budget-total",
            metavar="MINUTES",
            help=(
                "Wall minutes for the whole run: folds run fold-major, cheap first, and a task "
                "whose predicted cost (its classifier's timed folds, else a hint from the "
                "data's shape) does not fit the time left is not started; the leaderboard "
                "says what was cut."
            ),
            show_default=False,
        ),
    ] = None,
    aggregate: Annotated[
        str | None,
        typer.Option(
            "--aggregate",
            metavar="window|recording",
            help=(
                "recording: score each recording's windows as one prediction (the mean of "
                "their class probabilities; a majority vote for classifiers without them; the "
                "mean prediction of numeric targets); needs a data set extracted from "
                "recordings, one label per recording. Default: window (each window scored)."
            ),
            show_default=False,
        ),
    ] = None,
    ablate_groups: Annotated[
        str | None,
        typer.Option(
            "--ablate-groups",
            metavar="channel|family",
            help=(
                "Then rerun the classifiers on the same folds with each group of features "
                "removed (channel: the _1, _2... suffixes or CHANNEL[T] windows; family: a "
                "statistic across channels), each against the full set with the corrected "
                "t-test."
            ),
            show_default=False,
        ),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Cross-validate classifiers on a data set; every finished fold is stored at once.

    A data set with several targets gets the multi-target configurations (META:BASE, e.g.
    bcc:rf) unless --target picks one target for the multi-class catalogue. Numeric targets
    are a regression: regressors (linear, ridge, rf, xgb, ...; rc:ID chains several targets),
    ranked by mean absolute error. Ctrl-C keeps
    every finished fold: `touchbench bench --resume RUN` carries out the rest.
    """
    values = _bench_values(locals())  # first: the parameters, before any other name
    from touchbench.app.cli.progress import TaskProgress, TenthsProgress
    from touchbench.app.cli.requests import build_request
    from touchbench.app.errors import ConflictError
    from touchbench.app.services.bench import RunInterrupted, bench_here
    from touchbench.app.services.runs import RunCancelled
    from touchbench.app.store.states import RunBusy

    store = get_state(ctx).store
    if resume is not None:
        _check_resume(values)
    elif dataset is None:
        raise typer.BadParameter("missing DATASET (or --resume RUN)")
    bench = None if resume is not None else build_request(BenchRequest, BENCH_OPTIONS, **values)
    request = build_request(
        BenchHereRequest, BENCH_OPTIONS, bench=bench, resume=resume, ablate_groups=ablate_groups
    )
    jobs = _check_jobs(jobs, oversubscribe)
    if scheduler is not None:
        from touchbench.benchmark.run.dask_backend import connect

        connect(scheduler).close()  # fail before a run exists, not after
    # On stderr whatever the output: --json keeps stdout to the JSON, not the progress.
    progress = TaskProgress()
    try:
        with progress:
            benched = bench_here(
                store,
                request,
                jobs=jobs,
                scheduler=scheduler,
                callbacks=progress.callbacks(),
                # a line per tenth of the work: an ablation reruns every classifier per group
                on_ablation=TenthsProgress("ablation", quiet=as_json),
            )
    except RunBusy as busy:
        raise ConflictError(f"{busy} (`touchbench cancel {busy.run_id}` stops it)") from None
    except RunInterrupted as interrupted:  # Ctrl-C or SIGTERM (app.cli.signals)
        code = getattr(interrupted.__cause__, "exit_code", EXIT_INTERRUPTED)
        message = _kept_message(store, interrupted.run_id, Status.INTERRUPTED)
        raise ExitWith(message, code) from None
    except RunCancelled as cancelled:
        message = _kept_message(store, cancelled.run.id, Status.CANCELLED)
        raise ExitWith(message, EXIT_FAILED) from None
    if benched.independent is not None:
        _print_independent(benched.independent, as_json)
        return
    run = benched.run
    assert run is not None  # a run of its own when the targets are not benchmarked apart
    if run.status == Status.FAILED:
        _print_run_report(store, run.id, metric, baseline, as_json)
        raise ExitWith(
            f"run {run.id} failed: {run.error} (`touchbench leaderboard {run.id}` lists why)",
            EXIT_FAILED,
        )
    if benched.ablation_job is not None and not as_json:
        info(f"ablation kept as job {benched.ablation_job}")
    _print_run_report(store, run.id, metric, baseline, as_json, benched.ablation)


def _options_of(command: Callable[..., Any]) -> dict[str, str]:
    """How the command line spells each parameter of ``command``, as typer reads its
    signature: its first option name, or an argument's metavar (what a refused field is
    shown as, :mod:`app.cli.requests`)."""
    spelt = {}
    for name, parameter in get_params_from_function(command).items():
        declared = parameter.default
        if isinstance(declared, OptionInfo) and declared.param_decls:
            spelt[name] = declared.param_decls[0]
        elif isinstance(declared, ArgumentInfo):
            spelt[name] = declared.metavar or name.upper()
    return spelt


#: The option of each parameter of ``bench``: each field of
#: :class:`app.schemas.runs.BenchRequest` (and ``resume`` and ``ablate_groups`` of
#: :class:`app.schemas.runs.BenchHereRequest`) is a parameter of the same name, declared once,
#: in the command's signature.
BENCH_OPTIONS = _options_of(bench_command)
#: Fields given as comma-separated lists (``-c nb,j48``).
_COMMA_LISTS = ("classifiers", "position")
#: Fields that only say how ``bench`` prints the leaderboard of a resumed run.
_REPORT_FIELDS = ("metric", "baseline")


def _split(text: str | None) -> list[str] | None:
    """``a, b,c`` as ``["a", "b", "c"]``; ``None`` when not given."""
    return None if text is None else [part.strip() for part in text.split(",") if part.strip()]


def _bench_values(parameters: Mapping[str, Any]) -> dict[str, Any]:
    """The fields of a :class:`BenchRequest` from ``bench``'s parameters: lists split, an
    option not given (``None``, a repeatable one empty) left out of the request's way."""
    values = {}
    for field in BenchRequest.model_fields:
        value = parameters[field]
        if field in _COMMA_LISTS:
            value = _split(value)
        elif isinstance(value, list):
            value = value or None
        values[field] = value
    return values


def _check_resume(values: Mapping[str, object]) -> None:
    """A resumed run keeps what it was asked: refuse options that would change it."""
    if values["dataset"] is not None:
        raise typer.BadParameter("give either DATASET or --resume RUN, not both")
    for field, value in values.items():
        if field not in _REPORT_FIELDS and value is not None and value is not False:
            raise typer.BadParameter(
                f"{BENCH_OPTIONS[field]} is kept by the run; drop it with --resume"
            )


def cancel_command(
    ctx: typer.Context,
    run_id: Annotated[
        int, typer.Argument(metavar="RUN", help="Run id (see `touchbench runs`).", min=1)
    ],
    as_json: JsonOption = False,
) -> None:
    """Cancel a run: a queued run at once, a running one as soon as its process hears of it."""
    from touchbench.app.services.lifecycle import cancel_run

    run = cancel_run(get_state(ctx).store, run_id)
    if as_json:
        print_json(run.to_json())
        return
    if run.status == Status.CANCELLED:
        info(f"run {run.id} cancelled ({run.n_results}/{run.n_tasks} tasks kept)")
    else:
        info(f"run {run.id} is cancelling: {run.owner} stops it within about half a second")


def _check_jobs(jobs: int, oversubscribe: bool) -> int:
    from touchbench.benchmark.run.engine import available_cores

    cores = available_cores()
    if jobs > cores and not oversubscribe:
        raise typer.BadParameter(
            f"{jobs} jobs but this machine has {cores} core(s); each job is a process with "
            "its own copy of the data (add --oversubscribe to run more anyway)",
            param_hint="--jobs",
        )
    return jobs


def _kept_message(store: Store, run_id: int, what: str) -> str:
    from touchbench.app.services.lifecycle import get_run

    run = get_run(store, run_id)
    return (
        f"run {run.id} {what}: {run.n_results} of {run.n_tasks} tasks are stored; "
        f"`touchbench bench --resume {run.id}` carries out the rest"
    )


def _print_run_report(
    store: Store,
    run_id: int,
    metric: str | None,
    baseline: str | None,
    as_json: bool,
    ablation: AblationResult | None = None,
) -> None:
    ranked = _ranked(store, run_id, metric, baseline)
    report = ranked.report()
    if as_json:
        extra = {} if ablation is None else {"ablation": ablation.to_json()}
        print_json({**report.to_json(), **extra})
        return
    _print_leaderboard(ranked)
    _print_run_tables(report)
    if ablation is not None:
        from touchbench.app.reports.answer_tables import ablation_table

        run_table(ablation_table(ablation))
        info(
            "change: mean of (without - full) over the folds; can go: no significant change; "
            "needed: significantly worse without"
        )


def _ranked(
    store: Store,
    run_id: int,
    metric: str | None,
    baseline: str | None,
    beside: Sequence[int] = (),
    aggregate: str | None = None,
) -> RunLeaderboard:
    """A run's leaderboard; a run without results says how to carry it out."""
    from touchbench.app.errors import AppError
    from touchbench.app.services.runs import NoResultsError, run_leaderboard

    try:
        return run_leaderboard(
            store, run_id, metric=metric, baseline=baseline, beside=beside, aggregate=aggregate
        )
    except NoResultsError as missing:
        run = missing.run
        if missing.under_way:
            raise
        raise AppError(
            f"run {run.id} has no results yet (it is {run.status}; "
            f"`touchbench bench --resume {run.id}` carries it out)"
        ) from None


def runs_command(ctx: typer.Context, as_json: JsonOption = False) -> None:
    """List benchmark runs with their status and progress."""
    from touchbench.app.schemas.runs import RunList
    from touchbench.app.services.lifecycle import list_runs

    runs = list_runs(get_state(ctx).store)
    if as_json:
        print_json(RunList(runs=[run.schema() for run in runs]).to_json())
        return
    if not runs:
        info("no runs yet: `touchbench bench DATASET` starts one")
        return
    table(
        None,
        ["id", "dataset", "targets", "classifiers", "tasks", "status", "started"],
        [
            (
                run.id,
                run.dataset_name,
                ", ".join(run.targets),
                len(run.classifiers),
                run.tasks_text(),
                run.status,
                run.created_at.strftime("%Y-%m-%d %H:%M"),
            )
            for run in runs
        ],
    )


def leaderboard_command(
    ctx: typer.Context,
    run_id: Annotated[
        int, typer.Argument(metavar="RUN", help="Run id (see `touchbench runs`).", min=1)
    ],
    metric: Annotated[
        str | None, typer.Option("--metric", metavar="NAME", help="Rank by this metric.")
    ] = None,
    baseline: Annotated[
        str | None,
        typer.Option("--baseline", metavar="ID", help="Classifier the t-test compares against."),
    ] = None,
    output_format: Annotated[
        str,
        typer.Option(
            "--format", "-f", metavar="FORMAT", help="table, json, csv, markdown or arff."
        ),
    ] = "table",
    beside: Annotated[
        list[int] | None,
        typer.Option(
            "--beside",
            metavar="RUN",
            help=(
                "Also rank this run's classifiers (same data set and target; repeatable), "
                "e.g. a paper's imported WEKA results: t-tested where the folds pair, "
                "means only where they do not."
            ),
        ),
    ] = None,
    aggregate: RescoreOption = None,
    as_json: JsonOption = False,
) -> None:
    """Show a run's leaderboard with WEKA's significance marks (v better, * worse)."""
    if as_json:
        output_format = "json"
    if output_format not in FORMATS:
        raise typer.BadParameter(
            f"'{output_format}' is not one of {', '.join(FORMATS)}", param_hint="--format"
        )
    from touchbench.app.reports.leaderboard import (
        leaderboard_csv,
        leaderboard_markdown,
        metric_columns,
    )

    store = get_state(ctx).store
    ranked = _ranked(store, run_id, metric, baseline, beside or (), aggregate)
    run, board = ranked.run, ranked.board
    columns = metric_columns(run, board)
    if output_format == "json":
        print_json(ranked.report().to_json())
    elif output_format == "csv":
        sys.stdout.write(
            leaderboard_csv(board, columns, ranked.besides, aggregate=ranked.aggregate)
        )
    elif output_format == "markdown":
        sys.stdout.write(leaderboard_markdown(run, board, columns, ranked.besides, ranked.notes()))
    elif output_format == "arff":
        from touchbench.app.reports.results_arff import write_results_arff

        write_results_arff(ranked, sys.stdout)
    else:
        _print_leaderboard(ranked)
        _print_run_tables(ranked.report())


def _print_run_tables(report: LeaderboardSchema) -> None:
    """Tuned twins beside their defaults, what each fold chose, and a multi-target
    regression's scores per target (nothing of what the run lacks)."""
    from touchbench.app.reports.run_tables import run_tables

    for shown in run_tables(report):
        run_table(shown)


def _print_independent(result: IndependentResult, as_json: bool) -> None:
    if as_json:
        print_json(result.to_json())
        return
    rows: list[tuple[object, ...]] = []
    for target, (run, board) in result.runs.items():
        best = board.rows[0]
        rows.append(
            (
                target,
                run.id,
                best.classifier,
                f"{best.metrics['accuracy'][0]:.4f}",
                f"{best.metrics['f1_weighted'][0]:.4f}",
            )
        )
    product = result.product
    rows.append(("product", "", "", f"{product['accuracy']:.4f}", f"{product['f1_weighted']:.4f}"))
    table(
        "each target classified independently (best multi-class classifier per target)",
        ["target", "run", "best", "accuracy", "f1_weighted"],
        rows,
    )


def _print_leaderboard(ranked: RunLeaderboard) -> None:
    from touchbench.app.reports.leaderboard import (
        beside_notes,
        leaderboard_header,
        leaderboard_rows,
        metric_columns,
    )

    run, board = ranked.run, ranked.board
    columns = metric_columns(run, board)
    direction = " (lower is better)" if board.lower_is_better else ""
    scored = ", scored per recording" if ranked.per_recording else ""
    table(
        f"run {run.id}: {run.dataset_name} ({', '.join(run.targets)}), "
        f"{run.folds_text}, "
        f"ranked by {board.metric}{direction}{scored}",
        leaderboard_header(board, columns, ranked.besides),
        leaderboard_rows(board, columns, ranked.besides),
    )
    for note in beside_notes(ranked.besides):
        info(note)
    if board.baseline is None:
        info(f"no task of run {run.id} succeeded; the notes say why")
    else:
        v, same, worse = board.summary
        info(
            f"marks against {board.baseline}: v significantly better, * significantly worse "
            f"(corrected resampled t-test, alpha 0.05); (v/ /*) = ({v}/{same}/{worse})"
        )
    for note in ranked.notes():
        info(note)
