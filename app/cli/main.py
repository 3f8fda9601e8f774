"""The ``touchbench`` command: one console script, one sub-command per job.

Exit status: 0 success, 2 bad input or usage (one line on stderr), 1 anything unexpected.
"""

from __future__ import annotations

import gc
import os
import sys
import traceback
from typing import Annotated

import typer

from app.cli import bench as bench_commands
from app.cli import capture as capture_commands
from app.cli import datasets as datasets_commands
from app.cli import demo as demo_commands
from app.cli import extract as extract_commands
from app.cli import help as help_pages
from app.cli import models as models_commands
from app.cli import reports as reports_commands
from app.cli import serve as serve_commands
from app.cli.output import EXIT_FAILED, EXIT_INTERRUPTED, ExitWith
from app.cli.requests import describe, reset
from app.cli.signals import interrupts
from app.cli.state import CliState
from app.errors import USER_ERRORS, FieldError
from app.settings import get_settings

EXIT_USAGE = 2
EXIT_UNEXPECTED = EXIT_FAILED


help_pages.install()

app = typer.Typer(
    name="touchbench",
    help=(
        "Benchmark classifiers for robot touch sensing, WEKA/MEKA style: import ARFF/CSV "
        "data sets (or extract them from recordings), run k-fold cross-validation over dozens "
        "of multi-class and multi-target classifiers, read leaderboards with WEKA's "
        "corrected t-test, and train models for live prediction."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _print_version(value: bool) -> None:
    if value:
        from importlib import metadata

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
                "SQLAlchemy URL of the store, e.g. sqlite:///touchbench.db or "
                "postgresql://user@host/db. Default: $TOUCHBENCH_DATABASE_URL, else "
                "sqlite:///touchbench.db in the current directory."
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
    ctx.obj = CliState(database_url=db or get_settings().database_url)


datasets_commands.register(app)
bench_commands.register(app)
models_commands.register(app)
extract_commands.register(app)
demo_commands.register(app)
serve_commands.register(app)
reports_commands.register(app)
capture_commands.register(app)

# What importing the CLI made (some 100 000 objects that live as long as the process) is
# moved out of the cyclic collector's reach: every full collection would walk it again, and
# one more runs at exit, together a few tenths of a second of an import's CPU time.
gc.freeze()


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns (and, as a console script, exits with) the status."""
    command = typer.main.get_command(app)
    reset()
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
    except USER_ERRORS as error:
        message = describe(error) if isinstance(error, FieldError) else str(error)
        print(f"touchbench: error: {message}", file=sys.stderr)
        return _exit(EXIT_USAGE)
    except KeyboardInterrupt as interrupt:
        print("touchbench: interrupted", file=sys.stderr)
        return getattr(interrupt, "exit_code", EXIT_INTERRUPTED)
    except Exception as error:  # anything else is a bug: say so in one line, trace on request
        if os.environ.get("TOUCHBENCH_DEBUG"):
            traceback.print_exc()
        print(
            f"touchbench: unexpected error: {type(error).__name__}: {error} "
            "(set TOUCHBENCH_DEBUG=1 for the traceback)",
            file=sys.stderr,
        )
        return _exit(EXIT_UNEXPECTED)
    if returned == EXIT_INTERRUPTED:  # typer turned a Ctrl-C into this status, silently
        print("touchbench: interrupted", file=sys.stderr)
    return returned if isinstance(returned, int) else 0


def _exit(code: int | None) -> int:
    return 0 if code is None else int(code)


def run() -> None:
    sys.exit(main())


if __name__ == "__main__":
    run()
