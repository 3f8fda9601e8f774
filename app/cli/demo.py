"""The demo command: the whole path on simulated sessions, in a folder of its own."""

from __future__ import annotations

# Imports inside functions: start-up time. This module holds several commands and the
# one chosen loads only what it uses (the CLI imports the module when a command of it
# is chosen).
from pathlib import Path
from typing import Annotated

import typer

from touchbench.app.cli.output import console, info, table
from touchbench.app.cli.state import get_state


def register(app: typer.Typer) -> None:
    app.command("demo")(demo_command)


def demo_command(
    ctx: typer.Context,
    folder: Annotated[
        Path, typer.Option("--dir", help="Folder for the recordings, labels and the store.")
    ] = Path("touchbench-demo"),
    sessions: Annotated[int, typer.Option("--sessions", min=2, help="Simulated sessions.")] = 4,
    jobs: Annotated[int, typer.Option("--jobs", "-j", min=1, help="Parallel workers.")] = 1,
) -> None:
    """Simulate touch sessions, extract features, benchmark, train and predict.

    Unless --db is given, the store is FOLDER/touchbench.db, so the demo never touches
    your own store.
    """
    from touchbench.app.reports.leaderboard import (
        leaderboard_header,
        leaderboard_rows,
        metric_columns,
    )
    from touchbench.app.services.demo import run_demo
    from touchbench.app.store.database import Store

    state = get_state(ctx)
    folder.mkdir(parents=True, exist_ok=True)
    explicit_db = ctx.find_root().params.get("db")
    store = state.store if explicit_db else Store(f"sqlite:///{folder.resolve()}/touchbench.db")
    result = run_demo(folder, store, n_sessions=sessions, jobs=jobs, say=info)
    columns = metric_columns(result.run, result.leaderboard)
    table(
        f"leaderboard of run {result.run.id} ({result.leaderboard.metric}, "
        f"{result.run.config.folds}-fold)",
        leaderboard_header(result.leaderboard, columns),
        leaderboard_rows(result.leaderboard, columns),
    )
    for target, accuracy in result.predictions.accuracy.items():
        console.print(
            f"model '{result.model_name}' on the unseen session: {target} accuracy {accuracy:.3f}"
        )
    if result.live:
        console.print(f"model '{result.model_name}' live on a fresh take (replayed):")
    for touch in result.live:
        said = ", ".join(f"{target} {value}" for target, (value, _) in touch.predictions.items())
        truth = next(
            (t for t in result.live_truth if t[0] < touch.end and touch.start < t[1]), None
        )
        actual = f"  (true: {truth[2]}, {truth[3]})" if truth else ""
        console.print(f"  {touch.start:7.2f}-{touch.end:7.2f} s  {said}{actual}")
    info(
        f"everything is in {folder}/ (recordings, labels.csv, holdout.arff, touchbench.db); "
        f"try: touchbench --db sqlite:///{folder}/touchbench.db leaderboard {result.run.id}"
    )
