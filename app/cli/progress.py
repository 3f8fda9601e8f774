"""Progress of long runs: tasks done, the classifier at work, time left.

On stderr, so that stdout stays the command's output (a table, or JSON with ``--json``,
even when stdout is redirected): a bar when stderr is a terminal, else one plain line
per finished task (logs, CI, ``2> run.log``).
"""

from __future__ import annotations

import sys
from types import TracebackType

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from touchbench.app.cli.output import info
from touchbench.app.services.runs import Callbacks
from touchbench.benchmark.results import TaskKey, TaskResult


class TaskProgress:
    """Callbacks for :mod:`app.services.runs` that draw a bar; a context manager."""

    def __init__(self, *, enabled: bool | None = None, lines: bool | None = None) -> None:
        terminal = sys.stderr.isatty()
        self.enabled = terminal if enabled is None else enabled
        #: One plain line per finished task instead of the bar.
        self.lines = (not self.enabled) if lines is None else lines
        self._total: int | None = None
        self._done = 0
        self._progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("[dim]{task.fields[current]}"),
            TimeElapsedColumn(),
            TextColumn("eta"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=False,
            disable=not self.enabled,
        )
        self._task = self._progress.add_task("tasks", total=None, current="")
        self.failures = 0

    def __enter__(self) -> TaskProgress:
        self._progress.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self._progress.stop()

    def callbacks(self) -> Callbacks:
        return Callbacks(
            on_plan=self.plan,
            on_start=self.start,
            on_result=self.finish,
            on_warning=self.warn,
            on_note=self.note,
            on_end=lambda run: self._progress.stop(),  # what follows the run is not its bar
        )

    def plan(self, total: int, done: int) -> None:
        self._progress.update(self._task, total=total, completed=done)
        self._total, self._done = total, done
        if self.lines:
            self._line(f"{total} task(s), {done} done before")

    def start(self, key: TaskKey) -> None:
        self._progress.update(
            self._task, current=f"{key.classifier} (repeat {key.repeat + 1}, fold {key.fold + 1})"
        )

    def finish(self, result: TaskResult) -> None:
        if result.status != "ok":
            self.failures += 1
            self.warn(
                f"{result.key.classifier} fold {result.key.fold + 1}: {result.status}: "
                f"{result.error}"
            )
        self._progress.advance(self._task)
        self._done += 1
        if self.lines:
            key = result.key
            self._line(
                f"{self._done}/{self._total if self._total is not None else '?'} "
                f"{key.classifier} repeat {key.repeat + 1} fold {key.fold + 1}: {result.status}"
            )

    def _line(self, text: str) -> None:
        """A plain progress line on stderr (no markup, no colour)."""
        print(f"progress: {text}", file=sys.stderr, flush=True)

    def warn(self, message: str) -> None:
        """Something the user should look at (a failed task...)."""
        self._progress.console.print(
            f"[yellow]warning:[/yellow] {escape(message)}", highlight=False, soft_wrap=True
        )

    def note(self, message: str) -> None:
        """A routine adjustment worth knowing (fewer folds, how folds are stratified...)."""
        self._progress.console.print(f"note: {escape(message)}", highlight=False, soft_wrap=True)


class TenthsProgress:
    """One line on stderr per tenth of a job's tasks (an ablation, a learning curve), from
    the partial answers it reports (``done``, ``total``, ``complete``); silent with
    ``--json``, whose stdout is the answer alone anyway."""

    def __init__(self, what: str, *, quiet: bool) -> None:
        self._what = what
        self._quiet = quiet
        self._shown = 0

    def __call__(self, partial: object) -> None:
        done, total = getattr(partial, "done", 0), getattr(partial, "total", 0)
        tenth = done // max(total // 10, 1)
        if self._quiet or (tenth <= self._shown and not getattr(partial, "complete", False)):
            return
        self._shown = tenth
        info(f"{self._what}: {done} of {total} tasks done")
