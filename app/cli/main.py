"""The ``touchbench`` command: one console script, one sub-command per job.

Exit status: 0 success, 2 bad input or usage (one line on stderr), 1 anything unexpected.
"""

from __future__ import annotations

import contextvars
import errno
import gc
import os
import sys
import traceback
from typing import Annotated

import typer

from touchbench.app.cli import help as help_pages
from touchbench.app.cli.exits import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_USAGE, ExitWith
from touchbench.app.cli.lazy import LazyGroup, Subcommand
from touchbench.app.cli.signals import interrupted_status, interrupts
from touchbench.app.cli.state import CliState
from touchbench.app.environment import (
    DATABASE_URL_VARIABLE,
    DEFAULT_DATABASE_URL,
    database_url,
    debug,
)

EXIT_UNEXPECTED = EXIT_FAILED

#: Every sub-command, in the order ``touchbench --help`` lists them: its name, the module whose
#: ``register`` adds it, and its one-line help (its help's first paragraph, which
#: tests/app/cli/test_startup.py holds equal).  A module is imported when one of its commands
#: is chosen, so that each command pays only for what it uses.
COMMANDS = (
    Subcommand(
        "import",
        "touchbench.app.cli.datasets",
        "Import an ARFF or CSV file as a data set, named after the file.",
    ),
    Subcommand("datasets", "touchbench.app.cli.listing", "List the data sets in the store."),
    Subcommand(
        "show",
        "touchbench.app.cli.datasets",
        "Show a data set's schema, class distribution per target and missing values.",
    ),
    Subcommand(
        "export",
        "touchbench.app.cli.datasets",
        "Write a data set back as ARFF (the relation keeps MEKA's -C header for its targets).",
    ),
    Subcommand("rename", "touchbench.app.cli.datasets", "Give a data set another name."),
    Subcommand(
        "delete",
        "touchbench.app.cli.datasets",
        "Delete a data set with its instances, runs and results (not while a run uses it).",
    ),
    Subcommand(
        "classifiers",
        "touchbench.app.cli.bench",
        "List the classifier catalogue (id, WEKA name, family, capabilities).",
    ),
    Subcommand(
        "bench",
        "touchbench.app.cli.bench",
        "Cross-validate classifiers on a data set; every finished fold is stored at once.",
    ),
    Subcommand(
        "runs", "touchbench.app.cli.bench", "List benchmark runs with their status and progress."
    ),
    Subcommand(
        "leaderboard",
        "touchbench.app.cli.bench",
        "Show a run's leaderboard with WEKA's significance marks (v better, * worse).",
    ),
    Subcommand(
        "import-results",
        "touchbench.app.cli.answers",
        "Import a WEKA Experimenter results file (InstanceResultListener ARFF) as a finished "
        "run, so that leaderboards and reports rank the paper's classifiers beside ours.",
    ),
    Subcommand(
        "classes",
        "touchbench.app.cli.answers",
        "Show per-class precision, recall and F1, the confusion matrix (summed over folds) "
        "and the expected calibration error of a run's classifiers, per target.",
    ),
    Subcommand(
        "calibration",
        "touchbench.app.cli.answers",
        "Show the expected calibration error of a run's classifiers from their out-of-fold "
        "probabilities, and draw their reliability diagram.",
    ),
    Subcommand(
        "importance",
        "touchbench.app.cli.answers",
        "Permutation importance of a run's classifier on each of its outer test folds, per "
        "feature and per group of features (channel, feature family), with the t-test of each "
        "group's drop. Kept as a job: the run's web page and report show it.",
    ),
    Subcommand(
        "learning-curve",
        "touchbench.app.cli.answers",
        "Cross-validate classifiers on growing shares of each training fold (stratified, "
        "group-aware; the test folds stay whole): the share at which each comes within a point "
        'of its full score answers "do I need to record more?". Kept as a job with its progress.',
    ),
    Subcommand(
        "cancel",
        "touchbench.app.cli.bench",
        "Cancel a run: a queued run at once, a running one as soon as its process hears of it.",
    ),
    Subcommand(
        "train",
        "touchbench.app.cli.models",
        "Fit a classifier on every instance of a data set and store the model.",
    ),
    Subcommand(
        "models",
        "touchbench.app.cli.models",
        "List trained models, a row per version, with their aliases (artifacts are not read).",
    ),
    Subcommand(
        "predict",
        "touchbench.app.cli.models",
        "Predict every instance of a file; attributes are matched to the model's by name.",
    ),
    Subcommand(
        "delete-model",
        "touchbench.app.cli.models",
        "Delete a trained model (one version: NAME alone is its newest).",
    ),
    Subcommand(
        "alias",
        "touchbench.app.cli.models",
        "Point an alias of a model (NAME@ALIAS) at one of its versions.",
    ),
    Subcommand(
        "promote",
        "touchbench.app.cli.models",
        "Make a version the model's champion: NAME@champion, which `live`, `serve` and live "
        "WebSocket sessions on it follow, answers with it from now on (`rollback` undoes).",
    ),
    Subcommand(
        "rollback",
        "touchbench.app.cli.models",
        "Point the champion (or --alias) back at the version it pointed at before its last move.",
    ),
    Subcommand(
        "export-model",
        "touchbench.app.cli.models",
        "Write a model as one ONNX graph (preprocessing and classifier), checked against the "
        "model on its training instances; predictions then run it in ONNX Runtime.",
    ),
    Subcommand(
        "extract",
        "touchbench.app.cli.extract",
        "Detect touch events in recordings, extract features, and store them as a data set.",
    ),
    Subcommand(
        "extractors",
        "touchbench.app.cli.extract",
        "List the extractors and event detectors with every option (-O KEY=VALUE of extract):"
        " its type, default and meaning.",
    ),
    Subcommand(
        "demo",
        "touchbench.app.cli.demo",
        "Simulate touch sessions, extract features, benchmark, train and predict.",
    ),
    Subcommand(
        "serve",
        "touchbench.app.cli.serve",
        "Serve the REST API (data sets, recording uploads, runs, leaderboards, models, "
        "predictions) at http://HOST:PORT/api, its documentation at /docs.",
    ),
    Subcommand(
        "compare",
        "touchbench.app.cli.reports",
        "Compare the classifiers that all the runs share, one score per data set (the run's "
        "mean): average ranks, Friedman's test (chi-square and Iman-Davenport F), the Nemenyi"
        " critical difference, Holm's test against the best, and the groups not significantly"
        " different (Demšar 2006). With one run, its folds are the blocks (descriptive only).",
    ),
    Subcommand(
        "plot",
        "touchbench.app.cli.reports",
        "Draw one plot of a run as SVG (text kept as text) or PNG.",
    ),
    Subcommand(
        "report",
        "touchbench.app.cli.reports",
        "Write one self-contained HTML file (inline SVG, no network) with each run's "
        "leaderboard and marks, plots, configuration and library versions, and the comparison"
        " across runs: ready to attach to a paper's supplementary material.",
    ),
    Subcommand(
        "devices",
        "touchbench.app.cli.capture",
        "List the capture devices PortAudio sees (index, name, input channels, default rate).",
    ),
    Subcommand(
        "record",
        "touchbench.app.cli.capture",
        "Record a labelled take into a session folder: OUT/take-NNN.wav plus a row of "
        "OUT/labels.csv (file,TARGET...), the input of `touchbench extract`.",
    ),
    Subcommand(
        "simulate", "touchbench.app.cli.capture", "Write simulated recordings and their labels CSV."
    ),
    Subcommand(
        "live",
        "touchbench.app.cli.capture",
        "Predict every touch of a live stream with a model: its own event detection and "
        "extractor run on the stream, and each touch is printed as soon as it ends.",
    ),
    Subcommand(
        "ros",
        "touchbench.app.cli.ros",
        "Run a ROS node that predicts every touch of an audio or taxel topic with a model and "
        "publishes each as a std_msgs/String JSON message (what `live --json` prints).",
    ),
)


class TouchbenchGroup(LazyGroup):
    """The ``touchbench`` group: :data:`COMMANDS`, each module imported when chosen.

    ``--db URL`` is the group's, but is taken after the command's name too
    (``touchbench datasets --db URL``), as people write it.
    """

    subcommands = COMMANDS

    def parse_args(self, ctx: typer.Context, args: list[str]) -> list[str]:  # type: ignore[override]
        return super().parse_args(ctx, global_options_first(args))


def global_options_first(args: list[str]) -> list[str]:
    """``args`` with every ``--db URL`` (or ``--db=URL``) after the command's name moved
    before it; nothing after ``--`` is touched."""
    names = {command.name for command in COMMANDS}
    position = next((i for i, arg in enumerate(args) if arg in names), None)
    if position is None:
        return args
    moved, rest, i = [], list(args[: position + 1]), position + 1
    while i < len(args):
        arg = args[i]
        if arg == "--":
            rest += args[i:]
            break
        if arg == "--db" and i + 1 < len(args):
            moved += args[i : i + 2]
            i += 2
            continue
        if arg.startswith("--db="):
            moved.append(arg)
        else:
            rest.append(arg)
        i += 1
    return moved + rest


help_pages.install()

app = typer.Typer(
    name="touchbench",
    help=(
        "Benchmark classifiers for robot touch sensing, WEKA/MEKA style: import ARFF/CSV "
        "data sets (or extract them from recordings), run k-fold cross-validation over dozens "
        "of multi-class and multi-target classifiers, read leaderboards with WEKA's "
        "corrected t-test, and train models for live prediction."
    ),
    cls=TouchbenchGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _print_version(value: bool) -> None:
    if value:
        from importlib import metadata  # start-up time: only --version reads it

        print(f"touchbench {metadata.version('touchbench')}")
        raise typer.Exit()


@app.callback()
def root(
    ctx: typer.Context,
    db: Annotated[
        str | None,
        typer.Option(
            "--db",
            metavar="URL",
            help=(
                f"SQLAlchemy URL of the store, e.g. {DEFAULT_DATABASE_URL} or "
                f"postgresql://user@host/db. Default: ${DATABASE_URL_VARIABLE}, else "
                f"{DEFAULT_DATABASE_URL} in the current directory."
            ),
            show_default=False,
        ),
    ] = None,
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            callback=_print_version,
            is_eager=True,
            help="Print touchbench's version and exit.",
        ),
    ] = False,
) -> None:
    ctx.obj = CliState(database_url=db or database_url())


# What importing the CLI made (objects that live as long as the process) is moved out of the
# cyclic collector's reach: every full collection would walk it again, and one more runs at
# exit.  Most such objects come with the chosen command's module (some 60 000 for `datasets`,
# with SQLAlchemy and the store), which app.cli.lazy freezes the same way once imported.
gc.freeze()


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns (and, as a console script, exits with) the status.

    Each call runs in a context of its own, so that what a command leaves in context
    variables (the options of its request, :mod:`app.cli.requests`) ends with it.
    """
    return contextvars.copy_context().run(_main, argv)


def _main(argv: list[str] | None) -> int:
    command = typer.main.get_command(app)
    try:
        with interrupts():
            returned = command.main(args=argv, prog_name="touchbench", standalone_mode=False)
    except typer.Exit as done:
        return _exit(done.exit_code)
    except ExitWith as outcome:
        print(f"touchbench: {outcome}", file=sys.stderr)
        return outcome.exit_code
    except typer.Abort as abort:  # click's wrapping of a KeyboardInterrupt
        print("touchbench: interrupted", file=sys.stderr)
        return getattr(abort.__cause__, "exit_code", EXIT_INTERRUPTED)
    except typer.TyperException as error:  # typer's (vendored click's) usage errors
        context = getattr(error, "ctx", None)
        hint = f" (see '{context.command_path} --help')" if context is not None else ""
        message = error.format_message() if hasattr(error, "format_message") else str(error)
        print(f"touchbench: error: {message}{hint}", file=sys.stderr)
        return _exit(EXIT_USAGE)
    except KeyboardInterrupt as interrupt:
        print("touchbench: interrupted", file=sys.stderr)
        return getattr(interrupt, "exit_code", EXIT_INTERRUPTED)
    except SystemExit as stop:  # the reader went away (`show mini | head -1`): nothing wrong
        if not _reader_gone(stop):
            raise
        _discard_output()
        return 0
    except Exception as error:
        return _failed(error)
    if returned == EXIT_INTERRUPTED:  # typer turned an interrupt into this status, silently
        print("touchbench: interrupted", file=sys.stderr)
        return interrupted_status()  # 143 for SIGTERM, as the README promises
    return returned if isinstance(returned, int) else 0


def _failed(error: Exception) -> int:
    """One line on stderr for a command that raised ``error``, and the exit status.

    Bad input (:data:`app.errors.USER_ERRORS`) exits 2; anything else is a bug: said so in
    one line, with the traceback on request.
    """
    # loaded when a command fails: start-up time (app.errors imports the drivers and NumPy)
    from touchbench.app.cli.requests import describe
    from touchbench.app.errors import USER_ERRORS, FieldError

    if isinstance(error, USER_ERRORS):
        message = describe(error) if isinstance(error, FieldError) else str(error)
        print(f"touchbench: error: {message}", file=sys.stderr)
        return EXIT_USAGE
    if debug():
        traceback.print_exc()
    # the first line only: a driver's error adds the statement and its parameters below it
    message = next(iter(str(error).strip().splitlines()), "")
    print(
        f"touchbench: unexpected error: {type(error).__name__}: {message} "
        "(set TOUCHBENCH_DEBUG=1 for the traceback)",
        file=sys.stderr,
    )
    return EXIT_UNEXPECTED


def _reader_gone(stop: SystemExit) -> bool:
    """Whether ``stop`` is how click or rich answer a closed standard output: both exit 1
    while handling the ``BrokenPipeError`` (click for a command's output, rich for a table
    or a help page), where the command did nothing wrong."""
    cause: BaseException | None = stop.__context__
    while cause is not None:
        if isinstance(cause, OSError) and cause.errno == errno.EPIPE:
            return True
        cause = cause.__context__
    return False


def _discard_output() -> None:
    """Send what is still to be written to the standard output nowhere, so that the flush
    at exit does not meet the closed pipe again (Python would print that it ignored it)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # no real standard output (a test's captured one)
        pass


def _exit(code: int | None) -> int:
    return 0 if code is None else int(code)


def run() -> None:
    sys.exit(main())


if __name__ == "__main__":
    run()
