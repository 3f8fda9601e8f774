"""A run's progress as a tqdm bar: a widget in Jupyter, a line in a terminal."""

from __future__ import annotations

# Imports inside functions: start-up time: tqdm's notebook widgets load with the first bar.
import warnings
from typing import Any

from touchbench.app.services.runs import Callbacks
from touchbench.benchmark.results import TaskResult


class RunBar:
    """The callbacks of a run that drive one progress bar (``with RunBar() as bar``).

    Parameters
    ----------
    show : bool
        Draw the bar; ``False`` keeps quiet (warnings still reach Python's warnings).
    """

    def __init__(self, *, show: bool = True) -> None:
        self.show = show
        self._bar: Any = None
        self.failures = 0

    def __enter__(self) -> RunBar:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def callbacks(self) -> Callbacks:
        return Callbacks(
            on_plan=self._plan,
            on_result=self._result,
            on_warning=self.warn,
            on_note=self.warn,
            on_end=lambda run: self.close(),
        )

    def _plan(self, total: int, done: int) -> None:
        if not self.show:
            return
        from tqdm.auto import tqdm

        self._bar = tqdm(total=total, initial=done, desc="touchbench", unit="task")

    def _result(self, result: TaskResult) -> None:
        if result.status != "ok":
            self.failures += 1
        if self._bar is not None:
            self._bar.set_postfix_str(
                f"{result.key.classifier} fold {result.key.fold + 1}", refresh=False
            )
            self._bar.update(1)

    @staticmethod
    def warn(message: str) -> None:
        """An adjustment the run made (fewer folds than asked...), as a Python warning."""
        warnings.warn(message, stacklevel=1)
